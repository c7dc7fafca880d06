"""The named bundles in which the flight loop's arrays travel.

A flight's state, configuration, plan and logs are plain float64 arrays (each with its
:class:`tlm_sim.slots.Layout`); :func:`tlm_sim.flight.run_flight` takes them as a few named
tuples instead of two dozen positional arrays. numba types a ``NamedTuple`` of arrays as a
heterogeneous tuple: unpacking one costs nothing, and the fields are read by name
(``state.ekf``). Only numpy is imported here, so :mod:`tlm_sim.precompile` can name the bundle
types without importing the flight code.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "EkfInputs", "FlightLogs", "FlightPlan", "LoopTick", "LoopWork", "VehicleConfig",
    "VehicleInputs", "VehicleState",
]


class VehicleState(NamedTuple):
    """Everything that evolves during a flight."""

    x: np.ndarray  #: truth state (tlm_sim.dynamics.layout, SI units, NED / body FRD)
    s: np.ndarray  #: sensor state (tlm_sim.sensors.layout)
    ekf: np.ndarray  #: EKF lanes, one row per lane (tlm_sim.ekf.layout)
    sel: np.ndarray  #: the EKF's lane selector (tlm_sim.ekf.layout SEL_*)
    c: np.ndarray  #: autopilot state (tlm_sim.control.layout)
    dcm: np.ndarray  #: the DCM attitude estimator (tlm_sim.control.dcm_layout)
    gsf: np.ndarray  #: the EKF lanes' yaw estimators, one row per lane (tlm_sim.ekf.gsf_layout)
    rng: np.ndarray  #: sensor noise streams, one row per sensor (tlm_sim.rng.new_streams)
    wind_rng: np.ndarray  #: the wind turbulence generator (tlm_sim.rng.new_rng)


class VehicleConfig(NamedTuple):
    """The configuration arrays built from the parameters (a scheduled change rewrites
    slots of them in flight)."""

    frame: np.ndarray  #: frame, motors, environment (tlm_sim.dynamics.frame)
    scfg: np.ndarray  #: sensors (tlm_sim.sensors.layout C_*)
    ecfg: np.ndarray  #: EKF (tlm_sim.ekf.layout C_*)
    g: np.ndarray  #: autopilot (tlm_sim.control.layout G_*)


class FlightPlan(NamedTuple):
    """What the flight is to do, and where and when."""

    path: np.ndarray  #: the mission as NED points and per-leg data (control.wpnav.PATH_COLS)
    seg: np.ndarray  #: scratch path for take-off, RTL and landing segments
    sched: np.ndarray  #: scheduled parameter changes (tlm_sim.flight.build_schedule)
    applied: np.ndarray  #: per change, the time [us] it took effect (-1: never)
    home: np.ndarray  #: home latitude, longitude [deg] and altitude AMSL [m]
    gps_time: np.ndarray  #: GPS week and milliseconds of week at boot
    #: the pilot's transmitter: rows (time since boot [us], channels 1..8 [us PWM]) in time
    #: order, each held until the next (tlm_sim.sensors.rc); no rows: SITL's idle receiver
    rc: np.ndarray
    #: the ground station's mode requests of a pilot-flown flight: rows (time since boot [us],
    #: mode number) in time order (tlm_sim.control.pilot); no rows: none
    gcs: np.ndarray


class FlightLogs(NamedTuple):
    """The log buffers the loop fills."""

    bufs: tuple  #: one 2-D buffer per logged message (tlm_sim.logger K_*)
    counts: np.ndarray  #: rows written per buffer
    txt: np.ndarray  #: the text log (tlm_sim.ardupilot TEXT_ROW), its row count in c[TXT_N]


class LoopWork(NamedTuple):
    """Scratch the main loop hands between its stages (tlm_sim.flight.new_work)."""

    dang: np.ndarray  #: per IMU, the delta angle of this tick [rad]
    dvel: np.ndarray  #: per IMU, the delta velocity of this tick [m/s]
    rows: np.ndarray  #: the per-tick vectors (tlm_sim.flight.WORK rows)
    eo: np.ndarray  #: the EKF's output block (tlm_sim.ekf.layout O_*)


class EkfInputs(NamedTuple):
    """What the EKF takes in one main-loop tick (tlm_sim.ekf.lanes.ekf_update)."""

    dang: np.ndarray  #: per IMU, the delta angle of this tick [rad] (body FRD)
    dvel: np.ndarray  #: per IMU, the delta velocity of this tick [m/s] (body FRD)
    imu_ok: np.ndarray  #: [imu] its accel, [N_IMU + imu] its gyro delivered samples (0/1)
    gps_new: bool  #: a GPS epoch arrived this tick
    gps_pos: np.ndarray  #: its position NED from the origin [m]
    gps_vel: np.ndarray  #: its velocity NED [m/s]
    gps_fix: bool  #: it has a 3-D fix
    baro_new: bool  #: a primary-baro sample arrived this tick
    baro_alt: float  #: its altitude above the origin [m, up]
    mag_new: bool  #: a compass tick
    mag: np.ndarray  #: the compass block (sensors.layout MAG records)
    armed: bool  #: the vehicle is armed (lane switching, constant-position noise, compass reset)


class VehicleInputs(NamedTuple):
    """What the autopilot reads in one main-loop tick (tlm_sim.control.modes.vehicle_step):
    the AHRS view (tlm_sim.control.ahrs), the EKF's output block for its failsafe checks, and
    the power module's and the RC receiver's readings."""

    pos: np.ndarray  #: position NED from home ground [m]
    vel: np.ndarray  #: velocity NED [m/s]
    q: np.ndarray  #: attitude quaternion body -> NED
    gyro: np.ndarray  #: body rates, filtered, bias removed [rad/s] (body FRD)
    acc_ned: np.ndarray  #: kinematic acceleration NED, gravity removed [m/s^2]
    eo: np.ndarray  #: the EKF's output block (tlm_sim.ekf.layout O_*)
    v_batt: float  #: battery voltage [V]
    rc_last_frame_us: float  #: time of the last RC frame [us]
    rc_throttle: float  #: that frame's throttle channel [us PWM]


class LoopTick(NamedTuple):
    """One main-loop tick: its time, its number, and which sensors delivered on it."""

    t_us: int  #: time since boot [us]
    tick: int  #: main-loop ticks so far (400 Hz)
    gps_new: bool  #: a GPS epoch arrived
    baro_new: bool  #: a primary-baro sample arrived
    mag_new: bool  #: a compass tick
