"""ArduCopter's pre-arm checks, the driver that arms the vehicle, and the boot texts.

Pre-arm checks (AP_Arming / AP_Arming_Copter, for what tlm simulates): each group reports its
first failing check and every group runs, in ArduCopter's order -- RC (``RC not found``,
``Throttle below failsafe``), altitude estimate, baro (health, EKF-baro altitude disparity),
INS (health, accelerometers / gyros consistent for 10 s, EKF attitude), compass (health, field
strength, consistency), GPS (3-D fix, home, GPS-AHRS distance, then the mandatory ones: the
AHRS' own check, ``Need Position Estimate``, GPS glitching, EKF variances, HDOP), battery
(arming voltage, failsafe levels) and the battery failsafe. ``ARMING_CHECK`` selects groups as
in ArduPilot (0: only the position and altitude estimates). An arm attempt runs them, then the
arm-only checks (AHRS health, compass health, leaning); the failures are the ``Arm: ...``
lines. Disarmed, they also run at 1 Hz (AP_Arming::update) and are shown as ``PreArm: ...``
every 30 s, or 4 s after they start failing again.

The driver: as the script that flew the reference SITL flights, it switches to GUIDED and tries
to arm every 2 s until an attempt passes; with the boot phase (``TLM_BOOT_PHASE`` 1) from
3.75 s (:mod:`tlm_sim.boot`), without it from ``TLM_ARM_TIME``. It gives up ARM_TIMEOUT_S after
its first attempt: the flight then ends unarmed (``end_reason`` "not_armed"), never flies.

The checks ask the EKF through its output block (``tlm_sim.ekf.layout`` O_*: the primary
lane's health, alignment, position, glitch flag and test ratios, and one status record per lane
for EKF3's pre_arm_check, which iterates its cores); nothing here reads a lane.

Text log: every failed attempt, every shown pre-arm report and every EKF lifecycle event
(:mod:`tlm_sim.ekf.lifecycle`, published once in the lanes' status records) becomes a row of
the flight's text log (TXT_* columns, kept in ``FlightLog.meta["texts"]``);
:mod:`tlm_sim.flightlog.texts` writes ArduCopter's wording.
"""

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import events as E
from tlm_sim.control import layout as C
from tlm_sim.control.pilot_modes import has_manual_throttle
from tlm_sim.ekf import layout as EK
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.baro import baro_set_field_elevation

ARM_RETRY_S = 2.0  # the driver's arm attempts: every 2 s (every reference log)
#: the driver gives up this long after its first attempt [s]: three times the 38 s the
#: reference flights waited for the EKF, so a slow boot still flies while a vehicle that
#: cannot arm ends after 2 minutes on the ground
ARM_TIMEOUT_S = 120.0
PREARM_PERIOD_S = 1.0  # AP_Arming::update
PREARM_DISPLAY_S = 30.0  # PREARM_DISPLAY_PERIOD
PREARM_REPORT_S = 4.0  # show a new failure at most this soon after the last report
CONSISTENT_S = 10.0  # accels / gyros must have been consistent this long
GYRO_INCONSISTENT = math.radians(5.0)  # rad/s (ins.gyros_consistent(5))
ALT_DISPARITY_M = 1.0  # PREARM_MAX_ALT_DISPARITY_CM
AHRS_GPS_ERROR_M = 10.0  # AP_ARMING_AHRS_GPS_ERROR_MAX
MAG_XYZ_ANGLE = math.radians(90.0)  # AP_COMPASS_MAX_XYZ_ANG_DIFF
MAG_XY_ANGLE = math.radians(60.0)  # AP_COMPASS_MAX_XY_ANG_DIFF
MAG_XY_LENGTH = 0.2  # AP_COMPASS_MAX_XY_LENGTH_DIFF (200 mGauss) [gauss]

MODE_NEEDS_GPS = (AP.MODE_AUTO, AP.MODE_GUIDED, AP.MODE_LOITER, AP.MODE_RTL, AP.MODE_POSHOLD)


@tick_jit
def txt_row(c, txt, t_us, kind, mask):
    """Append a text log row (TimeUS, kind, mask; aux values 0); returns its index or -1 when
    the log is full."""
    n = int(c[C.TXT_N])
    if n >= txt.shape[0]:
        return -1
    c[C.TXT_N] = n + 1
    txt[n, AP.TXT_TIME] = t_us
    txt[n, AP.TXT_KIND] = kind
    txt[n, AP.TXT_MASK] = mask
    for k in range(AP.A_GPS_AHRS, AP.N_TXT_COLS):
        txt[n, k] = 0.0
    return n


@tick_jit
def arming_init(c, g):
    """The driver and the 1 Hz checks before boot; the sensors counted consistent from long
    ago without the boot phase (their 10 s wait is part of SITL's start-up)."""
    c[C.ARM_NEXT_T] = g[C.G_ARM_FIRST]
    c[C.ARM_TIME_S] = -1.0
    c[C.PREARM_NEXT_T] = g[C.G_PREARM_FIRST]
    c[C.PREARM_SHOWN_T] = 0.0
    since = -1.0 if g[C.G_BOOT] != 0.0 else -1.0e9
    c[C.ACC_PASS_T] = since
    c[C.GYR_PASS_T] = since


@tick_jit
def _enabled(g, bit):
    chk = int(g[C.G_ARMING_CHECK])
    return (chk & AP.CHK_ALL) != 0 or (chk & bit) != 0


@tick_jit
def _consistent(c, slot, ok, t_s, n_sensors):
    """AP_Arming's consistency window: ok must hold CONSISTENT_S since it was first seen."""
    if not ok:
        c[slot] = -1.0
        return False
    if c[slot] == -1.0:
        c[slot] = t_s
    return n_sensors < 2 or t_s - c[slot] >= CONSISTENT_S


@tick_jit
def _imus_consistent(g, s):
    """(accels within ARMING_ACCTHRESH of the first one, z difference halved; gyros within
    5 deg/s), over the IMUs delivering samples."""
    b0 = S.IMU_BASE
    acc_ok = True
    gyr_ok = True
    for i in range(1, S.N_IMU):
        b = S.IMU_BASE + i * S.IMU_STRIDE
        dx = s[b + S.I_ACC_F] - s[b0 + S.I_ACC_F]
        dy = s[b + S.I_ACC_F + 1] - s[b0 + S.I_ACC_F + 1]
        dz = 0.5 * (s[b + S.I_ACC_F + 2] - s[b0 + S.I_ACC_F + 2])
        if dx * dx + dy * dy + dz * dz > g[C.G_ACC_THRESH] ** 2:
            acc_ok = False
        gx = s[b + S.I_GYR_F] - s[b0 + S.I_GYR_F]
        gy = s[b + S.I_GYR_F + 1] - s[b0 + S.I_GYR_F + 1]
        gz = s[b + S.I_GYR_F + 2] - s[b0 + S.I_GYR_F + 2]
        if gx * gx + gy * gy + gz * gz > GYRO_INCONSISTENT**2:
            gyr_ok = False
    return acc_ok, gyr_ok


@inline_jit
def _ins_checks(c, g, t_s, s, eo):
    """The INS group (first failure) and Copter's EKF attitude check; returns the mask."""
    mask = 0
    if not _enabled(g, AP.CHK_INS):
        return mask
    gyro_ok = True
    acc_ok = True
    for i in range(S.N_IMU):
        b = S.IMU_BASE + i * S.IMU_STRIDE
        gyro_ok = gyro_ok and s[b + S.I_GYR_OK] != 0.0
        acc_ok = acc_ok and s[b + S.I_ACC_OK] != 0.0
    acc_cons, gyr_cons = _imus_consistent(g, s)
    if not gyro_ok:
        mask |= AP.F_GYRO_HEALTH
    elif not acc_ok:
        mask |= AP.F_ACC_HEALTH
    elif not _consistent(c, C.ACC_PASS_T, acc_cons, t_s, S.N_IMU):
        mask |= AP.F_ACC_INCONS
    elif not _consistent(c, C.GYR_PASS_T, gyr_cons, t_s, S.N_IMU):
        mask |= AP.F_GYRO_INCONS
    if not _attitude_valid(eo):
        mask |= AP.F_EKF_ATTITUDE
    return mask


@tick_jit
def _attitude_valid(eo):
    """EKF3's attitude status: a healthy primary lane with tilt and yaw aligned."""
    return eo[EK.O_HEALTHY] != 0.0 and eo[EK.O_TILT_DONE] != 0.0 and eo[EK.O_YAW_DONE] != 0.0


@inline_jit
def _compass_checks(g, s, txt, r):
    """The compass group: the first compass healthy, its field strength, all compasses
    pointing alike (AP_Compass consistent()); returns the mask (the field in mGauss into
    row r)."""
    if not _enabled(g, AP.CHK_COMPASS):
        return 0
    m0 = S.MAG_BASE
    if s[m0 + S.M_HEALTHY] == 0.0:
        return AP.F_COMPASS_HEALTH
    fx, fy, fz = s[m0 + S.M_FIELD], s[m0 + S.M_FIELD + 1], s[m0 + S.M_FIELD + 2]
    field = 1000.0 * math.sqrt(fx * fx + fy * fy + fz * fz)
    if field > AP.MAG_FIELD_MAX or field < AP.MAG_FIELD_MIN:
        if r >= 0:
            txt[r, AP.A_MAG_FIELD] = field
        return AP.F_MAG_FIELD
    for i in range(1, S.N_MAG):
        m = S.MAG_BASE + i * S.MAG_STRIDE
        if s[m + S.M_HEALTHY] == 0.0:
            continue
        ax, ay, az = s[m + S.M_FIELD], s[m + S.M_FIELD + 1], s[m + S.M_FIELD + 2]
        n_xyz = math.sqrt((ax * ax + ay * ay + az * az) * (fx * fx + fy * fy + fz * fz))
        n_xy = math.sqrt((ax * ax + ay * ay) * (fx * fx + fy * fy))
        if n_xy == 0.0:
            return AP.F_COMPASS_INCONS
        if math.acos(min(max((ax * fx + ay * fy + az * fz) / n_xyz, -1.0), 1.0)) > MAG_XYZ_ANGLE:
            return AP.F_COMPASS_INCONS
        if math.acos(min(max((ax * fx + ay * fy) / n_xy, -1.0), 1.0)) > MAG_XY_ANGLE:
            return AP.F_COMPASS_INCONS
        if (ax - fx) ** 2 + (ay - fy) ** 2 > MAG_XY_LENGTH**2:
            return AP.F_COMPASS_INCONS
    return 0


@inline_jit
def _gps_checks(c, g, gps, eo, txt, r):
    """AP_Arming's GPS group (3-D fix, home, GPS vs AHRS position) for a mode that needs GPS;
    returns the mask (the distance into row r)."""
    if not _enabled(g, AP.CHK_GPS):
        return 0
    if gps[S.GE_STATUS] != 0.0 and gps[S.GE_FIX_3D] == 0.0:  # (0: the GPS is not found yet)
        return AP.F_GPS_FIX
    if c[C.HOME_SET] == 0.0:
        return AP.F_WAIT_HOME
    if eo[EK.O_F_HORIZ_POS] != 0.0 and gps[S.GE_STATUS] != 0.0:
        d = math.sqrt((gps[S.GE_PN] - eo[EK.O_PN]) ** 2 + (gps[S.GE_PE] - eo[EK.O_PE]) ** 2)
        if d > AHRS_GPS_ERROR_M:
            if r >= 0:
                txt[r, AP.A_GPS_AHRS] = d
            return AP.F_GPS_AHRS
    return 0


@inline_jit
def _mandatory_gps_checks(c, g, eo, txt, r):
    """Copter's mandatory GPS checks (run with every ARMING_CHECK): the AHRS' check (EKF
    started, every lane healthy), the position estimate, GPS glitching, the EKF variances
    against FS_EKF_THRESH; returns the mask (details into row r)."""
    if eo[EK.O_ALIGNED] == 0.0:
        if r >= 0:
            txt[r, AP.A_LANE] = AP.AHRS_NOT_STARTED
        return AP.F_AHRS
    for i in range(int(eo[EK.O_N_LANES])):
        if eo[EK.O_LANES + i * EK.LANE_STRIDE + EK.LS_HEALTHY] == 0.0:
            if r >= 0:
                txt[r, AP.A_LANE] = i
            return AP.F_AHRS
    pos_ok = (eo[EK.O_F_HORIZ_POS] != 0.0 and eo[EK.O_F_CONST_POS] == 0.0
              and c[C.EKF_FAILSAFE] == 0.0)
    if not pos_ok:
        return AP.F_NEED_POS
    if eo[EK.O_GPS_GLITCHING] != 0.0:
        return AP.F_GPS_GLITCH
    thr = g[C.G_FS_EKF_THRESH]
    if thr > 0.0:
        var = -1
        if math.sqrt(max(eo[EK.O_MAG_TR], 0.0)) >= thr:
            var = AP.VAR_COMPASS
        elif math.sqrt(max(eo[EK.O_POS_TR], 0.0)) >= thr:
            var = AP.VAR_POSITION
        elif math.sqrt(max(eo[EK.O_VEL_TR], 0.0)) >= thr:
            var = AP.VAR_VELOCITY
        elif math.sqrt(max(eo[EK.O_HGT_TR], 0.0)) >= thr:
            var = AP.VAR_HEIGHT
        if var >= 0:
            if r >= 0:
                txt[r, AP.A_VARIANCE] = var
            return AP.F_EKF_VARIANCE
    return 0


@inline_jit
def _battery_checks(c, g, txt, r):
    """AP_BattMonitor's arming checks and Copter's battery failsafe check; returns the mask."""
    mask = 0
    if _enabled(g, AP.CHK_BATTERY):
        v = c[C.BM_VOLT]
        remaining = g[C.G_BATT_CAPACITY] - c[C.BM_MAH]
        code = -1
        if g[C.G_BATT_ARM_VOLT] > 0.0 and v < g[C.G_BATT_ARM_VOLT]:
            code = AP.BATT_BELOW_ARM_VOLT
        elif v > 0.0 and g[C.G_BATT_LOW_VOLT] > 0.0 and v < g[C.G_BATT_LOW_VOLT]:
            code = AP.BATT_LOW_VOLT
        elif g[C.G_BATT_LOW_MAH] > 0.0 and remaining < g[C.G_BATT_LOW_MAH]:
            code = AP.BATT_LOW_CAP
        elif v > 0.0 and g[C.G_BATT_CRT_VOLT] > 0.0 and v < g[C.G_BATT_CRT_VOLT]:
            code = AP.BATT_CRT_VOLT
        elif g[C.G_BATT_CRT_MAH] > 0.0 and remaining < g[C.G_BATT_CRT_MAH]:
            code = AP.BATT_CRT_CAP
        if code >= 0:
            mask |= AP.F_BATTERY
            if r >= 0:
                txt[r, AP.A_BATTERY] = code
    if _enabled(g, AP.CHK_VOLTAGE) and c[C.BATT_FS] != 0.0:
        mask |= AP.F_BATT_FS
    return mask


@tick_jit
def prearm_checks(c, g, t_s, s, gps, eo, report):
    """ArduCopter's pre-arm checks now; returns the mask of failing checks (F_*), their
    details written into text row r (-1: none). A function of its own, not an inline_jit
    section: numba inlined it, with its five inlined check groups, into both its callers, and
    ``arming_step``'s cold compile took 9.9 s of CPU instead of 2.5 s (same flights)."""
    txt, r = report  # the text log and the row for the details (-1: none)
    mode = c[C.MODE]
    mask = 0
    if _enabled(g, AP.CHK_RC) and g[C.G_FS_THR_ENABLE] != 0.0:
        if s[S.RC_LAST_FRAME_US] <= 0.0:
            mask |= AP.F_RC_NOT_FOUND
        elif s[S.RC_CH + 2] < g[C.G_FS_THR_VALUE]:
            mask |= AP.F_THR_LOW
    if not has_manual_throttle(mode) and not (eo[EK.O_HEALTHY] != 0.0
                                              and eo[EK.O_F_VERT_POS] != 0.0):
        mask |= AP.F_NEED_ALT
    if _enabled(g, AP.CHK_BARO):
        healthy = True
        for i in range(S.N_BARO):
            healthy = healthy and s[S.BARO_BASE + i * S.BARO_STRIDE + S.BA_HEALTHY] != 0.0
        if not healthy:
            mask |= AP.F_BARO
        elif (eo[EK.O_F_HORIZ_POS] != 0.0 and eo[EK.O_F_CONST_POS] == 0.0
              and abs(-eo[EK.O_PD] - s[S.B_ALT]) > ALT_DISPARITY_M):
            mask |= AP.F_ALT_DISPARITY
    mask |= _ins_checks(c, g, t_s, s, eo)
    mask |= _compass_checks(g, s, txt, r)
    needs_gps = False
    for m in MODE_NEEDS_GPS:
        needs_gps = needs_gps or mode == m
    gps_fail = _gps_checks(c, g, gps, eo, txt, r) if needs_gps else 0
    if gps_fail == 0 and needs_gps:
        gps_fail = _mandatory_gps_checks(c, g, eo, txt, r)
        if gps_fail == 0 and _enabled(g, AP.CHK_GPS) and gps[S.GE_HDOP] > g[C.G_HDOP_GOOD]:
            gps_fail = AP.F_HDOP
    mask |= gps_fail
    mask |= _battery_checks(c, g, txt, r)
    return mask


@inline_jit
def arm_checks(c, g, s, q, eo):
    """The checks of an arm command after the pre-arm checks passed: AHRS health, the
    compass, leaning beyond ANGLE_MAX; returns the mask."""
    if eo[EK.O_HEALTHY] == 0.0:
        return AP.F_ARM_AHRS
    if s[S.MAG_BASE + S.M_HEALTHY] == 0.0:
        return AP.F_ARM_COMPASS
    if _enabled(g, AP.CHK_INS):
        cos_tilt = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2])
        if cos_tilt < math.cos(g[C.G_ANGLE_MAX]):
            return AP.F_ARM_LEANING
    return 0


@inline_jit
def _prearm_update(c, g, t_us, s, gps, eo, txt):
    """AP_Arming::update at 1 Hz: the checks, shown every 30 s or 4 s after they start
    failing again; armed, they pass without running (ArduCopter returns at once)."""
    t_s = t_us * 1e-6
    c[C.PREARM_NEXT_T] += PREARM_PERIOD_S
    show = ((c[C.PREARM_REPORT] != 0.0 and t_s - c[C.PREARM_SHOWN_T] > PREARM_REPORT_S)
            or t_s - c[C.PREARM_SHOWN_T] > PREARM_DISPLAY_S)
    if show:
        c[C.PREARM_REPORT] = 0.0
        c[C.PREARM_SHOWN_T] = t_s
    if c[C.ARMED] != 0.0:
        c[C.PREARM_LAST_OK] = 1.0
        return
    r = txt_row(c, txt, t_us, AP.KIND_PREARM, 0) if show else -1
    mask = prearm_checks(c, g, t_s, s, gps, eo, (txt, r))
    if r >= 0:
        if mask != 0:
            txt[r, AP.TXT_MASK] = mask
        else:
            c[C.TXT_N] -= 1.0  # nothing to show
    ok = mask == 0
    if not ok and c[C.PREARM_LAST_OK] != 0.0:
        c[C.PREARM_REPORT] = 1.0
    c[C.PREARM_LAST_OK] = 1.0 if ok else 0.0


@inline_jit
def _attempt(c, g, t_us, sensors, vin, txt, ev):
    """One arm attempt of the driver: the checks, then arming or an "Arm:" text row."""
    eo, q = vin.eo, vin.q  # the autopilot's inputs (tlm_sim.bundles.VehicleInputs)
    s, gps = sensors  # the sensor state and the latest GPS epoch
    t_s = t_us * 1e-6
    r = txt_row(c, txt, t_us, AP.KIND_ARM, 0)
    mask = prearm_checks(c, g, t_s, s, gps, eo, (txt, r))
    if mask == 0:
        mask = arm_checks(c, g, s, q, eo)
    if mask != 0:
        if r >= 0:
            txt[r, AP.TXT_MASK] = mask
        nxt = g[C.G_ARM_SECOND] if t_s < g[C.G_ARM_SECOND] else c[C.ARM_NEXT_T] + ARM_RETRY_S
        c[C.ARM_NEXT_T] = nxt
        return False
    if r >= 0:
        c[C.TXT_N] -= 1.0
    return True


@tick_jit
def arming_step(c, g, t_us, sensors, vin, txt, ev):
    """The driver and the 1 Hz pre-arm checks, once per main-loop tick after the vehicle's
    step. Returns True on the tick an attempt passes: the caller arms the vehicle."""
    eo = vin.eo  # the autopilot's inputs (tlm_sim.bundles.VehicleInputs)
    s, gps = sensors  # the sensor state and the latest GPS epoch
    t_s = t_us * 1e-6
    if t_s >= c[C.PREARM_NEXT_T]:
        _prearm_update(c, g, t_us, s, gps, eo, txt)
    if c[C.ARMED] != 0.0 or c[C.DISARM_TIME] >= 0.0 or c[C.ARM_GAVE_UP] != 0.0:
        return False
    if g[C.G_PILOT] != 0.0:  # the pilot arms: an attempt when the rudder gesture asks
        if c[C.PIL_ARM_REQ] == 0.0:
            return False
        c[C.PIL_ARM_REQ] = 0.0
        return _attempt(c, g, t_us, sensors, vin, txt, ev)
    switched = c[C.MODE] != AP.MODE_GUIDED and t_s >= g[C.G_DRIVER_T]
    if switched:  # the driver's GUIDED (its MODE row is the arming's when that is now)
        c[C.MODE] = AP.MODE_GUIDED
    passed = False
    if t_s >= c[C.ARM_NEXT_T]:
        if t_s >= g[C.G_ARM_GIVE_UP]:
            c[C.ARM_GAVE_UP] = 1.0
        else:
            passed = _attempt(c, g, t_us, sensors, vin, txt, ev)
    if switched and not passed:
        E.log_mode(ev, t_us, AP.MODE_GUIDED, AP.RSN_GCS)
    return passed


@inline_jit
def boot_texts_due(c, eo):
    """Whether :func:`tlm_sim.control.arming.lifecycle_texts` has work this tick: a lane's
    lifecycle event published in the EKF's output block eo, or home / field elevation not yet
    set (cheap: the loop runs it only then)."""
    if c[C.FIELD_SET] != 1.0 or c[C.HOME_SET] == 0.0:
        return True
    for i in range(int(eo[EK.O_N_LANES])):
        if eo[EK.O_LANES + i * EK.LANE_STRIDE + EK.LS_EVENTS] != 0.0:
            return True
    return False


@tick_jit
def _lane_texts(c, t_us, eo, txt, ev):
    """The lifecycle events the lanes published this tick (eo's lane records) as text rows,
    event by event and lane by lane (the order EKF3's cores print them in one loop)."""
    for k in range(AP.N_EKF_EVT):
        bit = 1 << k
        for i in range(int(eo[EK.O_N_LANES])):
            b = EK.O_LANES + i * EK.LANE_STRIDE
            if int(eo[b + EK.LS_EVENTS]) & bit == 0:
                continue
            r = txt_row(c, txt, t_us, AP.KIND_EKF, bit)
            if r >= 0:  # EKF3 names the lane by its IMU, the compass by its index
                txt[r, AP.A_LANE] = eo[b + EK.LS_IMU]
                txt[r, AP.A_MAG_FIELD] = eo[b + EK.LS_MAG]
            # Copter watches the primary
            if bit == AP.EKF_EVT_YAW and i == int(eo[EK.O_PRIMARY]):
                E.log_ev(ev, t_us, AP.EV_EKF_YAW_RESET)
            if bit == AP.EKF_EVT_INIT and i == 0:
                txt_row(c, txt, t_us + 2500.0, AP.KIND_AHRS_ACTIVE, 0)


@tick_jit
def lifecycle_texts(c, now, eo, s, home_alt, txt, ev):
    """Every tick: the lanes' EKF lifecycle events into text rows (EV EKF_YAW_RESET at a yaw
    alignment, "AHRS: EKF3 active" after lane 0 starts); home set when the primary lane has
    its origin (EV SET_HOME); the baro's field elevation (and ground temperature) at its first
    reading after an origin is set ("Field Elevation Set")."""
    t_us, baro_new = float(now.t_us), now.baro_new  # this tick (tlm_sim.bundles.LoopTick)
    origin = False
    pending = 0
    for i in range(int(eo[EK.O_N_LANES])):
        b = EK.O_LANES + i * EK.LANE_STRIDE
        origin = origin or eo[b + EK.LS_ORIGIN_OK] != 0.0
        pending |= int(eo[b + EK.LS_EVENTS])
    if pending != 0:
        _lane_texts(c, t_us, eo, txt, ev)
    if c[C.HOME_SET] == 0.0 and eo[EK.O_ORIGIN_OK] != 0.0:
        c[C.HOME_SET] = 1.0
        E.log_ev(ev, t_us, AP.EV_SET_HOME)
    # AP_Baro sets the field elevation at its next reading after the origin (FIELD_SET 0.5:
    # an origin seen, the reading pending)
    if c[C.FIELD_SET] == 0.5 and baro_new:
        c[C.FIELD_SET] = 1.0
        baro_set_field_elevation(s, home_alt)
        r = txt_row(c, txt, t_us, AP.KIND_FIELD_ELEV, 0)
        if r >= 0:
            txt[r, AP.A_MAG_FIELD] = home_alt
    if c[C.FIELD_SET] == 0.0 and origin:
        c[C.FIELD_SET] = 0.5
