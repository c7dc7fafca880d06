"""EKF3's EKF-GSF yaw estimator (``EKFGSF_yaw``), one per EKF lane: a yaw that needs no
compass.

Each lane (EK3_GSF_RUN_MASK) runs a bank of ``N_MODELS`` hypotheses on its IMU data. Every
model is an AHRS complementary filter (its rotation matrix follows the gyro, its tilt is pulled
towards the low-passed accel and a gyro bias is learnt from that correction) with a three-state
EKF on top: velocity north/east predicted from the accel rotated by the model's attitude, and
the model's yaw. GPS NE velocity is fused into every EKF; a Gaussian sum filter weighs the
models by the likelihood of their innovations and gives a composite yaw and its variance.

The firmware keeps five AHRS; they differ only by a rotation about the vertical. They start
equal (the tilt alignment), the yaw alignment and every fusion turn a model's matrix about the
earth vertical (``R <- Rz(a) R``), and what moves them otherwise is the same for all: the gyro,
and a tilt correction and bias learning that read only the matrix's last row (the earth
vertical in body axes), which a turn about the vertical leaves alone. tlm therefore runs one
AHRS (``G_R``, ``G_GBIAS``) and keeps each model's heading offset from it (``M_COS``,
``M_SIN``): the same numbers up to rounding, at a fifth of the cost.

Lifecycle as in EKF3: the AHRS tilt aligns once from an accel sample within 10 % of 1 g
(boot); the bank runs (``G_RUN``) while the vehicle is armed and the lane's GPS speed accuracy
test passes, taking the lane's gyro bias when it starts; the first GPS velocity after that
resets the bank (velocities from GPS, yaws spread evenly over +-180 deg, equal weights) and
starts the fusion (``G_FUSING``: XKY0 / XKY1 are logged from then on); disarming stops it. All
models' weights under the floor reset the bank. The main EKF does not use the estimate (tlm
has no yaw reset to it).

Timing: EKF3 runs the estimator at its prediction steps on IMU data at the delayed horizon,
so that a GPS velocity meets the IMU data of its own time. tlm sums the lane's IMU deltas to
EKF3's 12 ms steps (``C_TARGET_DT``, 5 main-loop ticks), delays the steps by the assumed GPS
delay (``C_GPS_DELAY``, to the nearest step) in a delay line and fuses a GPS velocity when it
arrives. The models' yaw states and the composite yaw and variance are outputs only (nothing
in the filter reads them back while it fuses): :func:`gsf_refresh` computes them when they are
read (the XKY0 log), as the firmware's every-step values.

Two range tests of the firmware are reproduced as they act, not as their comments read: the
accel-gain taper compares the previous gain (at most 0.2) with the g-ratio limits, so the tilt
correction is off whenever the filtered accel is below 1 g and follows ``0.2 (3 - 2 n)^2``
above; the chi-square test of the velocity innovations uses the innovation variance's
off-diagonal with a + sign. Both are what SITL's XKY0 shows.
"""

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.ekf.gsf_layout import (
    G_ACC,
    G_ACC_GAIN,
    G_BUF,
    G_BUF_COUNT,
    G_BUF_HEAD,
    G_ENABLED,
    G_FUSING,
    G_GBIAS,
    G_N_CLIPS,
    G_R,
    G_RUN,
    G_SUM_DANG,
    G_SUM_DT,
    G_SUM_DVEL,
    G_TILT_ALIGNED,
    G_W,
    G_YAW,
    G_YAW_VAR,
    M_COS,
    M_INNOV,
    M_P,
    M_S,
    M_SIN,
    M_VE,
    M_VN,
    M_YAW,
    MODEL_BASE,
    MODEL_STRIDE,
    N_GSF,
    N_MODELS,
    NBUF_STEPS,
    STEP_ROW,
)
from tlm_sim.ekf.lanes import lane_imu_sources
from tlm_sim.ekf.layout import (
    BGX,
    C_DT,
    C_GPS_DELAY,
    C_GSF_RUN_MASK,
    C_TARGET_DT,
    C_VELNE_NSE,
    GPS_SACC_F,
    GPS_SPD_FAIL,
    IMU_INDEX,
)

GYRO_NOISE = 0.1  # yaw rate noise of the covariance prediction [rad/s]
ACCEL_NOISE = 2.0  # horizontal accel noise of the covariance prediction [m/s^2]
TILT_GAIN = 0.2  # AHRS tilt correction gain at 1 g [1/s]
GYRO_BIAS_GAIN = 0.04  # AHRS gyro bias learning gain [1/s]
ACCEL_FILT_RATIO = 10.0  # tilt-loop time constant / accel low-pass time constant
BIAS_LIMIT = math.radians(5.0)  # AHRS gyro bias limit [rad/s]
BIAS_SPIN_MAX = 0.175  # no bias learning above this rotation rate [rad/s]
MIN_VEL_ACC = 0.5  # floor of the GPS velocity accuracy [m/s]
MIN_VAR = 1e-6  # floor of the covariance diagonal
MIN_WEIGHT = 1e-5  # floor of a model weight
TEST_RATIO_MAX = 25.0  # innovations are compressed beyond 5 sigma
YAW_INCREMENT = 2.0 * math.pi / N_MODELS  # spacing of the initial yaw hypotheses [rad]


@tick_jit
def gsf_init(gsf, cfg):
    """Every lane's estimator off and empty; lane i gets one if bit i of EK3_GSF_RUN_MASK
    (cfg C_GSF_RUN_MASK) is set."""
    mask = int(cfg[C_GSF_RUN_MASK])
    for ln in range(gsf.shape[0]):
        for j in range(N_GSF):
            gsf[ln, j] = 0.0
        gsf[ln, G_ENABLED] = 1.0 if (mask >> ln) & 1 else 0.0
        gsf[ln, G_BUF_HEAD] = -1.0


@tick_jit
def gsf_update(gsf, ekf, cfg, inputs):
    """One main-loop tick of every lane's estimator, after the EKF's (its gyro bias, GPS checks).

    inputs: the tick's :class:`tlm_sim.bundles.EkfInputs`, as the EKF had them: the IMU deltas
    [rad, m/s, body FRD] and health (as :func:`tlm_sim.ekf.lanes.lane_imu_sources` reads it),
    a new GPS epoch's NE velocity [m/s] and 3-D fix, whether the vehicle is armed.
    """
    dang, dvel, imu_ok, armed = inputs.dang, inputs.dvel, inputs.imu_ok, inputs.armed
    gps_new, gps_fix = inputs.gps_new, inputs.gps_fix
    gps_vn, gps_ve = inputs.gps_vel[0], inputs.gps_vel[1]
    for ln in range(gsf.shape[0]):
        g = gsf[ln]
        if g[G_ENABLED] == 0.0:
            continue
        e = ekf[ln]
        if not armed or e[GPS_SPD_FAIL] != 0.0:
            g[G_RUN] = 0.0
        elif g[G_RUN] == 0.0:  # flying or about to: start with the lane's gyro bias
            g[G_RUN] = 1.0
            for k in range(3):
                g[G_GBIAS + k] = e[BGX + k]
        if _delay_line(g, cfg, int(e[IMU_INDEX]), dang, dvel, imu_ok):
            gsf_step(g)
        if gps_new and gps_fix and g[G_RUN] != 0.0 and g[G_TILT_ALIGNED] != 0.0:
            gsf_fuse_vel(g, gps_vn, gps_ve, max(e[GPS_SACC_F], cfg[C_VELNE_NSE]))


@inline_jit
def _delay_line(g, cfg, imu, dang, dvel, imu_ok):
    """Add this tick's deltas of the lane's IMU to the step sums; a complete step (C_TARGET_DT)
    goes into the delay line. True when a step C_GPS_DELAY old is out in G_SUM_* to run."""
    gi, ai = lane_imu_sources(imu, imu_ok, dang.shape[0])
    if gi < 0 or ai < 0:
        return False
    dt = cfg[C_DT]
    for k in range(3):
        g[G_SUM_DANG + k] += dang[gi, k]
        g[G_SUM_DVEL + k] += dvel[ai, k]
    g[G_SUM_DT] += dt
    if g[G_SUM_DT] < cfg[C_TARGET_DT] - 0.5 * dt:
        return False
    head = (int(g[G_BUF_HEAD]) + 1) % NBUF_STEPS
    n = min(int(cfg[C_GPS_DELAY] / g[G_SUM_DT] + 0.5), NBUF_STEPS - 1)
    row = G_BUF + head * STEP_ROW
    for k in range(7):  # the new step in, G_SUM_* cleared (the row layout follows G_SUM_*)
        g[row + k] = g[G_SUM_DANG + k]
        g[G_SUM_DANG + k] = 0.0
    g[G_BUF_HEAD] = head
    count = min(g[G_BUF_COUNT] + 1.0, float(NBUF_STEPS))
    g[G_BUF_COUNT] = count
    if count <= n:
        return False
    old = G_BUF + ((head - n) % NBUF_STEPS) * STEP_ROW
    for k in range(7):  # the delayed step out into G_SUM_* (gsf_step clears it)
        g[G_SUM_DANG + k] = g[old + k]
    return True


@tick_jit
def gsf_step(g):
    """EKFGSF_yaw::update on the summed delayed deltas (then cleared): accel low-pass, tilt
    alignment, tilt-correction gain, the AHRS prediction and, while fusing, every model's EKF
    prediction (the composite yaw: :func:`gsf_refresh`)."""
    dt = g[G_SUM_DT]
    dax, day, daz = g[G_SUM_DANG], g[G_SUM_DANG + 1], g[G_SUM_DANG + 2]
    dvx, dvy, dvz = g[G_SUM_DVEL], g[G_SUM_DVEL + 1], g[G_SUM_DVEL + 2]
    for k in range(3):
        g[G_SUM_DANG + k] = 0.0
        g[G_SUM_DVEL + k] = 0.0
    g[G_SUM_DT] = 0.0
    coef = min(ACCEL_FILT_RATIO * dt * TILT_GAIN, 1.0)
    inv = 1.0 / max(dt, 0.001)
    ax, ay, az = dvx * inv, dvy * inv, dvz * inv
    g[G_ACC] = g[G_ACC] * (1.0 - coef) + ax * coef
    g[G_ACC + 1] = g[G_ACC + 1] * (1.0 - coef) + ay * coef
    g[G_ACC + 2] = g[G_ACC + 2] * (1.0 - coef) + az * coef
    if g[G_TILT_ALIGNED] == 0.0:
        n2 = ax * ax + ay * ay + az * az
        if (0.9 * GRAVITY_MSS) ** 2 < n2 < (1.1 * GRAVITY_MSS) ** 2:
            _align_tilt(g, dvx, dvy, dvz)
            g[G_TILT_ALIGNED] = 1.0
            g[G_ACC], g[G_ACC + 1], g[G_ACC + 2] = ax, ay, az
        return
    norm = math.sqrt(g[G_ACC] ** 2 + g[G_ACC + 1] ** 2 + g[G_ACC + 2] ** 2)
    ng = norm / GRAVITY_MSS
    # the firmware's taper (see the module docstring): off below 1 g
    if ng > 1.0 and g[G_ACC_GAIN] <= 1.5:
        g[G_ACC_GAIN] = TILT_GAIN * (3.0 - 2.0 * ng) ** 2
    elif ng <= 1.0 and g[G_ACC_GAIN] > 0.5:
        g[G_ACC_GAIN] = TILT_GAIN * (2.0 * ng - 1.0) ** 2
    else:
        g[G_ACC_GAIN] = 0.0
    _ahrs_predict(g, dax, day, daz, dt, norm)
    if g[G_FUSING] == 0.0:
        return
    r = G_R
    dvn = g[r] * dvx + g[r + 1] * dvy + g[r + 2] * dvz
    dve = g[r + 3] * dvx + g[r + 4] * dvy + g[r + 5] * dvz
    for m in range(N_MODELS):
        _ekf_predict(g, MODEL_BASE + m * MODEL_STRIDE, dvn, dve, dt)
    if g[G_RUN] == 0.0:
        g[G_FUSING] = 0.0


@tick_jit
def gsf_refresh(g):
    """While the bank fuses: every model's yaw state from its AHRS, then the weighted composite
    yaw (as a vector sum, free of wrapping) and its variance (G_YAW, G_YAW_VAR)."""
    if g[G_FUSING] == 0.0:
        return
    yc = 0.0
    ys = 0.0
    for m in range(N_MODELS):
        b = MODEL_BASE + m * MODEL_STRIDE
        y = _model_yaw(g, b)
        g[b + M_YAW] = y
        yc += g[G_W + m] * math.cos(y)
        ys += g[G_W + m] * math.sin(y)
    yaw = math.atan2(ys, yc)
    var = 0.0
    for m in range(N_MODELS):
        b = MODEL_BASE + m * MODEL_STRIDE
        d = _wrap_pi(g[b + M_YAW] - yaw)
        var += g[G_W + m] * (g[b + M_P + 8] + d * d)
    g[G_YAW] = yaw
    g[G_YAW_VAR] = var


@tick_jit
def _wrap_pi(a):
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@inline_jit
def _ahrs_predict(g, dax, day, daz, dt, norm):
    """The AHRS step: tilt correction towards the filtered accel (k x a, k the earth down axis
    in body), gyro bias learning below BIAS_SPIN_MAX, rotation by the corrected delta angle."""
    cx = cy = cz = 0.0
    gain = g[G_ACC_GAIN]
    if gain > 0.0:
        kx, ky, kz = g[G_R + 6], g[G_R + 7], g[G_R + 8]
        ax, ay, az = g[G_ACC], g[G_ACC + 1], g[G_ACC + 2]
        f = gain / norm
        cx = (ky * az - kz * ay) * f
        cy = (kz * ax - kx * az) * f
        cz = (kx * ay - ky * ax) * f
    rx, ry, rz = dax / dt, day / dt, daz / dt
    if rx * rx + ry * ry + rz * rz < BIAS_SPIN_MAX * BIAS_SPIN_MAX:
        _learn_bias(g, G_GBIAS, cx * (GYRO_BIAS_GAIN * dt))
        _learn_bias(g, G_GBIAS + 1, cy * (GYRO_BIAS_GAIN * dt))
        _learn_bias(g, G_GBIAS + 2, cz * (GYRO_BIAS_GAIN * dt))
    gx = dax + (cx - g[G_GBIAS]) * dt
    gy = day + (cy - g[G_GBIAS + 1]) * dt
    gz = daz + (cz - g[G_GBIAS + 2]) * dt
    for i in range(3):  # R (I + [d x]), then each row back to unit length (linearised)
        r = G_R + 3 * i
        x, y, z = g[r], g[r + 1], g[r + 2]
        nx = x + y * gz - z * gy
        ny = y + z * gx - x * gz
        nz = z + x * gy - y * gx
        n2 = nx * nx + ny * ny + nz * nz
        f = 1.5 - 0.5 * n2 if n2 > 0.0 else 1.0
        g[r], g[r + 1], g[r + 2] = nx * f, ny * f, nz * f


@tick_jit
def _learn_bias(g, j, step):
    """One axis of an AHRS gyro bias moved by -step, limited to BIAS_LIMIT (NaN -> 0)."""
    v = g[j] - step
    if math.isnan(v):
        v = 0.0
    g[j] = min(max(v, -BIAS_LIMIT), BIAS_LIMIT)


@tick_jit
def _model_yaw(g, b):
    """The yaw of model b's AHRS (Rz(offset) G_R): its 321 Euler yaw, or its 312 first rotation
    when the body x axis is nearer the vertical than the y axis (no gimbal lock)."""
    c, s = g[b + M_COS], g[b + M_SIN]
    r = G_R
    if abs(g[r + 6]) < abs(g[r + 7]):
        return math.atan2(s * g[r] + c * g[r + 3], c * g[r] - s * g[r + 3])
    return math.atan2(-(c * g[r + 1] - s * g[r + 4]), s * g[r + 1] + c * g[r + 4])


@inline_jit
def _ekf_predict(g, b, dvn, dve, dt):
    """One model's EKF prediction from the delta velocity rotated to NED by the AHRS (dvn,
    dve [m/s], offset 0): turned by the model's offset and added to its NE velocity;
    covariance F P F' + Q with F = [[1, 0, -dvE], [0, 1, dvN], [0, 0, 1]] and
    Q = diag(q, q, q_yaw) (equal forward/right accel noise; the yaw state is its AHRS's,
    :func:`gsf_refresh`)."""
    c, s = g[b + M_COS], g[b + M_SIN]
    n = c * dvn - s * dve
    e = s * dvn + c * dve
    g[b + M_VN] += n
    g[b + M_VE] += e
    q = (ACCEL_NOISE * dt) ** 2
    q_yaw = (GYRO_NOISE * dt) ** 2
    p = b + M_P
    p00, p01, p02 = g[p], g[p + 1], g[p + 2]
    p11, p12, p22 = g[p + 4], g[p + 5], g[p + 8]
    n00 = max(p00 - 2.0 * e * p02 + e * e * p22 + q, MIN_VAR)
    n01 = p01 - e * p12 + n * p02 - e * n * p22
    n02 = p02 - e * p22
    n11 = max(p11 + 2.0 * n * p12 + n * n * p22 + q, MIN_VAR)
    n12 = p12 + n * p22
    n22 = max(p22 + q_yaw, MIN_VAR)
    _set_sym(g, p, (n00, n01, n02, n11, n12, n22))


@tick_jit
def _set_sym(g, p, n):
    """Store a symmetric 3x3 matrix row-major at g[p:p + 9]; n: its upper triangle (n00, n01,
    n02, n11, n12, n22)."""
    n00, n01, n02, n11, n12, n22 = n
    g[p], g[p + 1], g[p + 2] = n00, n01, n02
    g[p + 3], g[p + 4], g[p + 5] = n01, n11, n12
    g[p + 6], g[p + 7], g[p + 8] = n02, n12, n22


@tick_jit
def _correct(g, b, vn, ve, obs_var):
    """One model's GPS NE velocity fusion (innovations compressed to 5 sigma); the yaw change
    is applied to its AHRS. False when the innovation variance is singular (nothing fused)."""
    p = b + M_P
    i0 = g[b + M_VN] - vn
    i1 = g[b + M_VE] - ve
    g[b + M_INNOV] = i0
    g[b + M_INNOV + 1] = i1
    s00 = g[p] + obs_var
    s11 = g[p + 4] + obs_var
    s01 = g[p + 1]
    g[b + M_S], g[b + M_S + 1], g[b + M_S + 2], g[b + M_S + 3] = s00, s01, s01, s11
    det = s00 * s11 - s01 * s01
    if abs(det) <= 1e-6:
        return False
    # the firmware's test ratio (+ sign on the off-diagonal, module docstring)
    ratio = (i0 * (i0 * s11 + i1 * s01) + i1 * (i0 * s01 + i1 * s00)) / det
    scale = math.sqrt(TEST_RATIO_MAX / ratio) if ratio > TEST_RATIO_MAX else 1.0
    # K = P H' S^-1 (3 x 2), P -= K S K'
    k00 = (g[p] * s11 - g[p + 1] * s01) / det
    k01 = (g[p + 1] * s00 - g[p] * s01) / det
    k10 = (g[p + 3] * s11 - g[p + 4] * s01) / det
    k11 = (g[p + 4] * s00 - g[p + 3] * s01) / det
    k20 = (g[p + 6] * s11 - g[p + 7] * s01) / det
    k21 = (g[p + 7] * s00 - g[p + 6] * s01) / det
    # (K S) row r = (k_r0 s00 + k_r1 s01, k_r0 s01 + k_r1 s11) = P[r, 0:2]
    n00 = max(g[p] - (g[p] * k00 + g[p + 1] * k01), MIN_VAR)
    n01 = g[p + 1] - (g[p] * k10 + g[p + 1] * k11)
    n02 = g[p + 2] - (g[p] * k20 + g[p + 1] * k21)
    n11 = max(g[p + 4] - (g[p + 3] * k10 + g[p + 4] * k11), MIN_VAR)
    n12 = g[p + 5] - (g[p + 3] * k20 + g[p + 4] * k21)
    n22 = max(g[p + 8] - (g[p + 6] * k20 + g[p + 7] * k21), MIN_VAR)
    _set_sym(g, p, (n00, n01, n02, n11, n12, n22))
    g[b + M_VN] -= (k00 * i0 + k01 * i1) * scale
    g[b + M_VE] -= (k10 * i0 + k11 * i1) * scale
    dyaw = -(k20 * i0 + k21 * i1) * scale
    _turn(g, b, math.cos(dyaw), math.sin(dyaw))
    return True


@tick_jit
def _turn(g, b, c, s):
    """Turn model b's AHRS about the earth vertical by the angle of unit vector (c, s): its
    heading offset, kept unit length (linearised)."""
    oc, os_ = g[b + M_COS], g[b + M_SIN]
    nc = oc * c - os_ * s
    ns = os_ * c + oc * s
    f = 1.5 - 0.5 * (nc * nc + ns * ns)
    g[b + M_COS] = nc * f
    g[b + M_SIN] = ns * f


@tick_jit
def _density(g, b):
    """Likelihood of a model's last innovations under a zero-mean Gaussian with covariance S."""
    s00, s01, s10, s11 = g[b + M_S], g[b + M_S + 1], g[b + M_S + 2], g[b + M_S + 3]
    inv_det = 1.0 / max(s00 * s11 - s01 * s10, 1e-12)
    i0 = g[b + M_INNOV]
    i1 = g[b + M_INNOV + 1]
    md = (i0 * (s11 * i0 - s01 * i1) + i1 * (s00 * i1 - s10 * i0)) * inv_det
    return math.exp(-0.5 * md) * math.sqrt(inv_det) / (2.0 * math.pi)


@tick_jit
def gsf_fuse_vel(g, vn, ve, vel_acc):
    """EKFGSF_yaw::fuseVelData: GPS NE velocity [m/s] with its 1-sigma accuracy [m/s]. The
    first one after the bank started aligns it; later ones update every model and the weights
    (a reset when every weight is at the floor)."""
    obs_var = max(vel_acc, MIN_VEL_ACC) ** 2
    if g[G_FUSING] == 0.0:
        gsf_reset(g)
        for m in range(N_MODELS):
            b = MODEL_BASE + m * MODEL_STRIDE
            g[b + M_VN] = vn
            g[b + M_VE] = ve
            g[b + M_P] = obs_var
            g[b + M_P + 4] = obs_var
        _align_yaw(g)
        g[G_FUSING] = 1.0
        return
    ok = True
    for m in range(N_MODELS):
        if not _correct(g, MODEL_BASE + m * MODEL_STRIDE, vn, ve, obs_var):
            ok = False
    if not ok:
        return
    total = 0.0
    clips = 0
    for m in range(N_MODELS):
        w = _density(g, MODEL_BASE + m * MODEL_STRIDE) * g[G_W + m]
        if w < MIN_WEIGHT:
            clips += 1
            w = MIN_WEIGHT
        g[G_W + m] = w
        total += w
    g[G_N_CLIPS] = clips
    if clips < N_MODELS:
        for m in range(N_MODELS):
            g[G_W + m] /= total
    else:
        gsf_reset(g)


@tick_jit
def gsf_reset(g):
    """EKF states and weights back to the start (the AHRS filters keep theirs): zero velocity,
    yaws spread evenly over +-180 deg with the half spacing as their uncertainty, equal
    weights; the fusion stops until the next GPS velocity aligns the bank again."""
    g[G_FUSING] = 0.0
    var = (0.5 * YAW_INCREMENT) ** 2
    for m in range(N_MODELS):
        b = MODEL_BASE + m * MODEL_STRIDE
        g[b + M_VN] = 0.0
        g[b + M_VE] = 0.0
        g[b + M_YAW] = -math.pi + (0.5 + m) * YAW_INCREMENT
        for j in range(9):
            g[b + M_P + j] = 0.0
        g[b + M_P + 8] = var
        for j in range(4):
            g[b + M_S + j] = 0.0
        g[b + M_INNOV] = 0.0
        g[b + M_INNOV + 1] = 0.0
        g[G_W + m] = 1.0 / N_MODELS
    g[G_YAW] = 0.0
    g[G_YAW_VAR] = var


@inline_jit
def _align_tilt(g, dvx, dvy, dvz):
    """Every model's AHRS level from one delta velocity (the accel assumed to be gravity), yaw
    zero: rows north, east, down of the earth axes in body."""
    n = math.sqrt(dvx * dvx + dvy * dvy + dvz * dvz)
    dx, dy, dz = -dvx / n, -dvy / n, -dvz / n
    nx, ny, nz = 1.0 - dx * dx, -dx * dy, -dx * dz  # body x minus its down component
    f = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    nx, ny, nz = nx * f, ny * f, nz * f
    ex, ey, ez = dy * nz - dz * ny, dz * nx - dx * nz, dx * ny - dy * nx
    r = G_R
    g[r], g[r + 1], g[r + 2] = nx, ny, nz
    g[r + 3], g[r + 4], g[r + 5] = ex, ey, ez
    g[r + 6], g[r + 7], g[r + 8] = dx, dy, dz
    for m in range(N_MODELS):
        g[MODEL_BASE + m * MODEL_STRIDE + M_COS] = 1.0
        g[MODEL_BASE + m * MODEL_STRIDE + M_SIN] = 0.0


@inline_jit
def _align_yaw(g):
    """Each model's AHRS turned to its EKF yaw (the hypothesis), keeping its tilt: the heading
    offset becomes the hypothesis minus the AHRS's yaw (321 Euler yaw, or the 312 first
    rotation when the body x axis is nearer the vertical than the y axis: a turn about the
    vertical adds to either)."""
    r = G_R
    if abs(g[r + 6]) < abs(g[r + 7]):
        yaw0 = math.atan2(g[r + 3], g[r])
    else:
        yaw0 = math.atan2(-g[r + 1], g[r + 4])
    for m in range(N_MODELS):
        b = MODEL_BASE + m * MODEL_STRIDE
        a = g[b + M_YAW] - yaw0
        g[b + M_COS] = math.cos(a)
        g[b + M_SIN] = math.sin(a)
