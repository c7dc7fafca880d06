"""ArduCopter 4.7's pilot-flown modes: STABILIZE, ACRO, ALT_HOLD, LOITER and POSHOLD from the
sticks (design: ../shared/design/pilot-modes-and-vibration.md, Part A; our implementation).

The sticks arrive read by :mod:`tlm_sim.control.pilot` (c[PIL_*]: roll, pitch and yaw in -1..1
outside their dead zones, the throttle as control_in 0..1000). Per main-loop tick
:func:`pilot_step` turns them into the controllers' targets:

- lean angles (A4.1 ``rc_input_to_roll_pitch``): STABILIZE up to ANGLE_MAX, ALT_HOLD and
  POSHOLD up to ANGLE_MAX within the throttle-headroom lean limit, LOITER's acceleration from
  LOIT_ANG_MAX;
- yaw rate (A4.2): PILOT_Y_RATE with PILOT_Y_EXPO, shaped at ATC_ACCEL_Y_MAX (and
  PILOT_Y_RATE_TC);
- STABILIZE's throttle (A4.4): the stick through the curve that puts mid-stick at the hover
  throttle, with angle boost;
- ACRO (mode_acro.cpp): body rates from the sticks (ACRO_RP_RATE, ACRO_Y_RATE, their expo)
  and the trainer, the attitude target turned at them (ATT_RATE_BF_IN); STABILIZE's throttle
  curve around ACRO_THR_MID, without angle boost;
- ALT_HOLD, LOITER, POSHOLD's climb rate (A4.3): the dead band THR_DZ around mid-stick,
  PILOT_SPEED_UP / _DN, shaped at PILOT_ACCEL_Z and PSC_JERK_Z, held by the vertical position
  controller; on the ground the stick above the dead band starts the pilot takeoff (A9:
  throttle rising over TKOFF_SLEW_TIME until the copter climbs, then PILOT_TKOFF_ALT);
- LOITER (A10): the stick's acceleration, predicted through the attitude shaping, drives a
  desired velocity with drag (top speed LOIT_SPEED) and, once the stick is released for
  LOIT_BRK_DELAY, a jerk-limited brake (LOIT_BRK_ACCEL, LOIT_BRK_JERK); the position
  controller follows it (LOIT_ACC_MAX, 2 m);
- POSHOLD (A11): per axis the pilot's lean, then a brake angle from the velocity
  (PHLD_BRAKE_RATE, PHLD_BRAKE_ANGLE), then LOITER's position hold, with wind compensation.

Spool states are tlm's: ground idle (MOT_SPIN_ARM) through the arming delay and while landed
with the stick low; no separate spool-up ramp.
"""

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.control import events as E
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import (
    attitude_reset,
    euler_rate_to_body,
    rate_reset,
    shape_angle,
    sqrt_ctrl,
    throttle_mix_update,
    wrap_pi,
)
from tlm_sim.control.mixer import MOT_SPOOL_TIME_S, output_idle, voltage_compensation
from tlm_sim.control.position import (
    LEAN_LIMIT_MIN,
    althold_lean_update,
    angle_boost,
    soften_for_landing_xy,
    xy_control,
    xy_reset,
    z_control,
    z_reset,
)
from tlm_sim.rotation import heading_vector

#: ArduCopter's arming delay (ARMING_DELAY_SEC): the motors stay at ground idle this long
ARMING_DELAY_S = 2.0
#: the motors are "spooled up" (THROTTLE_UNLIMITED) after the arming delay and MOT_SPOOL_TIME
SPOOLED_UP_S = ARMING_DELAY_S + MOT_SPOOL_TIME_S
LEAN_CAP = math.radians(85.0)  # rc_input_to_roll_pitch's largest angle
EXPO_MAX = 0.95  # input_expo: no expo at or beyond this
#: the vertical shaping's acceleration ceiling when braking a descent (AC_PosControl)
ACCEL_Z_DOWN_CAP = 7.5
#: FLT_EPSILON in cm/s as m/s: below it ArduPilot's desired climb counts as zero
FLT_EPSILON_CM = 1.1920929e-9
# POSHOLD (mode_poshold.cpp), angles in centidegrees, times in milliseconds
PH_PILOT_OVERRIDE = 0
PH_BRAKE = 1
PH_BRAKE_READY = 2
PH_BRAKE_TO_LOITER = 3
PH_LOITER = 4
PH_CONTROLLER_TO_PILOT = 5
PH_SPEED_0 = 10.0  # cm/s: "nearly stopped"
PH_BRAKE_TIME_MAX_MS = 6000.0
PH_BRAKE_TO_LOITER_MS = 1500.0
PH_CONTROLLER_TO_PILOT_MS = 500.0
PH_WIND_DELAY_MS = 1500.0
PH_SMOOTH = 0.0125  # per loop at 400 Hz
PH_NO_SMOOTH_CD = 1800.0
PH_WIND_TC = 0.0025  # per loop
PH_WIND_LEAN = 0.6666  # of ANGLE_MAX
# ACRO's trainer (ArduCopter config.h)
ACRO_LEVEL_MAX = math.radians(30.0)  # ACRO_LEVEL_MAX_ANGLE: levelling acts up to this lean
ACRO_LEVEL_MAX_OVERSHOOT = math.radians(10.0)  # ACRO_LEVEL_MAX_OVERSHOOT


@tick_jit
def lean_angles(roll_in, pitch_in, angle_max, angle_limit):
    """Stick (roll_in, pitch_in in -1..1; pitch + = stick back, nose up) -> (roll, pitch) [rad]:
    each axis linear up to angle_max, their combined tilt within angle_limit (at least 10 deg;
    ArduPilot's rc_input_to_roll_pitch)."""
    a = min(angle_max, LEAN_CAP)
    lim = min(max(angle_limit, LEAN_LIMIT_MIN), a)
    tx = -math.tan(a * pitch_in)
    ty = math.tan(a * roll_in)
    n = math.sqrt(tx * tx + ty * ty)
    t_lim = math.tan(lim)
    if n > t_lim:
        tx *= t_lim / n
        ty *= t_lim / n
    pitch = -math.atan(tx)
    return math.atan(math.cos(pitch) * ty), pitch


@tick_jit
def yaw_rate(g, yaw_in):
    """Yaw stick (-1..1) -> desired yaw rate [rad/s]: PILOT_Y_RATE with PILOT_Y_EXPO."""
    return g[C.G_PILOT_Y_RATE] * input_expo(yaw_in, g[C.G_PILOT_Y_EXPO])


@tick_jit
def climb_rate(g, thr_in):
    """Throttle stick control_in (0..1000) -> desired climb rate [m/s, up]: 0 within THR_DZ of
    mid-stick, PILOT_SPEED_UP at full stick, -PILOT_SPEED_DN at zero
    (get_pilot_desired_climb_rate)."""
    mid = g[C.G_THR_MID]
    dz = g[C.G_THR_DZ]
    hi = mid + dz
    lo = mid - dz
    up = g[C.G_PILOT_SPEED_UP]
    dn = g[C.G_PILOT_SPEED_DN]
    if thr_in > hi and hi < 1000.0:
        r = up * (thr_in - hi) / (1000.0 - hi)
    elif thr_in < lo and lo > 0.0:
        r = dn * (thr_in - lo) / lo
    else:
        r = 0.0
    return min(max(r, -dn), up)


@tick_jit
def manual_throttle(g, thr_in, hover):
    """STABILIZE's throttle curve (get_pilot_desired_throttle): control_in 0..1000 -> 0..1,
    piecewise linear with mid-stick at 0.5, then an expo that maps mid-stick to the hover
    throttle."""
    mid = g[C.G_THR_MID] if g[C.G_THR_MID] > 0.0 else 500.0
    if thr_in < mid:
        x = 0.5 * thr_in / mid
    else:
        x = 0.5 + 0.5 * (thr_in - mid) / (1000.0 - mid)
    e = min(max(-(hover - 0.5) / 0.375, -0.5), 1.0)
    x = min(max(x, 0.0), 1.0)
    return x * (1.0 - e) + e * x * x * x


@tick_jit
def lean_to_accel(roll, pitch, cy, sy):
    """Horizontal acceleration NE [m/s^2] of level thrust at lean (roll, pitch) [rad] and
    heading (cos, sin) = (cy, sy) (AC_Loiter's stick acceleration)."""
    cr = math.cos(roll)
    k = GRAVITY_MSS / max(cr * math.cos(pitch), 0.1)
    sp = math.sin(pitch) * cr
    sr = math.sin(roll)
    return k * (-cy * sp - sy * sr), k * (-sy * sp + cy * sr)


#: the modes tlm flies from the sticks (:func:`is_pilot_mode` in the loop; this tuple for
#: Python code: the replay's notes and requests)
PILOT_MODES: tuple[int, ...] = (AP.MODE_STABILIZE, AP.MODE_ACRO, AP.MODE_ALT_HOLD,
                                AP.MODE_LOITER, AP.MODE_POSHOLD)


@tick_jit
def is_pilot_mode(mode):
    """Whether the mode is one tlm flies from the sticks (STABILIZE, ACRO, ALT_HOLD, LOITER,
    POSHOLD)."""
    return (mode == AP.MODE_STABILIZE or mode == AP.MODE_ALT_HOLD or mode == AP.MODE_LOITER
            or mode == AP.MODE_POSHOLD or mode == AP.MODE_ACRO)


@tick_jit
def has_manual_throttle(mode):
    """Mode::has_manual_throttle: the throttle stick drives the motors (STABILIZE, ACRO)."""
    return mode == AP.MODE_STABILIZE or mode == AP.MODE_ACRO


@inline_jit
def _heading(q):
    """(cos, sin) of the heading of the body->NED quaternion q (1, 0 when vertical)."""
    hx, hy, n = heading_vector(q)
    if n < 1e-9:
        return 1.0, 0.0
    return hx / n, hy / n


@tick_jit
def pilot_mode_enter(c, g, t_s, inputs, from_manual):
    """Enter a pilot mode (the switch, or arming in it): the heading follows the yaw stick,
    the vertical shaping starts from the present climb (with the accel integrator at the
    manual throttle's when coming from STABILIZE), LOITER's and POSHOLD's targets from the
    present position and velocity."""
    pos, vel = inputs.pos, inputs.vel
    c[C.ATT_YAW_RATE_IN] = 1.0
    if c[C.MODE] == AP.MODE_ACRO:
        if c[C.ATT_RATE_BF_IN] == 0.0:  # the body rates continue the angle target's rates
            _euler_rate_to_ang_vel(c, c[C.ATT_ROLL_RATE_T], c[C.ATT_PITCH_RATE_T],
                                   c[C.ATT_YAW_RATE_T], C.ATT_ANG_VEL_T)
        c[C.ATT_RATE_BF_IN] = 1.0
    else:
        c[C.ATT_RATE_BF_IN] = 0.0
    c[C.YAW_RATE_CMD] = 0.0
    c[C.PIL_VEL_D] = vel[2]
    c[C.PIL_ACC_D] = 0.0
    c[C.PZ_POS_T] = pos[2]
    if from_manual:
        c[C.PZ_I] = c[C.THR_OUT] - c[C.THR_HOVER]
    _loiter_init(c, t_s, pos, vel)
    c[C.PH_WIND] = 0.0
    c[C.PH_WIND + 1] = 0.0
    state = PH_LOITER if c[C.LANDED] != 0.0 else PH_PILOT_OVERRIDE
    for k in range(2):
        c[C.PH_STATE + k] = state
        c[C.PH_PILOT + k] = 0.0
        c[C.PH_BRAKE + k] = 0.0
        c[C.PH_OUT + k] = 0.0


@inline_jit
def _loiter_init(c, t_s, pos, vel):
    """AC_Loiter::init_target: position and velocity targets from the estimate."""
    c[C.PXY_POS_T] = pos[0]
    c[C.PXY_POS_T + 1] = pos[1]
    for k in range(2):
        c[C.LOIT_VEL + k] = vel[k]
        c[C.PXY_VEL_FF + k] = vel[k]
        c[C.PXY_ACC_FF + k] = 0.0
        c[C.LOIT_ACC + k] = 0.0
    c[C.LOIT_PRED] = c[C.ATT_ROLL_T]
    c[C.LOIT_PRED + 1] = c[C.ATT_PITCH_T]
    c[C.LOIT_PRED_RATE] = 0.0
    c[C.LOIT_PRED_RATE + 1] = 0.0
    c[C.LOIT_BRK] = 0.0
    c[C.LOIT_BRK_T] = t_s


@tick_jit
def pilot_step(c, g, t_us, inputs, cos_tilt):
    """One main-loop tick of the armed vehicle in a pilot mode (c[MODE]); leaves the targets
    for the attitude controller and returns (throttle, boosted throttle, whether the attitude
    and rate controllers and the mixer are to run: False while the motors idle on the
    ground, which this function has then set)."""
    dt = g[C.G_DT]
    t_s = t_us * 1e-6
    mode = c[C.MODE]
    c[C.YAW_RATE_CMD] = yaw_rate(g, c[C.PIL_YAW])
    if mode == AP.MODE_STABILIZE:
        return _stabilize(c, g, inputs, cos_tilt)
    if mode == AP.MODE_ACRO:
        return _acro(c, g, inputs)
    climb = climb_rate(g, c[C.PIL_THR])
    c[C.PIL_CLIMB] = climb
    spooled = c[C.SUB_TIMER] >= SPOOLED_UP_S and c[C.PIL_AUTO_ARMED] != 0.0
    if c[C.PIL_TKOFF] == 0.0 and c[C.LANDED] != 0.0 and climb > 0.0 and spooled:
        c[C.PIL_TKOFF] = 1.0
        c[C.PIL_TKOFF_THR] = 0.0
    if c[C.PIL_TKOFF] == 1.0:
        return _takeoff_ground(c, g, t_us, inputs, cos_tilt, climb)
    if c[C.LANDED] != 0.0 or not spooled:
        _idle(c, g, inputs)
        return 0.0, 0.0, False
    if c[C.PIL_TKOFF] == 2.0:
        climb = _takeoff_climb(c, g, inputs.pos[2], climb)
    _climb_shaping(c, g, climb, dt)
    if mode == AP.MODE_LOITER:
        _loiter_xy(c, g, t_s, inputs, True)
    elif mode == AP.MODE_POSHOLD:
        _poshold_xy(c, g, t_us, inputs)
    else:
        _stick_lean(c, g, c[C.ALTHOLD_LEAN])
        _xy_idle(c, inputs.pos)
    thr = z_control(c, g, (inputs.pos[2], inputs.vel[2], -inputs.acc_ned[2]),
                    (c[C.LIM_THR_LO] != 0.0, c[C.LIM_THR_HI] != 0.0),
                    (g[C.G_PILOT_SPEED_UP], g[C.G_PILOT_SPEED_DN], g[C.G_PILOT_ACCEL_Z],
                     g[C.G_PILOT_POSZ_ERR_UP], g[C.G_PILOT_POSZ_ERR_DN]))
    thr, thr_b = _throttle_out(c, g, thr, cos_tilt)
    return thr, thr_b, True


@inline_jit
def _stick_lean(c, g, limit):
    """Roll and pitch commands [rad] from the sticks: each axis to ANGLE_MAX, their tilt
    within ``limit`` (A4.1)."""
    roll, pitch = lean_angles(c[C.PIL_ROLL], c[C.PIL_PITCH], g[C.G_ANGLE_MAX], limit)
    c[C.ATT_ROLL_CMD] = roll
    c[C.ATT_PITCH_CMD] = pitch


@inline_jit
def _xy_idle(c, pos):
    """The horizontal position controller at rest where the copter is (ALT_HOLD and
    STABILIZE do not run it): a mode that takes it up (LAND from the switch or a failsafe)
    starts from here, as ArduCopter initialises an inactive controller."""
    xy_reset(c, pos[0], pos[1], 0.0, 0.0)


@inline_jit
def _throttle_out(c, g, thr, cos_tilt):
    """The throttle to the mixer: recorded, the lean limit updated; returns (thr, boosted)."""
    c[C.THR_OUT] = thr
    althold_lean_update(c, g, thr)
    thr_b = angle_boost(thr, cos_tilt)
    c[C.THR_OUT_BOOSTED] = thr_b
    return thr, thr_b


@tick_jit
def pilot_mix_want(c, g):
    """Copter::update_throttle_mix in a pilot mode: STABILIZE and ACRO ATC_THR_MIX_MIN with the
    throttle stick at 0, else ATC_THR_MIX_MAN; the others ATC_THR_MIX_MAX in active flight,
    ATC_THR_MIX_MIN when landed, or descending with no large lean request, attitude error or
    acceleration."""
    if has_manual_throttle(c[C.MODE]):
        return g[C.G_THR_MIX_MIN] if c[C.PIL_THR] <= 0.0 else g[C.G_THR_MIX_MAN]
    if c[C.LANDED] != 0.0:
        return g[C.G_THR_MIX_MIN]
    lean2 = c[C.ATT_ROLL_CMD] ** 2 + c[C.ATT_PITCH_CMD] ** 2
    a_lp2 = c[C.ALP] ** 2 + c[C.ALP + 1] ** 2 + c[C.ALP + 2] ** 2
    active = (lean2 > math.radians(15.0) ** 2 or c[C.ATT_THRUST_ERR] > math.radians(30.0)
              or a_lp2 > 9.0 or c[C.PIL_VEL_D] <= 0.0)
    return g[C.G_THR_MIX_MAX] if active else g[C.G_THR_MIX_MIN]


@inline_jit
def _idle(c, g, inputs):
    """Motors at ground idle (the arming delay, landed with the stick low): targets held at
    the present attitude, position and height, integrators cleared, the throttle mix falling
    to its minimum."""
    pos, vel, q = inputs.pos, inputs.vel, inputs.q
    output_idle(c, g, g[C.G_MOT_SPIN_ARM])
    cy, sy = _heading(q)
    attitude_reset(c, 0.0, 0.0, math.atan2(sy, cy))
    rate_reset(c)
    xy_reset(c, pos[0], pos[1], 0.0, 0.0)
    z_reset(c, g, pos[2], vel[2], 0.0)
    c[C.PIL_VEL_D] = 0.0
    c[C.PIL_ACC_D] = 0.0
    c[C.THR_OUT] = 0.0
    c[C.THR_OUT_BOOSTED] = 0.0
    c[C.THR_IN_RAW] = 0.0
    _loiter_init(c, 0.0, pos, vel)
    for k in range(2):
        c[C.PH_STATE + k] = PH_PILOT_OVERRIDE
        c[C.PH_PILOT + k] = 0.0
        c[C.PH_BRAKE + k] = 0.0
        c[C.PH_WIND + k] = 0.0
    voltage_compensation(c, g, inputs.v_batt)
    throttle_mix_update(c, g, g[C.G_THR_MIX_MIN], 0.0, 0.0)
    c[C.THR_AVG_MAX] = c[C.THR_HOVER] * g[C.G_THR_MIX_MIN]


@inline_jit
def _stabilize(c, g, inputs, cos_tilt):
    """STABILIZE: lean to ANGLE_MAX from the sticks, the throttle from the stick's curve;
    ground idle while the throttle stick is at zero (or in the arming delay); the land flag
    clears once the motors leave their lower limit."""
    if c[C.PIL_THR_ZERO] != 0.0 or c[C.SUB_TIMER] < ARMING_DELAY_S:
        _idle(c, g, inputs)
        return 0.0, 0.0, False
    _stick_lean(c, g, g[C.G_ANGLE_MAX])
    _xy_idle(c, inputs.pos)
    thr = manual_throttle(g, c[C.PIL_THR], c[C.THR_HOVER])
    c[C.THR_IN_RAW] = thr
    _leave_ground(c)
    thr, thr_b = _throttle_out(c, g, thr, cos_tilt)
    return thr, thr_b, True


@inline_jit
def _leave_ground(c):
    """A manual-throttle mode clears the landed flag once the motors leave their lower
    limit."""
    if c[C.LANDED] != 0.0 and c[C.LIM_THR_LO] == 0.0:
        c[C.LANDED] = 0.0
        c[C.MAYBE_LANDED] = 0.0
        c[C.LAND_TIMER] = 0.0


@inline_jit
def _acro(c, g, inputs):
    """ACRO (mode_acro.cpp): body rates from the sticks and the trainer (:func:`acro_rates`),
    flown through the attitude target (ATT_RATE_BF_IN); the throttle from the stick's curve
    with mid-stick at ACRO_THR_MID (the hover throttle when 0), without angle boost; ground
    idle while the throttle stick is at zero (or in the arming delay)."""
    if c[C.PIL_THR_ZERO] != 0.0 or c[C.SUB_TIMER] < ARMING_DELAY_S:
        _idle(c, g, inputs)
        return 0.0, 0.0, False
    acro_rates(c, g, inputs.q)
    _xy_idle(c, inputs.pos)
    mid = g[C.G_ACRO_THR_MID]
    thr = manual_throttle(g, c[C.PIL_THR], mid if mid > 0.0 else c[C.THR_HOVER])
    c[C.THR_IN_RAW] = thr
    _leave_ground(c)
    c[C.THR_OUT] = thr
    althold_lean_update(c, g, thr)
    c[C.THR_OUT_BOOSTED] = thr
    return thr, thr, True


@tick_jit
def acro_rates(c, g, q):
    """ModeAcro::get_pilot_desired_rates -> c[ACRO_RATE_CMD..+3], body rates [rad/s]: the
    roll and pitch sticks (within a circle of 1) through ACRO_RP_EXPO to ACRO_RP_RATE, the yaw
    stick through ACRO_Y_EXPO to ACRO_Y_RATE; with ACRO_TRAINER the target's roll and pitch
    (to +-30 deg) are levelled at ACRO_BAL_ROLL / _PITCH per second, and with ACRO_TRAINER 2
    beyond ANGLE_MAX a square-root controller (gain ACRO_RP_RATE / 10 deg, ATC_ACCEL_R/P_MAX)
    pulls them back; with ACRO_TRAINER 1 the levelling fades with the largest stick and the
    vehicle's cos(pitch) (q, the EKF attitude body->NED), the sum limited per axis to
    ||stick rate| - |levelling||."""
    roll_in, pitch_in, yaw_in = c[C.PIL_ROLL], c[C.PIL_PITCH], c[C.PIL_YAW]
    n = math.sqrt(roll_in * roll_in + pitch_in * pitch_in)
    if n > 1.0:
        roll_in /= n
        pitch_in /= n
    rp = g[C.G_ACRO_RP_RATE]
    c[C.ACRO_RATE_CMD] = rp * input_expo(roll_in, g[C.G_ACRO_RP_EXPO])
    c[C.ACRO_RATE_CMD + 1] = rp * input_expo(pitch_in, g[C.G_ACRO_RP_EXPO])
    c[C.ACRO_RATE_CMD + 2] = g[C.G_ACRO_Y_RATE] * input_expo(yaw_in, g[C.G_ACRO_Y_EXPO])
    trainer = g[C.G_ACRO_TRAINER]
    if trainer == 0.0:
        return
    level_r = _trainer_level(g, 0, wrap_pi(c[C.ATT_ROLL_T]), trainer == 2.0)
    level_p = _trainer_level(g, 1, wrap_pi(c[C.ATT_PITCH_T]), trainer == 2.0)
    _euler_rate_to_ang_vel(c, level_r, level_p, 0.0, C.ACRO_LEVEL)
    if trainer == 2.0:
        for k in range(3):
            c[C.ACRO_RATE_CMD + k] += c[C.ACRO_LEVEL + k]
        return
    sp = min(max(2.0 * (q[0] * q[2] - q[3] * q[1]), -1.0), 1.0)
    mix = min(max(1.0 - max(abs(roll_in), abs(pitch_in), abs(yaw_in)), 0.0), 1.0)
    mix *= math.sqrt(1.0 - sp * sp)
    for k in range(3):
        req = c[C.ACRO_RATE_CMD + k]
        lv = c[C.ACRO_LEVEL + k] * mix
        lim = abs(abs(req) - abs(lv))
        c[C.ACRO_RATE_CMD + k] = min(max(req + lv, -lim), lim)


@inline_jit
def _trainer_level(g, k, a, limited):
    """The trainer's earth-frame rate [rad/s] for axis k (0 roll, 1 pitch) at target angle a
    [rad]: levelling, and with ``limited`` the pull back inside ANGLE_MAX."""
    rate = -min(max(a, -ACRO_LEVEL_MAX), ACRO_LEVEL_MAX) * g[C.G_ACRO_BAL + k]
    amax = g[C.G_ANGLE_MAX]
    if limited and abs(a) > amax:
        edge = amax if a > 0.0 else -amax
        rate += sqrt_ctrl(edge - a, g[C.G_ACRO_RP_RATE] / ACRO_LEVEL_MAX_OVERSHOOT,
                          g[C.G_ACCEL_MAX + k], g[C.G_DT])
    return rate


@tick_jit
def input_expo(x, expo):
    """ArduPilot's input_expo: a stick x (clamped to -1..1) through expo (none at or beyond
    0.95)."""
    x = min(max(x, -1.0), 1.0)
    if expo < EXPO_MAX:
        return (1.0 - expo) * x / (1.0 - expo * abs(x))
    return x


@inline_jit
def _euler_rate_to_ang_vel(c, droll, dpitch, dyaw, out):
    """euler_rate_to_ang_vel at the attitude target (ATT_ROLL_T, ATT_PITCH_T): euler rates
    [rad/s] -> body rates in c[out..out+3]."""
    r, p = c[C.ATT_ROLL_T], c[C.ATT_PITCH_T]
    trig = (math.sin(r), math.cos(r), math.sin(p), math.cos(p))
    c[out], c[out + 1], c[out + 2] = euler_rate_to_body(trig, droll, dpitch, dyaw)


@inline_jit
def _takeoff_ground(c, g, t_us, inputs, cos_tilt, climb):
    """The pilot takeoff while still on the ground (A9): the throttle rises from 0 to 1 over
    TKOFF_SLEW_TIME, the vertical controller restarted every tick, until the copter climbs
    (throttle at TKOFF_THR_MAX, half the climb acceleration, or the climb speed the stick
    asks for, within 10-50 % of PILOT_SPEED_UP): then airborne, landed cleared (EV
    NOT_LANDED), and with PILOT_TKOFF_ALT a climb to that height."""
    pos, vel = inputs.pos, inputs.vel
    dt = g[C.G_DT]
    thr = min(c[C.PIL_TKOFF_THR] + dt / max(g[C.G_TKOFF_SLEW], 0.01), 1.0)
    c[C.PIL_TKOFF_THR] = thr
    z_reset(c, g, pos[2], vel[2], thr)
    c[C.THR_IN_RAW] = thr
    up = g[C.G_PILOT_SPEED_UP]
    v_lift = min(max(climb, 0.1 * up), 0.5 * up)
    lifted = (thr >= min(g[C.G_TKOFF_THR_MAX], 0.9) or -inputs.acc_ned[2] >= 0.5 * (
        g[C.G_PILOT_ACCEL_Z]) or -vel[2] >= v_lift)
    if c[C.MODE] == AP.MODE_LOITER:
        _loiter_init(c, t_us * 1e-6, pos, vel)
        c[C.ATT_ROLL_CMD] = 0.0
        c[C.ATT_PITCH_CMD] = 0.0
    elif c[C.MODE] == AP.MODE_POSHOLD:
        _loiter_init(c, t_us * 1e-6, pos, vel)
        c[C.PH_STATE] = PH_PILOT_OVERRIDE
        c[C.PH_STATE + 1] = PH_PILOT_OVERRIDE
        _poshold_xy(c, g, t_us, inputs)
    else:
        _stick_lean(c, g, c[C.ALTHOLD_LEAN])
    if lifted:
        c[C.LANDED] = 0.0
        c[C.MAYBE_LANDED] = 0.0
        c[C.LAND_TIMER] = 0.0
        c[C.PIL_TKOFF] = 2.0 if g[C.G_TKOFF_ALT] > 0.0 else 0.0
        c[C.PIL_TKOFF_ALT] = pos[2] - g[C.G_TKOFF_ALT]
        c[C.PIL_VEL_D] = vel[2]
        c[C.PIL_ACC_D] = 0.0
    thr, thr_b = _throttle_out(c, g, thr, cos_tilt)
    return thr, thr_b, True


@inline_jit
def _takeoff_climb(c, g, pd, climb):
    """The airborne part of a takeoff to PILOT_TKOFF_ALT: at least the climb that reaches the
    height (square-root shaped, PSC_POSZ_P and PILOT_ACCEL_Z), the pilot's own climb if
    faster; over at 99.9 % of the height or on a descent command. Returns the climb rate."""
    if climb < 0.0:
        c[C.PIL_TKOFF] = 0.0
        return climb
    left = pd - c[C.PIL_TKOFF_ALT]  # m still to climb
    if left <= 0.001 * g[C.G_TKOFF_ALT]:
        c[C.PIL_TKOFF] = 0.0
        return climb
    need = sqrt_ctrl(left, g[C.G_POSZ_P], g[C.G_PILOT_ACCEL_Z], 0.0)
    return min(max(climb, need), g[C.G_PILOT_SPEED_UP])


@inline_jit
def _climb_shaping(c, g, climb, dt):
    """AC_PosControl's input_vel_accel_U for the pilot's climb rate [m/s, up]: the desired
    height and climb integrate the desired acceleration, which moves towards the square-root
    law's (jerk PSC_JERK_Z, acceleration PILOT_ACCEL_Z) at most PSC_JERK_Z per second; they
    become the vertical controller's targets (PZ_POS_T, PZ_VEL_FF, PZ_ACC_FF, down)."""
    a = c[C.PIL_ACC_D]
    v = c[C.PIL_VEL_D]
    c[C.PZ_POS_T] += v * dt + 0.5 * a * dt * dt
    v += a * dt
    amax = g[C.G_PILOT_ACCEL_Z]
    jerk = g[C.G_PILOT_JERK_Z]
    want = sqrt_ctrl(-climb - v, jerk / amax, jerk, dt) if amax > 0.0 else 0.0
    want = min(max(want, -amax), min(amax, ACCEL_Z_DOWN_CAP))
    a += min(max(want - a, -jerk * dt), jerk * dt)
    if climb == 0.0 and abs(v) < FLT_EPSILON_CM and abs(a) < FLT_EPSILON_CM:
        v = 0.0  # ArduPilot's float32 is_zero: the hover learning sees "no desired climb"
        a = 0.0
    c[C.PIL_VEL_D] = v
    c[C.PIL_ACC_D] = a
    c[C.PZ_VEL_FF] = v
    c[C.PZ_ACC_FF] = a


@inline_jit
def _predict_angle(c, g, k, cmd, dt):
    """AC_AttitudeControl's input-shaping predictor for roll (k 0) or pitch (k 1): the
    predicted angle moves towards cmd as the attitude target would (1/ATC_INPUT_TC, the
    axis' ATC_ACCEL_*_MAX; :func:`tlm_sim.control.attitude.shape_angle`)."""
    shape_angle(c, (C.LOIT_PRED + k, C.LOIT_PRED_RATE + k), cmd,
                (g[C.G_INPUT_TC], g[C.G_ACCEL_MAX + k], dt), False)


@inline_jit
def _loiter_xy(c, g, t_s, inputs, stick_in):
    """LOITER's horizontal step (AC_Loiter): stick -> acceleration (none without stick_in, as
    POSHOLD runs it), the predicted acceleration integrated into the desired velocity with
    drag (terminal speed LOIT_SPEED at full stick) and braking once the stick has been
    centred LOIT_BRK_DELAY; the position target moves with it and the position controller
    follows (LOIT_ACC_MAX, 2 m of error). While the land detector says "maybe landed" the
    position target decays to the estimate and the velocity integrator may not grow along the
    acceleration target (soften_for_landing)."""
    dt = g[C.G_DT]
    pos, vel, q = inputs.pos, inputs.vel, inputs.q
    cy, sy = _heading(q)
    ang = g[C.G_LOIT_ANG_MAX]
    roll, pitch = 0.0, 0.0
    if stick_in:
        roll, pitch = lean_angles(c[C.PIL_ROLL], c[C.PIL_PITCH], ang, c[C.ALTHOLD_LEAN])
    an, ae = lean_to_accel(roll, pitch, cy, sy) if (roll != 0.0 or pitch != 0.0) else (0.0, 0.0)
    c[C.LOIT_ACC] = an
    c[C.LOIT_ACC + 1] = ae
    _predict_angle(c, g, 0, roll, dt)
    _predict_angle(c, g, 1, pitch, dt)
    pan, pae = lean_to_accel(c[C.LOIT_PRED], c[C.LOIT_PRED + 1], cy, sy)
    vn = c[C.LOIT_VEL] + pan * dt
    ve = c[C.LOIT_VEL + 1] + pae * dt
    speed = math.sqrt(vn * vn + ve * ve)
    v_max = g[C.G_LOIT_SPEED]
    drag = GRAVITY_MSS * math.tan(ang) * speed / v_max
    stick = an != 0.0 or ae != 0.0
    if stick:
        c[C.LOIT_BRK_T] = t_s
    b_want = 0.0
    if not stick and t_s - c[C.LOIT_BRK_T] > g[C.G_LOIT_BRK_DELAY]:
        b_want = min(max(sqrt_ctrl(speed, 0.5 * g[C.G_VELXY_P], g[C.G_LOIT_BRK_JERK], dt), 0.0),
                     g[C.G_LOIT_BRK_ACCEL])
    jerk_dt = g[C.G_LOIT_BRK_JERK] * dt
    b = c[C.LOIT_BRK] + min(max(b_want - c[C.LOIT_BRK], -jerk_dt), jerk_dt)
    c[C.LOIT_BRK] = b
    if speed > 0.0:
        un, ue = vn / speed, ve / speed
        s_new = max(speed - (drag + b) * dt, 0.0)
        s_new = min(s_new, v_max)
        vn, ve = un * s_new, ue * s_new
        an -= b * un
        ae -= b * ue
    c[C.LOIT_VEL] = vn
    c[C.LOIT_VEL + 1] = ve
    c[C.PXY_POS_T] += vn * dt
    c[C.PXY_POS_T + 1] += ve * dt
    if c[C.MAYBE_LANDED] != 0.0:
        soften_for_landing_xy(c, pos, dt)
    c[C.PXY_VEL_FF] = vn
    c[C.PXY_VEL_FF + 1] = ve
    c[C.PXY_ACC_FF] = an
    c[C.PXY_ACC_FF + 1] = ae
    ty = c[C.ATT_YAW_T]
    xy_control(c, g, pos, vel, math.cos(ty), math.sin(ty),
               (g[C.G_LOIT_ACC_MAX], g[C.G_LOIT_ERR_MAX]))


RAD_TO_CD = 18000.0 / math.pi


@inline_jit
def _pilot_lean(c, g, k, raw, dt):
    """update_pilot_lean_angle_cd: the pilot's lean on axis k follows the stick at once when
    it reverses or exceeds 18 deg, else returns to it no faster than 1.25 % per loop or
    PHLD_BRAKE_RATE, whichever is faster."""
    f = c[C.PH_PILOT + k]
    if (f > 0.0 and raw < 0.0) or (f < 0.0 and raw > 0.0) or abs(raw) > PH_NO_SMOOTH_CD:
        f = raw
    elif f > 0.0:
        f = max(f - max(f * PH_SMOOTH, 100.0 * g[C.G_PHLD_BRAKE_RATE] * dt), raw)
    else:
        f = min(f + max(-f * PH_SMOOTH, 100.0 * g[C.G_PHLD_BRAKE_RATE] * dt), raw)
    c[C.PH_PILOT + k] = f


@inline_jit
def _brake_angle(c, g, k, v_cms, dt):
    """update_brake_angle_from_velocity: axis k's brake angle [cd] towards
    -G v (1 + 500 / (|v| + 60)) (v [cm/s] along the lean, G = (15 PHLD_BRAKE_RATE + 95) /
    100), at most PHLD_BRAKE_RATE, within PHLD_BRAKE_ANGLE."""
    rate = g[C.G_PHLD_BRAKE_RATE]
    gain = (15.0 * rate + 95.0) * 0.01
    lean = -gain * v_cms * (1.0 + 500.0 / (abs(v_cms) + 60.0))
    d = 100.0 * rate * dt
    b = c[C.PH_BRAKE + k]
    b = min(max(lean, b - d), b + d)
    lim = g[C.G_PHLD_BRAKE_ANGLE]
    c[C.PH_BRAKE + k] = min(max(b, -lim), lim)


@inline_jit
def _to_pilot(c, k, now_ms, out_cd):
    """An axis leaves a controller state for CONTROLLER_TO_PILOT_OVERRIDE, keeping its output
    out_cd for the blend."""
    c[C.PH_STATE + k] = PH_CONTROLLER_TO_PILOT
    c[C.PH_C2P_T0 + k] = now_ms
    c[C.PH_PILOT + k] = 0.0
    c[C.PH_CTRL_OUT + k] = out_cd


@inline_jit
def _mix(ratio, first, second):
    """mix_controls: ratio (clamped 0..1) of first, the rest of second."""
    r = min(max(ratio, 0.0), 1.0)
    return r * first + (1.0 - r) * second


@inline_jit
def _poshold_axis(c, g, k, target_cd, v_cms, now_ms):
    """One axis (k 0 roll, 1 pitch) of POSHOLD's per-axis states PILOT_OVERRIDE, BRAKE /
    BRAKE_READY_TO_LOITER and CONTROLLER_TO_PILOT_OVERRIDE; returns its output [cd] (the
    combined loiter states are the caller's). target_cd: the stick's lean; v_cms: the
    velocity along it [cm/s]."""
    dt = g[C.G_DT]
    rate = g[C.G_PHLD_BRAKE_RATE]
    st = c[C.PH_STATE + k]
    wind = c[C.PH_WIND_ANG + k]
    out = c[C.PH_OUT + k]
    if st == PH_PILOT_OVERRIDE:
        _pilot_lean(c, g, k, target_cd, dt)
        if target_cd == 0.0 and abs(c[C.PH_PILOT + k]) < 2.0 * rate:
            c[C.PH_STATE + k] = PH_BRAKE
            c[C.PH_BRAKE + k] = 0.0
            c[C.PH_BRAKE_PEAK + k] = 0.0
            c[C.PH_BRAKE_T0 + k] = now_ms
            c[C.PH_BRAKE_UPD + k] = 0.0
        out = c[C.PH_PILOT + k] + wind
    elif st == PH_BRAKE or st == PH_BRAKE_READY:
        _brake_angle(c, g, k, v_cms, dt)
        b = abs(c[C.PH_BRAKE + k])
        if c[C.PH_BRAKE_UPD + k] == 0.0:
            if b >= c[C.PH_BRAKE_PEAK + k]:
                c[C.PH_BRAKE_PEAK + k] = b
            else:  # the brake angle peaked: the brake time counts from now
                c[C.PH_BRAKE_T0 + k] = now_ms
                c[C.PH_BRAKE_UPD + k] = 1.0
        else:
            # 1.5 x the time to level at PHLD_BRAKE_RATE [ms], in whole ms
            timeout = float(int(min(PH_BRAKE_TIME_MAX_MS, 15.0 * c[C.PH_BRAKE_PEAK + k] / rate)))
            if abs(v_cms) <= PH_SPEED_0 and now_ms - c[C.PH_BRAKE_T0 + k] > 500.0 and (
                    timeout > 500.0):
                c[C.PH_BRAKE_T0 + k] = now_ms - timeout + 500.0
            if now_ms - c[C.PH_BRAKE_T0 + k] > timeout:
                c[C.PH_STATE + k] = PH_BRAKE_READY
        out = c[C.PH_BRAKE + k] + wind
        if target_cd != 0.0:
            _to_pilot(c, k, now_ms, out)
    elif st == PH_CONTROLLER_TO_PILOT:
        _pilot_lean(c, g, k, target_cd, dt)
        t0 = c[C.PH_C2P_T0 + k]
        if now_ms - t0 > PH_CONTROLLER_TO_PILOT_MS:
            c[C.PH_STATE + k] = PH_PILOT_OVERRIDE
        # (as coded at this firmware: the blend starts at the pilot's angle and ends at the
        # controller's, then the pilot's)
        out = _mix((now_ms - t0) / PH_CONTROLLER_TO_PILOT_MS, c[C.PH_CTRL_OUT + k],
                   c[C.PH_PILOT + k] + wind)
    return out


@inline_jit
def _wind_update(c, g, now_ms, vel):
    """update_wind_comp_estimate (in LOITER): 1.5 s after the loiter began and below 10 cm/s,
    the earth-frame wind compensation low-passes the position controller's acceleration
    target (set at once where it is 0), limited to 2/3 of ANGLE_MAX's lean."""
    if now_ms - c[C.PH_WIND_T0] < PH_WIND_DELAY_MS:
        return
    if math.sqrt(vel[0] * vel[0] + vel[1] * vel[1]) * 100.0 > PH_SPEED_0:
        return
    for k in range(2):
        a = c[C.PXY_ACC_T + k] * 100.0
        w = c[C.PH_WIND + k]
        c[C.PH_WIND + k] = a if w == 0.0 else (1.0 - PH_WIND_TC) * w + PH_WIND_TC * a
    lim = math.tan(PH_WIND_LEAN * g[C.G_ANGLE_MAX]) * GRAVITY_MSS * 100.0
    n = math.sqrt(c[C.PH_WIND] ** 2 + c[C.PH_WIND + 1] ** 2)
    if lim > 0.0 and n > lim:
        c[C.PH_WIND] *= lim / n
        c[C.PH_WIND + 1] *= lim / n


@inline_jit
def _poshold_xy(c, g, t_us, inputs):
    """POSHOLD's horizontal step (mode_poshold.cpp at this firmware): per axis the pilot's
    lean, then a brake angle against the velocity until the brake time runs out; when both
    axes are ready, a 1.5 s blend into LOITER's position hold; a stick leaves a controller
    state through a 0.5 s blend. The wind compensation learnt in LOITER is added to the
    pilot's and the brake's angles. Sets ATT_ROLL_CMD / ATT_PITCH_CMD."""
    pos, vel, q = inputs.pos, inputs.vel, inputs.q
    now_ms = float(t_us // 1000)
    cy, sy = _heading(q)
    roll_t, pitch_t = lean_angles(c[C.PIL_ROLL], c[C.PIL_PITCH], g[C.G_ANGLE_MAX],
                                  c[C.ALTHOLD_LEAN])
    tr = roll_t * RAD_TO_CD
    tp = pitch_t * RAD_TO_CD
    vn = vel[0] * 100.0
    ve = vel[1] * 100.0
    v_fw = vn * cy + ve * sy
    v_rt = -vn * sy + ve * cy
    if c[C.PH_STATE] != PH_LOITER or c[C.PH_STATE + 1] != PH_LOITER:
        wn, we = c[C.PH_WIND], c[C.PH_WIND + 1]
        g100 = GRAVITY_MSS * 100.0
        c[C.PH_WIND_ANG] = math.atan((-wn * sy + we * cy) / g100) * RAD_TO_CD
        c[C.PH_WIND_ANG + 1] = math.atan(-(wn * cy + we * sy) / g100) * RAD_TO_CD
    out_r = _poshold_axis(c, g, 0, tr, v_rt, now_ms)
    out_p = _poshold_axis(c, g, 1, tp, -v_fw, now_ms)
    if c[C.PH_STATE] == PH_BRAKE_READY and c[C.PH_STATE + 1] == PH_BRAKE_READY:
        c[C.PH_STATE] = PH_BRAKE_TO_LOITER
        c[C.PH_STATE + 1] = PH_BRAKE_TO_LOITER
        c[C.PH_B2L_T0] = now_ms
        _loiter_init(c, t_us * 1e-6, pos, vel)
        for k in range(2):
            c[C.LOIT_VEL + k] = 0.0
            c[C.PXY_VEL_FF + k] = 0.0
            c[C.LOIT_PRED + k] = 0.0
        c[C.PH_WIND_T0] = now_ms
    st = c[C.PH_STATE]
    if st == PH_BRAKE_TO_LOITER or st == PH_LOITER:
        c[C.PH_STATE + 1] = st
        _loiter_xy(c, g, t_us * 1e-6, inputs, False)
        loit_r = c[C.ATT_ROLL_CMD] * RAD_TO_CD
        loit_p = c[C.ATT_PITCH_CMD] * RAD_TO_CD
        if st == PH_BRAKE_TO_LOITER:
            t0 = c[C.PH_B2L_T0]
            if now_ms - t0 > PH_BRAKE_TO_LOITER_MS:
                c[C.PH_STATE] = PH_LOITER
                c[C.PH_STATE + 1] = PH_LOITER
            ratio = (now_ms - t0) / PH_BRAKE_TO_LOITER_MS
            _brake_angle(c, g, 0, v_rt, g[C.G_DT])
            _brake_angle(c, g, 1, -v_fw, g[C.G_DT])
            # (as coded: the blend starts at the loiter's angle and ends at the brake's)
            out_r = _mix(ratio, c[C.PH_BRAKE] + c[C.PH_WIND_ANG], loit_r)
            out_p = _mix(ratio, c[C.PH_BRAKE + 1] + c[C.PH_WIND_ANG + 1], loit_p)
        else:
            out_r = loit_r
            out_p = loit_p
            _wind_update(c, g, now_ms, vel)
        loiter = st == PH_LOITER
        if tr != 0.0:
            _to_pilot(c, 0, now_ms, out_r)
            c[C.PH_STATE + 1] = PH_BRAKE_READY
            if loiter:
                c[C.PH_BRAKE + 1] = 0.0
        if tp != 0.0:
            _to_pilot(c, 1, now_ms, out_p)
            if tr == 0.0:
                c[C.PH_STATE] = PH_BRAKE_READY
                if loiter:
                    c[C.PH_BRAKE] = 0.0
    c[C.PH_OUT] = out_r
    c[C.PH_OUT + 1] = out_p
    lim = g[C.G_ANGLE_MAX] * RAD_TO_CD
    c[C.ATT_ROLL_CMD] = min(max(out_r, -lim), lim) / RAD_TO_CD
    c[C.ATT_PITCH_CMD] = min(max(out_p, -lim), lim) / RAD_TO_CD


@tick_jit
def log_land_complete(c, t_us, was_landed, ev):
    """EV LAND_COMPLETE when the land detector has just set the landed flag."""
    if c[C.LANDED] != 0.0 and not was_landed:
        E.log_ev(ev, t_us, AP.EV_LAND_COMPLETE)
