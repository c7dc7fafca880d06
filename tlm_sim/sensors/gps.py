"""Simulated u-blox GPS as SITL models it: 5 Hz epochs, 100 ms lag, no horizontal noise.

The receiver reports the true (delayed) position and velocity; while SIM_GPS1_ENABLE is 0 it keeps
streaming the true position with fix type "no fix" (Status 1) and 3 satellites, as SITL's first GPS
does. Status 6 (RTK fixed) and NSats = SIM_GPS1_NUMSATS while locked; HDop is constant.
"""

import math

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.rng import uniform_pm1
from tlm_sim.sensors import layout as S

GPS_STATUS_NO_FIX = 1
GPS_STATUS_RTK_FIXED = 6


@tick_jit
def gps_init(s, t_us):
    """Clear the delay line; the first epoch is due at t_us."""
    g = S.GPS_BASE
    for k in range(S.GPS_SIZE):
        s[g + k] = 0.0
    s[g + S.G_NEXT_US] = t_us


@tick_jit
def gps_push_truth(s, x, t_s):
    """Append the current position/velocity to the delay line (call every main-loop tick).

    Reads the sensors' view of the truth (SITL's sensor smoothing, ``X.SPN``/``X.SVN``).
    """
    g = S.GPS_BASE
    head = (int(s[g + S.G_HEAD]) + 1) % S.GPS_HIST_N
    s[g + S.G_HEAD] = head
    if s[g + S.G_COUNT] < S.GPS_HIST_N:
        s[g + S.G_COUNT] += 1.0
    r = g + S.G_HIST + head * S.G_ROW
    s[r] = t_s
    for k in range(3):
        s[r + 1 + k] = x[X.SPN + k]
        s[r + 4 + k] = x[X.SVN + k]


@tick_jit
def gps_due(s, t_us):
    """True if a GPS epoch is due at t_us; schedules the next one."""
    g = S.GPS_BASE
    if t_us >= s[g + S.G_NEXT_US]:
        return True
    return False


@tick_jit
def gps_measure(s, cfg, t_us, out, rng):
    """Produce one GPS epoch at t_us into out[N_GPS_EPOCH] (sensors.layout GE_*: position and
    velocity NED from home ground [m, m/s], status, satellites, 3-D fix). Position and velocity
    are the truth interpolated at t - lag."""
    g = S.GPS_BASE
    s[g + S.G_NEXT_US] += cfg[S.C_GPS_PERIOD_US]
    t_want = t_us * 1e-6 - cfg[S.C_GPS_LAG_S]
    head = int(s[g + S.G_HEAD])
    n = int(s[g + S.G_COUNT])
    # walk back to the newest row older than t_want
    j = head
    for _ in range(n - 1):
        jp = (j - 1) % S.GPS_HIST_N
        if s[g + S.G_HIST + j * S.G_ROW] <= t_want:
            break
        j = jp
    r1 = g + S.G_HIST + j * S.G_ROW
    r2 = g + S.G_HIST + ((j + 1) % S.GPS_HIST_N) * S.G_ROW
    t1 = s[r1]
    t2 = s[r2]
    w = 0.0
    if j != head and t2 > t1:
        w = min(max((t_want - t1) / (t2 - t1), 0.0), 1.0)
    for k in range(6):  # GE_PN..GE_VD follow the history row's pn..vd
        out[S.GE_PN + k] = s[r1 + 1 + k] * (1.0 - w) + (s[r2 + 1 + k] * w if w > 0.0 else 0.0)
    out[S.GE_PD] -= cfg[S.C_GPS_NOISE] * math.sin(0.0005 * t_us * 1e-3)
    for k in range(3):
        if cfg[S.C_GPS_VERR + k] != 0.0:
            out[S.GE_VN + k] += cfg[S.C_GPS_VERR + k] * uniform_pm1(rng)
    if cfg[S.C_GPS_ENABLE] != 0.0:
        out[S.GE_STATUS] = GPS_STATUS_RTK_FIXED
        out[S.GE_NSATS] = cfg[S.C_GPS_NUMSATS]
        out[S.GE_FIX_3D] = 1.0
    else:
        out[S.GE_STATUS] = GPS_STATUS_NO_FIX
        out[S.GE_NSATS] = 3.0
        out[S.GE_FIX_3D] = 0.0
