"""Navigation EKF: an EKF3-like error-state filter, one lane per IMU, with primary selection.

Design (``ardupilot-reference.md`` sections 3.2-3.4, 3.8):

* Nominal state 16 (quaternion body->NED, velocity NED, position NED, gyro bias, accel bias);
  covariance over 15 error states (earth-frame attitude error, velocity, position, gyro bias,
  accel bias). No magnetic-field or wind states: the earth field is fixed from TLM_MAG_*.
* State propagation every 400 Hz tick from each lane's own IMU deltas; covariance prediction
  when >= 12 ms of IMU data has accumulated (every 5 ticks = 80 Hz, as EKF3), block-sparse.
* Sequential scalar fusion: GPS velocity N/E/D and position N/E against the lane's stored past
  state (ring buffer, delay GPS1_DELAY_MS, default 0.12 s), baro height (EK3_HGT_DELAY), 3-axis
  magnetometer (current time); EKF3 innovation gates and test ratios.
* Aiding: GPS timeouts 7 s (horizontal position/velocity invalid), 15 s (constant-position
  mode, EK3_NOAID_M_NSE); reset to GPS on timeout, on variance > EK3_GLITCH_RAD^2 and when
  GPS returns. EKF3's bad-IMU response (vertical velocity from GPS, gates bypassed, 5 m/s^2
  accel noise, height reset after 1 s) for accelerometer failures.
* Output observer (EKF3's output complementary filter, EK3_TAU_OUTPUT): controllers and logs
  read each lane's output, which follows the filter's velocity/position corrections with a
  first-order lag of 0.25 s (EKF3 adds a small integral term); resets move both at once.
  This matters where the filter state jumps without a reset, e.g. the bad-IMU response
  setting the vertical velocity to GPS: the output (and the altitude controller) keeps the old
  belief for a few tenths of a second, as ArduCopter's does.
* Lane health, error score, relative errors and the ERR 24-style primary switch (section 3.4).
* Not modelled: the output observer for the attitude (corrections are applied at once),
  earth/body magnetic field learning, wind, GPS-quality checks.

Public API (all per-tick functions are ``@njit`` and allocation-free):

* :func:`build_ekf_config` / :func:`new_ekf` -- Python, once per flight.
* :func:`ekf_update` (or :func:`ekf_predict`, :func:`ekf_fuse_gps`, :func:`ekf_fuse_baro`,
  :func:`ekf_fuse_mag`, :func:`ekf_select_primary`) -- every 400 Hz main-loop tick.
* :func:`ekf_output` / :func:`ekf_output_nav` / :func:`ekf_primary` -- what controllers and
  loggers read (the output block; ekf_output_nav fills its per-tick part).

Array layouts: :mod:`tlm_sim.ekf.layout`.
"""

from tlm_sim.ekf.config import (
    build_ekf_config,
    gps_delay_s,
    lane_imus,
    new_ekf,
)
from tlm_sim.ekf.lanes import (
    ekf_fuse_baro,
    ekf_fuse_gps,
    ekf_fuse_mag,
    ekf_gps_accuracy,
    ekf_init,
    ekf_output,
    ekf_output_nav,
    ekf_predict,
    ekf_primary,
    ekf_select_primary,
    ekf_update,
    quat_to_euler,
)

__all__ = [
    "build_ekf_config",
    "ekf_fuse_baro",
    "ekf_fuse_gps",
    "ekf_fuse_mag",
    "ekf_gps_accuracy",
    "ekf_init",
    "ekf_output",
    "ekf_output_nav",
    "ekf_predict",
    "ekf_primary",
    "ekf_select_primary",
    "ekf_update",
    "gps_delay_s",
    "lane_imus",
    "new_ekf",
    "quat_to_euler",
]
