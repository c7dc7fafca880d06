"""Navigation EKF: an EKF3-like error-state filter, one lane per IMU, with primary selection.

Public API (all per-tick functions are ``@njit`` and allocation-free):

* :func:`build_ekf_config` / :func:`new_ekf` -- Python, once per flight.
* :func:`ekf_update` (or :func:`ekf_predict`, :func:`ekf_fuse_gps`, :func:`ekf_fuse_baro`,
  :func:`ekf_fuse_mag`, :func:`ekf_select_primary`) -- every 400 Hz main-loop tick.
* :func:`ekf_output` / :func:`ekf_primary` -- what controllers and loggers read.

Array layouts: :mod:`tlm_sim.ekf.layout`.
"""

from tlm_sim.ekf.config import build_ekf_config, earth_field_ned, lane_imus, new_ekf
from tlm_sim.ekf.lanes import (
    ekf_fuse_baro,
    ekf_fuse_gps,
    ekf_fuse_mag,
    ekf_init,
    ekf_output,
    ekf_predict,
    ekf_primary,
    ekf_select_primary,
    ekf_update,
    quat_to_euler,
)

__all__ = [
    "build_ekf_config",
    "earth_field_ned",
    "ekf_fuse_baro",
    "ekf_fuse_gps",
    "ekf_fuse_mag",
    "ekf_output",
    "ekf_predict",
    "ekf_primary",
    "ekf_init",
    "ekf_select_primary",
    "ekf_update",
    "lane_imus",
    "new_ekf",
    "quat_to_euler",
]
