"""The in-loop log: preallocated float64 buffers, one row appender, column indices by name.

Buffers come as a tuple in ``tlm_sim.flightlog.LOGGED_MESSAGES`` order (the K_* constants below
index it); columns follow each message's ArduPilot field order (``tlm_sim.flightlog.schema``),
values in the units pymavlink shows (degrees, metres, m/s, deg/s, cm/s^2 where ArduPilot logs
them). :func:`new_row` is the only way a row is appended; rows beyond a buffer's capacity are
dropped (the counts never exceed the buffer size). Each subsystem writes its own messages
(``sensors.log``, ``ekf.log``, ``control.log``, ``control.events``, ``dynamics.log``), addressing
columns by name through the ``*_COLS`` constants here, made from the schema at import::

    r = new_row(bufs, counts, K_GPS, t_us)
    if r >= 0:
        bufs[K_GPS][r, GPS_COLS.Lat] = lat

(a NamedTuple of ints is a compile-time constant to numba: ``GPS_COLS.Lat`` compiles to 7).
"""

import math
from collections import namedtuple
from typing import Any

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.flightlog.flightlog import allocate_buffers
from tlm_sim.flightlog.schema import SCHEMAS
from tlm_sim.rotation import quat_to_euler

K_GPS, K_GPA, K_IMU, K_RATE, K_VIBE, K_ATT, K_BARO, K_MAG, K_RCIN, K_RCOU = range(10)
K_MODE, K_EV, K_ERR, K_XKF1, K_XKF4, K_CTUN, K_BAT, K_POS, K_SIM = range(10, 19)
K_PSCN, K_PSCE, K_PSCD, K_XKFS = 19, 20, 21, 22
K_XKF2, K_XKF3, K_XKF5, K_XKQ, K_XKV1, K_XKV2 = range(23, 29)
K_DCM, K_AHR2, K_XKY0, K_XKY1 = 29, 30, 31, 32
K_ARM, K_ORGN, K_LDET, K_MOTB, K_MISE, K_SIM2 = range(33, 39)
LOG_ORDER = (
    "GPS", "GPA", "IMU", "RATE", "VIBE", "ATT", "BARO", "MAG", "RCIN", "RCOU", "MODE", "EV",
    "ERR", "XKF1", "XKF4", "CTUN", "BAT", "POS", "SIM", "PSCN", "PSCE", "PSCD", "XKFS",
    "XKF2", "XKF3", "XKF5", "XKQ", "XKV1", "XKV2", "DCM", "AHR2", "XKY0", "XKY1",
    "ARM", "ORGN", "LDET", "MOTB", "MISE", "SIM2",
)  # must equal tlm_sim.flightlog.LOGGED_MESSAGES (checked by the tests)

#: The event messages (MODE, EV, ERR: consecutive in LOG_ORDER) as a tuple of their own,
#: indexed by E_*, with their row counts ``counts[K_MODE:K_ERR + 1]`` (a view): what the
#: vehicle logic writes into. A short tuple, because numba passes each array of a tuple as
#: seven arguments to every function that takes it (the whole log is 39 arrays).
E_MODE, E_EV, E_ERR = 0, 1, 2
assert (K_EV, K_ERR) == (K_MODE + E_EV, K_MODE + E_ERR)

RAD2DEG = 180.0 / math.pi
TIME_US = 0  # every message's first column: TimeUS (checked against the schema by the tests)


def schema_columns(name: str) -> Any:
    """Column indices of message ``name``'s log buffer by column name (a NamedTuple of ints,
    ``schema_columns("GPS").Lat == 7``), from ``tlm_sim.flightlog.schema``."""
    cols = SCHEMAS[name].columns
    return namedtuple(f"{name}_COLS", cols)(*range(len(cols)))


GPS_COLS, GPA_COLS, IMU_COLS, RATE_COLS, VIBE_COLS, ATT_COLS, BARO_COLS, MAG_COLS = (
    schema_columns(n) for n in LOG_ORDER[:8])
RCIN_COLS, RCOU_COLS, MODE_COLS, EV_COLS, ERR_COLS, XKF1_COLS, XKF4_COLS, CTUN_COLS = (
    schema_columns(n) for n in LOG_ORDER[8:16])
BAT_COLS, POS_COLS, SIM_COLS, PSCN_COLS, PSCE_COLS, PSCD_COLS, XKFS_COLS = (
    schema_columns(n) for n in LOG_ORDER[16:23])
XKF2_COLS, XKF3_COLS, XKF5_COLS, XKQ_COLS, XKV1_COLS, XKV2_COLS = (
    schema_columns(n) for n in LOG_ORDER[23:29])
DCM_COLS, AHR2_COLS, XKY0_COLS, XKY1_COLS = (schema_columns(n) for n in LOG_ORDER[29:33])
ARM_COLS, ORGN_COLS, LDET_COLS, MOTB_COLS, MISE_COLS, SIM2_COLS = (
    schema_columns(n) for n in LOG_ORDER[33:39])


def event_buffers(bufs: tuple[np.ndarray, ...], counts: np.ndarray
                  ) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """The event buffers (E_* order) of a log-buffer tuple and a view of their row counts."""
    return (bufs[K_MODE], bufs[K_EV], bufs[K_ERR]), counts[K_MODE:K_ERR + 1]


def new_buffers(duration_s: float) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """Zeroed log buffers for a flight of ``duration_s`` [s] as the tuple the flight loop takes
    (LOG_ORDER), and their row counts."""
    bufs = allocate_buffers(duration_s, LOG_ORDER)
    return tuple(bufs[n] for n in LOG_ORDER), np.zeros(len(LOG_ORDER), dtype=np.int64)


@tick_jit
def new_row(bufs, counts, k, t_us):
    """Reserve the next row of buffer k, write TimeUS; returns the row index or -1 when full."""
    n = counts[k]
    buf = bufs[k]
    if n >= buf.shape[0]:
        return -1
    buf[n, TIME_US] = t_us
    counts[k] = n + 1
    return n


@tick_jit
def euler_deg(qw, qx, qy, qz):
    """(roll, pitch, yaw 0..360) [deg] of a body->NED quaternion."""
    roll, pitch, yaw = quat_to_euler(qw, qx, qy, qz)
    yd = yaw * RAD2DEG
    if yd < 0.0:
        yd += 360.0
    return roll * RAD2DEG, pitch * RAD2DEG, yd
