"""Per-tick EKF driver: lane prediction, measurement dispatch, primary-lane selection, outputs.

Call order per 400 Hz main-loop tick (or use :func:`ekf_update`, which does exactly this):

1. :func:`ekf_predict` -- every lane integrates its own IMU's delta angle/velocity and moves
   its output towards its filter state (output observer, EK3_TAU_OUTPUT); covariance
   prediction runs when >= EKF3's 12 ms target of IMU data has accumulated (every 5 ticks);
   alignment, aiding-mode transitions, constant-position fusion and status flags.
2. :func:`ekf_fuse_gps` / :func:`ekf_fuse_baro` when a new sample arrived; :func:`ekf_fuse_mag`
   on every compass tick (each lane's compass choice, :mod:`tlm_sim.ekf.compass`).
3. :func:`ekf_select_primary` -- lane scores, health and the ERR 24-style primary switch.

Controllers read the primary lane, via :func:`ekf_output` or directly
``ekf[int(sel[SEL_PRIMARY]), QW..]`` (indices in :mod:`tlm_sim.ekf.layout`).
"""

from __future__ import annotations

import math

from tlm_sim._jit import inline_jit, tick_jit
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.ekf.compass import lane_read_mag
from tlm_sim.ekf.core import (
    buffer_push,
    filter_now,
    output_track,
    predict_covariance,
    propagate,
    reset_block,
    set_quat_euler,
)
from tlm_sim.ekf.fusion import (
    is_finite_lane,
    lane_fuse_baro,
    lane_fuse_constpos,
    lane_fuse_gps,
    lane_gps_accuracy,
    stop_aiding,
    update_flags,
)
from tlm_sim.ekf.layout import (
    ACC_DT,
    AID_ABSOLUTE,
    AID_MODE,
    AID_NONE,
    ALIGN_DT,
    ALIGN_FX,
    ALIGN_FY,
    ALIGN_FZ,
    ALIGNED,
    BAD_IMU,
    BAX,
    BGX,
    BUF_COUNT,
    BUF_HEAD,
    BUF_OFS,
    C_ABIAS_PNSE,
    C_ACC_PNSE,
    C_ALIGN_TIME,
    C_ALT_NSE,
    C_BAD_IMU_ACC_NSE,
    C_BAD_IMU_HOLD,
    C_BOOT,
    C_DT,
    C_EKF_START,
    C_ERR_THRESH,
    C_GBIAS_PNSE,
    C_GPS_DELAY,
    C_GYRO_PNSE,
    C_LANE_IMU,
    C_LANE_INIT_T,
    C_SCORE_LAG,
    C_SELECT_T,
    C_TARGET_DT,
    C_TAU_OUTPUT,
    C_TILT_DRIFT,
    CONSTPOS_E,
    CONSTPOS_N,
    DT_EKF_AVG,
    ES_ATT,
    ES_BA,
    ES_BG,
    ES_POS,
    ES_VEL,
    F_ATTITUDE,
    F_CONST_POS,
    F_HORIZ_POS,
    F_HORIZ_VEL,
    F_USING_GPS,
    F_VERT_POS,
    FAULT,
    GPS_GLITCHING,
    GPS_NOISE_SCALE,
    HEALTHY,
    HGT_TR,
    IMU_INDEX,
    IMU_OK,
    INNOV_HGT,
    INNOV_VD,
    LANE_STRIDE,
    LIFE_EVENTS,
    LS_EVENTS,
    LS_HEALTHY,
    LS_IMU,
    LS_MAG,
    LS_ORIGIN_OK,
    MAG_HAVE,
    MAG_IDX,
    MAG_TR,
    MAX_LANES,
    N_EKF,
    N_PREDICT,
    NS,
    O_ALIGNED,
    O_BAD_IMU,
    O_BAX,
    O_BGX,
    O_F_ATTITUDE,
    O_F_CONST_POS,
    O_F_HORIZ_POS,
    O_F_HORIZ_VEL,
    O_F_USING_GPS,
    O_F_VERT_POS,
    O_GPS_GLITCHING,
    O_HEALTHY,
    O_HGT_TR,
    O_IMU,
    O_INNOV_HGT,
    O_INNOV_VD,
    O_LANES,
    O_MAG_TR,
    O_N_LANES,
    O_ORIGIN_OK,
    O_PITCH,
    O_POS_RESET_COUNT,
    O_POS_TR,
    O_PRIMARY,
    O_PRIMARY_CHANGES,
    O_QW,
    O_R00,
    O_ROLL,
    O_SQRT_HGT,
    O_SQRT_MAG,
    O_SQRT_POS,
    O_SQRT_VEL,
    O_TILT_DONE,
    O_VEL_RESET_COUNT,
    O_VEL_TR,
    O_VN,
    O_YAW,
    O_YAW_DONE,
    ORIGIN_OK,
    OUT_EPN,
    OUT_IPN,
    P0,
    POS_RESET_COUNT,
    POS_TIMEOUT,
    POS_TR,
    QW,
    QX,
    QY,
    QZ,
    R00,
    R20,
    R21,
    R22,
    RNG_ON_GND,
    SCORE,
    SCORE_PREV,
    SEL_CHANGES,
    SEL_HEALTHY_SINCE,
    SEL_N_LANES,
    SEL_PRIMARY,
    SEL_REL_ERR,
    SEL_RUN,
    SEL_T_PRIMARY,
    SEL_T_SWITCH,
    T_ALIGNED,
    T_BAD_IMU,
    T_BARO_LAST,
    T_CONSTPOS,
    T_GPS_CHK_FAIL,
    T_GPS_FUSED,
    T_HGT_PASS,
    T_LAST,
    T_MAG_PASS,
    T_POS_PASS,
    T_SCORE,
    T_VEL_PASS,
    TERRAIN,
    TILT_BAD_T,
    TILT_DONE,
    TILT_RESET_COUNT,
    VEL_RESET_COUNT,
    VEL_TR,
    VN,
    YAW_DONE,
)
from tlm_sim.ekf.lifecycle import (
    EKF3_INIT_ROT_SD,
    lane_alignment_checks,
    lane_gps_checks,
    lane_started,
    mag_heading,
)
from tlm_sim.rotation import quat_to_euler

# initial standard deviations at alignment
INIT_TILT_SD = 0.05  # rad
STATIC_GYRO = 0.1  # rad/s: IMU at rest below this rotation rate
STATIC_ACC = 0.5  # m/s^2: ... and with |specific force| this close to g
STATIC_TILT_COS = math.cos(math.radians(30.0))  # re-level beyond 30 deg of tilt error
STATIC_TIME = 0.25  # s at rest with that error before re-levelling
INIT_YAW_SD = 0.1  # rad
INIT_VEL_SD = 0.5  # m/s
INIT_POS_SD = 1.0  # m
INIT_GBIAS_SD = math.radians(2.5)  # rad/s (EKF3: 2.5 deg/s)
INIT_ABIAS_SD = 0.1  # m/s^2


@tick_jit
def ekf_init(ekf, sel, cfg):
    """Reset all lanes to "waiting for alignment" and the selector to lane 0 primary.

    ekf.shape[0] must equal cfg[C_N_LANES]; lane i integrates IMU cfg[C_LANE_IMU + i].
    """
    n = ekf.shape[0]
    for i in range(n):
        for j in range(N_EKF):
            ekf[i, j] = 0.0
        ekf[i, QW] = 1.0
        ekf[i, T_LAST] = -1.0
        ekf[i, AID_MODE] = AID_NONE
        ekf[i, IMU_INDEX] = cfg[C_LANE_IMU + i]
        ekf[i, IMU_OK] = 1.0
        ekf[i, BUF_HEAD] = -1.0
        ekf[i, T_BAD_IMU] = -1.0e9
        ekf[i, T_BARO_LAST] = -1.0e9
        ekf[i, DT_EKF_AVG] = cfg[C_TARGET_DT]
        ekf[i, T_GPS_CHK_FAIL] = -1.0
    for j in range(sel.shape[0]):
        sel[j] = 0.0
    sel[SEL_N_LANES] = n
    sel[SEL_T_SWITCH] = -1.0
    sel[SEL_HEALTHY_SINCE] = -1.0
    for i in range(MAX_LANES):
        sel[SEL_T_PRIMARY + i] = -1.0e9


@tick_jit
def _align(e, cfg, t):
    """Tilt from the averaged specific force, yaw from the magnetometer; initialise P."""
    f = 1.0 / e[ALIGN_DT]
    fx = e[ALIGN_FX] * f
    fy = e[ALIGN_FY] * f
    fz = e[ALIGN_FZ] * f
    roll = math.atan2(-fy, -fz)
    pitch = math.atan2(fx, math.sqrt(fy * fy + fz * fz))
    set_quat_euler(e, roll, pitch, mag_heading(e, cfg, roll, pitch))
    for j in range(VN, BAX + 3):
        e[j] = 0.0
    for j in range(NS * NS):
        e[P0 + j] = 0.0
    # the boot phase starts from EKF3's initial attitude uncertainty (tilt alignment waits for
    # it to fall below 5 deg); without it the lane starts aligned (tlm_sim.ekf.lifecycle)
    tilt_sd = EKF3_INIT_ROT_SD if cfg[C_BOOT] != 0.0 else INIT_TILT_SD
    reset_block(e, ES_ATT, 2, tilt_sd**2)
    reset_block(e, ES_ATT + 2, 1, INIT_YAW_SD**2)
    reset_block(e, ES_VEL, 3, INIT_VEL_SD**2)
    reset_block(e, ES_POS, 2, INIT_POS_SD**2)
    reset_block(e, ES_POS + 2, 1, cfg[C_ALT_NSE] ** 2)
    reset_block(e, ES_BG, 3, INIT_GBIAS_SD**2)
    reset_block(e, ES_BA, 3, INIT_ABIAS_SD**2)
    e[ACC_DT] = 0.0
    e[TERRAIN] = RNG_ON_GND  # EKF3 ResetHeight on the ground: the vehicle sits on the terrain
    e[ALIGNED] = 1.0
    e[T_ALIGNED] = t
    e[AID_MODE] = AID_NONE
    e[CONSTPOS_N] = 0.0
    e[CONSTPOS_E] = 0.0
    e[T_CONSTPOS] = t
    e[T_HGT_PASS] = t
    e[T_POS_PASS] = t
    e[T_VEL_PASS] = t
    e[T_MAG_PASS] = t
    e[T_GPS_FUSED] = -1.0e9
    e[POS_TIMEOUT] = 0.0
    e[GPS_NOISE_SCALE] = 1.0
    e[T_BAD_IMU] = -1.0e9
    e[BAD_IMU] = 0.0
    e[T_BARO_LAST] = -1.0e9
    e[BUF_HEAD] = -1.0
    e[BUF_COUNT] = 0.0
    for j in range(6):
        e[BUF_OFS + j] = 0.0
        e[OUT_EPN + j] = 0.0
        e[OUT_IPN + j] = 0.0
    lane_started(e, cfg)


@tick_jit
def _static_tilt_check(e, dang, dvel, gi, ai, dt):
    """Re-level a lane whose tilt is grossly wrong while its IMU is at rest (tlm model choice).

    After a tumble the simulated ground contact sets the vehicle level without a rotation the
    gyros could see (SITL's NO_MOVEMENT behaviour), which leaves the error-state filter with
    a tilt error far outside its small-angle model. EKF3 in the reference logs is level again
    within ~1 s of the impact; tlm reproduces that by re-aligning roll/pitch from the specific
    force (keeping yaw, resetting the attitude covariance) once the IMU has been at rest
    (|gyro| < STATIC_GYRO, | |f| - g | < STATIC_ACC) with a tilt error > STATIC_TILT_ERR for
    STATIC_TIME. Manoeuvres cannot trigger it: they rotate the vehicle or change |f|, and a
    30 deg error is beyond any steady-flight difference between estimated and sensed tilt.
    """
    if dt <= 0.0:
        return
    # the tests on the deltas, squared (|dang| > STATIC_GYRO dt, ...): no square root or
    # division on the every-tick path, which in hover and steady cruise passes the first two
    # tests and ends at the third
    ax, ay, az = dang[gi, 0], dang[gi, 1], dang[gi, 2]
    if ax * ax + ay * ay + az * az > (STATIC_GYRO * dt) ** 2:
        e[TILT_BAD_T] = 0.0
        return
    vx, vy, vz = dvel[ai, 0], dvel[ai, 1], dvel[ai, 2]
    dv2 = vx * vx + vy * vy + vz * vz
    lo = (GRAVITY_MSS - STATIC_ACC) * dt
    hi = (GRAVITY_MSS + STATIC_ACC) * dt
    if dv2 < lo * lo or dv2 > hi * hi:
        e[TILT_BAD_T] = 0.0
        return
    # estimated "down" in body axes (third row of the body->NED matrix) vs the sensed one:
    # the cosine of the angle between them, -(R2 . dvel) / |dvel|, above STATIC_TILT_COS
    c = -(e[R20] * vx + e[R21] * vy + e[R22] * vz)
    if c > 0.0 and c * c > STATIC_TILT_COS * STATIC_TILT_COS * dv2:
        e[TILT_BAD_T] = 0.0
        return
    fx, fy, fz = vx / dt, vy / dt, vz / dt
    e[TILT_BAD_T] += dt
    if e[TILT_BAD_T] < STATIC_TIME:
        return
    _, _, yaw = quat_to_euler(e[QW], e[QX], e[QY], e[QZ])
    set_quat_euler(e, math.atan2(-fy, -fz), math.atan2(fx, math.sqrt(fy * fy + fz * fz)), yaw)
    reset_block(e, ES_ATT, 2, INIT_TILT_SD**2)
    e[TILT_BAD_T] = 0.0
    e[TILT_RESET_COUNT] += 1.0


@tick_jit
def lane_imu_sources(imu, imu_ok, n_imu):
    """(gyro, accel) instance a lane whose own IMU is imu integrates this tick: its own sensor
    while it delivers samples, else the first one that does (EKF3's readIMUData: no lane
    switch, no message). With every accel stopped the lane goes on integrating its own
    accel's held (stale) sample, as EKF3 keeps reading its stale "first usable" accel; with
    every gyro stopped (which tlm refuses in a flight: SITL freezes) gi is -1 and the lane
    stops predicting. imu_ok[i]: accel i delivered samples this tick; imu_ok[n_imu + i]: gyro i
    did (a shorter imu_ok: the gyros follow the accels).

    EKF3 swaps in the bias it learnt separately for the borrowed sensor ("inactive bias"); tlm
    keeps the lane's bias states, which model what every tlm IMU shares (the common gyro drift;
    SIM_GYRn_BIAS and SIM_ACCn_BIAS differences between IMUs are not transferred)."""
    g0 = n_imu if imu_ok.shape[0] >= 2 * n_imu else 0
    if imu_ok[imu] != 0 and imu_ok[g0 + imu] != 0:
        return imu, imu  # the usual case: its own IMU delivers both
    ai = imu if imu_ok[imu] != 0 else -1
    gi = imu if imu_ok[g0 + imu] != 0 else -1
    for j in range(n_imu):
        if ai < 0 and imu_ok[j] != 0:
            ai = j
        if gi < 0 and imu_ok[g0 + j] != 0:
            gi = j
    if ai < 0:
        ai = imu
    return gi, ai


@tick_jit
def lane_predict(e, cfg, t, dang, dvel, imu_ok, armed):
    """One main-loop tick of one lane (see the module docstring); t in seconds."""
    dt = cfg[C_DT] if e[T_LAST] < 0.0 else t - e[T_LAST]
    e[T_LAST] = t
    if dt <= 0.0 or dt > 0.1:
        dt = cfg[C_DT]
    gi, ai = lane_imu_sources(int(e[IMU_INDEX]), imu_ok, dang.shape[0])
    if gi < 0 or ai < 0 or e[FAULT] != 0.0:
        e[IMU_OK] = 1.0 if gi >= 0 and ai >= 0 else 0.0
        update_flags(e, cfg, t)
        return
    e[IMU_OK] = 1.0
    if e[ALIGNED] == 0.0:
        if t < cfg[C_EKF_START] - cfg[C_ALIGN_TIME]:  # the EKF has not started yet (boot)
            update_flags(e, cfg, t)
            return
        e[ALIGN_FX] += dvel[ai, 0]
        e[ALIGN_FY] += dvel[ai, 1]
        e[ALIGN_FZ] += dvel[ai, 2]
        e[ALIGN_DT] += dt
        if e[ALIGN_DT] >= cfg[C_ALIGN_TIME] and e[MAG_HAVE] != 0.0:
            _align(e, cfg, t)
        update_flags(e, cfg, t)
        return
    _static_tilt_check(e, dang, dvel, gi, ai, dt)
    propagate(e, dang, dvel, gi, ai, dt)
    output_track(e, dt, cfg[C_TAU_OUTPUT], int(cfg[C_GPS_DELAY] / cfg[C_DT] + 0.5),
                 e[BAD_IMU] != 0.0)
    buffer_push(e)
    if e[ACC_DT] >= cfg[C_TARGET_DT] - 0.5 * dt:
        tt = e[ACC_DT]
        acc_nse = cfg[C_ACC_PNSE]
        if e[BAD_IMU] != 0.0:
            if t - e[T_BAD_IMU] >= cfg[C_BAD_IMU_HOLD]:
                e[BAD_IMU] = 0.0
            else:
                acc_nse = max(acc_nse, cfg[C_BAD_IMU_ACC_NSE])
        predict_covariance(
            e,
            (cfg[C_GYRO_PNSE] * tt) ** 2,
            (acc_nse * tt) ** 2,
            (cfg[C_GBIAS_PNSE] * tt) ** 2,
            (cfg[C_ABIAS_PNSE] * tt) ** 2,
        )
        e[N_PREDICT] += 1.0
        e[DT_EKF_AVG] = 0.98 * e[DT_EKF_AVG] + 0.02 * tt
        e[TERRAIN] = max(e[TERRAIN], filter_now(e, 2) + RNG_ON_GND)
        lane_alignment_checks(e, cfg)
        if not is_finite_lane(e):
            e[FAULT] = 1.0
            update_flags(e, cfg, t)
            return
    # aiding: absolute -> none after the tilt-drift time without GPS position or velocity
    if e[AID_MODE] == AID_ABSOLUTE:
        drift = cfg[C_TILT_DRIFT]
        if t - e[T_POS_PASS] > drift and t - e[T_VEL_PASS] > drift:
            stop_aiding(e, cfg, t)
    if e[AID_MODE] == AID_NONE:
        lane_fuse_constpos(e, cfg, t, armed)
    update_flags(e, cfg, t)


@tick_jit
def ekf_predict(ekf, cfg, t_us, dang, dvel, imu_ok, armed):
    """Predict all lanes by one main-loop tick.

    t_us: time since boot [us]; dang[imu, 0:3] delta angle [rad] and dvel[imu, 0:3] delta
    velocity [m/s] (body FRD) accumulated over the tick; imu_ok[imu] / imu_ok[N_IMU + imu]: 0
    when that IMU's accel / gyro samples stopped (:func:`lane_imu_sources`); armed: selects the
    constant-position noise (on-ground value while disarmed).
    """
    t = t_us * 1e-6
    for i in range(ekf.shape[0]):
        lane_predict(ekf[i], cfg, t, dang, dvel, imu_ok, armed)


@tick_jit
def ekf_fuse_gps(ekf, cfg, t_us, pos, vel, fix_3d):
    """New GPS sample: pos[0:3] NED [m] from the origin (only N, E are used; height comes from
    the baro), vel[0:3] NED [m/s], lagged by the assumed GPS delay (cfg C_GPS_DELAY). Nothing is
    fused unless fix_3d (a no-fix sample is how a GPS loss looks)."""
    if not fix_3d:
        return
    t = t_us * 1e-6
    for i in range(ekf.shape[0]):
        lane_fuse_gps(ekf[i], cfg, t, pos, vel)


@tick_jit
def ekf_gps_accuracy(ekf, cfg, t_us, gps):
    """A new 3-D-fix GPS sample's quality (call before :func:`ekf_update` fuses it): the
    reported accuracies, the satellite count and the flight checks of every lane
    (:func:`tlm_sim.ekf.fusion.lane_gps_accuracy`). gps: the epoch (``tlm_sim.sensors.layout``
    GE_*). Without calls the fusion uses the EK3_*_M_NSE noises and the tests pass."""
    t = t_us * 1e-6
    for i in range(ekf.shape[0]):
        lane_gps_accuracy(ekf[i], cfg, t, gps)


@tick_jit
def ekf_gps_checks(ekf, cfg, t_us, gps):
    """A new 3-D-fix GPS sample through each aligned lane's GPS checks (EKF3's
    calcGpsGoodToAlign, run on every sample, in flight too) and, with the boot phase, the
    origin (:func:`tlm_sim.ekf.lifecycle.lane_gps_checks`). gps: the epoch
    (``tlm_sim.sensors.layout`` GE_*: position NE [m], velocity NED [m/s], satellites, HDOP,
    accuracies [m])."""
    t = t_us * 1e-6
    for i in range(ekf.shape[0]):
        e = ekf[i]
        if e[ALIGNED] != 0.0 and e[FAULT] == 0.0:
            lane_gps_checks(e, cfg, t, gps)


@tick_jit
def ekf_fuse_baro(ekf, cfg, t_us, alt):
    """New baro sample: altitude above the origin [m, up]."""
    t = t_us * 1e-6
    for i in range(ekf.shape[0]):
        lane_fuse_baro(ekf[i], cfg, t, alt)


@tick_jit
def ekf_fuse_mag(ekf, cfg, t_us, mag, armed):
    """Compass tick: mag is the sensors' compass block (``tlm_sim.sensors.layout`` MAG records:
    body field [gauss], new sample, healthy, time); each lane fuses its own compass's new
    sample and changes compass when that one fails (:func:`tlm_sim.ekf.compass.lane_read_mag`)."""
    t = t_us * 1e-6
    for i in range(ekf.shape[0]):
        lane_read_mag(ekf[i], cfg, t, mag, armed)


@tick_jit
def lane_score(e):
    """EKF3 error score max(0.5 (vel + pos), hgt) of a lane (0 before alignment)."""
    if e[ALIGNED] == 0.0:
        return 0.0
    return max(0.5 * (e[VEL_TR] + e[POS_TR]), e[HGT_TR])


@tick_jit
def lane_healthy(e, cfg, t):
    """Lane health: aligned, IMU delivering, no fault, out of its first second, and not all of
    the velocity, position and height test ratios above 1."""
    if e[ALIGNED] == 0.0 or e[FAULT] != 0.0 or e[IMU_OK] == 0.0:
        return False
    if t - e[T_ALIGNED] < cfg[C_LANE_INIT_T]:
        return False
    return not (e[VEL_TR] > 1.0 and e[POS_TR] > 1.0 and e[HGT_TR] > 1.0)


@inline_jit
def _score_lanes(ekf, cfg, t):
    """Each lane's score (its previous one and the time [s] it changed kept) and health at
    time t [s]."""
    for i in range(ekf.shape[0]):
        e = ekf[i]
        score = lane_score(e)
        if score != e[SCORE]:
            e[SCORE_PREV] = e[SCORE]
            e[T_SCORE] = t
            e[SCORE] = score
        e[HEALTHY] = 1.0 if lane_healthy(e, cfg, t) else 0.0


@inline_jit
def _accumulate_rel_err(ekf, sel, cfg, t, p, sp):
    """The non-primary lanes' relative errors against primary p (score sp, seen C_SCORE_LAG
    late), see :func:`ekf_select_primary`."""
    sp_seen = ekf[p, SCORE_PREV] if t - ekf[p, T_SCORE] < cfg[C_SCORE_LAG] - 1e-9 else sp
    thr = max(cfg[C_ERR_THRESH], 0.05)
    for i in range(ekf.shape[0]):
        if i == p:
            continue
        d = ekf[i, SCORE] - sp_seen
        if d > 0.0 or d < -thr:
            sel[SEL_REL_ERR + i] = min(max(sel[SEL_REL_ERR + i] + d, -1.0), 1.0)


@inline_jit
def _latch_selection(sel, cfg, t, healthy_p):
    """Before the selection runs: it starts (latched) once the primary has been healthy for
    C_SELECT_T [s]."""
    if healthy_p:
        if sel[SEL_HEALTHY_SINCE] < 0.0:
            sel[SEL_HEALTHY_SINCE] = t
        if t - sel[SEL_HEALTHY_SINCE] >= cfg[C_SELECT_T]:
            sel[SEL_RUN] = 1.0
    else:
        sel[SEL_HEALTHY_SINCE] = -1.0


@inline_jit
def _switch_candidate(ekf, sel, cfg, t, p, imu_dead):
    """(lane, relative error) of the healthy lane with the lowest relative error that was not
    primary in the last C_SELECT_T [s] (any healthy lane when the primary's IMU is dead);
    (-1, 1e30) when there is none."""
    best = -1
    best_rel = 1.0e30
    for i in range(ekf.shape[0]):
        if i == p or ekf[i, HEALTHY] == 0.0:
            continue
        if t - sel[SEL_T_PRIMARY + i] < cfg[C_SELECT_T] and not imu_dead:
            continue
        if sel[SEL_REL_ERR + i] < best_rel:
            best_rel = sel[SEL_REL_ERR + i]
            best = i
    return best, best_rel


@tick_jit
def ekf_select_primary(ekf, sel, cfg, t_us, armed):
    """Update lane scores/health and switch the primary lane as EKF3 does (section 3.4).

    Relative errors of the non-primary lanes accumulate score_i - score_primary when positive
    or below -max(EK3_ERR_THRESH, 0.05), clamped to +-1; the primary's score enters them
    C_SCORE_LAG after it changed (EKF3's cores fuse a few IMU samples apart, so a sample that
    changes every lane's score shows in the other lanes first). Once the primary has been
    healthy for 10 s (latched) and while armed, the primary switches to the healthy lane with
    the lowest relative error that was not primary in the last 10 s when the primary is
    unhealthy, or its score exceeds 1 (and the candidate's is lower), or the candidate's
    relative error <= -0.5.
    If the primary's IMU stops delivering samples it switches at once (our addition).
    Returns True when the primary changed on this call.
    """
    t = t_us * 1e-6
    _score_lanes(ekf, cfg, t)
    p = int(sel[SEL_PRIMARY])
    sp = ekf[p, SCORE]
    _accumulate_rel_err(ekf, sel, cfg, t, p, sp)
    healthy_p = ekf[p, HEALTHY] != 0.0
    if sel[SEL_RUN] == 0.0:
        _latch_selection(sel, cfg, t, healthy_p)
    imu_dead = ekf[p, IMU_OK] == 0.0
    if not imu_dead and (sel[SEL_RUN] == 0.0 or not armed):
        return False
    best, best_rel = _switch_candidate(ekf, sel, cfg, t, p, imu_dead)
    if best < 0:
        return False
    switch = imu_dead or not healthy_p or (sp > 1.0 and ekf[best, SCORE] < sp) or best_rel <= -0.5
    if not switch:
        return False
    sel[SEL_T_PRIMARY + p] = t
    sel[SEL_PRIMARY] = best
    sel[SEL_CHANGES] += 1.0
    sel[SEL_T_SWITCH] = t
    for i in range(MAX_LANES):
        sel[SEL_REL_ERR + i] = 0.0
    return True


@tick_jit
def ekf_update(ekf, sel, cfg, t_us, inputs):
    """One main-loop tick: predict, fuse the new samples flagged, select the primary lane.

    t_us: time since boot [us]; inputs: the tick's :class:`tlm_sim.bundles.EkfInputs` (IMU
    deltas and health, the GPS epoch, the baro altitude, the compass block, whether armed:
    armed enables lane switching, sets the constant-position noise, resets the compass choice).
    Returns True when the primary lane changed on this tick (log ERR 24 then).
    """
    ekf_predict(ekf, cfg, t_us, inputs.dang, inputs.dvel, inputs.imu_ok, inputs.armed)
    if inputs.gps_new:
        ekf_fuse_gps(ekf, cfg, t_us, inputs.gps_pos, inputs.gps_vel, inputs.gps_fix)
    if inputs.baro_new:
        ekf_fuse_baro(ekf, cfg, t_us, inputs.baro_alt)
    if inputs.mag_new:
        ekf_fuse_mag(ekf, cfg, t_us, inputs.mag, inputs.armed)
    return ekf_select_primary(ekf, sel, cfg, t_us, inputs.armed)


@tick_jit
def ekf_output_nav(ekf, sel, out):
    """Fill the per-tick part of out[N_OUT] (layout O_*) from the primary lane: what the
    autopilot reads every main-loop tick (control.ahrs): primary index, attitude, velocity,
    position, biases, status flags, the lane's IMU and rotation matrix, innovations, test
    ratios and bad-IMU flag; what the pre-arm checks ask (health, alignment, GPS glitching,
    height test ratio, origin) and every lane's status record (O_LANES: health, origin, IMU,
    compass and the lifecycle events raised since the last call, which the lanes then forget:
    each event is published once, for the text log). :func:`ekf_output` fills the rest."""
    p = int(sel[SEL_PRIMARY])
    e = ekf[p]
    out[O_PRIMARY] = p
    for j in range(4):
        out[O_QW + j] = e[QW + j]
    for j in range(6):
        out[O_VN + j] = e[VN + j]
    for j in range(3):
        out[O_BGX + j] = e[BGX + j]
        out[O_BAX + j] = e[BAX + j]
    out[O_F_ATTITUDE] = e[F_ATTITUDE]
    out[O_F_HORIZ_VEL] = e[F_HORIZ_VEL]
    out[O_F_HORIZ_POS] = e[F_HORIZ_POS]
    out[O_F_VERT_POS] = e[F_VERT_POS]
    out[O_F_CONST_POS] = e[F_CONST_POS]
    out[O_F_USING_GPS] = e[F_USING_GPS]
    out[O_IMU] = e[IMU_INDEX]
    for j in range(9):
        out[O_R00 + j] = e[R00 + j]
    out[O_INNOV_VD] = e[INNOV_VD]
    out[O_INNOV_HGT] = e[INNOV_HGT]
    out[O_VEL_TR] = e[VEL_TR]
    out[O_POS_TR] = e[POS_TR]
    out[O_MAG_TR] = e[MAG_TR]
    out[O_BAD_IMU] = e[BAD_IMU]
    out[O_HEALTHY] = e[HEALTHY]
    out[O_ALIGNED] = e[ALIGNED]
    out[O_TILT_DONE] = e[TILT_DONE]
    out[O_YAW_DONE] = e[YAW_DONE]
    out[O_GPS_GLITCHING] = e[GPS_GLITCHING]
    out[O_HGT_TR] = e[HGT_TR]
    out[O_ORIGIN_OK] = e[ORIGIN_OK]
    out[O_N_LANES] = ekf.shape[0]
    for i in range(ekf.shape[0]):
        b = O_LANES + i * LANE_STRIDE
        out[b + LS_HEALTHY] = ekf[i, HEALTHY]
        out[b + LS_ORIGIN_OK] = ekf[i, ORIGIN_OK]
        out[b + LS_IMU] = ekf[i, IMU_INDEX]
        out[b + LS_MAG] = ekf[i, MAG_IDX]
        out[b + LS_EVENTS] = ekf[i, LIFE_EVENTS]  # published once: the lane forgets them
        ekf[i, LIFE_EVENTS] = 0.0


@tick_jit
def ekf_output(ekf, sel, out):
    """Fill all of out[N_OUT] (layout O_*) from the primary lane: :func:`ekf_output_nav`'s
    part, the Euler angles, the square roots of the test ratios (what ekf_check compares with
    FS_EKF_THRESH), the counters, and zeros in the status records of lanes that do not run.
    The only EKF block the rest of the vehicle reads (the flight fills the per-tick part every
    tick, all of it before the 10 Hz logging)."""
    ekf_output_nav(ekf, sel, out)
    e = ekf[int(sel[SEL_PRIMARY])]
    r, pt, y = quat_to_euler(e[QW], e[QX], e[QY], e[QZ])
    out[O_ROLL] = r
    out[O_PITCH] = pt
    out[O_YAW] = y
    out[O_SQRT_VEL] = math.sqrt(max(e[VEL_TR], 0.0))
    out[O_SQRT_POS] = math.sqrt(max(e[POS_TR], 0.0))
    out[O_SQRT_HGT] = math.sqrt(max(e[HGT_TR], 0.0))
    out[O_SQRT_MAG] = math.sqrt(max(e[MAG_TR], 0.0))
    out[O_PRIMARY_CHANGES] = sel[SEL_CHANGES]
    out[O_POS_RESET_COUNT] = e[POS_RESET_COUNT]
    out[O_VEL_RESET_COUNT] = e[VEL_RESET_COUNT]
    for k in range(O_LANES + ekf.shape[0] * LANE_STRIDE, O_LANES + MAX_LANES * LANE_STRIDE):
        out[k] = 0.0  # the status records of lanes that do not run


@tick_jit
def ekf_primary(sel):
    """Index of the primary lane."""
    return int(sel[SEL_PRIMARY])
