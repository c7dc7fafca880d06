"""Multicopter motor mixer with thrust linearisation (AP_MotorsMatrix structure, our
implementation). The frame's motor matrix (roll, pitch and yaw factor per motor, largest
magnitude 0.5) is configuration: G_N_MOTORS and G_MIX_ROLL/PITCH/YAW, from
:mod:`tlm_sim.frames` by FRAME_CLASS / FRAME_TYPE.

Roll/pitch/yaw demands (+-1 motor units) and throttle (0..1 thrust fraction) are compensated for
battery voltage (1/lift_max, from the battery monitor's resting-voltage estimate) and air density
(1/(rho/1.225), AP_MOTORS_DENSITY_COMP), mixed with roll/pitch priority over yaw (yaw limited to
the headroom, at least MOT_YAW_HEADROOM), the throttle placed for best attitude authority, then
each motor's thrust fraction is linearised through MOT_THST_EXPO into an actuator value and a
whole-microsecond PWM. The throttle may be lifted above the demand to keep the lowest motor at
0 only up to THR_AVG_MAX, the attitude controller's average maximum (ATC_THR_MIX_MIN/MAX, see
:func:`tlm_sim.control.attitude.throttle_mix_update`); beyond it the roll/pitch/yaw demand is
scaled down (AP_MotorsMatrix's rpy_scale).

Motor loss (AP_MotorsMatrix::check_for_failed_motor and the thrust boost, ArduCopter 4.7):

* After each mix :func:`motor_loss_monitor` low-passes every motor's output before the 0..1
  clip (0.5 s time constant), names the highest the lost motor (MOTOR_LOST, held while the
  thrust boost is on) and finds the thrust unbalanced when that output x n / the sum reaches
  1.5, balanced again at 1.25 or below -- on frames of six or more motors only.
* The thrust-loss check (:func:`tlm_sim.control.failsafe.thrust_loss_check`: 1 s at full
  throttle, descending, level) turns the boost on: ERR 25/1 and "Potential Thrust Loss (n)".
  While boosted and unbalanced THRUST_BOOST_RATIO ramps to 1 over MOT_SPOOL_TIME
  (:func:`boost_ratio_update`); by that ratio the lost motor is left out of the top of the
  range (roll/pitch scaling and the throttle ceiling: it may go past full output and is
  clipped), its yaw room no longer limits yaw and the yaw floor rises from MOT_YAW_HEADROOM to
  0.5. The boost goes off once the highest filtered output is below 0.9, the thrust balanced
  and the throttle below its maximum.
* A quad is never unbalanced, so its ratio stays 0: the boost holds the thrust-loss check off,
  and in the mix the lost motor's room in the direction the yaw demand moves it limits yaw
  after the MOT_YAW_HEADROOM floor (as ArduCopter's order of the two; typically no yaw that
  would raise the saturated motor further). Nothing else changes.

Measured on built-in mission 1 (seed 0, motor n dead from 120 to 150 s in AUTO, cruise at
20 m): with ArduCopter's hex settings (ATC_RAT_RLL_IMAX = ATC_RAT_PIT_IMAX = 1.0, MOT_YAW_HEADROOM
0) a hexa (+ or X) descends 6.6-6.8 m in the 2.9-3.4 s before the detection, then holds its
height (within 0.7 m) and track (error at most 1.8-7.4 m), turns 56-91 deg away from its
heading and holds the new one, keeps AUTO and finishes the mission; with the default IMAX 0.5
the integrator cannot hold the ~0.75 pitch (roll) output the mix needs and the crash check
disarms it in the air 15.6 s (+) / 20.6 s (X) after the loss. An octa (+) never saturates (no
ERR 25, 0.7 m dip); a quad falls within 3 s. tests/test_frames_motor_loss.py.
"""

import math

from tlm_sim._jit import tick_jit
from tlm_sim.control import layout as C

MOT_SPOOL_TIME_S = 0.5  # MOT_SPOOL_TIME (default; the parameter is not modelled)
MOTOR_FILT_TC_S = 0.5  # time constant of the motor-loss monitor's output filter
MOTOR_LOSS_MIN_MOTORS = 6  # frames with fewer motors never report an unbalanced thrust
MOTOR_LOST_BALANCE = 1.5  # highest filtered output x n / sum: unbalanced at or above
MOTOR_LOST_REBALANCE = 1.25  # ... balanced again at or below
THRUST_BOOST_OFF = 0.9  # the boost goes off once the highest filtered output is below this


@tick_jit
def lift_max(g, v_batt):
    """Voltage compensation: (ratio, lift_max) with ratio = clamp(V, MIN, MAX)/MAX."""
    vmax = g[C.G_MOT_BAT_MAX]
    vmin = g[C.G_MOT_BAT_MIN]
    if vmax <= 0.0 or vmin <= 0.0 or v_batt <= 0.0:
        return 1.0, 1.0
    ratio = min(max(v_batt, vmin), vmax) / vmax
    e = g[C.G_MOT_EXPO]
    return ratio, ratio * (1.0 - e) + e * ratio * ratio


@tick_jit
def thrust_to_actuator(g, thrust, ratio, lift):
    """Thrust fraction 0..1 -> actuator 0..1 (thrust curve + voltage scaling + spin limits)."""
    e = g[C.G_MOT_EXPO]
    t = min(max(thrust, 0.0), 1.0) * lift
    if e > 0.0:
        a = ((e - 1.0) + math.sqrt((1.0 - e) * (1.0 - e) + 4.0 * e * t)) / (2.0 * e)
    else:
        a = t
    a = min(a / ratio, 1.0)
    return g[C.G_MOT_SPIN_MIN] + (g[C.G_MOT_SPIN_MAX] - g[C.G_MOT_SPIN_MIN]) * a


@tick_jit
def density_gain(c):
    """Air-density compensation gain 1/rho_ratio of the motor outputs (AP_Motors thrust
    linearisation: the ratio is used while within 0.3..1.5, clamped to 0.5..1.25; 1 when no
    ratio is set). It is why SITL hovers at ThO 0.363 where the frame's hover thrust is 0.39:
    at CMAC (604 m AMSL in flight) rho/1.225 = 0.943."""
    r = c[C.AIR_RHO_RATIO]
    if r <= 0.3 or r >= 1.5:
        return 1.0
    return 1.0 / min(max(r, 0.5), 1.25)


@tick_jit
def resting_voltage_estimate(c, g, v_batt):
    """The battery monitor's resting-voltage estimate [V]: the voltage plus the sag it infers
    from the current, modelled as G_BATT_SAG_HOVER (TLM_BATT_SAG_HOV) times the mean motor
    thrust fraction over MOT_THST_HOVER (the current follows the thrust), plus what the
    monitor's resistance estimate has learnt beyond its start value (I (R - R0): zero while
    the voltage holds, see tlm_sim.control.battery)."""
    extra = c[C.BM_CURR] * (c[C.BM_RES] - g[C.G_BATT_RES0]) if c[C.BM_VREF] > 0.0 else 0.0
    v = v_batt + extra
    sag = g[C.G_BATT_SAG_HOVER]
    hover = c[C.THR_HOVER]
    if sag == 0.0 or hover <= 0.0:
        return v
    n = int(g[C.G_N_MOTORS])
    t = 0.0
    for i in range(n):
        t += c[C.MIX_THRUST + i]
    return v + sag * (t / n) / hover


@tick_jit
def voltage_compensation(c, g, v_batt):
    """The motors' voltage compensation of this tick (AP_Motors' update_lift_max_from_batt_
    voltage, which ArduCopter runs every loop, armed or not): (ratio, lift_max) of the battery
    monitor's resting-voltage estimate, also kept in c[MOT_BATT_RATIO], c[MOT_LIFT_MAX] (MOTB).
    tlm applies the ratio unfiltered (ArduPilot low-passes it at 0.5 Hz)."""
    ratio, lift = lift_max(g, resting_voltage_estimate(c, g, v_batt))
    c[C.MOT_BATT_RATIO] = ratio
    c[C.MOT_LIFT_MAX] = lift
    return ratio, lift


@tick_jit
def boost_ratio_update(c, g):
    """The motors' spool logic for a lost motor (AP_MotorsMulticopter::output_logic, throttle
    unlimited), once per tick before the mix: THRUST_BOOST_RATIO ramps towards 1 at
    1/MOT_SPOOL_TIME per second while the thrust boost is on and the monitor finds the thrust
    unbalanced, and back towards 0 otherwise."""
    step = g[C.G_DT] / MOT_SPOOL_TIME_S
    r = c[C.THRUST_BOOST_RATIO]
    if c[C.THRUST_BOOST] != 0.0 and c[C.THRUST_UNBALANCED] != 0.0:
        c[C.THRUST_BOOST_RATIO] = min(1.0, r + step)
    elif r > 0.0:
        c[C.THRUST_BOOST_RATIO] = max(0.0, r - step)


@tick_jit
def _high_low(g, roll, pitch, rp_scale, yaw, motors):
    """Highest and lowest motor output of a roll/pitch (times rp_scale) plus yaw demand. With
    a lost motor (index ``lost``, -1: none) the highest is taken over the others, and the lost
    motor's output, where higher, is blended in by 1 - r (r: THRUST_BOOST_RATIO): at r = 1
    the lost motor may go past the top of the range, the others keep their authority. motors:
    (n, lost, r), the frame's motor count, the lost motor and the boost ratio."""
    n, lost, r = motors
    hi = -1e9
    lo = 1e9
    v_lost = -1e9
    for i in range(n):
        v = (roll * g[C.G_MIX_ROLL + i] + pitch * g[C.G_MIX_PITCH + i]) * rp_scale
        if yaw != 0.0:
            v += yaw * g[C.G_MIX_YAW + i]
        lo = min(lo, v)
        if i == lost:
            v_lost = v
        else:
            hi = max(hi, v)
    if v_lost > hi:
        hi = r * hi + (1.0 - r) * v_lost
    return hi, lo


@tick_jit
def _yaw_allowed(g, roll, pitch, rp_scale, thr_best, motors, yaw):
    """The yaw demand that fits around thr_best: the least room of the motors with a yaw
    factor (either way), at least the floor MOT_YAW_HEADROOM. While the thrust boost is on
    (``lost``: the lost motor, -1 when off) that motor's room does not count, the floor is
    r 0.5 + (1 - r) MOT_YAW_HEADROOM (r: THRUST_BOOST_RATIO), and afterwards the lost motor's
    room in the direction the yaw demand moves it limits the result by 1 - r, floor or not
    (AP_MotorsMatrix::output_armed_stabilizing). motors: (n, lost, r) as for
    :func:`_high_low`."""
    n, lost, r = motors
    allowed = 1.0
    room_lost = 1.0
    for i in range(n):
        yf = g[C.G_MIX_YAW + i]
        if yf != 0.0:
            rp = (roll * g[C.G_MIX_ROLL + i] + pitch * g[C.G_MIX_PITCH + i]) * rp_scale
            if i == lost:
                room = 1.0 - (thr_best + rp) if yaw * yf > 0.0 else thr_best + rp
                room_lost = max(room, 0.0) / abs(yf)
            else:
                room = min((1.0 - (thr_best + rp)) / abs(yf), (thr_best + rp) / abs(yf))
                allowed = min(allowed, room)
    allowed = max(allowed, r * 0.5 + (1.0 - r) * g[C.G_MOT_YAW_HEADROOM])
    if lost >= 0:
        allowed = r * allowed + (1.0 - r) * min(allowed, room_lost)
    return allowed


@tick_jit
def motor_loss_monitor(c, g, n, comp, thr_adj):
    """AP_MotorsMatrix::check_for_failed_motor, after each mix (MIX_THRUST_FILT already
    updated): MOTOR_LOST = the motor with the highest filtered output (held while the thrust
    boost is on); the thrust is unbalanced once that output x n / (sum of the filtered outputs)
    reaches MOTOR_LOST_BALANCE (frames of MOTOR_LOSS_MIN_MOTORS or more only) and balanced again
    at or below MOTOR_LOST_REBALANCE; the thrust boost goes off once the throttle is below its
    maximum (comp: the compensation gain, the maximum being 1 before it), the highest filtered
    output below THRUST_BOOST_OFF and the thrust balanced. thr_adj: the throttle the mix placed
    (thrust fraction)."""
    high = 0.0
    total = 0.0
    boost = c[C.THRUST_BOOST] != 0.0
    for i in range(n):
        f = c[C.MIX_THRUST_FILT + i]
        total += f
        if f > high:
            high = f
            if not boost:
                c[C.MOTOR_LOST] = i
    balance = high * n / total if total > 0.1 else 1.0
    if n >= MOTOR_LOSS_MIN_MOTORS and balance >= MOTOR_LOST_BALANCE:
        c[C.THRUST_UNBALANCED] = 1.0
    if balance <= MOTOR_LOST_REBALANCE:
        c[C.THRUST_UNBALANCED] = 0.0
    if comp > thr_adj and high < THRUST_BOOST_OFF and c[C.THRUST_UNBALANCED] == 0.0:
        c[C.THRUST_BOOST] = 0.0


@tick_jit
def mix(c, g, roll, pitch, yaw, throttle, v_batt):
    """Mix and write MIX_THRUST/MIX_ACT/MIX_PWM, the LIM_* saturation flags and the motor-loss
    monitor's state (MIX_THRUST_FILT, MOTOR_LOST, THRUST_UNBALANCED, THRUST_BOOST_RATIO; the
    thrust boost is switched off here once no longer needed).

    v_batt: battery voltage [V] (the resting-voltage estimate is formed here)."""
    ratio, lift = voltage_compensation(c, g, v_batt)
    comp = density_gain(c) / lift
    roll *= comp
    pitch *= comp
    yaw *= comp
    thr = min(max(throttle * comp, 0.0), 1.0)
    lim_rp = 0.0
    lim_yaw = 0.0
    lim_lo = 0.0
    lim_hi = 0.0
    n = int(g[C.G_N_MOTORS])
    boost_ratio_update(c, g)
    r = c[C.THRUST_BOOST_RATIO]
    lost = int(c[C.MOTOR_LOST]) if c[C.THRUST_BOOST] != 0.0 else -1
    # roll/pitch first
    motors = (n, lost, r)
    rp_hi, rp_lo = _high_low(g, roll, pitch, 1.0, 0.0, motors)
    rp_scale = 1.0
    if rp_hi - rp_lo > 1.0:
        rp_scale = 1.0 / (rp_hi - rp_lo)
        lim_rp = 1.0
    # yaw headroom: keep every motor within [0, 1] around the best throttle
    thr_best = 0.5 * (1.0 - (rp_hi + rp_lo) * rp_scale)
    thr_best = min(max(thr_best, 0.0), 1.0)
    yaw_allowed = _yaw_allowed(g, roll, pitch, rp_scale, thr_best, motors, yaw)
    if abs(yaw) > yaw_allowed:
        yaw = math.copysign(yaw_allowed, yaw)
        lim_yaw = 1.0
    hi, lo = _high_low(g, roll, pitch, rp_scale, yaw, motors)
    scale = 1.0
    if hi - lo > 1.0:
        scale = 1.0 / (hi - lo)
        lim_rp = 1.0
        lim_yaw = 1.0
    # attitude control may raise the throttle to keep the lowest motor at 0 only up to the
    # average maximum (THR_AVG_MAX): beyond it the roll/pitch/yaw demand is scaled down
    avg_max = min(max(c[C.THR_AVG_MAX] * comp, thr), 1.0)
    if avg_max + lo * scale < 0.0:
        scale = min(scale, -avg_max / lo)
        lim_rp = 1.0
        lim_yaw = 1.0
    hi *= scale
    lo *= scale
    # throttle: as demanded, but move it to keep the mix inside [0, 1]
    t = thr
    if t + lo < 0.0:
        t = -lo
        lim_lo = 1.0
    if t + hi > 1.0:
        t = 1.0 - hi
        lim_hi = 1.0
    if thr <= 0.0:
        lim_lo = 1.0
    if thr >= 1.0:
        lim_hi = 1.0
    alpha = g[C.G_DT] / (g[C.G_DT] + MOTOR_FILT_TC_S)
    for i in range(n):
        v = t + ((roll * g[C.G_MIX_ROLL + i] + pitch * g[C.G_MIX_PITCH + i]) * rp_scale
                 + yaw * g[C.G_MIX_YAW + i]) * scale
        c[C.MIX_THRUST_FILT + i] += alpha * (v - c[C.MIX_THRUST_FILT + i])
        v = min(max(v, 0.0), 1.0)
        c[C.MIX_THRUST + i] = v
        a = thrust_to_actuator(g, v, ratio, lift)
        c[C.MIX_ACT + i] = a
        c[C.MIX_PWM + i] = pwm_out(g, a)
    c[C.LIM_RP] = lim_rp
    c[C.LIM_YAW] = lim_yaw
    c[C.LIM_THR_LO] = lim_lo
    c[C.LIM_THR_HI] = lim_hi
    c[C.MOT_THR_OUT] = t / comp
    motor_loss_monitor(c, g, n, comp, t)


@tick_jit
def pwm_out(g, actuator):
    """PWM [us] of an actuator value 0..1 as the motor library outputs it: a whole number of
    microseconds, the fraction dropped (AP_MotorsMulticopter::output_to_pwm returns an int16
    and SITL's servo input is uint16 microseconds). The 1 us steps make the collective thrust
    jitter by ~0.02 N per motor: the broadband vertical acceleration (and VIBE z) that SITL's
    IMU shows in flight on top of the sensor noise (normal_s11, cruise: IMU0 AccZ Welch power
    ~1e-6 (m/s^2)^2/Hz at 2-5 Hz on both IMUs, X unaffected)."""
    pwm = g[C.G_MOT_PWM_MIN] + (g[C.G_MOT_PWM_MAX] - g[C.G_MOT_PWM_MIN]) * actuator
    return float(int(pwm))


@tick_jit
def output_idle(c, g, spin):
    """All motors at a fixed actuator value (0 = stopped, MOT_SPIN_ARM = ground idle); the
    thrust boost is off (as in the motors' shut-down and ground-idle states) and the filtered
    outputs decay towards the zero thrust demand."""
    n = int(g[C.G_N_MOTORS])
    alpha = g[C.G_DT] / (g[C.G_DT] + MOTOR_FILT_TC_S)
    for i in range(n):
        c[C.MIX_THRUST + i] = 0.0
        c[C.MIX_ACT + i] = spin
        c[C.MIX_PWM + i] = pwm_out(g, spin)
        c[C.MIX_THRUST_FILT + i] -= alpha * c[C.MIX_THRUST_FILT + i]
    c[C.THRUST_BOOST] = 0.0  # shut down / ground idle: no thrust boost
    c[C.THRUST_BOOST_RATIO] = 0.0
    c[C.MOT_THR_OUT] = 0.0  # no throttle placed (MOTB.ThrOut)
    motor_loss_monitor(c, g, n, 1.0, 0.0)
    c[C.LIM_RP] = 1.0
    c[C.LIM_YAW] = 1.0
    c[C.LIM_THR_LO] = 1.0
    c[C.LIM_THR_HI] = 0.0


#: points of the throttle slew detector (AP_Motors' DerivativeFilterFloat_Size7)
SLEW_POINTS = 7


@tick_jit
def throttle_slew_update(c, g, t_us, q):
    """AP_MotorsMulticopter::update_throttle_filter, every main-loop tick at t_us [us], q: the
    EKF attitude body->NED the controllers used.

    The motors' throttle input is AC_PosControl's demand unclamped (THR_IN_RAW) with
    AC_AttitudeControl_Multi's angle boost (x 1/cos(tilt), the cosine floored at 0.1, faded
    out between 84 and 90 deg of tilt; no upper limit), 0 at ground idle; it is low-passed at
    2 Hz and clamped to 0..1 while armed, 0 while disarmed (THR_FILT); when that changed, a
    sample of it for the 7-point slew detector; the detector's slope [1/s], its magnitude
    low-passed at 50 Hz: THR_SLEW_RATE, logged as RATE.AOutSlew.

    tlm's mixer takes the clamped, unfiltered throttle (RATE.AOut, CTUN.ThO), ArduPilot's the
    filtered one: THR_FILT feeds the detector only. Where the filtered throttle sits at a limit
    (1.0 at full throttle) it does not change, no sample comes and the rate stays at its last
    value: engine_s14.bin logs a constant AOutSlew 0.346 while its copter lies on the ground
    at full throttle, 79.5 during the tumble before (the last rise to 1.0)."""
    last = c[C.THR_FILT]
    if c[C.ARMED] != 0.0:
        thr = 0.0
        if c[C.SUBMODE] != C.SUB_GROUND_IDLE:
            cos_tilt = 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2])
            inverted = min(max(10.0 * cos_tilt, 0.0), 1.0)
            thr = c[C.THR_IN_RAW] * inverted / min(max(cos_tilt, 0.1), 1.0)
        f = last + g[C.G_THR_FILT_A] * (thr - last)
        f = min(max(f, 0.0), 1.0)
    else:
        f = 0.0
    c[C.THR_FILT] = f
    if f != last:
        _slew_sample(c, f, float(t_us))
    rate = abs(_slew_slope(c) * 1e6)
    c[C.THR_SLEW_RATE] += g[C.G_SLEW_FILT_A] * (rate - c[C.THR_SLEW_RATE])


@tick_jit
def _slew_sample(c, value, t_us):
    """DerivativeFilter::update: a new (value, time) into the ring unless the time repeats."""
    i = int(c[C.SLEW_IDX])
    prev = SLEW_POINTS - 1 if i == 0 else i - 1
    if c[C.SLEW_TIMES + prev] == t_us:
        return
    c[C.SLEW_TIMES + i] = t_us
    c[C.SLEW_SAMPLES + i] = value
    c[C.SLEW_IDX] = (i + 1) % SLEW_POINTS
    c[C.SLEW_NEW] = 1.0


@tick_jit
def _slew_slope(c):
    """DerivativeFilter::slope (Holoborodko's 7-point smooth differentiator on uneven times)
    [1/us]: the last slope again when no sample came since; 0 until the ring has filled (its
    last two time slots differ)."""
    if c[C.SLEW_NEW] == 0.0:
        return c[C.SLEW_LAST]
    if c[C.SLEW_TIMES + SLEW_POINTS - 1] == c[C.SLEW_TIMES + SLEW_POINTS - 2]:
        return 0.0
    base = int(c[C.SLEW_IDX]) + 10  # the oldest sample is k = -3, the newest k = 3
    out = 0.0
    for k, w in ((1, 10.0), (2, 16.0), (3, 6.0)):
        hi = (base + k) % SLEW_POINTS
        lo = (base - k) % SLEW_POINTS
        out += w * (c[C.SLEW_SAMPLES + hi] - c[C.SLEW_SAMPLES + lo]) / (
            c[C.SLEW_TIMES + hi] - c[C.SLEW_TIMES + lo])
    out /= 32.0
    if not math.isfinite(out):
        out = 0.0
    c[C.SLEW_NEW] = 0.0
    c[C.SLEW_LAST] = out
    return out
