"""The autopilot's log messages: at 10 Hz RATE, ATT, RCOU, CTUN, PSCN/PSCE/PSCD, BAT (the battery
monitor, :mod:`tlm_sim.control.battery`), MOTB (the motors' battery compensation), DCM and AHR2
(the DCM estimator, :mod:`tlm_sim.control.dcm`); on events, checked every main-loop tick, ARM
(arming, disarming), ORGN (EKF origin and home), LDET (the land detector) and
MISE (the mission item started). Columns by name (:mod:`tlm_sim.logger`); attitude and heights
from the EKF output block (``ekf.layout`` O_*).

MISE and ARM rows carry what the loop knows (TimeUS, item index; state, method); the mission
item's own fields and ARM.ArmChecks are the flight's inputs, filled in once the flight is over
(:func:`tlm_sim.flight.fill_evidence`)."""

import math

from tlm_sim import ardupilot as AP
from tlm_sim import logger as L
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import dcm_layout as DL
from tlm_sim.control import layout as C
from tlm_sim.control.battery import resting_voltage
from tlm_sim.control.dcm import dcm_eulers, dcm_location, dcm_quaternion
from tlm_sim.ekf import layout as EK
from tlm_sim.frames import MAX_MOTORS
from tlm_sim.geo import ne_to_latlon_scalar
from tlm_sim.sensors import layout as S

RATE, ATT, RCOU, CTUN, PSC = L.RATE_COLS, L.ATT_COLS, L.RCOU_COLS, L.CTUN_COLS, L.PSCN_COLS
BAT, MOTB, ARM, ORGN, LDET, MISE = (L.BAT_COLS, L.MOTB_COLS, L.ARM_COLS, L.ORGN_COLS,
                                    L.LDET_COLS, L.MISE_COLS)
ORGN_EKF_ORIGIN, ORGN_AHRS_HOME = 0, 1  # ORGN.Type (LogOriginType)
#: ArduCopter's mission item numbers: 0 home, 1 NAV_TAKEOFF, then the waypoints (the first at
#: home; each may follow a DO_CHANGE_SPEED), then NAV_RETURN_TO_LAUNCH (as the CMD rows tlm
#: writes, tlm_sim.mission.Mission.items)
CMD_TAKEOFF = 1


@tick_jit
def log_control_10hz(log, t_us, c, eo, s, pos):
    """The autopilot's 10 Hz rows from its state c, the EKF output eo, the baro altitude in the
    sensor state s and its position estimate pos [m, NED]."""
    bufs = log[0]  # the log buffers
    _log_rate(log, t_us, c)
    _log_att(log, t_us, c, eo)
    r = L.new_row(log, L.K_RCOU, t_us)
    if r >= 0:
        for k in range(MAX_MOTORS):  # outputs beyond the frame's motors read 0, as in SITL
            bufs[L.K_RCOU][r, RCOU.C1 + k] = round(c[C.MIX_PWM + k])
    _log_ctun(log, t_us, c, eo, s, pos)
    for ax in range(3):
        _log_psc(log, t_us, c, eo, pos, ax)
    _log_bat(log, t_us, c)
    _log_motb(log, t_us, c)


@inline_jit
def _log_motb(log, t_us, c):
    """MOTB: the motors' lift_max and voltage ratio (tlm_sim.control.mixer.voltage_compensation),
    throttle limit (1: MOT_BAT_CURR_MAX 0, the current limit is off, as in SITL), the average
    throttle limit the attitude controller gives the mixer, the throttle the mixer placed, and
    the motor-loss flags: thrust boost | thrust balanced << 1."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_MOTB, t_us)
    if r >= 0:
        b = bufs[L.K_MOTB]
        b[r, MOTB.LiftMax] = c[C.MOT_LIFT_MAX]
        b[r, MOTB.BatVolt] = c[C.MOT_BATT_RATIO]
        b[r, MOTB.ThLimit] = 1.0
        b[r, MOTB.ThrAvMx] = c[C.THR_AVG_MAX]
        b[r, MOTB.ThrOut] = c[C.MOT_THR_OUT]
        b[r, MOTB.FailFlags] = ((1.0 if c[C.THRUST_BOOST] != 0.0 else 0.0)
                                + (0.0 if c[C.THRUST_UNBALANCED] != 0.0 else 2.0))


@inline_jit
def mission_item(c):
    """The mission item AUTO runs: NAV_TAKEOFF from the switch to AUTO, the first waypoint
    once the takeoff has reached its altitude, then the navigation item after each waypoint
    done (c[NAV_CNUM], kept by the navigation: the last waypoint's successor is the mission's
    RTL; DO_CHANGE_SPEED items between two start with the second, as AP_Mission starts them
    on its way to the next navigation item)."""
    if c[C.SUBMODE] == C.SUB_TAKEOFF and c[C.TAKEOFF_DONE_T] < 0.0:
        return CMD_TAKEOFF
    return c[C.NAV_CNUM]


@inline_jit
def vehicle_events_due(c, origin_ready):
    """Whether :func:`log_vehicle_events` has a row to write this tick (a few comparisons
    against the last rows, kept in c: the loop asks every tick)."""
    return (origin_ready or c[C.ARMED] != c[C.ARM_LOGGED]
            or c[C.LDET_FLAGS] != c[C.LDET_LOG_FLAGS] or c[C.LDET_COUNT] != c[C.LDET_LOG_COUNT]
            or (c[C.MODE] == AP.MODE_AUTO and mission_item(c) > c[C.MISE_LOGGED]))


@tick_jit
def log_vehicle_events(log, t_us, c, pos, origin_ready, home):
    """The on-event messages, when :func:`vehicle_events_due` (after the autopilot's step):
    ORGN once home is set from the EKF's origin (``origin_ready``; EV SET_HOME is the arming
    driver's, :mod:`tlm_sim.control.arming`), ARM (and ORGN:
    ArduCopter sets home to the current position when arming) on a change of the armed state,
    LDET, MISE. pos: the EKF position NED [m] from the origin; home: the EKF origin (degrees,
    m AMSL)."""
    counts = log[1]  # the log buffers' row counts
    home_lat, home_lon, home_alt = home[0], home[1], home[2]  # deg, deg, m AMSL
    if origin_ready and counts[L.K_ORGN] == 0:
        _log_home_and_origin(log, t_us, pos, home_lat, home_lon, home_alt)
    armed = c[C.ARMED]
    if armed != c[C.ARM_LOGGED]:
        c[C.ARM_LOGGED] = armed
        _log_arm(log, t_us, c, armed)
        if armed != 0.0:
            _log_home_and_origin(log, t_us, pos, home_lat, home_lon, home_alt)
    if c[C.LDET_FLAGS] != c[C.LDET_LOG_FLAGS] or c[C.LDET_COUNT] != c[C.LDET_LOG_COUNT]:
        _log_ldet(log, t_us, c)
    if c[C.MODE] == AP.MODE_AUTO:
        _log_mise(log, t_us, c)


@inline_jit
def _log_arm(log, t_us, c, armed):
    """ARM: the new state, not forced, by the arming's method (MAVLink: the GCS arms, as the
    reference driver did; RUDDER: the pilot's gesture) or the disarm's; ArmChecks 0 here (on
    arming: ARMING_CHECK, filled after the flight)."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_ARM, t_us)
    if r >= 0:
        b = bufs[L.K_ARM]
        b[r, ARM.ArmState] = armed
        b[r, ARM.ArmChecks] = 0.0
        b[r, ARM.Forced] = 0.0
        b[r, ARM.Method] = c[C.ARM_METHOD] if armed != 0.0 else c[C.DISARM_METHOD]


@inline_jit
def _log_home_and_origin(log, t_us, pos, home_lat, home_lon, home_alt):
    """ORGN Type 0 (the EKF origin: the mission's home at ground level, tlm's NED origin) and
    Type 1 (the AHRS home: the EKF's current position, lat/lon/alt AMSL)."""
    bufs = log[0]  # the log buffers
    lat, lon = ne_to_latlon_scalar(pos[0], pos[1], home_lat, home_lon)
    for k in range(2):
        r = L.new_row(log, L.K_ORGN, t_us)
        if r >= 0:
            b = bufs[L.K_ORGN]
            b[r, ORGN.Type] = k
            b[r, ORGN.Lat] = home_lat if k == ORGN_EKF_ORIGIN else lat
            b[r, ORGN.Lng] = home_lon if k == ORGN_EKF_ORIGIN else lon
            b[r, ORGN.Alt] = home_alt if k == ORGN_EKF_ORIGIN else home_alt - pos[2]


@inline_jit
def _log_ldet(log, t_us, c):
    """LDET as Copter::Log_LDET: the land detector's flags and count, changed since the last
    row, at most every 20 ms (whole milliseconds; the first row at once)."""
    bufs, counts = log[0], log[1]  # the log buffers and their row counts
    ms = t_us // 1000
    if counts[L.K_LDET] > 0 and ms - c[C.LDET_LOG_MS] < 20:
        return
    r = L.new_row(log, L.K_LDET, t_us)
    if r >= 0:
        bufs[L.K_LDET][r, LDET.Flags] = c[C.LDET_FLAGS]
        bufs[L.K_LDET][r, LDET.Count] = c[C.LDET_COUNT]
        c[C.LDET_LOG_FLAGS] = c[C.LDET_FLAGS]
        c[C.LDET_LOG_COUNT] = c[C.LDET_COUNT]
        c[C.LDET_LOG_MS] = ms


@inline_jit
def _log_mise(log, t_us, c):
    """MISE for each mission item AUTO has started since the last row (:func:`mission_item`):
    the row's TimeUS and CNum; the item's fields are filled in after the flight."""
    bufs = log[0]  # the log buffers
    idx = mission_item(c)
    while c[C.MISE_LOGGED] < idx:
        r = L.new_row(log, L.K_MISE, t_us)
        if r < 0:
            return
        c[C.MISE_LOGGED] += 1.0
        bufs[L.K_MISE][r, MISE.CNum] = c[C.MISE_LOGGED]


@inline_jit
def _log_bat(log, t_us, c):
    """BAT: the battery monitor's voltage, resting voltage, current, consumed mAh and Wh,
    resistance estimate and remaining percentage."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_BAT, t_us)
    if r >= 0:
        b = bufs[L.K_BAT]
        b[r, BAT.Inst] = 0.0
        b[r, BAT.Volt] = c[C.BM_VOLT]
        b[r, BAT.VoltR] = resting_voltage(c)
        b[r, BAT.Curr] = c[C.BM_CURR]
        b[r, BAT.CurrTot] = c[C.BM_MAH]
        b[r, BAT.EnrgTot] = c[C.BM_WH]
        b[r, BAT.Temp] = 0.0
        b[r, BAT.Res] = c[C.BM_RES]
        b[r, BAT.RemPct] = c[C.BM_REMPCT]
        b[r, BAT.H] = 1.0
        b[r, BAT.SH] = 0.0


@inline_jit
def _log_rate(log, t_us, c):
    """RATE: rate targets, measurements and outputs per axis [deg/s], vertical acceleration,
    throttle and its slew rate (tlm_sim.control.mixer.throttle_slew_update)."""
    bufs = log[0]  # the log buffers
    d = L.RAD2DEG
    r = L.new_row(log, L.K_RATE, t_us)
    if r >= 0:
        b = bufs[L.K_RATE]
        for k in range(3):  # (RDes, R, ROut), (PDes, P, POut), (YDes, Y, YOut)
            rb = C.RATE_BASE + k * C.RATE_STRIDE
            b[r, RATE.RDes + 3 * k] = c[rb + C.R_TARGET] * d
            b[r, RATE.R + 3 * k] = c[rb + C.R_MEAS] * d
            b[r, RATE.ROut + 3 * k] = c[rb + C.R_OUT]
        b[r, RATE.ADes] = c[C.PZ_ACC_T] * 100.0
        b[r, RATE.A] = c[C.PZ_ACC_MEAS] * 100.0
        b[r, RATE.AOut] = c[C.THR_OUT_BOOSTED] if c[C.ARMED] != 0.0 else 0.0
        b[r, RATE.AOutSlew] = c[C.THR_SLEW_RATE]


@inline_jit
def _log_att(log, t_us, c, eo):
    """ATT: attitude targets and the EKF's attitude [deg, yaw 0..360]."""
    bufs = log[0]  # the log buffers
    d = L.RAD2DEG
    r = L.new_row(log, L.K_ATT, t_us)
    if r >= 0:
        b = bufs[L.K_ATT]
        yaw = eo[EK.O_YAW] * d
        b[r, ATT.DesRoll] = c[C.ATT_ROLL_T] * d
        b[r, ATT.Roll] = eo[EK.O_ROLL] * d
        b[r, ATT.DesPitch] = c[C.ATT_PITCH_T] * d
        b[r, ATT.Pitch] = eo[EK.O_PITCH] * d
        yd = c[C.ATT_YAW_T] * d
        b[r, ATT.DesYaw] = yd + 360.0 if yd < 0.0 else yd
        b[r, ATT.Yaw] = yaw + 360.0 if yaw < 0.0 else yaw
        b[r, ATT.AEKF] = 3.0


@inline_jit
def _log_ctun(log, t_us, c, eo, s, pos):
    """CTUN: throttle, altitude target and estimates (the position controller's: 0 while the
    EKF has no valid height), climb rates."""
    bufs = log[0]  # the log buffers
    r = L.new_row(log, L.K_CTUN, t_us)
    if r >= 0:
        b = bufs[L.K_CTUN]
        b[r, CTUN.ThI] = c[C.THR_IN_RAW]
        b[r, CTUN.ABst] = c[C.THR_OUT_BOOSTED] - c[C.THR_OUT]
        b[r, CTUN.ThO] = c[C.THR_OUT_BOOSTED] if c[C.ARMED] != 0.0 else 0.0
        b[r, CTUN.ThH] = c[C.THR_HOVER]
        b[r, CTUN.DAlt] = -c[C.PZ_POS_T]
        b[r, CTUN.Alt] = -pos[2]
        b[r, CTUN.BAlt] = s[S.B_ALT]
        b[r, CTUN.DSAlt] = math.nan
        b[r, CTUN.SAlt] = 0.0
        b[r, CTUN.TAlt] = math.nan
        b[r, CTUN.DCRt] = round(-c[C.PZ_VEL_T] * 100.0)
        b[r, CTUN.CRt] = round(-eo[EK.O_VD] * 100.0)


@inline_jit
def _log_psc(log, t_us, c, eo, pos, ax):
    """PSCN (ax 0), PSCE (1) or PSCD (2): position, velocity and acceleration desired, target
    and actual. The three messages share one column order (PSC names PSCN's columns)."""
    bufs = log[0]  # the log buffers
    kbuf = L.K_PSCN + ax
    r = L.new_row(log, kbuf, t_us)
    if r < 0:
        return
    b = bufs[kbuf]
    if ax < 2:
        b[r, PSC.DPN] = c[C.PXY_POS_T + ax]
        b[r, PSC.TPN] = c[C.PXY_POS_T + ax]
        b[r, PSC.DVN] = c[C.PXY_VEL_FF + ax]
        b[r, PSC.TVN] = c[C.PXY_VEL_T + ax]
        b[r, PSC.DAN] = c[C.PXY_ACC_FF + ax]
        b[r, PSC.TAN] = c[C.PXY_ACC_T + ax]
    else:
        b[r, PSC.DPN] = c[C.PZ_POS_T]
        b[r, PSC.TPN] = c[C.PZ_POS_T]
        b[r, PSC.DVN] = c[C.PZ_VEL_T]
        b[r, PSC.TVN] = c[C.PZ_VEL_T]
        b[r, PSC.DAN] = -c[C.PZ_ACC_T]
        b[r, PSC.TAN] = -c[C.PZ_ACC_T]
    b[r, PSC.PN] = pos[ax]
    b[r, PSC.VN] = eo[EK.O_VN + ax]
    b[r, PSC.AN] = (lean_angles_to_accel(c[C.ATT_ROLL_T], c[C.ATT_PITCH_T], eo[EK.O_YAW], ax)
                    if ax < 2 else -c[C.PZ_ACC_MEAS])


@inline_jit
def lean_angles_to_accel(roll, pitch, yaw, ax):
    """Horizontal acceleration [m/s^2] north (ax 0) or east (1) that a thrust holding the
    weight at lean angles roll, pitch [rad] and heading yaw [rad] gives (AC_PosControl's
    lean-angles-to-acceleration: g x the NE thrust components over the vertical one, the
    vertical one floored at 0.1)."""
    sr, cr = math.sin(roll), math.cos(roll)
    sp, cp = math.sin(pitch), math.cos(pitch)
    sy, cy = math.sin(yaw), math.cos(yaw)
    vertical = max(cr * cp, 0.1)
    if ax == 0:
        return AP.GRAVITY_MSS * (-cy * sp * cr - sy * sr) / vertical
    return AP.GRAVITY_MSS * (-sy * sp * cr + cy * sr) / vertical


DCMC, AHR2 = L.DCM_COLS, L.AHR2_COLS


@tick_jit
def log_dcm_10hz(log, t_us, d, g, sensors, eo, home):
    """DCM (the estimator's state) and AHR2 (the AHRS's secondary solution: the DCM's, while the
    EKF is the active one) at 10 Hz from the DCM array d (:mod:`tlm_sim.control.dcm`); g: the
    controller configuration, sensors: (s, gps), the sensor state (baro) and the latest GPS
    epoch, eo: the EKF
    output block, home: degrees, m AMSL. AHR2's angles are truncated to centidegrees as the
    firmware's integer casts do."""
    s, gps = sensors
    bufs = log[0]  # the log buffers
    home_lat, home_lon, home_alt = home[0], home[1], home[2]  # deg, deg, m AMSL
    if d[DL.D_INIT] == 0.0:
        return
    dcm_eulers(d)
    rd = L.RAD2DEG
    yaw = (d[DL.D_YAW] * rd) % 360.0
    r = L.new_row(log, L.K_DCM, t_us)
    if r >= 0:
        b = bufs[L.K_DCM]
        b[r, DCMC.Roll] = d[DL.D_ROLL] * rd
        b[r, DCMC.Pitch] = d[DL.D_PITCH] * rd
        b[r, DCMC.Yaw] = yaw
        b[r, DCMC.ErrRP] = d[DL.D_ERR_RP]
        b[r, DCMC.ErrYaw] = d[DL.D_ERR_YAW]
        b[r, DCMC.VWN] = 0.0
        b[r, DCMC.VWE] = 0.0
        b[r, DCMC.VWD] = 0.0
    if eo[EK.O_F_ATTITUDE] == 0.0:  # the DCM is the active solution: no secondary to log
        return
    r = L.new_row(log, L.K_AHR2, t_us)
    if r >= 0:
        b = bufs[L.K_AHR2]
        have, north, east, alt = dcm_location(d, g, s, gps, t_us * 1e-6, home_alt)
        lat, lon = ne_to_latlon_scalar(north, east, home_lat, home_lon) if have else (0.0, 0.0)
        b[r, AHR2.Roll] = int(d[DL.D_ROLL] * rd * 100.0) * 0.01
        b[r, AHR2.Pitch] = int(d[DL.D_PITCH] * rd * 100.0) * 0.01
        b[r, AHR2.Yaw] = int(yaw * 100.0) * 0.01
        b[r, AHR2.Alt] = math.nan if not have and alt == 0.0 else alt
        b[r, AHR2.Lat] = lat
        b[r, AHR2.Lng] = lon
        qw, qx, qy, qz = dcm_quaternion(d)
        b[r, AHR2.Q1] = qw
        b[r, AHR2.Q2] = qx
        b[r, AHR2.Q3] = qy
        b[r, AHR2.Q4] = qz
