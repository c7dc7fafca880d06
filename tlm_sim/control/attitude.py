"""ArduCopter-style attitude and rate control (AC_AttitudeControl structure, our implementation).

Angle targets are shaped with a square-root controller (gain 1/ATC_INPUT_TC, acceleration limits
ATC_ACCEL_*_MAX; the heading with the commanded heading rate as feed-forward), the attitude error
between the shaped target and the EKF attitude is turned into body-rate targets by a square-root
controller (ATC_ANG_*_P) plus rate feed-forward, and per-axis rate PIDs (ATC_RAT_*) produce
roll/pitch/yaw outputs in motor units (+-1).
"""

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.control import layout as C
from tlm_sim.rotation import quat_mul_normalised, quat_to_euler, rotation_half_angle


@tick_jit
def sqrt_ctrl(error, p, accel_max, dt):
    """Square-root controller: linear (p*e) near zero, sqrt(2*a*|e|) far out; output limited to
    |e|/dt so it never overshoots within one step. accel_max <= 0 gives a pure P controller."""
    if accel_max <= 0.0:
        out = p * error
    elif p == 0.0:
        out = math.copysign(math.sqrt(2.0 * accel_max * abs(error)), error)
    else:
        lin = accel_max / (p * p)
        if abs(error) <= lin:
            out = p * error
        else:
            out = math.copysign(math.sqrt(2.0 * accel_max * (abs(error) - 0.5 * lin)), error)
    if dt > 0.0:
        lim = abs(error) / dt
        if out > lim:
            out = lim
        elif out < -lim:
            out = -lim
    return out


@tick_jit
def wrap_pi(a):
    """Wrap an angle to [-pi, pi) (fast path for angles already within one turn)."""
    if -math.pi <= a < math.pi:
        return a
    if -3.0 * math.pi <= a < 3.0 * math.pi:
        return a - 2.0 * math.pi if a >= math.pi else a + 2.0 * math.pi
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@tick_jit
def shape_angle(c, slots, cmd, shaping, wrap):
    """Move a target angle (slots: its and its rate's slots of c) towards cmd with a
    square-root rate demand and an accel limit (shaping: time constant, accel limit, dt)."""
    angle_i, rate_i = slots
    tc, accel_max, dt = shaping
    err = cmd - c[angle_i]
    if wrap:
        err = wrap_pi(err)
    want = sqrt_ctrl(err, 1.0 / tc, accel_max, dt)
    r = c[rate_i]
    dv = accel_max * dt
    if dv <= 0.0:
        pass  # no acceleration limit
    elif want > r + dv:
        want = r + dv
    elif want < r - dv:
        want = r - dv
    c[rate_i] = want
    a = c[angle_i] + want * dt
    c[angle_i] = wrap_pi(a) if wrap else a


@tick_jit
def attitude_reset(c, roll, pitch, yaw):
    """Set the attitude targets to the given euler angles [rad] with zero target rates."""
    _set_targets(c, roll, pitch, yaw)
    c[C.ATT_ROLL_RATE_T] = 0.0
    c[C.ATT_PITCH_RATE_T] = 0.0
    c[C.ATT_YAW_RATE_T] = 0.0
    c[C.ATT_ANG_VEL_T] = 0.0
    c[C.ATT_ANG_VEL_T + 1] = 0.0
    c[C.ATT_ANG_VEL_T + 2] = 0.0


@inline_jit
def _set_targets(c, roll, pitch, yaw):
    """The euler targets and commands [rad] at once (the shaping starts from rest there)."""
    c[C.ATT_ROLL_T] = roll
    c[C.ATT_PITCH_T] = pitch
    c[C.ATT_YAW_T] = yaw
    c[C.ATT_ROLL_CMD] = roll
    c[C.ATT_PITCH_CMD] = pitch
    c[C.ATT_YAW_CMD] = yaw


#: thrust-vector error beyond which the feed-forward fades out and yaw is left alone [rad]
#: (AC_AttitudeControl's AC_ATTITUDE_THRUST_ERROR_ANGLE, 30 deg)
THRUST_ERROR_ANGLE = math.radians(30.0)


@tick_jit
def attitude_update(c, g, q, gyro, body_rate_out):
    """Shape the commanded angles (ATT_*_CMD) and compute body-rate targets [rad/s].

    q: EKF attitude quaternion body->NED (w, x, y, z); gyro: body rates [rad/s]. Writes
    body_rate_out[0:3]. The attitude error is split into a tilt of the thrust axis and a heading
    error about it (limited to G_YAW_ERR_MAX, the target heading dragged along beyond that), as
    AC_AttitudeControl does. When the thrust vector is more than 30 deg off its target the
    feed-forward fades out and the yaw-rate target blends into the measured yaw rate, fully
    at 60 deg (ArduCopter recovers the thrust direction first: a copter tumbling after a motor
    loss does not also fight its heading).
    """
    dt = g[C.G_DT]
    if c[C.ATT_RATE_BF_IN] != 0.0:
        _shape_rate_bf(c, g, dt)
    else:
        _shape_angles(c, g, dt)

    # target quaternion from euler (ZYX)
    cr = math.cos(0.5 * c[C.ATT_ROLL_T])
    sr = math.sin(0.5 * c[C.ATT_ROLL_T])
    cp = math.cos(0.5 * c[C.ATT_PITCH_T])
    sp = math.sin(0.5 * c[C.ATT_PITCH_T])
    cy = math.cos(0.5 * c[C.ATT_YAW_T])
    sy = math.sin(0.5 * c[C.ATT_YAW_T])
    tw, tx, ty, tz = _euler_quat(sr, cr, sp, cp, sy, cy)
    # error rotation in the body frame: q_err = q^-1 * q_target
    qw, qx, qy, qz = q[0], -q[1], -q[2], -q[3]
    ew = qw * tw - qx * tx - qy * ty - qz * tz
    ex = qw * tx + qx * tw + qy * tz - qz * ty
    ey = qw * ty - qx * tz + qy * tw + qz * tx
    ez = qw * tz + qx * ty - qy * tx + qz * tw
    if ew < 0.0:
        ew, ex, ey, ez = -ew, -ex, -ey, -ez
    # split the error as ArduCopter does: first the rotation that tilts the body's thrust axis
    # (z) onto the target's (about an axis in the body x-y plane), then the remaining rotation
    # about the thrust axis (the heading error)
    zx = 2.0 * (ex * ez + ew * ey)  # target z axis in the body frame
    zy = 2.0 * (ey * ez - ew * ex)
    zz = min(max(1.0 - 2.0 * (ex * ex + ey * ey), -1.0), 1.0)
    # half-angle sine and cosine of the thrust-vector error angle te
    sh = math.sqrt(0.5 * (1.0 - zz))
    ch = math.sqrt(0.5 * (1.0 + zz))
    if sh < 0.05:  # te = 2 asin(sh), series exact to double precision here
        s2 = sh * sh
        te = 2.0 * sh * (1.0 + s2 * (1.0 / 6.0 + s2 * (3.0 / 40.0 + s2 * 5.0 / 112.0)))
    else:
        te = 2.0 * math.asin(min(sh, 1.0))
    c[C.ATT_THRUST_ERR] = te
    sxy = math.sqrt(zx * zx + zy * zy)
    if sxy > 1e-12:
        ax = -zy / sxy
        ay = zx / sxy
    else:
        ax = 1.0
        ay = 0.0
    e0 = ax * te
    e1 = ay * te
    hw = ch * ew + sh * (ax * ex + ay * ey)
    hz = ch * ez - sh * (ax * ey - ay * ex)
    if hw > 0.0 and abs(hz) < 0.05 * hw:  # 2 atan(hz / hw), series
        r = hz / hw
        r2 = r * r
        e2 = 2.0 * r * (1.0 - r2 * (1.0 / 3.0 - r2 * (0.2 - r2 / 7.0)))
    else:
        e2 = wrap_pi(2.0 * math.atan2(hz, hw))
    # a heading error beyond what saturates the yaw-rate loop drags the target along
    hmax = g[C.G_YAW_ERR_MAX]
    dy = c[C.ATT_YAW_RATE_T]
    dy_axis = 0.0
    if e2 > hmax or e2 < -hmax:
        lim = hmax if e2 > 0.0 else -hmax
        c[C.ATT_YAW_T] = wrap_pi(c[C.ATT_YAW_T] - (e2 - lim))
        _keep_thrust_direction(c, e2 - lim)
        # the heading rate the limit takes back stays in the feed-forward, but about the
        # thrust axis (AC_AttitudeControl's thrust vector + heading target: the heading
        # turns about the thrust axis, the thrust direction does not move with it)
        dy_axis = min(max((e2 - lim) / dt, min(dy, 0.0)), max(dy, 0.0))
        e2 = lim
        # the error rotation to the moved target: the tilt, then e2 about the thrust axis
        hc = math.cos(0.5 * e2)
        hs = math.sin(0.5 * e2)
        ew = ch * hc
        ex = sh * (ax * hc + ay * hs)
        ey = sh * (ay * hc - ax * hs)
        ez = ch * hs
    ff = _feed_forward(c, (sr, cr, sp, cp), dy - dy_axis, dy_axis, (ew, ex, ey, ez))
    r0 = sqrt_ctrl(e0, g[C.G_ANG_P], g[C.G_ANG_ACCEL], dt)
    r1 = sqrt_ctrl(e1, g[C.G_ANG_P + 1], g[C.G_ANG_ACCEL + 1], dt)
    r2 = sqrt_ctrl(e2, g[C.G_ANG_P + 2], g[C.G_ANG_ACCEL + 2], dt)
    _rate_targets(body_rate_out, te, (r0, r1, r2), ff, gyro[2])


@inline_jit
def _keep_thrust_direction(c, shift):
    """Re-express the roll and pitch targets (and their shaped rates) about a heading target
    that was just turned back by ``shift`` [rad], so that the target's thrust direction stays
    where it was in the earth frame.

    AC_AttitudeControl::thrust_heading_rotation_angles limits the heading error by resetting
    the target quaternion to the body attitude x the thrust-vector correction x the limited
    heading correction: the target keeps its thrust direction, only its heading moves. tlm's
    target is euler (roll and pitch about the heading target), so turning the heading alone
    would turn the tilt with it. It matters when the copter tumbles after a motor loss: the
    heading target is then dragged round at the yaw rate (hundreds of deg/s) and the lean
    direction would spin with it (engine_s14.bin: with it, tlm's desired roll, pitch and yaw
    follow SITL's through the fall, and the copter lands with SITL's heading)."""
    cs = math.cos(shift)
    sn = math.sin(shift)
    r = c[C.ATT_ROLL_T]
    p = c[C.ATT_PITCH_T]
    # the target z axis in the old heading frame (ZYX euler), turned into the new one
    zx = math.sin(p) * math.cos(r)
    zy = -math.sin(r)
    zz = math.cos(p) * math.cos(r)
    hx = cs * zx - sn * zy
    hy = sn * zx + cs * zy
    c[C.ATT_ROLL_T] = -math.asin(min(max(hy, -1.0), 1.0))
    c[C.ATT_PITCH_T] = math.atan2(hx, zz)
    # the shaped tilt rates turn with the tilt (pitch ~ x, -roll ~ y of the heading frame)
    dp = c[C.ATT_PITCH_RATE_T]
    dr = c[C.ATT_ROLL_RATE_T]
    c[C.ATT_PITCH_RATE_T] = cs * dp + sn * dr
    c[C.ATT_ROLL_RATE_T] = cs * dr - sn * dp


@inline_jit
def _feed_forward(c, half_angles, dye, dy_axis, q_err):
    """Rate feed-forward in the body frame [rad/s]: the target's euler rates (roll, pitch and
    the heading rate dye that turns the euler heading target) as an angular velocity in the
    target frame, plus dy_axis about the target's thrust axis, rotated into the body frame by
    the error rotation q_err = (ew, ex, ey, ez) (AC_AttitudeControl's rotation_target_to_body:
    it matters when the copter is far off its target). half_angles: (sr, cr, sp, cp), the sines
    and cosines of half the target roll and pitch."""
    sr, cr, sp, cp = half_angles
    ew, ex, ey, ez = q_err
    sin_r = 2.0 * sr * cr
    cos_r = cr * cr - sr * sr
    sin_p = 2.0 * sp * cp
    cos_p = cp * cp - sp * sp
    v0, v1, v2 = euler_rate_to_body((sin_r, cos_r, sin_p, cos_p), c[C.ATT_ROLL_RATE_T],
                                    c[C.ATT_PITCH_RATE_T], dye)
    return _rotate(ew, ex, ey, ez, v0, v1, v2 + dy_axis)


@inline_jit
def euler_rate_to_body(trig, droll, dpitch, dyaw):
    """AC_AttitudeControl::euler_rate_to_ang_vel: 321 euler rates [rad/s] -> the angular
    velocity in the frame of the attitude whose roll and pitch have the sines and cosines
    ``trig`` = (sin_r, cos_r, sin_p, cos_p)."""
    sin_r, cos_r, sin_p, cos_p = trig
    return (droll - sin_p * dyaw, cos_r * dpitch + sin_r * cos_p * dyaw,
            -sin_r * dpitch + cos_r * cos_p * dyaw)


@inline_jit
def _euler_quat(sr, cr, sp, cp, sy, cy):
    """The ZYX (321) quaternion of the euler angles whose halves have the sines and cosines
    (sr, cr), (sp, cp), (sy, cy)."""
    return (cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy)


@inline_jit
def _rotate(qw, qx, qy, qz, vx, vy, vz):
    """The vector v rotated by the unit quaternion q (q v q*)."""
    tx = 2.0 * (qy * vz - qz * vy)
    ty = 2.0 * (qz * vx - qx * vz)
    tz = 2.0 * (qx * vy - qy * vx)
    return (vx + qw * tx + qy * tz - qz * ty, vy + qw * ty + qz * tx - qx * tz,
            vz + qw * tz + qx * ty - qy * tx)


@inline_jit
def _shape_yaw(c, g, tc, dt):
    """The heading target moves towards the command with its rate (YAW_RATE_CMD) as
    feed-forward, slew-limited (G_SLEW_YAW) and acceleration-limited; tc: input time constant
    [s], dt [s]. With a rate input (ATT_YAW_RATE_IN, the pilot's yaw stick) the heading rate
    follows YAW_RATE_CMD instead: :func:`_shape_yaw_rate`."""
    if c[C.ATT_YAW_RATE_IN] != 0.0:
        _shape_yaw_rate(c, g, dt)
        return
    yerr = wrap_pi(c[C.ATT_YAW_CMD] - c[C.ATT_YAW_T])
    yrate = c[C.YAW_RATE_CMD] + sqrt_ctrl(yerr, 1.0 / tc, g[C.G_ACCEL_MAX + 2], dt)
    smax = g[C.G_SLEW_YAW]
    yrate = min(max(yrate, -smax), smax)
    yr0 = c[C.ATT_YAW_RATE_T]
    dv = g[C.G_ACCEL_MAX + 2] * dt
    if dv > 0.0:
        yrate = min(max(yrate, yr0 - dv), yr0 + dv)
    c[C.ATT_YAW_RATE_T] = yrate
    c[C.ATT_YAW_T] = wrap_pi(c[C.ATT_YAW_T] + yrate * dt)


@inline_jit
def _shape_yaw_rate(c, g, dt):
    """AC_AttitudeControl's input_shaping_ang_vel for the heading: the heading rate moves
    towards the commanded rate YAW_RATE_CMD [rad/s] (through a first-order lag of
    PILOT_Y_RATE_TC when set) at most ATC_ACCEL_Y_MAX per second, no slew limit; the
    heading command follows the target."""
    want = c[C.YAW_RATE_CMD]
    r0 = c[C.ATT_YAW_RATE_T]
    tc = g[C.G_PILOT_Y_TC]
    if tc > 0.0:
        want = r0 + (want - r0) * min(dt / tc, 1.0)
    dv = g[C.G_ACCEL_MAX + 2] * dt
    if dv > 0.0:
        want = min(max(want, r0 - dv), r0 + dv)
    c[C.ATT_YAW_RATE_T] = want
    c[C.ATT_YAW_T] = wrap_pi(c[C.ATT_YAW_T] + want * dt)
    c[C.ATT_YAW_CMD] = c[C.ATT_YAW_T]


@inline_jit
def _shape_angles(c, g, dt):
    """The angle targets move towards the commanded angles (ATT_*_CMD) through the input
    shaping (ATC_INPUT_TC, ATC_ACCEL_*_MAX); the heading as :func:`_shape_yaw`."""
    tc = g[C.G_INPUT_TC]
    amax = g[C.G_ACCEL_MAX]
    shape_angle(c, (C.ATT_ROLL_T, C.ATT_ROLL_RATE_T), c[C.ATT_ROLL_CMD], (tc, amax, dt), False)
    amax = g[C.G_ACCEL_MAX + 1]
    shape_angle(c, (C.ATT_PITCH_T, C.ATT_PITCH_RATE_T), c[C.ATT_PITCH_CMD], (tc, amax, dt), False)
    _shape_yaw(c, g, tc, dt)


@inline_jit
def _shape_rate_bf(c, g, dt):
    """AC_AttitudeControl::input_rate_bf_roll_pitch_yaw (ACRO, rate feed-forward on): the
    attitude target turns by the shaped body rates ATT_ANG_VEL_T over dt, then those move
    towards the commanded ACRO_RATE_CMD [rad/s] (input_shaping_ang_vel: a first-order lag of
    ACRO_RP_RATE_TC / ACRO_Y_RATE_TC when set, then at most ATC_ACCEL_*_MAX per second). The
    euler targets and their rates follow, so that an angle mode switched to next starts from
    them (the rates stay as they were where the target pitch is within 0.06 deg of
    vertical, as ang_vel_to_euler_rate gives up there)."""
    r, p, y = c[C.ATT_ROLL_T], c[C.ATT_PITCH_T], c[C.ATT_YAW_T]
    cr, sr = math.cos(0.5 * r), math.sin(0.5 * r)
    cp, sp = math.cos(0.5 * p), math.sin(0.5 * p)
    cy, sy = math.cos(0.5 * y), math.sin(0.5 * y)
    q = _euler_quat(sr, cr, sp, cp, sy, cy)
    w0, w1, w2 = c[C.ATT_ANG_VEL_T], c[C.ATT_ANG_VEL_T + 1], c[C.ATT_ANG_VEL_T + 2]
    h, k = rotation_half_angle(w0, w1, w2, dt)
    qw, qx, qy, qz = quat_mul_normalised(q, (h, k * w0, k * w1, k * w2))
    r, p, y = quat_to_euler(qw, qx, qy, qz)
    for i in range(3):
        want = c[C.ACRO_RATE_CMD + i]
        w = c[C.ATT_ANG_VEL_T + i]
        tc = g[C.G_ACRO_TC + i]
        if tc > 0.0:
            want = w + sqrt_ctrl(want - w, 1.0 / max(tc, 0.01), 0.0, dt) * dt
        dv = g[C.G_ACCEL_MAX + i] * dt
        if dv > 0.0:
            want = min(max(want, w - dv), w + dv)
        c[C.ATT_ANG_VEL_T + i] = want
    w0, w1, w2 = c[C.ATT_ANG_VEL_T], c[C.ATT_ANG_VEL_T + 1], c[C.ATT_ANG_VEL_T + 2]
    _set_targets(c, r, p, y)
    cos_p = math.cos(p)
    if abs(cos_p) > 1e-3:  # ang_vel_to_euler_rate
        sin_r, cos_r = math.sin(r), math.cos(r)
        c[C.ATT_ROLL_RATE_T] = w0 + (sin_r * w1 + cos_r * w2) * math.tan(p)
        c[C.ATT_PITCH_RATE_T] = cos_r * w1 - sin_r * w2
        c[C.ATT_YAW_RATE_T] = (sin_r * w1 + cos_r * w2) / cos_p


@inline_jit
def _rate_targets(body_rate_out, te, rates, ff, gyro_z):
    """Body-rate targets [rad/s] from the angle controllers' rates (r0, r1, r2) and the
    feed-forward ff (ff0, ff1, ff2): the feed-forward fades out while the thrust-vector error
    te [rad] is beyond THRUST_ERROR_ANGLE, the yaw target blending into the measured yaw rate
    gyro_z."""
    r0, r1, r2 = rates
    ff0, ff1, ff2 = ff
    if te <= THRUST_ERROR_ANGLE:
        body_rate_out[0] = r0 + ff0
        body_rate_out[1] = r1 + ff1
        body_rate_out[2] = r2 + ff2
    elif te > 2.0 * THRUST_ERROR_ANGLE:
        body_rate_out[0] = r0
        body_rate_out[1] = r1
        body_rate_out[2] = gyro_z
    else:
        k = 1.0 - (te - THRUST_ERROR_ANGLE) / THRUST_ERROR_ANGLE
        body_rate_out[0] = r0 + ff0 * k
        body_rate_out[1] = r1 + ff1 * k
        body_rate_out[2] = gyro_z * (1.0 - k) + (r2 + ff2) * k


@tick_jit
def rate_pid(c, g, axis, target, meas, limited):
    """One AC_PID step for a body axis (0 roll, 1 pitch, 2 yaw); returns the output (+-1 units).

    target and meas in rad/s; limited: the mixer saturated this axis (integrator may only shrink).
    """
    b = C.RATE_BASE + axis * C.RATE_STRIDE
    dt = g[C.G_DT]
    c[b + C.R_TARGET] = target
    c[b + C.R_MEAS] = meas
    c[b + C.R_TF] += g[C.G_RAT_FLTT + axis] * (target - c[b + C.R_TF])
    err = c[b + C.R_TF] - meas
    ef_prev = c[b + C.R_EF]
    c[b + C.R_EF] += g[C.G_RAT_FLTE + axis] * (err - c[b + C.R_EF])
    ef = c[b + C.R_EF]
    d = (ef - ef_prev) / dt
    c[b + C.R_DF] += g[C.G_RAT_FLTD + axis] * (d - c[b + C.R_DF])
    i_new = c[b + C.R_I] + g[C.G_RAT_I + axis] * ef * dt
    imax = g[C.G_RAT_IMAX + axis]
    i_new = min(max(i_new, -imax), imax)
    if not limited or abs(i_new) < abs(c[b + C.R_I]):
        c[b + C.R_I] = i_new
    out = (
        g[C.G_RAT_P + axis] * ef
        + g[C.G_RAT_D + axis] * c[b + C.R_DF]
        + c[b + C.R_I]
        + g[C.G_RAT_FF + axis] * c[b + C.R_TF]
    )
    c[b + C.R_OUT] = out
    return out


@tick_jit
def rate_reset(c):
    """Zero the rate PIDs (on arming / disarmed)."""
    for k in range(3 * C.RATE_STRIDE):
        c[C.RATE_BASE + k] = 0.0


#: throttle vs attitude priority: slew up and down per second, and its range
#: (AC_AttitudeControl_Multi::update_throttle_rpy_mix, AC_ATTITUDE_CONTROL_MAX)
THR_MIX_UP = 2.0
THR_MIX_DOWN = 0.5
THR_MIX_LO = 0.1
THR_MIX_HI = 5.0


@tick_jit
def throttle_mix_update(c, g, want, thr_in, thr_unboosted):
    """Slew the throttle vs attitude priority THR_RPY_MIX towards want (ATC_THR_MIX_MAX in
    the land detector's "active flight", else ATC_THR_MIX_MIN; ATC_THR_MIX_MAN in a
    manual-throttle mode with the stick up: Copter::update_throttle_mix), up at
    THR_MIX_UP and down at THR_MIX_DOWN per second; going down it drops at once to the mix
    the mixer actually used (the throttle it placed, MOT_THR_OUT, against thr_in, the throttle
    demand 0..1, and the hover throttle), as AC_AttitudeControl_Multi does each rate-loop
    tick. Then the highest average throttle the mixer may raise the motors to, THR_AVG_MAX:
    the higher of thr_in and thr_unboosted (the demand before angle boost), or its blend with
    the hover throttle by the mix if higher (set_throttle_out, get_throttle_avg_max)."""
    dt = g[C.G_DT]
    m = c[C.THR_RPY_MIX]
    hover = c[C.THR_HOVER]
    if m < want:
        m += min(THR_MIX_UP * dt, want - m)
    elif m > want:
        m -= min(THR_MIX_DOWN * dt, m - want)
        out = max(c[C.MOT_THR_OUT], thr_in)
        if out < hover:
            used = (out - thr_in) / (hover - thr_in)
        else:
            used = out / hover
        m = min(m, max(used, want))
    m = min(max(m, THR_MIX_LO), THR_MIX_HI)
    c[C.THR_RPY_MIX] = m
    t = min(max(max(thr_in, thr_unboosted), 0.0), 1.0)
    c[C.THR_AVG_MAX] = max(t, t * max(0.0, 1.0 - m) + hover * m)

