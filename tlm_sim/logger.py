"""In-loop log writers: rows of ArduPilot messages into the preallocated float64 buffers.

Buffers come as a tuple in ``tlm_sim.flightlog.LOGGED_MESSAGES`` order (the K_* constants below
index it); columns follow each message's ArduPilot field order, values in the units pymavlink
shows (degrees, metres, m/s, deg/s, cm/s^2 where ArduPilot logs them). Rows beyond a buffer's
capacity are dropped (the counts never exceed the buffer size).
"""

import math

from tlm_sim._jit import tick_jit
from tlm_sim.rotation import quat_to_euler

K_GPS, K_GPA, K_IMU, K_RATE, K_VIBE, K_ATT, K_BARO, K_MAG, K_RCIN, K_RCOU = range(10)
K_MODE, K_EV, K_ERR, K_XKF1, K_XKF4, K_CTUN, K_BAT, K_POS, K_SIM = range(10, 19)
K_PSCN, K_PSCE, K_PSCD = 19, 20, 21
LOG_ORDER = (
    "GPS", "GPA", "IMU", "RATE", "VIBE", "ATT", "BARO", "MAG", "RCIN", "RCOU", "MODE", "EV",
    "ERR", "XKF1", "XKF4", "CTUN", "BAT", "POS", "SIM", "PSCN", "PSCE", "PSCD",
)  # must equal tlm_sim.flightlog.LOGGED_MESSAGES (checked by the tests)

RAD2DEG = 180.0 / math.pi


@tick_jit
def new_row(bufs, counts, k, t_us):
    """Reserve the next row of buffer k, write TimeUS; returns the row index or -1 when full."""
    n = counts[k]
    buf = bufs[k]
    if n >= buf.shape[0]:
        return -1
    buf[n, 0] = t_us
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
