"""Simulated u-blox GPS as SITL models it: 5 Hz epochs, 100 ms lag, no horizontal noise.

The receiver reports the true (delayed) position and velocity; while SIM_GPS1_ENABLE is 0, and
before SIM_GPS1_LCKTIME, it keeps streaming the true position with fix type "no fix" (Status 1)
and 3 satellites, as SITL's first GPS does. Status 6 (RTK fixed) and NSats = SIM_GPS1_NUMSATS
while locked; HDop is constant. With the boot phase (TLM_BOOT_PHASE 1) the first epoch comes when
ArduPilot's GPS driver finds the receiver (``tlm_sim.boot.BOOT_GPS_DETECT_S``) and has no fix.

Faults in SITL's order (``GPS::update``, sitl-faults.md §5.2), after the lag: the glitch offsets
SIM_GPS1_GLTCH_X/Y (degrees of latitude/longitude, converted with the flat-earth scale at home)
and _Z (m of altitude), then the jamming model (SIM_GPS1_JAM, §5.3, :func:`gps_jam`).
"""

import math

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.geo import M_PER_DEG_LAT
from tlm_sim.rng import uniform_pm1
from tlm_sim.sensors import layout as S

GPS_STATUS_NO_FIX = 1
GPS_STATUS_RTK_FIXED = 6


# SITL's jamming model: how often each jammed quantity changes [Hz]
JAM_SATS_HZ = 3.0
JAM_VZ_HZ = 0.5
JAM_VEL_HZ = 0.8
JAM_POS_HZ = 1.1
JAM_ACC_HZ = 3.0
#: SITL's get_random16 state at start-up (AP_Math)
MWC_Z0 = 1234.0
MWC_W0 = 76542.0
#: speed accuracy the autopilot reads per m/s the simulator reports (cm/s written, mm/s read)
UBLOX_SACC_SCALE = 0.1


@tick_jit
def gps_init(s, t_us, home_lat=0.0):
    """Clear the delay line and the jamming state; the first epoch is due at t_us.

    home_lat [deg]: the flat-earth longitude scale of the glitch and jamming offsets."""
    g = S.GPS_BASE
    for k in range(S.GPS_SIZE):
        s[g + k] = 0.0
    s[g + S.G_NEXT_US] = t_us
    s[g + S.G_LON_SCALE] = max(math.cos(math.radians(home_lat)), 0.01)
    s[g + S.G_MWC_Z] = MWC_Z0
    s[g + S.G_MWC_W] = MWC_W0


@tick_jit
def _rand16(s):
    """SITL's get_random16: a 16-bit draw of two multiply-with-carry generators whose state
    starts at (1234, 76542) when the program starts and, in SITL, only the jamming model
    draws from. So every SITL jamming flight starts with the same draws (its blackout: no
    signal up to 1.4 s, one jammed epoch, none again to 3.0 s: gps_jam_s80/s81.bin alike);
    the flights part once SITL's other random source (rand_float, here the seeded stream)
    makes the satellite event fire at other epochs."""
    g = S.GPS_BASE
    z = int(s[g + S.G_MWC_Z])
    w = int(s[g + S.G_MWC_W])
    z = 36969 * (z & 0xFFFF) + (z >> 16)
    w = 18000 * (w & 0xFFFF) + (w >> 16)
    s[g + S.G_MWC_Z] = z
    s[g + S.G_MWC_W] = w
    return ((z << 16) + w) & 0xFFFF


@tick_jit
def _jam_fires(s, key, now_ms, hz, rng):
    """One of the jamming model's random events: fires (and records now_ms in slot key) when
    the time since its last firing exceeds 2 |U(-1, 1)| / hz, a fresh draw every epoch."""
    if (now_ms - s[key]) * 0.001 > 2.0 * abs(uniform_pm1(rng)) / hz:
        s[key] = now_ms
        return True
    return False


@tick_jit
def gps_jam(s, t_us, out, lock, rng):
    """SITL's jamming model on one epoch (sitl-faults.md §5.3); returns the lock flag.

    A jamming episode starts when the previous jammed epoch is more than 1 s old: the current
    (delayed, glitched) position is latched. For 1 s + U{0..4999} ms (a fresh draw each epoch)
    there is no signal (0 satellites, no lock); afterwards five random events change the
    satellites and lock (3 Hz: 2..16, lock with probability 1/2 from 4), the vertical velocity
    (0.5 Hz, 400 U m/s), the horizontal velocity (0.8 Hz), the latched position (1.1 Hz, a
    random walk of 200 U m north and 200 U metre-equivalents of longitude) and the accuracies
    (3 Hz: 300 |U| m, 50 |U| m/s); on epochs where an event does not fire that quantity keeps
    its normal value. The position is always the latched one; the altitude is never jammed.
    """
    g = S.GPS_BASE
    now_ms = math.floor(t_us * 1e-3)
    if now_ms - s[g + S.G_JAM_LAST_MS] > 1000.0:
        s[g + S.G_JAM_START_MS] = now_ms
        s[g + S.G_JAM_PN] = out[S.GE_PN]
        s[g + S.G_JAM_PE] = out[S.GE_PE]
    s[g + S.G_JAM_LAST_MS] = now_ms
    if now_ms - s[g + S.G_JAM_START_MS] < 1000 + _rand16(s) % 5000:
        out[S.GE_NSATS] = 0.0
        lock = False
    else:
        if _jam_fires(s, g + S.G_JAM_T_SATS, now_ms, JAM_SATS_HZ, rng):
            n = 2 + _rand16(s) % 15
            out[S.GE_NSATS] = n
            lock = n >= 4 and _rand16(s) % 2 != 0
        if _jam_fires(s, g + S.G_JAM_T_VZ, now_ms, JAM_VZ_HZ, rng):
            out[S.GE_VD] = 400.0 * uniform_pm1(rng)
        if _jam_fires(s, g + S.G_JAM_T_VEL, now_ms, JAM_VEL_HZ, rng):
            out[S.GE_VN] = 400.0 * uniform_pm1(rng)
            out[S.GE_VE] = 400.0 * uniform_pm1(rng)
        if _jam_fires(s, g + S.G_JAM_T_POS, now_ms, JAM_POS_HZ, rng):
            s[g + S.G_JAM_PN] += 200.0 * uniform_pm1(rng)
            s[g + S.G_JAM_PE] += 200.0 * uniform_pm1(rng) * s[g + S.G_LON_SCALE]
        if _jam_fires(s, g + S.G_JAM_T_ACC, now_ms, JAM_ACC_HZ, rng):
            out[S.GE_VACC] = 300.0 * abs(uniform_pm1(rng))
            out[S.GE_HACC] = 300.0 * abs(uniform_pm1(rng))
            out[S.GE_SACC] = 50.0 * abs(uniform_pm1(rng))
    out[S.GE_PN] = s[g + S.G_JAM_PN]
    out[S.GE_PE] = s[g + S.G_JAM_PE]
    return lock


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
    velocity NED from home ground [m, m/s], status, satellites, 3-D fix, reported accuracies).
    Position and velocity are the truth interpolated at t - lag; then the glitch offsets and
    the jamming model (module docstring). The u-blox message reports the satellites drawn
    while locked, 3 without lock."""
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
    # SITL's delayed lock (SIM_GPS1_LCKTIME); with the boot phase the driver's first message
    # after finding the receiver carries no fix (every reference log: Status 1, 3 satellites)
    lock = (cfg[S.C_GPS_ENABLE] != 0.0 and t_us >= cfg[S.C_GPS_LOCK_US]
            and not (cfg[S.C_BOOT] != 0.0 and s[S.G_EPOCHS] == 0.0))
    s[S.G_EPOCHS] += 1.0
    out[S.GE_HDOP] = cfg[S.C_GPS_HDOP]
    out[S.GE_NSATS] = cfg[S.C_GPS_NUMSATS]
    out[S.GE_HACC] = cfg[S.C_GPS_ACC]
    out[S.GE_VACC] = cfg[S.C_GPS_ACC]
    out[S.GE_SACC] = math.sqrt(cfg[S.C_GPS_VERR] ** 2 + cfg[S.C_GPS_VERR + 1] ** 2)
    out[S.GE_PN] += cfg[S.C_GPS_GLITCH] * M_PER_DEG_LAT
    out[S.GE_PE] += cfg[S.C_GPS_GLITCH + 1] * M_PER_DEG_LAT * s[g + S.G_LON_SCALE]
    out[S.GE_PD] -= cfg[S.C_GPS_GLITCH + 2]
    if cfg[S.C_GPS_JAM] != 0.0:
        lock = gps_jam(s, t_us, out, lock, rng)
    # SITL's u-blox encoding writes the speed accuracy in cm/s into NAV-PVT's sAcc, which
    # AP_GPS_UBLOX reads as mm/s: the autopilot sees a tenth of it (GPA.SAcc at most 4.95 m/s
    # in gps_jam_s80/s81.bin, where the jamming model draws 50 x |U| m/s)
    out[S.GE_SACC] *= UBLOX_SACC_SCALE
    out[S.GE_STATUS] = GPS_STATUS_RTK_FIXED if lock else GPS_STATUS_NO_FIX
    out[S.GE_FIX_3D] = 1.0 if lock else 0.0
    if not lock:
        out[S.GE_NSATS] = 3.0
