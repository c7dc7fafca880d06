"""Two simulated IMUs (accelerometer + gyro) as ArduPilot SITL samples them.

Samples at each instance's own rate (IMU0 gyro/accel 1000/1000 Hz, IMU1 760/800 Hz) from the
latest physics state (zero-order hold; the sensors' view of it, ``X.SWX``/``X.SFX``, SITL's
sensor smoothing, see tlm_sim.dynamics.smoothing), adds SITL's noise, bias, gyro drift and
failure overrides (SIM_ACCELn_FAIL), then does what the autopilot does with raw samples: accumulates
them for the EKF, low-pass filters them at INS_GYRO_FILTER / INS_ACCEL_FILTER (2nd-order
Butterworth) for the controllers and the IMU log, and computes the VIBE metric and clip count.
Body frame FRD; accel in m/s^2 (specific force, about (0, 0, -g) at rest), gyro in rad/s.
"""

import math

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.dynamics import layout as X
from tlm_sim.rng import uniform_pm1
from tlm_sim.sensors import layout as S

CLIP_LIMIT = (16.0 - 0.5) * 9.80665  # m/s^2, a sample beyond this on any axis counts as a clip


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
        s[b + S.I_T_SAMPLE_US] = t_us
        s[b + S.I_T_TAKE_US] = -1.0


@tick_jit
def imu_sample(s, x, cfg, t_us, throttle, rng):
    """Take every IMU sample due at physics time t_us [us] from truth state x.

    throttle: mean motor output 0..1 (SITL's noise scaling; "motors on" above SIM_INS_THR_MIN).
    rng: the sensor noise streams (rows S.RNG_*, tlm_sim.rng.new_streams); IMU i draws its gyro
    noise from row RNG_GYRO + i and its accelerometer noise from row RNG_ACC + i only.
    """
    t_s = t_us * 1e-6
    motors_on = throttle > cfg[S.C_INS_THR_MIN]
    drift = gyro_drift(t_s, cfg)
    for i in range(S.N_IMU):
        b = S.IMU_BASE + i * S.IMU_STRIDE
        s[b + S.I_T_SAMPLE_US] = t_us
        if t_us >= s[b + S.I_NEXT_GYR_US]:
            s[b + S.I_NEXT_GYR_US] += cfg[S.C_GYR_PERIOD_US + i]
            sc = cfg[S.C_NOISE_SCALE + i]
            if motors_on:
                a_g = cfg[S.C_GYR_RND + i] * throttle
            else:
                a_g = cfg[S.C_GYR_NOISE] * sc
            for k in range(3):
                g = x[X.SWX + k] + drift + cfg[S.C_GYR_BIAS + 3 * i + k]
                g += cfg[S.C_GYR_NOISE] * sc * uniform_pm1(rng[S.RNG_GYRO + i])
                if a_g != 0.0:
                    g += a_g * uniform_pm1(rng[S.RNG_GYRO + i])
                s[b + S.I_LAST_GYR + k] = g
                s[b + S.I_DANG + k] += g
                d = b + S.I_GYR_LPF + 2 * k
                s[b + S.I_GYR_F + k] = _biquad(s, d, cfg, S.C_GYR_LPF + 5 * i, g)
            s[b + S.I_GYR_COUNT] += 1.0
        if t_us >= s[b + S.I_NEXT_ACC_US]:
            s[b + S.I_NEXT_ACC_US] += cfg[S.C_ACC_PERIOD_US + i]
            fail = cfg[S.C_ACC_FAIL + i]
            clipped = False
            for k in range(3):
                if abs(fail) > 1e-6:
                    a = fail
                else:
                    a = x[X.SFX + k] + cfg[S.C_ACC_BIAS + 3 * i + k]
                    a += (cfg[S.C_ACC_NOISE] * cfg[S.C_NOISE_SCALE + i]
                          * uniform_pm1(rng[S.RNG_ACC + i]))
                    if motors_on and cfg[S.C_ACC_RND + i] != 0.0 and cfg[S.C_VIB_MOT_MAX] != 0.0:
                        # motor vibration: a sinusoid at the motor rotation rate (SIM_VIB_MOT_MAX)
                        f_hz = throttle * cfg[S.C_VIB_MOT_MAX]
                        a += cfg[S.C_ACC_RND + i] * math.sin(2.0 * math.pi * f_hz * t_s + k)
                if abs(a) > CLIP_LIMIT:
                    clipped = True
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
            if clipped:
                s[b + S.I_CLIP] += 1.0
            s[b + S.I_ACC_COUNT] += 1.0


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
    Returns 1.0 if the accel delivered samples this tick, else 0.0 (and holds the last value).
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
    return 1.0 if na > 0.0 else 0.0


@tick_jit
def vibe(s, i, k):
    """VIBE metric of IMU i, axis k [m/s^2]."""
    return math.sqrt(max(s[S.IMU_BASE + i * S.IMU_STRIDE + S.I_VIB_SQ + k], 0.0))
