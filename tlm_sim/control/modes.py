"""ArduCopter-style vehicle logic: arming, GUIDED takeoff, AUTO mission, RTL, LAND, land detector
and the radio failsafe; runs every main-loop tick and drives the position/attitude/rate
controllers and the mixer.

Flight sequence (as the reference SITL flights): boot in STABILIZE, GUIDED and arm when the
driver's attempt passes the pre-arm checks (tlm_sim.control.arming), take off to the first
waypoint's altitude, switch to AUTO, fly the waypoints, then the mission's RETURN_TO_LAUNCH
(climb to RTL_ALT, return at WPNAV_SPEED, loiter RTL_LOIT_TIME, land at LAND_SPEED below
LAND_ALT_LOW) and disarm when the land detector reports landed.

Failsafes: radio (RTL, or LAND when there is no position; by RC timeout or low throttle),
battery (tlm_sim.control.battery: BATT_FS_*_ACT), EKF (FS_EKF_THRESH/FS_EKF_ACTION:
LAND without position control after a 4 s pause, or AltHold), vibration (vibration compensation
in the altitude controller), the crash check (disarm) and the thrust-loss check (ERR 25); see
tlm_sim.control.failsafe.
"""

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import battery as B
from tlm_sim.control import events as E
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import (
    attitude_reset,
    attitude_update,
    rate_pid,
    rate_reset,
    sqrt_ctrl,
    throttle_mix_update,
)
from tlm_sim.control.failsafe import (
    CRASH_LEAN_COS,
    FS_EKF_ALTHOLD,
    FS_NONE,
    crash_check,
    failsafe_checks,
    thrust_loss_check,
    vertical_cf_update,
)
from tlm_sim.control.mixer import MOT_SPOOL_TIME_S, mix, output_idle, voltage_compensation
from tlm_sim.control.pilot_modes import (
    ARMING_DELAY_S,
    has_manual_throttle,
    is_pilot_mode,
    log_land_complete,
    pilot_mix_want,
    pilot_step,
)
from tlm_sim.control.position import (
    althold_lean_update,
    angle_boost,
    soften_for_landing_xy,
    xy_init_stopping_point,
    xy_reset,
    xy_update,
    z_reset,
    z_update,
)
from tlm_sim.control.wpnav import (
    P_CMD,
    P_CNUM,
    P_HOLD,
    path_resume,
    path_start,
    path_update,
    prepare_path,
)
from tlm_sim.rotation import heading, quat_to_euler

SPOOL_TIME_S = MOT_SPOOL_TIME_S
AUTO_ARMED_S = SPOOL_TIME_S + 0.3  # EV AUTO_ARMED after arming (reference logs: 0.8-1.0 s)
# ArduCopter's arming delay (ARMING_DELAY_SEC, pilot_modes.ARMING_DELAY_S): the motors stay at
# MOT_SPIN_ARM and a takeoff waits 2 s after arming; every reference log has EV 57 at 2.00 s,
# the throttle rising from there (above 0.2 at 2.9-3.0 s) and NOT_LANDED at 3.28 s
LAND_DETECT_S = 1.0  # LAND_DETECTOR_TRIGGER_SEC
LAND_MAYBE_S = 0.2
LAND_WITH_DELAY_S = 4.0  # failsafe LAND pauses this long before descending
# AUTO after the GUIDED takeoff: the reference driver switches at ~91.5 % of the takeoff
# altitude (CTUN.Alt at the MODE change: 0.908-0.920 of the first waypoint's altitude in the
# six reference logs); the mission's NAV_TAKEOFF then completes when the takeoff's altitude
# target is reached ("Mission: 2 WP" 1.8-2.2 s after AUTO, as DVD reaches 0) and the first
# waypoint, at home and that altitude, is "reached" 0.76-0.86 s later, when the route starts
TAKEOFF_AUTO_FRAC = 0.915
TAKEOFF_WP_DWELL_S = 0.8
HOVER_LEARN_SIN_LEAN = math.sin(math.radians(5.0))  # hover learning: |pitch| < 5 deg
HOVER_LEARN_TAN_LEAN = math.tan(math.radians(5.0))  # and |roll| < 5 deg
THR_MIX_LEAN = math.radians(15.0)  # LAND_CHECK_LARGE_ANGLE_CD
THR_MIX_ATT_ERR = math.radians(30.0)  # LAND_CHECK_ANGLE_ERROR_DEG
THR_MIX_ACCEL = 3.0  # LAND_CHECK_ACCEL_MOVING [m/s^2]
# the land detector's criteria: these LDET bits set (and LARGE_ANGLE clear)
LAND_CRITERIA = (AP.LDET_MOTOR_AT_LOWER_LIMIT | AP.LDET_THROTTLE_MIX_AT_MIN
                 | AP.LDET_ACCEL_STATIONARY | AP.LDET_DESCENT_RATE_LOW)
LAND_CRITERIA_MASK = LAND_CRITERIA | AP.LDET_LARGE_ANGLE


@tick_jit
def set_mode(c, mode, rsn, t_us, ev):
    """Change flight mode and write the MODE row (the reason kept for the arming's MODE row);
    a mode that is not flown from the sticks takes the heading as a command again."""
    c[C.MODE] = mode
    c[C.MODE_RSN] = rsn
    if not is_pilot_mode(mode):
        c[C.ATT_YAW_RATE_IN] = 0.0
    if mode != AP.MODE_ACRO:
        c[C.ATT_RATE_BF_IN] = 0.0
    E.log_mode(ev, t_us, mode, rsn)


@tick_jit
def _set_segment(seg, g, a, b):
    """Two-point path seg[0] = a -> seg[1] = b (NED points, m), legs prepared for path_update."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    seg[0, 0] = a0
    seg[0, 1] = a1
    seg[0, 2] = a2
    seg[1, 0] = b0
    seg[1, 1] = b1
    seg[1, 2] = b2
    prepare_path(seg, 2, g)


@tick_jit
def _start_rtl(c, g, pos, vel, seg):
    """Enter RTL's initial climb above the stopping point (AC_WPNav starts every new
    destination from the position controller's stopping point)."""
    alt = -pos[2]
    h = math.sqrt(pos[0] * pos[0] + pos[1] * pos[1])
    target = max(g[C.G_RTL_ALT], alt + g[C.G_RTL_CLIMB_MIN], 0.3)
    if g[C.G_RTL_CONE_SLOPE] > 0.0:
        cone = max(h * max(g[C.G_RTL_CONE_SLOPE], 0.5), 0.3, alt + g[C.G_RTL_CLIMB_MIN])
        target = min(target, cone)
    target = max(target, alt)
    c[C.SUBMODE] = C.SUB_RTL_CLIMB
    c[C.SUB_TIMER] = 0.0
    # the climb starts from the stopping point, the controller restarted without a bump
    sn, se = xy_init_stopping_point(c, g, pos, vel)
    _set_segment(seg, g, (sn, se, pos[2]), (sn, se, -target))
    path_start(c)


@tick_jit
def _position_ok(c):
    """ArduCopter's position_ok(): an EKF absolute position and no EKF failsafe."""
    return c[C.EKF_POS_OK] != 0.0 and c[C.EKF_FAILSAFE] == 0.0


@tick_jit
def start_land(c, pos, failsafe):
    """Enter LAND here: hold the height, without position control when the EKF has no
    position, pausing LAND_WITH_DELAY (4 s) first when a failsafe asked for it."""
    c[C.SUBMODE] = C.SUB_LAND
    c[C.SUB_TIMER] = 0.0
    c[C.LAND_NOGPS] = 0.0 if _position_ok(c) else 1.0
    c[C.LAND_PAUSE] = LAND_WITH_DELAY_S if failsafe else 0.0
    c[C.PZ_POS_T] = pos[2]
    c[C.PZ_VEL_FF] = 0.0
    c[C.PZ_ACC_FF] = 0.0


@tick_jit
def vehicle_step(c, g, t_us, inputs, path, seg, ev):
    """One 400 Hz main-loop tick of the autopilot; leaves motor PWMs in c[MIX_PWM:MIX_PWM+4].

    inputs: the tick's :class:`tlm_sim.bundles.VehicleInputs` (the AHRS view: EKF position and
    velocity NED [m, m/s] from home ground, attitude body->NED, filtered body rates without the
    bias [rad/s], kinematic acceleration NED without gravity [m/s^2]; the EKF's output block
    for the failsafe checks; battery voltage [V]; the last RC frame's time [us] and throttle
    channel [us]); path: the mission as NED points (path[0] = the takeoff point above home);
    seg: (>=2, 3) scratch path for takeoff/RTL segments; ev: the flight's event log
    buffers and their row counts (tlm_sim.logger E_*: MODE, EV, ERR).
    """
    pos, q, acc_ned, eo, v_batt = inputs.pos, inputs.q, inputs.acc_ned, inputs.eo, inputs.v_batt
    dt = g[C.G_DT]
    cos_tilt = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2])  # cos(roll) cos(pitch)
    _estimates_update(c, g, pos, acc_ned, dt)
    if c[C.ARMED] == 0.0:
        _disarmed_step(c, g)
        _motors_at_rest(c, g, v_batt)
        return
    c[C.SUB_TIMER] += dt
    sub = _radio_failsafe(c, g, t_us, int(c[C.SUBMODE]), inputs, seg, ev)
    sub = _nav_failsafes(c, g, t_us, sub, pos, eo, ev)
    sub = _battery_failsafe(c, g, t_us, sub, inputs, seg, ev)
    if c[C.ARMED] == 0.0:
        return
    if sub == C.SUB_GROUND_IDLE:
        _ground_idle(c, g, t_us, inputs, seg, ev)
        _motors_at_rest(c, g, v_batt)
        return
    if sub == C.SUB_PILOT:
        _pilot_tick(c, g, t_us, inputs, cos_tilt, ev)
        return
    yaw_cmd, yaw_rate_ff, land_vertical = _navigate(c, g, t_us, sub, inputs, (path, seg), ev)
    sub = int(c[C.SUBMODE])
    if sub == C.SUB_LAND and _land_descent(c, g, t_us, pos, land_vertical, ev):
        return
    thr = _controllers(c, g, sub, inputs, cos_tilt, yaw_cmd, yaw_rate_ff)
    _hover_learning(c, g, sub, thr, inputs)
    _land_detector(c, g, t_us, sub, thr, inputs, ev)
    _crash_checks(c, g, t_us, inputs, cos_tilt, ev)


@inline_jit
def _estimates_update(c, g, pos, acc_ned, dt):
    """Every tick, armed or not: the 1 Hz low-pass of the earth-frame acceleration (land and
    crash detectors), the height-rate filter and the air density ratio of the motors' density
    compensation (ArduCopter reads it from the baro)."""
    alpha = dt / (dt + 1.0 / (2.0 * math.pi * 1.0))
    for k in range(3):
        c[C.ALP + k] += alpha * (acc_ned[k] - c[C.ALP + k])
    vertical_cf_update(c, g, pos[2], acc_ned[2], dt)
    c[C.AIR_RHO_RATIO] = g[C.G_RHO_RATIO_HOME] - g[C.G_RHO_RATIO_GRAD] * pos[2]


@inline_jit
def _motors_at_rest(c, g, v_batt):
    """Disarmed or at ground idle (the controllers do not run): the motors' voltage
    compensation still follows the battery, the mixer's average throttle limit is the
    attitude controller's with no throttle and the mix at ATC_THR_MIX_MIN (MOTB), and the land
    detector reports landed (LDET: ArduCopter's land_complete branch, count 0)."""
    voltage_compensation(c, g, v_batt)
    c[C.THR_AVG_MAX] = c[C.THR_HOVER] * g[C.G_THR_MIX_MIN]
    c[C.LDET_FLAGS] = AP.LDET_LANDED + AP.LDET_LANDED_MAYBE
    c[C.LDET_COUNT] = 0.0


@inline_jit
def _disarmed_step(c, g):
    """Disarmed: motors off (the driver arms the vehicle: :func:`arm_vehicle`)."""
    output_idle(c, g, 0.0)
    rate_reset(c)


@tick_jit
def arm_vehicle(c, t_us, q, ev):
    """Arm in GUIDED (the mode is logged again, as AP_Arming_Copter::arm does) once the
    driver's attempt passed the checks (tlm_sim.control.arming): motors to ground idle, the
    takeoff follows the arming delay. q: EKF attitude body->NED (the home heading)."""
    set_mode(c, AP.MODE_GUIDED, AP.RSN_GCS, t_us, ev)
    c[C.ARMED] = 1.0
    c[C.ARM_TIME_S] = t_us * 1e-6
    c[C.ARM_METHOD] = AP.ARM_METHOD_MAVLINK
    c[C.LANDED] = 1.0
    c[C.HOME_YAW] = heading(q)
    c[C.SUBMODE] = C.SUB_GROUND_IDLE
    c[C.SUB_TIMER] = 0.0
    c[C.SPOOL] = 1.0
    E.log_ev(ev, t_us, AP.EV_ARMED)


@tick_jit
def _throttle_failsafe_count(c, g, rc_last_frame_us, rc_throttle):
    """ArduCopter's throttle failsafe counter, once per new RC frame: 3 frames in a row with
    throttle below FS_THR_VALUE (counting up to 3) ask for the radio failsafe; good frames
    count down and the failsafe may clear at 0. Returns (failsafe asked, clear allowed)."""
    if rc_last_frame_us != c[C.RC_LAST_SEEN_US]:
        c[C.RC_LAST_SEEN_US] = rc_last_frame_us
        if g[C.G_FS_THR_ENABLE] != 0.0:
            if rc_throttle < g[C.G_FS_THR_VALUE]:
                if c[C.RC_FAILSAFE] == 0.0:
                    c[C.RC_THR_LOW_N] = min(c[C.RC_THR_LOW_N] + 1.0, 3.0)
            else:
                c[C.RC_THR_LOW_N] = max(c[C.RC_THR_LOW_N] - 1.0, 0.0)
    low = g[C.G_FS_THR_ENABLE] != 0.0 and c[C.RC_THR_LOW_N] >= 3.0
    return low, c[C.RC_THR_LOW_N] == 0.0


@inline_jit
def _should_disarm_on_failsafe(c, sub):
    """Copter's should_disarm_on_failsafe, for the radio failsafe: on the ground (landed, or
    the arming delay's ground idle) disarm instead of flying the action; in STABILIZE and ACRO
    also with the throttle stick at zero (throttle_zero). AUTO disarms only if landed before
    auto_armed, which tlm's missions never are (they arm with the throttle up): never here."""
    mode = c[C.MODE]
    if mode == AP.MODE_AUTO:
        return False
    on_ground = (c[C.LANDED] != 0.0 and sub != C.SUB_TAKEOFF) or sub == C.SUB_GROUND_IDLE
    if has_manual_throttle(mode) and c[C.PIL_THR_ZERO] != 0.0:
        return True
    return on_ground


@inline_jit
def _radio_failsafe(c, g, t_us, sub, inputs, seg, ev):
    """The radio failsafe: no RC frame for RC_FS_TIMEOUT (ERR 2/2 and 5/1) or three frames with
    throttle below FS_THR_VALUE (SIM_RC_FAIL 2: ERR 5/1 only) -> disarm on the ground
    (:func:`_should_disarm_on_failsafe`, ARM.Method 16), else RTL (LAND without a position);
    frames again with a good throttle -> ERR 5/0. Returns the submode to continue with."""
    rc_last_frame_us, rc_throttle = inputs.rc_last_frame_us, inputs.rc_throttle
    rc_late = (t_us - rc_last_frame_us) * 1e-6 > g[C.G_RC_FS_TIMEOUT]
    thr_low, thr_ok = _throttle_failsafe_count(c, g, rc_last_frame_us, rc_throttle)
    if (rc_late or thr_low) and c[C.RC_FAILSAFE] == 0.0 and g[C.G_FS_THR_ENABLE] != 0.0:
        c[C.RC_FAILSAFE] = 1.0
        if rc_late:
            E.log_err(ev, t_us, AP.ERR_RADIO, AP.ERR_CODE_LATE_FRAME)
        E.log_err(ev, t_us, AP.ERR_FAILSAFE_RADIO, AP.ERR_CODE_FAILSAFE)
        if _should_disarm_on_failsafe(c, sub):
            disarm(c, g, t_us, AP.ARM_METHOD_RADIOFAILSAFE, ev)
            return C.SUB_LANDED
        landed = c[C.LANDED] != 0.0 and sub != C.SUB_TAKEOFF
        if not landed and sub != C.SUB_LAND and c[C.MODE] != AP.MODE_RTL:
            return rtl_or_land(c, g, t_us, inputs, seg, AP.RSN_RADIO_FAILSAFE, ev)
    elif not rc_late and thr_ok and c[C.RC_FAILSAFE] != 0.0:
        c[C.RC_FAILSAFE] = 0.0
        E.log_err(ev, t_us, AP.ERR_FAILSAFE_RADIO, AP.ERR_CODE_RESOLVED)
    return sub


@inline_jit
def rtl_or_land(c, g, t_us, inputs, seg, rsn, ev):
    """A failsafe's RTL, or LAND after a pause when there is no position; returns the new
    submode."""
    pos, vel = inputs.pos, inputs.vel
    if _position_ok(c):
        set_mode(c, AP.MODE_RTL, rsn, t_us, ev)
        _start_rtl(c, g, pos, vel, seg)
        return C.SUB_RTL_CLIMB
    set_mode(c, AP.MODE_LAND, rsn, t_us, ev)
    start_land(c, pos, True)
    return C.SUB_LAND


@inline_jit
def _battery_failsafe(c, g, t_us, sub, inputs, seg, ev):
    """The battery failsafe's action (Copter's handle_battery_failsafe), once the monitor has
    asked for one (c[BATT_FS_ACT], tlm_sim.control.battery): on the ground disarm; else Land
    (with a pause), RTL (or Land without a position), Terminate (disarm in the air). tlm has
    no SmartRTL, DO_LAND_START or Brake: their fallbacks fly (RTL, RTL, Land). Returns the
    submode."""
    pos = inputs.pos
    act = int(c[C.BATT_FS_ACT])
    if act < 0:
        return sub
    c[C.BATT_FS_ACT] = -1.0
    landed = (c[C.LANDED] != 0.0 and sub != C.SUB_TAKEOFF) or sub == C.SUB_GROUND_IDLE
    if landed or act == B.ACT_TERMINATE:
        method = AP.ARM_METHOD_BATTERYFAILSAFE if landed else AP.ARM_METHOD_TERMINATE
        disarm(c, g, t_us, method, ev)
        return C.SUB_LANDED
    if act == B.ACT_LAND or act == B.ACT_SMARTRTL_LAND or act == B.ACT_BRAKE_LAND:
        if c[C.MODE] != AP.MODE_LAND:
            set_mode(c, AP.MODE_LAND, AP.RSN_BATTERY_FAILSAFE, t_us, ev)
            start_land(c, pos, True)
            return C.SUB_LAND
    elif act != B.ACT_NONE and c[C.MODE] != AP.MODE_RTL and c[C.MODE] != AP.MODE_LAND:
        return rtl_or_land(c, g, t_us, inputs, seg, AP.RSN_BATTERY_FAILSAFE, ev)
    return sub


@inline_jit
def disarm(c, g, t_us, method, ev):
    """Disarm now by AP_Arming::Method ``method`` (EV DISARMED, ARM.Method; motors stopped;
    the flight ends 2 s later)."""
    E.log_ev(ev, t_us, AP.EV_DISARMED)
    c[C.DISARM_METHOD] = method
    c[C.ARMED] = 0.0
    c[C.SUBMODE] = C.SUB_LANDED
    c[C.DISARM_TIME] = t_us * 1e-6
    output_idle(c, g, 0.0)


@inline_jit
def _nav_failsafes(c, g, t_us, sub, pos, eo, ev):
    """The vibration and EKF failsafes (10 Hz): an EKF failsafe in flight -> LAND (or AltHold
    with FS_EKF_ACTION 2) where the mode needs a position. Returns the submode."""
    fs = failsafe_checks(c, g, t_us, eo, ev)
    if fs == FS_NONE or sub == C.SUB_GROUND_IDLE or c[C.LANDED] != 0.0:
        return sub
    mode = c[C.MODE]
    needs_position = (mode == AP.MODE_AUTO or mode == AP.MODE_GUIDED or mode == AP.MODE_RTL
                      or mode == AP.MODE_LOITER or mode == AP.MODE_POSHOLD)
    if not (needs_position or g[C.G_FS_EKF_ACTION] == 3.0):
        return sub
    if fs == FS_EKF_ALTHOLD:
        set_mode(c, AP.MODE_ALT_HOLD, AP.RSN_EKF_FAILSAFE, t_us, ev)
        start_land(c, pos, True)
        c[C.LAND_PAUSE] = 1e9  # AltHold with centred sticks: level, hold the height
    elif c[C.MODE] != AP.MODE_LAND:
        set_mode(c, AP.MODE_LAND, AP.RSN_EKF_FAILSAFE, t_us, ev)
        start_land(c, pos, True)
    return C.SUB_LAND


@inline_jit
def _ground_idle(c, g, t_us, inputs, seg, ev):
    """Armed on the ground: motors at MOT_SPIN_ARM, EV AUTO_ARMED, then after ARMING_DELAY the
    takeoff starts (controllers reset here, a vertical segment to the takeoff altitude)."""
    dt = g[C.G_DT]
    pos, vel, q = inputs.pos, inputs.vel, inputs.q
    output_idle(c, g, g[C.G_MOT_SPIN_ARM])
    attitude_reset(c, 0.0, 0.0, heading(q))
    if c[C.SUB_TIMER] >= AUTO_ARMED_S and c[C.SUB_TIMER] - dt < AUTO_ARMED_S:
        E.log_ev(ev, t_us, AP.EV_AUTO_ARMED)
    if c[C.SUB_TIMER] >= ARMING_DELAY_S:
        c[C.SUBMODE] = C.SUB_TAKEOFF
        c[C.SUB_TIMER] = 0.0
        c[C.SPOOL] = 2.0
        xy_reset(c, pos[0], pos[1], vel[0], vel[1])
        z_reset(c, g, pos[2], vel[2], 0.0)
        c[C.THR_OUT] = 0.0
        _set_segment(seg, g, (pos[0], pos[1], pos[2]), (pos[0], pos[1], -c[C.TAKEOFF_ALT]))
        path_start(c)


@inline_jit
def _navigate(c, g, t_us, sub, inputs, route, ev):
    """Navigation of the submode sub (takeoff, waypoints, RTL climb / return / loiter, land):
    moves the position targets along its path and switches submodes. Returns (yaw command
    [rad], yaw rate feed-forward [rad/s], whether LAND descends vertically). route: (path,
    seg), the mission path and the segment scratch."""
    pos, vel = inputs.pos, inputs.vel
    path, seg = route
    yaw_cmd = c[C.ATT_YAW_CMD]
    yaw_rate_ff = 0.0
    if sub == C.SUB_TAKEOFF:
        _nav_takeoff(c, g, t_us, pos, vel, seg, ev)
    elif sub == C.SUB_WP:
        heading = _nav_waypoints(c, g, t_us, pos, vel, path, seg)
        if not math.isnan(heading):
            yaw_cmd = heading
            yaw_rate_ff = c[C.YAW_RATE_CMD]
    elif sub == C.SUB_RTL_CLIMB:
        _nav_rtl_climb(c, g, pos, vel, seg)
    elif sub == C.SUB_RTL_RETURN:
        _nav_rtl_return(c, g, pos, vel, seg)
    elif sub == C.SUB_RTL_LOITER:
        yaw_cmd = _nav_rtl_loiter(c, g)
    return yaw_cmd, yaw_rate_ff, sub == C.SUB_LAND


@inline_jit
def _nav_takeoff(c, g, t_us, pos, vel, seg, ev):
    """GUIDED takeoff up the vertical segment; AUTO at TAKEOFF_AUTO_FRAC of the altitude, the
    route once the first waypoint has been held TAKEOFF_WP_DWELL_S."""
    dt = g[C.G_DT]
    # (the takeoff's own vertical profile, not slowed by the S-curve time scaler: ArduCopter
    # runs it outside AC_WPNav)
    heading, done = path_update(c, g, seg, 2, (pos, vel), 0.0, False)
    if c[C.MODE] != AP.MODE_AUTO and -pos[2] >= TAKEOFF_AUTO_FRAC * c[C.TAKEOFF_ALT]:
        # the driver's "altitude reached" -> AUTO; NAV_TAKEOFF runs on to the altitude
        set_mode(c, AP.MODE_AUTO, AP.RSN_GCS, t_us, ev)
        c[C.TAKEOFF_DONE_T] = -1.0
    if c[C.MODE] == AP.MODE_AUTO and done > 0.0:
        if c[C.TAKEOFF_DONE_T] < 0.0:
            c[C.TAKEOFF_DONE_T] = 0.0
        c[C.TAKEOFF_DONE_T] += dt
        if c[C.TAKEOFF_DONE_T] >= TAKEOFF_WP_DWELL_S:
            # first waypoint reached: the route starts from rest
            c[C.SUBMODE] = C.SUB_WP
            c[C.SUB_TIMER] = 0.0
            path_start(c)


@inline_jit
def _nav_waypoints(c, g, t_us, pos, vel, path, seg):
    """AUTO along the mission. At a point the path stops at (a hold, a LOITER_TIME, the point
    before a LAND, the last one), once the target has stopped there and the copter is within
    WP_RADIUS: hold it the point's P_HOLD seconds (ModeAuto::verify_nav_wp and
    verify_loiter_time: the timer starts when the waypoint is reached, in whole
    milliseconds), then go on: the next leg from rest, or at the last point RTL (the mission's
    RETURN_TO_LAUNCH) or its NAV_LAND. Returns the path's heading [rad] (NaN: keep the
    yaw)."""
    n_path = path.shape[0]
    heading, done = path_update(c, g, path, n_path, (pos, vel), 0.0, True)
    if done > 0.0:
        i = int(c[C.WP_INDEX])
        dn = path[i, 0] - pos[0]
        de = path[i, 1] - pos[1]
        t_ms = float(t_us // 1000)
        if c[C.HOLD_START_MS] == 0.0 and dn * dn + de * de <= g[C.G_WP_RADIUS] ** 2:
            c[C.HOLD_START_MS] = t_ms  # reached: AC_WPNav's reached_wp_destination latches
        if c[C.HOLD_START_MS] != 0.0 and (t_ms - c[C.HOLD_START_MS]) // 1000.0 >= path[i, P_HOLD]:
            c[C.HOLD_START_MS] = 0.0
            c[C.WP_REACHED] += 1.0
            if i < n_path - 1:
                c[C.NAV_CNUM] = path[i + 1, P_CNUM]
                path_resume(c, i)
            elif path[i, P_CMD] == AP.MAV_CMD_NAV_LAND:
                # ModeAuto::verify_land: at the landing point, descend (and disarm, landed)
                c[C.MISSION_LAND] = 1.0
                start_land(c, pos, False)
            else:
                c[C.NAV_CNUM] = path[i, P_CNUM] + 1.0  # the mission's RETURN_TO_LAUNCH
                _start_rtl(c, g, pos, vel, seg)
    return heading


@inline_jit
def _nav_rtl_climb(c, g, pos, vel, seg):
    """RTL's climb to the return altitude, then the return leg home at that altitude."""
    heading, done = path_update(c, g, seg, 2, (pos, vel), 0.0, True)
    if done > 0.0 and abs(pos[2] - seg[1, 2]) < 0.5:
        c[C.SUBMODE] = C.SUB_RTL_RETURN
        c[C.SUB_TIMER] = 0.0
        _set_segment(seg, g, (seg[1, 0], seg[1, 1], seg[1, 2]), (0.0, 0.0, seg[1, 2]))
        path_start(c)


@inline_jit
def _nav_rtl_return(c, g, pos, vel, seg):
    """RTL's return leg at RTL_SPEED; loiter once within WP_RADIUS of home."""
    speed_cap = g[C.G_RTL_SPEED]
    heading, done = path_update(c, g, seg, 2, (pos, vel), speed_cap, True)
    if done > 0.0 and pos[0] * pos[0] + pos[1] * pos[1] <= g[C.G_WP_RADIUS] ** 2:
        c[C.SUBMODE] = C.SUB_RTL_LOITER
        c[C.SUB_TIMER] = 0.0


@inline_jit
def _nav_rtl_loiter(c, g):
    """RTL's loiter above home for RTL_LOIT_TIME, then LAND; returns the yaw command (home's)."""
    c[C.PXY_VEL_FF] = 0.0
    c[C.PXY_VEL_FF + 1] = 0.0
    c[C.PXY_ACC_FF] = 0.0
    c[C.PXY_ACC_FF + 1] = 0.0
    c[C.PZ_VEL_FF] = 0.0
    c[C.PZ_ACC_FF] = 0.0
    if c[C.SUB_TIMER] >= g[C.G_RTL_LOIT_TIME]:
        c[C.SUBMODE] = C.SUB_LAND
        c[C.SUB_TIMER] = 0.0
    return c[C.HOME_YAW]


@inline_jit
def _land_descent(c, g, t_us, pos, land_vertical, ev):
    """LAND: hold the height through a failsafe's pause, else hold the landing point and
    descend; disarm once landed. Returns True when it disarmed (the tick ends)."""
    t_s, dt = t_us * 1e-6, g[C.G_DT]
    if c[C.LAND_PAUSE] > 0.0:
        # failsafe LAND: hold the height for LAND_WITH_DELAY before descending
        c[C.LAND_PAUSE] -= dt
        c[C.PZ_VEL_FF] = 0.0
        c[C.PZ_ACC_FF] = 0.0
        return False
    # horizontal hold at the landing point, descent rate by height
    c[C.PXY_VEL_FF] = 0.0
    c[C.PXY_VEL_FF + 1] = 0.0
    c[C.PXY_ACC_FF] = 0.0
    c[C.PXY_ACC_FF + 1] = 0.0
    c[C.PZ_ACC_FF] = 0.0
    if c[C.MAYBE_LANDED] != 0.0:
        # Mode::land_run_horizontal_control while land_complete_maybe
        soften_for_landing_xy(c, pos, dt)
    if land_vertical:
        # ArduCopter's land descent rate: the square-root controller (PSC_POSZ_P,
        # WPNAV_ACCEL_Z) towards LAND_ALT_LOW, kept between LAND_SPEED and LAND_SPEED_HIGH
        # (or WPNAV_SPEED_DN); the velocity target changes at most at WPNAV_ACCEL_Z and the
        # position target moves with it (velocity control, as land_at_climb_rate does)
        v_high = g[C.G_LAND_SPEED_HIGH] if g[C.G_LAND_SPEED_HIGH] > 0.0 else (
            g[C.G_WP_SPEED_DN])
        alt_low = max(g[C.G_LAND_ALT_LOW], 1.0)
        v_dn = sqrt_ctrl(-pos[2] - alt_low, g[C.G_POSZ_P], g[C.G_WP_ACCEL_Z], dt)
        v_dn = min(max(v_dn, g[C.G_LAND_SPEED]), max(v_high, g[C.G_LAND_SPEED]))
        dv = g[C.G_WP_ACCEL_Z] * dt
        v_dn = min(max(v_dn, c[C.PZ_VEL_FF] - dv), c[C.PZ_VEL_FF] + dv)
        c[C.PZ_VEL_FF] = v_dn
        c[C.PZ_POS_T] += v_dn * dt
    else:
        c[C.PZ_VEL_FF] = 0.0
        c[C.PZ_POS_T] = pos[2]
    if c[C.LANDED] != 0.0 and c[C.LAND_TIMER] >= LAND_DETECT_S:
        E.log_ev(ev, t_us, AP.EV_LAND_COMPLETE)
        E.log_ev(ev, t_us, AP.EV_DISARMED)
        # AUTO disarms when its last item (RTL) completes on the ground, LAND/RTL on landing,
        # as AUTO's NAV_LAND does (ModeAuto::verify_land)
        c[C.DISARM_METHOD] = (AP.ARM_METHOD_MISSIONEXIT if c[C.MODE] == AP.MODE_AUTO
                              and c[C.MISSION_LAND] == 0.0 else AP.ARM_METHOD_LANDED)
        c[C.ARMED] = 0.0
        c[C.SUBMODE] = C.SUB_LANDED
        c[C.DISARM_TIME] = t_s
        output_idle(c, g, 0.0)
        return True
    return False


@inline_jit
def _controllers(c, g, sub, inputs, cos_tilt, yaw_cmd, yaw_rate_ff):
    """Position (xy, z), attitude and rate controllers and the mixer; returns the throttle.

    The horizontal controller's acceleration becomes a thrust direction: roll and pitch about
    the attitude target's heading (ATT_YAW_T), not the vehicle's, as AC_PosControl's thrust
    vector with the heading (input_thrust_vector_heading) makes it. The two are the same in
    normal flight; after a motor failure has yawed the copter far from its target heading
    (motor_partial_s47: 45 deg), leaning in the vehicle's frame would tilt the thrust the
    wrong way."""
    pos, vel, q, gyro = inputs.pos, inputs.vel, inputs.q, inputs.gyro
    acc_up, v_batt = -inputs.acc_ned[2], inputs.v_batt
    if c[C.LAND_NOGPS] != 0.0 and sub == C.SUB_LAND:
        c[C.ATT_ROLL_CMD] = 0.0  # no position control: level, drift with the wind
        c[C.ATT_PITCH_CMD] = 0.0
    else:
        xy_update(c, g, pos, vel, math.cos(c[C.ATT_YAW_T]), math.sin(c[C.ATT_YAW_T]))
    c[C.ATT_YAW_CMD] = yaw_cmd
    c[C.YAW_RATE_CMD] = yaw_rate_ff
    thr = z_update(c, g, pos[2], vel[2], acc_up, c[C.LIM_THR_LO] != 0.0, c[C.LIM_THR_HI] != 0.0)
    c[C.THR_OUT] = thr
    althold_lean_update(c, g, thr)
    thr_b = angle_boost(thr, cos_tilt)
    c[C.THR_OUT_BOOSTED] = thr_b
    _attitude_rates_mix(c, g, (q, gyro, v_batt), sub, thr, thr_b)
    return thr


@inline_jit
def _attitude_rates_mix(c, g, meas, sub, thr, thr_b):
    """The attitude controller (its targets set), the rate PIDs, the throttle mix (of the
    submode sub: the pilot's modes or the autopilot's) and the mixer with the throttle thr
    (thr_b boosted). meas: the EKF attitude body->NED, the body rates [rad/s] and the
    battery voltage [V]."""
    q, gyro, v_batt = meas
    attitude_update(c, g, q, gyro, c[C.BODY_RATE_T : C.BODY_RATE_T + 3])
    rate_t0 = c[C.BODY_RATE_T]
    rate_t1 = c[C.BODY_RATE_T + 1]
    rate_t2 = c[C.BODY_RATE_T + 2]
    lim_rp = c[C.LIM_RP] != 0.0
    lim_y = c[C.LIM_YAW] != 0.0
    r_out = rate_pid(c, g, 0, rate_t0, gyro[0], lim_rp)
    p_out = rate_pid(c, g, 1, rate_t1, gyro[1], lim_rp)
    y_out = rate_pid(c, g, 2, rate_t2, gyro[2], lim_y)
    if sub == C.SUB_PILOT:
        want = pilot_mix_want(c, g)
    else:
        want = g[C.G_THR_MIX_MAX] if _attitude_first(c, sub) else g[C.G_THR_MIX_MIN]
    throttle_mix_update(c, g, want, thr_b, thr)
    mix(c, g, r_out, p_out, y_out, thr_b, v_batt)


@inline_jit
def _pilot_tick(c, g, t_us, inputs, cos_tilt, ev):
    """The armed vehicle in a pilot mode (tlm_sim.control.pilot_modes): the mode's targets,
    the controllers and mixer (unless the motors idle), hover learning outside STABILIZE and ACRO,
    the land detector (not while a takeoff's throttle rises on the ground; EV
    LAND_COMPLETE / NOT_LANDED), the crash checks."""
    was_landed = c[C.LANDED] != 0.0
    thr, thr_b, run = pilot_step(c, g, t_us, inputs, cos_tilt)
    if run:
        meas = (inputs.q, inputs.gyro, inputs.v_batt)
        _attitude_rates_mix(c, g, meas, C.SUB_PILOT, thr, thr_b)
    if was_landed and c[C.LANDED] == 0.0:
        E.log_ev(ev, t_us, AP.EV_NOT_LANDED)
        was_landed = False
    if not has_manual_throttle(c[C.MODE]):
        _hover_learning(c, g, C.SUB_PILOT, thr, inputs)
    taking_off = c[C.PIL_TKOFF] == 1.0
    _land_detector(c, g, t_us, C.SUB_TAKEOFF if taking_off else C.SUB_PILOT, thr, inputs, ev)
    log_land_complete(c, t_us, was_landed, ev)
    _crash_checks(c, g, t_us, inputs, cos_tilt, ev)


@inline_jit
def _attitude_first(c, sub):
    """Copter::update_throttle_mix for the autopilot's throttle: attitude control has priority
    over a low throttle demand (ATC_THR_MIX_MAX) unless landed, or unless descending with a
    lean target below 15 deg (or landing), an attitude error below 30 deg and the 1 Hz
    acceleration below 3 m/s^2 (ATC_THR_MIX_MIN). (The vertical controller's confidence,
    vel_U_control_ratio, is taken as 1: the mix is ATC_THR_MIX_MAX itself.)"""
    if c[C.LANDED] != 0.0:
        return False
    lean2 = c[C.ATT_ROLL_T] ** 2 + c[C.ATT_PITCH_T] ** 2
    large_angle_request = lean2 > THR_MIX_LEAN**2 and sub != C.SUB_LAND
    a_lp2 = c[C.ALP] ** 2 + c[C.ALP + 1] ** 2 + c[C.ALP + 2] ** 2
    return (large_angle_request or c[C.ATT_THRUST_ERR] > THR_MIX_ATT_ERR
            or a_lp2 > THR_MIX_ACCEL**2 or c[C.PZ_VEL_T] <= 0.0)


@inline_jit
def _hover_learning(c, g, sub, thr, inputs):
    """MOT_HOVER_LEARN 2 with ArduCopter's conditions: flying, no desired climb or descent,
    climb rate below 0.6 m/s, roll and pitch within 5 deg. (Cruise pitches the copter beyond
    5 deg, so SITL learns only in level hovers: normal_s11 keeps ThH 0.3876 from 15 s after
    arming to the RTL, where it drops to 0.3746.)"""
    dt, vel, q = g[C.G_DT], inputs.vel, inputs.q
    learning = (c[C.LANDED] == 0.0 and c[C.LAND_TIMER] == 0.0 and c[C.LIM_THR_LO] == 0.0
                and c[C.LIM_THR_HI] == 0.0 and abs(vel[2]) < 0.6 and c[C.PZ_VEL_FF] == 0.0
                and sub >= C.SUB_WP and thr > 0.0)
    if learning:
        # |roll|, |pitch| < 5 deg: sin(pitch) = 2 (w y - x z), tan(roll) = r21 / r22
        qw, qx, qy, qz = q[0], q[1], q[2], q[3]
        sp = 2.0 * (qw * qy - qx * qz)
        r21 = 2.0 * (qy * qz + qw * qx)
        r22 = 1.0 - 2.0 * (qx * qx + qy * qy)
        learning = abs(sp) < HOVER_LEARN_SIN_LEAN and abs(r21) < HOVER_LEARN_TAN_LEAN * r22
    if learning and g[C.G_HOVER_LEARN] == 2.0:
        h = c[C.THR_HOVER] + (thr - c[C.THR_HOVER]) * dt / (dt + 10.0)
        c[C.THR_HOVER] = min(max(h, 0.125), 0.6875)


@inline_jit
def _land_detector(c, g, t_us, sub, thr, inputs, ev):
    """Copter::update_land_detector: the motors at their lower limit (or the throttle below
    0.05), the attitude controller's mix at its minimum, no lean target above 15 deg and no
    attitude error above 30 deg, the 1 Hz acceleration at most 1 m/s^2 and the EKF's climb
    rate below 1 m/s for LAND_DETECT_S -> landed (EV LAND_COMPLETE_MAYBE after LAND_MAYBE_S);
    EV NOT_LANDED once above 0.5 m again. Leaves the condition bits and the pass count in
    c[LDET_FLAGS], c[LDET_COUNT] (LDET; only LANDED | LANDED_MAYBE and 0 once landed, as
    ArduCopter's land_complete branch)."""
    dt, vel, pos = g[C.G_DT], inputs.vel, inputs.pos
    was_landed = c[C.LANDED] != 0.0
    flags = _land_conditions(c, g, thr, vel[2])
    if (flags & LAND_CRITERIA_MASK) == LAND_CRITERIA and sub != C.SUB_TAKEOFF:
        c[C.LAND_TIMER] += dt
        if c[C.LAND_TIMER] >= LAND_MAYBE_S and c[C.MAYBE_LANDED] == 0.0:
            c[C.MAYBE_LANDED] = 1.0
            E.log_ev(ev, t_us, AP.EV_LAND_COMPLETE_MAYBE)
        if c[C.LAND_TIMER] >= LAND_DETECT_S:
            c[C.LANDED] = 1.0
    elif c[C.LAND_TIMER] != 0.0 or c[C.LANDED] != 0.0:
        c[C.LAND_TIMER] = 0.0
        c[C.MAYBE_LANDED] = 0.0
        if c[C.LANDED] != 0.0 and -pos[2] > 0.5:
            c[C.LANDED] = 0.0
            E.log_ev(ev, t_us, AP.EV_NOT_LANDED)
    if c[C.LANDED] != 0.0:
        flags = (0 if was_landed else flags) | (AP.LDET_LANDED | AP.LDET_LANDED_MAYBE)
        c[C.LDET_COUNT] = 0.0
    elif c[C.LAND_TIMER] > 0.0:
        if c[C.MAYBE_LANDED] != 0.0:
            flags |= AP.LDET_LANDED_MAYBE
        c[C.LDET_COUNT] = float(int(c[C.LAND_TIMER] / dt + 0.5))
    else:
        c[C.LDET_COUNT] = 0.0
    c[C.LDET_FLAGS] = flags


@inline_jit
def _land_conditions(c, g, thr, vd):
    """The land detector's condition bits (ardupilot.LDET_*; WOW and RANGEFINDER_BELOW_2M
    always, tlm has neither sensor) from the motors' lower limit, the throttle mix, the lean
    target and attitude error, the 1 Hz acceleration and the EKF's vertical velocity vd [m/s]
    (without branches: the loop evaluates it every tick in flight)."""
    lower = (c[C.LIM_THR_LO] != 0.0) | (thr <= 0.05)
    mix_min = c[C.THR_RPY_MIX] < 1.25 * g[C.G_THR_MIX_MIN]
    large = ((c[C.ATT_ROLL_T] * c[C.ATT_ROLL_T] + c[C.ATT_PITCH_T] * c[C.ATT_PITCH_T]
              > THR_MIX_LEAN * THR_MIX_LEAN) | (c[C.ATT_THRUST_ERR] > THR_MIX_ATT_ERR))
    still = c[C.ALP] * c[C.ALP] + c[C.ALP + 1] * c[C.ALP + 1] + c[C.ALP + 2] * c[C.ALP + 2] <= 1.0
    slow = abs(vd) < 1.0
    return (AP.LDET_WOW + AP.LDET_RANGEFINDER_BELOW_2M + AP.LDET_MOTOR_AT_LOWER_LIMIT * lower
            + AP.LDET_THROTTLE_MIX_AT_MIN * mix_min + AP.LDET_LARGE_ANGLE * large
            + AP.LDET_ACCEL_STATIONARY * still + AP.LDET_DESCENT_RATE_LOW * slow)


@inline_jit
def _crash_checks(c, g, t_us, inputs, cos_tilt, ev):
    """The thrust-loss check, and the crash check (leaning over 15 deg; not in ACRO, whose
    crash_check_enabled is false): a crash disarms (ERR 12/1, EV DISARMED)."""
    dt, q, vel = g[C.G_DT], inputs.q, inputs.vel
    thrust_loss_check(c, dt, q, vel[2], ev, t_us)
    if cos_tilt < CRASH_LEAN_COS and c[C.MODE] != AP.MODE_ACRO:
        roll, pitch, _ = quat_to_euler(q[0], q[1], q[2], q[3])
        if crash_check(c, g, dt, cos_tilt, roll, pitch, math.sqrt(vel[0] ** 2 + vel[1] ** 2)):
            E.log_err(ev, t_us, AP.ERR_CRASH_CHECK, AP.ERR_CODE_FAILSAFE)
            disarm(c, g, t_us, AP.ARM_METHOD_CRASH, ev)
    else:
        c[C.CRASH_TIMER] = 0.0
