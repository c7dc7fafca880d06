"""The pilot's side of ArduCopter's radio handling, for flights flown from RC input (a stick
script or a log's RCIN replayed; ``g[G_PILOT]`` 1): design
../shared/design/pilot-modes-and-vibration.md, A2, A3 and A6 (our implementation).

Each main-loop tick, before the vehicle's step (ArduCopter's rc_loop), :func:`pilot_rc`:

- reads the sticks from the receiver's channels (RCMAP_*): roll, pitch and yaw normalised to
  -1..1 outside RCn_DZ around RCn_TRIM (``norm_input_dz``), the yaw also as an angle of
  +-4500 (``pwm_to_angle_dz``), the throttle as control_in 0..1000 above RC3_MIN + RC3_DZ
  (``pwm_to_range_dz``); without valid input (radio failsafe, low-throttle frames) the
  sticks read centred;
- keeps the throttle_zero flag (set 400 ms after the throttle stick reaches 0, cleared at
  once) and auto_armed (EV AUTO_ARMED the first time the throttle is raised after arming);
- reads the mode switch on FLTMODE_CH (six positions split at 1231 / 1361 / 1491 / 1621 /
  1750 us, PWM at or below 800 or at or above 2200 ignored), debounced: a new position must
  read the same for 200 ms; then the mode FLTMODEn: STABILIZE, ACRO, ALT_HOLD, LOITER, POSHOLD
  (:mod:`tlm_sim.control.pilot_modes`), RTL or LAND; LOITER and POSHOLD are refused while
  armed without a position; other modes are refused (tlm flies no mission from a switch);
- the ground station's mode requests (MAVLink SET_MODE, ``FlightPlan.gcs``): each tried once
  at its time, reason GCS, under the same rules as the switch's;
- the rudder gestures (ARMING_RUDDER): yaw stick beyond 4000 of 4500 with the throttle at 0
  for 3 s asks for an arm attempt (the pre-arm and arm checks,
  :func:`tlm_sim.control.arming.arming_step`); with ARMING_RUDDER 2, yaw beyond -4000 with
  the throttle at 0 for 3 s disarms in STABILIZE, ACRO or once landed (ARM.Method RUDDER);
- auto-disarm: landed with the throttle at zero for DISARM_DELAY seconds disarms
  (ARM.Method DISARMDELAY).
"""


from tlm_sim import ardupilot as AP
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import events as E
from tlm_sim.control import layout as C
from tlm_sim.control.modes import disarm, rtl_or_land, set_mode, start_land
from tlm_sim.control.pilot_modes import (
    SPOOLED_UP_S,
    has_manual_throttle,
    is_pilot_mode,
    pilot_mode_enter,
)
from tlm_sim.rotation import heading

THROTTLE_ZERO_S = 0.4  # set_throttle_zero_flag: the stick at 0 this long
SWITCH_DEBOUNCE_S = 0.2  # RC_Channel's mode switch debounce
#: the 6-position switch's upper PWM bounds (read_6pos_switch) and the ignored range
SWITCH_BOUNDS = (1231.0, 1361.0, 1491.0, 1621.0, 1750.0)
SWITCH_PWM_MIN, SWITCH_PWM_MAX = 800.0, 2200.0
RUDDER_CD = 4000.0  # yaw stick beyond this of +-4500 for the gestures
RUDDER_HOLD_S = 3.0  # ARM_DELAY_MS of the rudder gesture
ANGLE_RANGE_CD = 4500.0


@tick_jit
def stick_norm(g, k, pwm):
    """norm_input_dz of stick k (0 roll, 1 pitch, 3 yaw): -1..1, 0 within RCn_DZ of RCn_TRIM,
    negated when reversed."""
    lo, hi = g[C.G_RC_MIN + k], g[C.G_RC_MAX + k]
    trim, dz = g[C.G_RC_TRIM + k], g[C.G_RC_DZ + k]
    r = 0.0
    if pwm > trim + dz and hi > trim + dz:
        r = (pwm - (trim + dz)) / (hi - (trim + dz))
    elif pwm < trim - dz and trim - dz > lo:
        r = (pwm - (trim - dz)) / ((trim - dz) - lo)
    if g[C.G_RC_REV + k] != 0.0:
        r = -r
    return min(max(r, -1.0), 1.0)


@tick_jit
def throttle_in(g, pwm):
    """pwm_to_range_dz of the throttle: control_in 0..1000 above RC3_MIN + RC3_DZ."""
    lo, hi, dz = g[C.G_RC_MIN + 2], g[C.G_RC_MAX + 2], g[C.G_RC_DZ + 2]
    r = min(max(pwm, lo), hi)
    if g[C.G_RC_REV + 2] != 0.0:
        r = hi - (r - lo)
    if r <= lo + dz or hi <= lo + dz:
        return 0.0
    return 1000.0 * (r - (lo + dz)) / (hi - (lo + dz))


@tick_jit
def switch_position(pwm):
    """Mode switch position 0..5 of a PWM [us], -1 outside 800..2200."""
    if pwm <= SWITCH_PWM_MIN or pwm >= SWITCH_PWM_MAX:
        return -1
    for k in range(5):
        if pwm < SWITCH_BOUNDS[k]:
            return k
    return 5


@tick_jit
def pilot_init(c):
    """Before the first frame: no switch position, no gesture, the throttle counted at zero,
    the boot mode's reason."""
    c[C.PIL_SW_POS] = -1.0
    c[C.PIL_SW_NEW] = -1.0
    c[C.PIL_RUDDER_T] = -1.0
    c[C.PIL_RUDDER_DIS_T] = -1.0
    c[C.PIL_THR_ZERO] = 1.0
    c[C.PIL_THR_ZERO_T] = 0.0
    c[C.PIL_DISARM_T] = -1.0
    c[C.MODE_RSN] = AP.RSN_INITIALISED
    c[C.PIL_GCS_ROW] = 0.0


@tick_jit
def pilot_rc(c, g, t_us, rc, inputs, out):
    """The pilot's radio this tick (rc: channels 1..8 [us] as the receiver delivered them;
    inputs: the tick's :class:`~tlm_sim.bundles.VehicleInputs`; out: (the RTL / LAND segment
    scratch, the event buffers)): sticks, throttle_zero, auto_armed, the mode switch, the
    rudder gestures, auto-disarm."""
    ev = out[1]
    t_s = t_us * 1e-6
    valid = c[C.RC_FAILSAFE] == 0.0 and c[C.RC_THR_LOW_N] == 0.0
    _read_sticks(c, g, rc, valid)
    if c[C.PIL_THR] > 0.0:
        c[C.PIL_THR_ZERO] = 0.0
        c[C.PIL_THR_ZERO_T] = -1.0
    elif c[C.PIL_THR_ZERO_T] < 0.0:
        c[C.PIL_THR_ZERO_T] = t_s
    elif t_s - c[C.PIL_THR_ZERO_T] >= THROTTLE_ZERO_S:
        c[C.PIL_THR_ZERO] = 1.0
    armed = c[C.ARMED] != 0.0
    if armed and c[C.PIL_THR_ZERO] == 0.0 and c[C.PIL_AUTO_ARMED] == 0.0:
        c[C.PIL_AUTO_ARMED] = 1.0
        E.log_ev(ev, t_us, AP.EV_AUTO_ARMED)
    ch = int(g[C.G_FLTMODE_CH])
    if valid and 0 <= ch < 8:
        _mode_switch(c, g, t_us, switch_position(rc[ch]), inputs, out)
    _rudder(c, g, t_us, ev)
    _auto_disarm(c, g, t_us, ev)


@inline_jit
def _read_sticks(c, g, rc, valid):
    """The sticks from the mapped channels (centred without valid input)."""
    if not valid:
        c[C.PIL_ROLL] = 0.0
        c[C.PIL_PITCH] = 0.0
        c[C.PIL_YAW] = 0.0
        c[C.PIL_YAW_ANGLE] = 0.0
    else:
        c[C.PIL_ROLL] = stick_norm(g, 0, rc[int(g[C.G_RC_MAP])])
        c[C.PIL_PITCH] = stick_norm(g, 1, rc[int(g[C.G_RC_MAP + 1])])
        yaw = stick_norm(g, 3, rc[int(g[C.G_RC_MAP + 3])])
        c[C.PIL_YAW] = yaw
        c[C.PIL_YAW_ANGLE] = ANGLE_RANGE_CD * yaw
    c[C.PIL_THR] = throttle_in(g, rc[int(g[C.G_RC_MAP + 2])])


@inline_jit
def _mode_switch(c, g, t_us, pos, inputs, out):
    """Debounce the switch position pos; a position read 200 ms becomes current and its mode
    is tried (once: a refused change waits for the switch to move)."""
    t_s = t_us * 1e-6
    if pos < 0 or pos == c[C.PIL_SW_POS]:
        c[C.PIL_SW_NEW] = -1.0
        return
    if pos != c[C.PIL_SW_NEW]:
        c[C.PIL_SW_NEW] = pos
        c[C.PIL_SW_T] = t_s
        return
    if t_s - c[C.PIL_SW_T] < SWITCH_DEBOUNCE_S:
        return
    c[C.PIL_SW_POS] = pos
    c[C.PIL_SW_NEW] = -1.0
    change_mode(c, g, t_us, (int(g[C.G_FLTMODE + pos]), AP.RSN_RC_COMMAND), inputs, out)


@tick_jit
def pilot_gcs(c, g, t_us, gcs, inputs, out):
    """The ground station's mode requests due at t_us (gcs: rows (time [us], mode number)),
    each tried once, reason GCS (out: (the RTL / LAND segment scratch, the event buffers))."""
    row = int(c[C.PIL_GCS_ROW])
    while row < gcs.shape[0] and gcs[row, 0] <= t_us:
        change_mode(c, g, t_us, (int(gcs[row, 1]), AP.RSN_GCS), inputs, out)
        row += 1
    c[C.PIL_GCS_ROW] = row


@tick_jit
def change_mode(c, g, t_us, request, inputs, out):
    """Copter::set_mode for a request (mode number, reason: RC_COMMAND from the switch, GCS
    over MAVLink); returns whether the mode is now the one asked for. Refused: an unflown
    mode; LOITER or POSHOLD while armed without a position; ACRO in the radio failsafe.
    out: (the RTL / LAND segment scratch, the event buffers)."""
    mode, rsn = request
    seg, ev = out
    if mode == c[C.MODE]:
        c[C.MODE_RSN] = rsn
        return True
    armed = c[C.ARMED] != 0.0
    airborne = armed and c[C.LANDED] == 0.0
    if mode == AP.MODE_ACRO and c[C.RC_FAILSAFE] != 0.0:
        return False  # ModeAcro::allows_entry_in_rc_failsafe
    if is_pilot_mode(mode):
        needs_position = mode == AP.MODE_LOITER or mode == AP.MODE_POSHOLD
        if armed and needs_position and not (c[C.EKF_POS_OK] != 0.0
                                             and c[C.EKF_FAILSAFE] == 0.0):
            return False
        from_manual = has_manual_throttle(c[C.MODE])
        set_mode(c, mode, rsn, t_us, ev)
        if armed:
            if c[C.SUBMODE] != C.SUB_PILOT:
                c[C.SUB_TIMER] = max(c[C.SUB_TIMER], SPOOLED_UP_S) if airborne else 0.0
                c[C.SUBMODE] = C.SUB_PILOT
            pilot_mode_enter(c, g, t_us * 1e-6, inputs, from_manual)
        return True
    if mode == AP.MODE_RTL:
        if airborne:
            rtl_or_land(c, g, t_us, inputs, seg, rsn, ev)
        else:
            set_mode(c, mode, rsn, t_us, ev)
        return True
    if mode == AP.MODE_LAND:
        set_mode(c, mode, rsn, t_us, ev)
        if airborne:
            start_land(c, inputs.pos, False)
        return True
    return False


@inline_jit
def _rudder(c, g, t_us, ev):
    """The yaw-stick gestures: arm (ARMING_RUDDER >= 1) by yaw right with the throttle at 0
    for 3 s (an arm attempt: PIL_ARM_REQ); disarm (ARMING_RUDDER 2) by yaw left with the
    throttle at 0 for 3 s, in STABILIZE, ACRO (manual throttle) or landed."""
    t_s = t_us * 1e-6
    rud = g[C.G_ARMING_RUDDER]
    thr_zero = c[C.PIL_THR] == 0.0
    yaw = c[C.PIL_YAW_ANGLE]
    if c[C.ARMED] == 0.0:
        c[C.PIL_RUDDER_DIS_T] = -1.0
        if rud >= 1.0 and yaw > RUDDER_CD and thr_zero:
            if c[C.PIL_RUDDER_T] < 0.0:
                c[C.PIL_RUDDER_T] = t_s
            elif t_s - c[C.PIL_RUDDER_T] >= RUDDER_HOLD_S:
                c[C.PIL_ARM_REQ] = 1.0
                c[C.PIL_RUDDER_T] = -1.0
        else:
            c[C.PIL_RUDDER_T] = -1.0
        return
    c[C.PIL_RUDDER_T] = -1.0
    may = has_manual_throttle(c[C.MODE]) or c[C.LANDED] != 0.0
    if rud == 2.0 and yaw < -RUDDER_CD and thr_zero and may:
        if c[C.PIL_RUDDER_DIS_T] < 0.0:
            c[C.PIL_RUDDER_DIS_T] = t_s
        elif t_s - c[C.PIL_RUDDER_DIS_T] >= RUDDER_HOLD_S:
            c[C.PIL_RUDDER_DIS_T] = -1.0
            disarm(c, g, t_us, AP.ARM_METHOD_RUDDER, ev)
    else:
        c[C.PIL_RUDDER_DIS_T] = -1.0


@inline_jit
def _auto_disarm(c, g, t_us, ev):
    """Copter::auto_disarm_check: armed, landed with the throttle at zero for DISARM_DELAY
    (> 0) seconds -> disarm."""
    t_s = t_us * 1e-6
    if (c[C.ARMED] == 0.0 or g[C.G_DISARM_DELAY] <= 0.0 or c[C.LANDED] == 0.0
            or c[C.PIL_THR_ZERO] == 0.0 or c[C.SUBMODE] != C.SUB_PILOT):
        c[C.PIL_DISARM_T] = -1.0
        return
    if c[C.PIL_DISARM_T] < 0.0:
        c[C.PIL_DISARM_T] = t_s
    elif t_s - c[C.PIL_DISARM_T] >= g[C.G_DISARM_DELAY]:
        c[C.PIL_DISARM_T] = -1.0
        disarm(c, g, t_us, AP.ARM_METHOD_DISARMDELAY, ev)


@tick_jit
def arm_pilot(c, g, t_us, inputs, ev):
    """Arm in the present mode after a rudder gesture's attempt passed the checks (the mode
    is logged again with its reason, as AP_Arming_Copter::arm does; ARM.Method RUDDER);
    returns False, arming nothing, in a mode tlm does not fly from the sticks."""
    mode = c[C.MODE]
    if not is_pilot_mode(mode):
        return False
    E.log_mode(ev, t_us, mode, c[C.MODE_RSN])
    c[C.ARMED] = 1.0
    c[C.ARM_TIME_S] = t_us * 1e-6
    c[C.ARM_METHOD] = AP.ARM_METHOD_RUDDER
    c[C.LANDED] = 1.0
    c[C.SUBMODE] = C.SUB_PILOT
    c[C.SUB_TIMER] = 0.0
    c[C.SPOOL] = 1.0
    c[C.PIL_AUTO_ARMED] = 0.0
    c[C.PIL_TKOFF] = 0.0
    E.log_ev(ev, t_us, AP.EV_ARMED)
    pilot_mode_enter(c, g, t_us * 1e-6, inputs, False)
    c[C.HOME_YAW] = heading(inputs.q)
    return True
