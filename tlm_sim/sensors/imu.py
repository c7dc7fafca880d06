"""Two simulated IMUs (accelerometer + gyro) as ArduPilot SITL samples them.

Samples at each instance's own rate (IMU0 gyro/accel 1000/1000 Hz, IMU1 760/800 Hz) from the
latest physics state (zero-order hold; the sensors' view of it, ``X.SWX``/``X.SFX``, SITL's
sensor smoothing, see tlm_sim.dynamics.smoothing), adds SITL's noise, bias, gyro drift and
scale errors, vibration (SITL's motor-locked and fixed-frequency sinusoids) and failures
(SIM_ACCELn_FAIL values, SIM_ACC_FAIL_MSK / SIM_GYR_FAIL_MSK stopped samples), then does what
the autopilot does with raw samples: accumulates them for the EKF, sets the health flags,
low-pass filters them at INS_GYRO_FILTER / INS_ACCEL_FILTER (2nd-order Butterworth) for the
controllers and the IMU log, and computes the VIBE metric and clip count.
Body frame FRD; accel in m/s^2 (specific force, about (0, 0, -g) at rest), gyro in rad/s.
"""

import math

import numpy as np

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.dynamics import layout as X
from tlm_sim.frames import MAX_MOTORS
from tlm_sim.rng import normal_pair, uniform_pm1
from tlm_sim.sensors import layout as S

CLIP_LIMIT = (16.0 - 0.5) * GRAVITY_MSS  # m/s^2, a sample beyond this on any axis counts as a clip
TWO_PI = 2.0 * math.pi
VIB_AMP_VARIATION = 0.05  # SITL: each vibration amplitude x (1 + 0.05 U)
VIB_FREQ_VARIATION = 0.12  # SITL: each motor phase step x (1 + 0.12 U), smearing the peaks


def lpf2p_coefficients(sample_hz: float, cutoff_hz: float) -> np.ndarray:
    """Second-order Butterworth low-pass biquad (b0, b1, b2, a1, a2); pass-through if cutoff 0."""
    if cutoff_hz <= 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0, 0.0])
    ohm = math.tan(math.pi * cutoff_hz / sample_hz)
    c = 1.0 + 2.0 * math.cos(math.pi / 4.0) * ohm + ohm * ohm
    b0 = ohm * ohm / c
    a1 = 2.0 * (ohm * ohm - 1.0) / c
    a2 = (1.0 - 2.0 * math.cos(math.pi / 4.0) * ohm + ohm * ohm) / c
    return np.array([b0, 2.0 * b0, b0, a1, a2])


@tick_jit
def _biquad(s, d, coef, c, x):
    """One biquad step on state s[d], s[d+1] with coefficients coef[c:c+5]; returns the output."""
    d0 = x - s[d] * coef[c + 3] - s[d + 1] * coef[c + 4]
    out = d0 * coef[c] + s[d] * coef[c + 1] + s[d + 1] * coef[c + 2]
    s[d + 1] = s[d]
    s[d] = d0
    return out


@tick_jit
def gyro_drift(t_s, cfg):
    """SITL gyro drift [rad/s], the same on every axis: a triangle wave in time."""
    speed = cfg[S.C_DRIFT_SPEED]
    period = 2.0 * cfg[S.C_DRIFT_TIME]
    if speed == 0.0 or period <= 0.0:
        return 0.0
    tm = t_s / 60.0
    if tm >= period:  # fmod (a libm call, every physics tick) only past the first period
        tm %= period
    if tm < 0.5 * period:
        return speed * tm
    return speed * (period - tm)


@tick_jit
def imu_init(s, cfg, t_us):
    """Reset both IMUs' accumulators and filters; first samples due at t_us."""
    for i in range(S.N_IMU):
        b = S.IMU_BASE + i * S.IMU_STRIDE
        for k in range(S.IMU_STRIDE):
            s[b + k] = 0.0
        s[b + S.I_NEXT_GYR_US] = t_us
        s[b + S.I_NEXT_ACC_US] = t_us
        s[b + S.I_ACC_OK] = 1.0
        s[b + S.I_GYR_OK] = 1.0
        s[b + S.I_T_SAMPLE_US] = t_us
        s[b + S.I_T_TAKE_US] = -1.0


@tick_jit
def imu_sample(s, x, cfg, t_us, throttle, pwm, rng):
    """Take every IMU sample due at physics time t_us [us] from truth state x.

    throttle: mean motor output 0..1 (SITL's noise scaling; "motors on" above SIM_INS_THR_MIN).
    pwm[0:8]: the outputs' PWM [us] (what they run at after an engine fault): their commands
    (PWM - 1000) / 1000 set the motor vibration frequencies.
    rng: the sensor noise streams (rows S.RNG_*, tlm_sim.rng.new_streams); IMU i draws its gyro
    noise from row RNG_GYRO + i and its accelerometer noise from row RNG_ACC + i only.
    A gyro (accel) whose SIM_GYR_FAIL_MSK (SIM_ACC_FAIL_MSK) bit is set produces nothing and
    its sample timer stands still, as in SITL; when the bit clears it samples at once and its
    timer catches up with the physics clock.
    """
    t_s = t_us * 1e-6
    motors_on = throttle > cfg[S.C_INS_THR_MIN]
    drift = gyro_drift(t_s, cfg)
    gyr_mask = int(cfg[S.C_GYR_FAIL_MSK])
    acc_mask = int(cfg[S.C_ACC_FAIL_MSK])
    if cfg[S.C_ROTOR_TC] > 0.0:
        _rotor_pwm(s, x, cfg, pwm)
        pwm = s[S.ROTOR_PWM:S.ROTOR_PWM + MAX_MOTORS]
    now = (t_s, drift, motors_on, throttle, pwm)  # this sampling call (_gyro_sample's now)
    for i in range(S.N_IMU):
        b = S.IMU_BASE + i * S.IMU_STRIDE
        s[b + S.I_T_SAMPLE_US] = t_us
        if t_us >= s[b + S.I_NEXT_GYR_US] and (gyr_mask >> i) & 1 == 0:
            _advance_timer(s, b + S.I_NEXT_GYR_US, cfg[S.C_GYR_PERIOD_US + i], t_us)
            _gyro_sample(s, x, cfg, (b, i), now, rng[S.RNG_GYRO + i])
            if cfg[S.C_GYR_WALK_STEP + i] != 0.0:
                _bias_walk(s, b + S.I_GYR_WALK, cfg[S.C_GYR_WALK_STEP + i], rng[S.RNG_GYRO + i])
        if t_us >= s[b + S.I_NEXT_ACC_US] and (acc_mask >> i) & 1 == 0:
            _advance_timer(s, b + S.I_NEXT_ACC_US, cfg[S.C_ACC_PERIOD_US + i], t_us)
            _accel_sample(s, x, cfg, (b, i), now, rng[S.RNG_ACC + i])
            if cfg[S.C_ACC_WALK_STEP + i] != 0.0:
                _bias_walk(s, b + S.I_ACC_WALK, cfg[S.C_ACC_WALK_STEP + i], rng[S.RNG_ACC + i])


@tick_jit
def _rotor_pwm(s, x, cfg, pwm):
    """With the rotor lag on (TLM_ROTOR_TC): each rotor's speed as the PWM that commands it at
    rest, s[ROTOR_PWM + m], from the motor model's lagged command x[M1 + m] through the frame's
    PWM range (so the vibration runs where :func:`_motor_command` puts it for a steady PWM,
    and follows the rotor, not the output); 0 for an output without a PWM (no motor)."""
    lo = cfg[S.C_ROTOR_PWM]
    span = cfg[S.C_ROTOR_PWM + 1]
    for m in range(MAX_MOTORS):
        s[S.ROTOR_PWM + m] = lo + span * x[X.M1 + m] if pwm[m] > 0.0 else 0.0


@tick_jit
def _bias_walk(s, slot, step, rng):
    """One sample's step of a bias random walk (TLM_GYR_WALK / TLM_ACC_WALK): each axis of
    s[slot:slot + 3] moves by a normal draw of standard deviation step (the walk's density
    x sqrt(sample period))."""
    n0, n1 = normal_pair(rng)
    n2 = normal_pair(rng)[0]
    s[slot] += step * n0
    s[slot + 1] += step * n1
    s[slot + 2] += step * n2


@inline_jit
def _advance_timer(s, slot, period, t_us):
    """Next sample time: one period on, and on past t_us after a stop (SIM_*_FAIL_MSK)."""
    nxt = s[slot] + period
    while nxt <= t_us:
        nxt += period
    s[slot] = nxt


@inline_jit
def _gyro_sample(s, x, cfg, imu, now, rng):
    """One published gyro sample of IMU i (imu: (b, i), its record at b; now: (t_s, drift,
    motors_on, throttle, pwm) of :func:`imu_sample`'s call), SITL's pipeline (§2.2): truth rates +
    drift + base noise, the second noise term (no SIM_VIB_*) or the vibration terms (with
    SIM_VIB_*, motors on, amplitude radians(SIM_GYRn_RND) x throttle), x (1 + SCALE/100),
    + BIAS; then accumulated for the EKF and low-pass filtered. With a SIM_VIB_* set the
    sample is :func:`_gyro_sample_vib`'s: this loop, run at every sample of every flight,
    holds no call (libm's sin, the motor model), which cost the per-sample path about 2 % of
    the flight loop."""
    b, i = imu
    drift, motors_on, throttle = now[1], now[2], now[3]
    sc = cfg[S.C_NOISE_SCALE + i]
    if motors_on:
        a_g = cfg[S.C_GYR_RND + i] * throttle
    else:
        a_g = cfg[S.C_GYR_NOISE] * sc
    if cfg[S.C_VIB_ON] != 0.0 or cfg[S.C_GYR_WALK_STEP + i] != 0.0:
        _gyro_sample_vib(s, x, cfg, imu, now, a_g, rng)
        return
    for k in range(3):
        g = x[X.SWX + k] + drift
        g += cfg[S.C_GYR_NOISE] * sc * uniform_pm1(rng)
        if a_g != 0.0:
            g += a_g * uniform_pm1(rng)
        _gyro_store(s, b, i, cfg, k, g)
    s[b + S.I_GYR_COUNT] += 1.0


@tick_jit
def _gyro_sample_vib(s, x, cfg, imu, now, a_g, rng):
    """:func:`_gyro_sample` with a SIM_VIB_* set or the bias walk on (TLM_GYR_WALK): the
    vibration terms replace the second noise term (while the motors run and the amplitude a_g
    is not 0), each scaled by its axis's gain (TLM_VIB_GYR_X/Y/Z); the walk adds to the bias."""
    b, i = imu
    t_s, drift, motors_on, pwm = now[0], now[1], now[2], now[4]
    sc = cfg[S.C_NOISE_SCALE + i]
    v_mot = 0.0
    vib_on = cfg[S.C_VIB_ON] != 0.0
    vib = vib_on and motors_on and a_g != 0.0
    if vib:
        v_mot = _motor_vibration(s, b + S.I_GYR_PHASE, cfg, pwm, a_g * cfg[S.C_VIB_MOT_MULT],
                                 (cfg[S.C_IMU_NSUB + i], cfg[S.C_GYR_PERIOD_US + i]), rng)
    walk = cfg[S.C_GYR_WALK_STEP + i] != 0.0
    for k in range(3):
        g = x[X.SWX + k] + drift
        g += cfg[S.C_GYR_NOISE] * sc * uniform_pm1(rng)
        if vib:
            g += (v_mot + _fixed_vibration(cfg, k, t_s, a_g, rng)) * cfg[S.C_VIB_GYR_AX + k]
        elif not vib_on and a_g != 0.0:  # no SIM_VIB_*: SITL's second noise term
            g += a_g * uniform_pm1(rng)
        if walk:  # before scale and bias: the walk is a rate error as the bias is
            g += s[b + S.I_GYR_WALK + k] / cfg[S.C_GYR_SCALE + 3 * i + k]
        _gyro_store(s, b, i, cfg, k, g)
    s[b + S.I_GYR_COUNT] += 1.0


@inline_jit
def _gyro_store(s, b, i, cfg, k, g):
    """Axis k of a gyro sample g before scale and bias: x (1 + SCALE/100) + BIAS, then the
    last sample, the EKF's accumulator and the low-pass filter."""
    g = g * cfg[S.C_GYR_SCALE + 3 * i + k] + cfg[S.C_GYR_BIAS + 3 * i + k]
    s[b + S.I_LAST_GYR + k] = g
    s[b + S.I_DANG + k] += g
    d = b + S.I_GYR_LPF + 2 * k
    s[b + S.I_GYR_F + k] = _biquad(s, d, cfg, S.C_GYR_LPF + 5 * i, g)


@inline_jit
def _accel_sample(s, x, cfg, imu, now, rng):
    """One published accel sample of IMU i (record at b), SITL's pipeline (§2.2): truth specific
    force / SCAL (per non-zero axis) + BIAS + base noise + the vibration terms (SIM_VIB_*,
    motors on, amplitude SIM_ACCn_RND), all replaced by SIM_ACCELn_FAIL when that is set; then
    accumulated for the EKF, low-pass filtered, and the VIBE metric and clip count. A
    vibrating sample is :func:`_accel_sample_vib`'s (no call in this loop, as for the gyro).
    imu: (b, i), IMU i's record at b; now: :func:`imu_sample`'s (t_s, drift, motors_on,
    throttle, pwm)."""
    b, i = imu
    motors_on = now[2]
    fail = cfg[S.C_ACC_FAIL + i]
    amp = cfg[S.C_ACC_RND + i]
    if ((motors_on and amp != 0.0 and cfg[S.C_VIB_ON] != 0.0 or cfg[S.C_ACC_SLOW + i] != 0.0)
            and abs(fail) <= 1e-6):
        _accel_sample_vib(s, x, cfg, imu, now, amp, rng)
        return
    clipped = False
    for k in range(3):
        if abs(fail) > 1e-6:
            a = fail
        else:
            a = _accel_truth(x, cfg, i, k, rng)
        clipped |= _accel_store(s, b, i, cfg, k, a)
    if clipped:
        s[b + S.I_CLIP] += 1.0
    s[b + S.I_ACC_COUNT] += 1.0


@tick_jit
def _accel_sample_vib(s, x, cfg, imu, now, amp, rng):
    """:func:`_accel_sample` of a vibrating accelerometer (motors on, SIM_ACCn_RND amp, a
    SIM_VIB_* set), of one with an imbalanced propeller (TLM_VIB_IMB) or a bias walk
    (TLM_ACC_WALK), without SIM_ACCELn_FAIL: the motor and fixed-frequency terms, each scaled
    by its axis's gain (TLM_VIB_ACC_X/Y/Z), the imbalance's turning force, the walk."""
    b, i = imu
    t_s, motors_on, pwm = now[0], now[2], now[4]
    sampling = (cfg[S.C_IMU_NSUB + 2 + i], cfg[S.C_ACC_PERIOD_US + i])
    vib = (cfg[S.C_VIB_ON] != 0.0 and motors_on
           and (amp != 0.0 or cfg[S.C_VIB_IMB] > 0.0))
    v_mot = 0.0
    imb = (0.0, 0.0)
    if vib:
        v_mot = _motor_vibration(s, b + S.I_ACC_PHASE, cfg, pwm, amp * cfg[S.C_VIB_MOT_MULT],
                                 sampling, rng)
        if cfg[S.C_VIB_IMB] > 0.0:
            imb = _imbalance(s, b + S.I_ACC_PHASE, cfg, pwm, sampling)
    walk = cfg[S.C_ACC_WALK_STEP + i] != 0.0
    clipped = False
    for k in range(3):
        a = _accel_truth(x, cfg, i, k, rng)
        if vib:
            a += (v_mot + _fixed_vibration(cfg, k, t_s, amp, rng)) * cfg[S.C_VIB_ACC_AX + k]
            if k < 2:
                a += imb[k]
        if walk:
            a += s[b + S.I_ACC_WALK + k]
        clipped |= _accel_store(s, b, i, cfg, k, a)
    if clipped:
        s[b + S.I_CLIP] += 1.0
    s[b + S.I_ACC_COUNT] += 1.0


@inline_jit
def _accel_truth(x, cfg, i, k, rng):
    """Axis k of IMU i's accel sample before vibration: truth / SCAL (when not 0) + BIAS +
    base noise."""
    a = x[X.SFX + k]
    scal = cfg[S.C_ACC_SCAL + 3 * i + k]
    if scal != 0.0:
        a /= scal
    a += cfg[S.C_ACC_BIAS + 3 * i + k]
    a += (cfg[S.C_ACC_NOISE] * cfg[S.C_NOISE_SCALE + i] * uniform_pm1(rng))
    return a


@inline_jit
def _accel_store(s, b, i, cfg, k, a):
    """Axis k of an accel sample a: the last sample, the EKF's accumulator, the low-pass
    filter and the VIBE metric; returns whether it clipped."""
    s[b + S.I_LAST_ACC + k] = a
    s[b + S.I_DVEL + k] += a
    d = b + S.I_ACC_LPF + 2 * k
    s[b + S.I_ACC_F + k] = _biquad(s, d, cfg, S.C_ACC_LPF + 5 * i, a)
    # VIBE: deviation from a 5 Hz floor, squared, filtered at 2 Hz
    fl = s[b + S.I_VIB_FLOOR + k]
    fl += cfg[S.C_VIB_FLOOR_A + i] * (a - fl)
    s[b + S.I_VIB_FLOOR + k] = fl
    dev = a - fl
    s[b + S.I_VIB_SQ + k] += cfg[S.C_VIB_SQ_A + i] * (dev * dev - s[b + S.I_VIB_SQ + k])
    return abs(a) > CLIP_LIMIT


@inline_jit
def _fixed_vibration(cfg, k, t_s, amp, rng):
    """SIM_VIB_FREQ term of axis k: sin(2 pi f_k t) x amp (1 + 0.05 U); 0 when f_k is 0."""
    f = cfg[S.C_VIB_FREQ + k]
    if f == 0.0:
        return 0.0
    return math.sin(TWO_PI * f * t_s) * amp * (1.0 + VIB_AMP_VARIATION * uniform_pm1(rng))


@inline_jit
def _motor_command(pwm):
    """SITL's vibrating-motor command 0..1 of an output at pwm [us]: (PWM - 1000) / 1000."""
    return min(max((pwm - 1000.0) * 1e-3, 0.0), 1.0)


@tick_jit
def _motor_vibration(s, ph, cfg, pwm, amp, sampling, rng):
    """SITL's motor vibration (SIM_VIB_MOT_*), the same on every axis: the mean over the nsub
    sub-samples of one published sample of, for each vibrating motor m and each harmonic h
    (SIM_VIB_MOT_HMNC bit h - 1), sin(h phi_m) amp (1 + 0.05 U). Motor m's phase phi_m (s[ph + m])
    advances each sub-sample by 2 pi f_m (1 + 0.12 U) / sub-sample rate, f_m = command_m x
    SIM_VIB_MOT_MAX with command_m = (PWM_m - 1000) / 1000 (times motor m's
    TLM_VIB_SPREAD factor): rpm-locked, smeared like real motors; with TLM_VIB_CMD_REF > 0
    each rotor's amplitude x (command_m / TLM_VIB_CMD_REF)^2. 0 when SIM_VIB_MOT_MAX is 0."""
    nsub, period_us = sampling  # sub-samples per published sample, its period [us]
    f_max = cfg[S.C_VIB_MOT_MAX]
    if f_max <= 0.0:
        return 0.0
    mask = int(cfg[S.C_VIB_MOT_MASK])
    hmnc = int(cfg[S.C_VIB_MOT_HMNC])
    n = int(nsub)
    w = TWO_PI * f_max * period_us * 1e-6 / nsub  # phase step per unit command
    ref = cfg[S.C_VIB_CMD_REF]
    total = 0.0
    for _ in range(n):
        for m in range(MAX_MOTORS):  # outputs 1..8; one without a PWM (0) has no motor
            if (mask >> m) & 1 == 0 or pwm[m] <= 0.0:
                continue
            cmd = _motor_command(pwm[m]) * cfg[S.C_VIB_MOT_FMUL + m]
            p = s[ph + m] + w * cmd * (1.0 + VIB_FREQ_VARIATION * uniform_pm1(rng))
            if p >= TWO_PI:
                p %= TWO_PI
            s[ph + m] = p
            a = amp
            if ref > 0.0:  # TLM_VIB_CMD_REF: the rotor's force goes with its speed squared
                a = amp * (cmd / ref) * (cmd / ref)
            for h in range(1, 9):
                if (hmnc >> (h - 1)) & 1:
                    total += (math.sin(h * p) * a
                              * (1.0 + VIB_AMP_VARIATION * uniform_pm1(rng)))
    return total / nsub


@tick_jit
def _imbalance(s, ph, cfg, pwm, sampling):
    """Specific force [m/s^2] body (x, y) of the imbalanced propeller (TLM_VIB_IMB_MOT,
    TLM_VIB_IMB): a force turning with its rotor, once per revolution, TLM_VIB_IMB x command^2
    (centrifugal: rpm squared), averaged over the sample's sub-samples. The rotor's phase is
    the motor vibration's (s[ph + m], advanced by :func:`_motor_vibration` over the same
    sub-samples; here stepped back through them at the mean rate). A planar force at the rotor
    only adds a yaw moment, so the gyros are left alone."""
    nsub, period_us = sampling
    m = int(cfg[S.C_VIB_IMB_MOT])
    if m < 0 or pwm[m] <= 0.0:
        return 0.0, 0.0
    cmd = _motor_command(pwm[m])
    amp = cfg[S.C_VIB_IMB] * cmd * cmd
    n = int(nsub)
    f = cfg[S.C_VIB_MOT_MAX] * cmd * cfg[S.C_VIB_MOT_FMUL + m]
    w = TWO_PI * f * period_us * 1e-6 / nsub
    p = s[ph + m]
    fx = 0.0
    fy = 0.0
    for j in range(n):
        q = p - j * w
        fx += math.cos(q)
        fy += math.sin(q)
    return amp * fx / nsub, amp * fy / nsub


@tick_jit
def imu_take_deltas(s, i, dt, dang, dvel):
    """Hand IMU i's samples of this main-loop tick to the EKF and reset the accumulators.

    Writes the mean rate times the time since the previous call into dang[i] [rad] and dvel[i]
    [m/s]: the physics time of the latest :func:`imu_sample` call minus that of the previous
    take, i.e. the interval the EKF integrates over (the 400 Hz loop runs on the 833 us physics
    clock, so it lasts 2499 us and, every ~2 s, 3332 us, as in SITL); dt [s] (the nominal loop
    period) on the first call. Integrating the deltas over the nominal period instead leaves the
    EKF's gravity term uncompensated for the extra 833 us: a 8 mm/s vertical velocity step every
    2.08 s that the altitude controller answers with a throttle and pitch kick.
    Returns 1.0 if the accel delivered samples this tick, else 0.0 (and holds the last value);
    sets the health flags I_ACC_OK / I_GYR_OK (IMU.AH / IMU.GH: a sample since the last tick,
    as ArduPilot's INS front end decides health every loop).
    """
    b = S.IMU_BASE + i * S.IMU_STRIDE
    t_now = s[b + S.I_T_SAMPLE_US]
    t_prev = s[b + S.I_T_TAKE_US]
    s[b + S.I_T_TAKE_US] = t_now
    if t_prev >= 0.0 and 0.0 < t_now - t_prev < 1e5:
        dt = (t_now - t_prev) * 1e-6
    ng = s[b + S.I_GYR_COUNT]
    na = s[b + S.I_ACC_COUNT]
    for k in range(3):
        if ng > 0.0:
            dang[i, k] = s[b + S.I_DANG + k] / ng * dt
        else:
            dang[i, k] = s[b + S.I_LAST_GYR + k] * dt
        if na > 0.0:
            dvel[i, k] = s[b + S.I_DVEL + k] / na * dt
        else:
            dvel[i, k] = s[b + S.I_LAST_ACC + k] * dt
        s[b + S.I_DANG + k] = 0.0
        s[b + S.I_DVEL + k] = 0.0
    s[b + S.I_GYR_COUNT] = 0.0
    s[b + S.I_ACC_COUNT] = 0.0
    s[b + S.I_GYR_OK] = 1.0 if ng > 0.0 else 0.0
    s[b + S.I_ACC_OK] = 1.0 if na > 0.0 else 0.0
    return 1.0 if na > 0.0 else 0.0


@tick_jit
def vibe(s, i, k):
    """VIBE metric of IMU i, axis k [m/s^2]."""
    return math.sqrt(max(s[S.IMU_BASE + i * S.IMU_STRIDE + S.I_VIB_SQ + k], 0.0))
