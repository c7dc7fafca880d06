"""Measurements of one lane: GPS velocity/position, baro height, magnetometer, constant position.

Every function takes one lane row ``e`` and the configuration ``cfg``; times ``t`` are seconds.
Delayed measurements (GPS, baro) are compared with the lane's past filter state (stored output
history plus the output tracking error, :func:`tlm_sim.ekf.core.filter_get`); corrections change
the filter state and reach the output through the output observer, resets move both.
Innovation test ratios follow EKF3: ``innovation^2 / (gate^2 * innovation variance)``
(velocity and position summed over their components), and a group is fused only when its ratio
is below 1.
"""

from __future__ import annotations

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.ekf.core import (
    apply_correction,
    clear_dx,
    filter_get,
    filter_now,
    fuse_h3,
    fuse_index,
    innov_var_h3,
    reset_block,
    shift_output,
)
from tlm_sim.ekf.layout import (
    AID_ABSOLUTE,
    AID_MODE,
    AID_NONE,
    ALIGNED,
    BAD_IMU,
    BARO_LAST,
    C_ABIAS_LIM,
    C_ALT_NSE,
    C_BAD_IMU_HOLD,
    C_BAD_IMU_TIMEOUT,
    C_BOOT,
    C_CONSTPOS_DT,
    C_DT,
    C_GBIAS_LIM,
    C_GLITCH_RAD,
    C_GPS_DELAY,
    C_HGT_DELAY,
    C_HGT_GATE,
    C_HGT_RETRY,
    C_MAG_D,
    C_MAG_E,
    C_MAG_GATE,
    C_MAG_N,
    C_MAG_NSE,
    C_NOAID_NSE,
    C_ONGROUND_NSE,
    C_POS_GATE,
    C_POS_RETRY,
    C_POS_RETRY_VEL,
    C_POSNE_NSE,
    C_USING_GPS_T,
    C_VEL_GATE,
    C_VELD_NSE,
    C_VELNE_NSE,
    C_YAW_GATE,
    C_YAW_NSE,
    CONSTPOS_E,
    CONSTPOS_N,
    ES_ATT,
    ES_POS,
    ES_VEL,
    F_ATTITUDE,
    F_CONST_POS,
    F_HORIZ_POS,
    F_HORIZ_VEL,
    F_USING_GPS,
    F_VERT_POS,
    F_VERT_VEL,
    FAULT,
    GPS_GLITCHING,
    GPS_GOOD,
    GPS_HACC_F,
    GPS_INNOV_FAIL,
    GPS_NOISE_SCALE,
    GPS_SACC_F,
    GPS_SPD_FAIL,
    HGT_RESET_COUNT,
    HGT_TR,
    IMU_OK,
    IN_FLIGHT,
    INFLIGHT_SEEN,
    INNOV_HGT,
    INNOV_MX,
    INNOV_MY,
    INNOV_MZ,
    INNOV_PE,
    INNOV_PN,
    INNOV_VD,
    INNOV_VE,
    INNOV_VN,
    INNOV_YAW,
    MAG_HAVE,
    MAG_LX,
    MAG_LY,
    MAG_LZ,
    MAG_TR,
    NS,
    OUT_EPD,
    OUT_EPN,
    OUT_EVD,
    P0,
    PD,
    PE,
    PN,
    POS_RESET_COUNT,
    POS_RESET_DE,
    POS_RESET_DN,
    POS_TIMEOUT,
    POS_TR,
    QW,
    QX,
    QY,
    QZ,
    R00,
    R01,
    R02,
    R10,
    R11,
    R12,
    R20,
    R21,
    R22,
    RNG_ON_GND,
    SACC_LPF,
    SACC_PEAK,
    T_BAD_IMU,
    T_BARO_LAST,
    T_CONSTPOS,
    T_GOOD_IMU,
    T_GPS_ACC,
    T_GPS_FUSED,
    T_HGT_PASS,
    T_INNOV_HIGH,
    T_INNOV_PASS,
    T_POS_PASS,
    T_VEL_PASS,
    TERRAIN,
    VD,
    VE,
    VEL_RESET_COUNT,
    VEL_RESET_DD,
    VEL_RESET_DE,
    VEL_RESET_DN,
    VEL_TR,
    VN,
    YAW_DONE,
)
from tlm_sim.ekf.lifecycle import (
    EKF3_INIT_ROT_SD,
    life_event,
    mag_heading,
    ready_to_use_gps,
    started_using_gps,
    yaw_align,
)
from tlm_sim.rotation import quat_to_euler
from tlm_sim.sensors.layout import GE_HACC, GE_NSATS, GE_SACC


@tick_jit
def _delay_ticks(cfg, delay_s):
    return int(delay_s / cfg[C_DT] + 0.5)


@tick_jit
def reset_vel_pos_to_gps(e, cfg, t, pos, vel, k):
    """Reset horizontal position and 3-D velocity to a GPS sample describing ``k`` ticks ago
    (pos: its position NE(D) [m], vel: its velocity NED [m/s]).

    The jump (GPS minus the past filter state) moves the filter state and the whole output
    history alike (the output tracking error is kept, as EKF3's resets shift the output
    buffer); the states are decorrelated and given the GPS noise variances.
    """
    pn, pe = pos[0], pos[1]
    vn, ve, vd = vel[0], vel[1], vel[2]
    dn = pn - filter_get(e, k, 0)
    de = pe - filter_get(e, k, 1)
    dvn = vn - filter_get(e, k, 3)
    dve = ve - filter_get(e, k, 4)
    dvd = vd - filter_get(e, k, 5)
    shift_output(e, 0, dn)
    shift_output(e, 1, de)
    shift_output(e, 3, dvn)
    shift_output(e, 4, dve)
    shift_output(e, 5, dvd)
    reset_block(e, ES_POS, 2, cfg[C_POSNE_NSE] ** 2)
    reset_block(e, ES_VEL, 2, cfg[C_VELNE_NSE] ** 2)
    reset_block(e, ES_VEL + 2, 1, cfg[C_VELD_NSE] ** 2)
    e[POS_RESET_COUNT] += 1.0
    e[POS_RESET_DN] = dn
    e[POS_RESET_DE] = de
    e[VEL_RESET_COUNT] += 1.0
    e[VEL_RESET_DN] = dvn
    e[VEL_RESET_DE] = dve
    e[VEL_RESET_DD] = dvd
    e[T_POS_PASS] = t
    e[T_VEL_PASS] = t
    e[T_GPS_FUSED] = t
    e[POS_TIMEOUT] = 0.0


@tick_jit
def reset_pos_to_gps(e, cfg, t, pn, pe, k):
    """EKF3's GPS position reset after a position timeout while GPS velocity still passes.

    The horizontal position (filter state and output history alike) jumps to the GPS sample
    describing ``k`` ticks ago; its variance becomes the GPS position noise; the test ratios
    are cleared (velocity is left alone)."""
    dn = pn - filter_get(e, k, 0)
    de = pe - filter_get(e, k, 1)
    shift_output(e, 0, dn)
    shift_output(e, 1, de)
    reset_block(e, ES_POS, 2, gps_pos_var(e, cfg))
    e[POS_RESET_COUNT] += 1.0
    e[POS_RESET_DN] = dn
    e[POS_RESET_DE] = de
    e[POS_TR] = 0.0
    e[VEL_TR] = 0.0
    e[T_POS_PASS] = t
    e[T_GPS_FUSED] = t
    e[POS_TIMEOUT] = 0.0


@tick_jit
def gps_pos_var(e, cfg):
    """Horizontal GPS position variance: the reported accuracy's envelope, at least the
    EK3_POSNE_M_NSE noise (EKF3 caps the accuracy at 100 m)."""
    return max(e[GPS_HACC_F], cfg[C_POSNE_NSE]) ** 2


@tick_jit
def lane_gps_accuracy(e, cfg, t, gps):
    """A 3-D-fix GPS sample's quality, as EKF3's readGpsData sees it before fusing the sample
    (gps: the epoch, ``tlm_sim.sensors.layout`` GE_*: reported accuracies, satellites).

    The reported horizontal and speed accuracies' decaying peak-hold envelopes (alpha = 0.0002
    per ms since the previous sample, tau 5 s) limited to [EK3_*_M_NSE, 100 m] and
    [.., 50 m/s]: the measurement noise of the position and velocity fusion; the noise scaler
    of the satellite count (gpsNoiseScaler). calcGpsGoodForFlight's two tests: the speed
    accuracy low-passed (0.2 per sample), peak-held with a 10 s decay, fails above 1.5 m/s and
    passes again below 1.0 m/s; the innovation consistency test (:func:`_gps_innovation_test`).
    """
    hacc, sacc, nsats = gps[GE_HACC], gps[GE_SACC], gps[GE_NSATS]
    dt = t - e[T_GPS_ACC] if e[T_GPS_ACC] > 0.0 else 0.0
    e[T_GPS_ACC] = t
    a = min(max(0.2 * dt, 0.0), 1.0)
    e[GPS_HACC_F] = max(min(max(e[GPS_HACC_F] * (1.0 - a), hacc), 100.0), cfg[C_POSNE_NSE])
    e[GPS_SACC_F] = max(min(max(e[GPS_SACC_F] * (1.0 - a), sacc), 50.0), cfg[C_VELNE_NSE])
    absolute = e[AID_MODE] == AID_ABSOLUTE
    if nsats >= 6.0 and absolute:
        e[GPS_NOISE_SCALE] = 1.0
    elif nsats >= 5.0 and absolute:
        e[GPS_NOISE_SCALE] = 1.4
    else:
        e[GPS_NOISE_SCALE] = 2.0
    e[SACC_LPF] = min(max(0.2 * sacc + 0.8 * e[SACC_LPF], 0.0), 10.0)
    e[SACC_PEAK] = max(e[SACC_LPF], (1.0 - min(dt / 10.0, 1.0)) * e[SACC_PEAK])
    if e[SACC_PEAK] > 1.5:
        e[GPS_SPD_FAIL] = 1.0
    elif e[SACC_PEAK] < 1.0:
        e[GPS_SPD_FAIL] = 0.0
    _gps_innovation_test(e, t)


@tick_jit
def _gps_innovation_test(e, t):
    """calcGpsGoodForFlight's innovation consistency test at a 3-D-fix sample, on the test
    ratios of the last fused sample: it fails when they have not both been below 1 at a sample
    for 1 s, and passes again after 10 s of samples without either reaching 1. While the
    bad-IMU response fuses GPS without gates the ratios count as passing (tlm model choice:
    SITL's accelerometer-failure flight accel_s13 reports no GPS glitch while tlm's ratios
    exceed 1 there). Outside absolute aiding the test is reset (:func:`gps_glitch_check`)."""
    if e[AID_MODE] != AID_ABSOLUTE or e[T_INNOV_PASS] <= 0.0:
        return
    if (e[VEL_TR] < 1.0 and e[POS_TR] < 1.0) or e[BAD_IMU] != 0.0:
        e[T_INNOV_PASS] = t
    elif e[VEL_TR] > 0.7 or e[POS_TR] > 0.7:
        e[T_INNOV_HIGH] = t
    if t - e[T_INNOV_PASS] > 1.0:
        e[GPS_INNOV_FAIL] = 1.0
    elif t - e[T_INNOV_HIGH] > 10.0:
        e[GPS_INNOV_FAIL] = 0.0


@tick_jit
def gps_glitch_check(e, t):
    """EKF3's gps_glitching flag: a GPS quality test of the last sample (speed accuracy or
    innovation consistency, :func:`lane_gps_accuracy`) failing while aiding with GPS. Outside
    absolute aiding the innovation test is reset (passing)."""
    if e[AID_MODE] != AID_ABSOLUTE or e[T_INNOV_PASS] <= 0.0:
        e[T_INNOV_PASS] = t
        e[T_INNOV_HIGH] = t
        e[GPS_INNOV_FAIL] = 0.0
        e[GPS_GLITCHING] = 0.0
        return
    fail = e[GPS_INNOV_FAIL] != 0.0 or e[GPS_SPD_FAIL] != 0.0
    e[GPS_GLITCHING] = 1.0 if fail else 0.0


@tick_jit
def stop_aiding(e, cfg, t):
    """EKF3 entering constant-position mode (aiding NONE after the tilt-drift time without GPS).

    As EKF3's setAidingMode with its ResetVelocity/ResetPosition for a non-absolute mode: the
    horizontal velocity is set to zero with variance EK3_VELNE_M_NSE^2, the horizontal position
    is kept as the last known position (EK3_POSNE_M_NSE^2 variance) that the constant-position
    pseudo-measurement then holds, and the output (what controllers and logs read) is set to
    the filter state on both. The reference logs show it: at "EKF3 IMUx stopped aiding" XKF1
    VN/VE drop to 0.000 and XKV1's velocity/position variances to 0.09 / 0.25 (gps_s12 at
    103.35 s, combined_s21 at 86.82 s).
    """
    e[VEL_RESET_DN] = -filter_now(e, 3)
    e[VEL_RESET_DE] = -filter_now(e, 4)
    for col in range(2):
        # velocity: filter and output to zero
        shift_output(e, 3 + col, -e[VN + col])
        e[OUT_EPN + 3 + col] = 0.0
        # position: output to the filter's
        dp = e[OUT_EPN + col]
        shift_output(e, col, dp)
        e[OUT_EPN + col] = 0.0
    e[POS_RESET_COUNT] += 1.0
    e[POS_RESET_DN] = 0.0
    e[POS_RESET_DE] = 0.0
    e[VEL_RESET_COUNT] += 1.0
    e[VEL_RESET_DD] = 0.0
    reset_block(e, ES_VEL, 2, cfg[C_VELNE_NSE] ** 2)
    reset_block(e, ES_POS, 2, cfg[C_POSNE_NSE] ** 2)
    e[AID_MODE] = AID_NONE
    life_event(e, AP.EKF_EVT_STOPPED)
    e[CONSTPOS_N] = e[PN]
    e[CONSTPOS_E] = e[PE]
    e[T_CONSTPOS] = t - cfg[C_CONSTPOS_DT]


@tick_jit
def reset_height(e, r_hgt, pd_new, k):
    """EKF3's height reset: the filter height ``k`` ticks ago becomes pd_new [m, down].

    As EKF3's ResetHeight, the output height and vertical velocity (and their history) are set
    to the filter's: the vertical output tracking errors are cleared; on the ground (the lane
    not in flight) the terrain state is put 0.05 m below the new height, as EKF3 assumes the
    vehicle sits on the ground (in flight the prediction's constraint keeps it below).
    """
    if e[IN_FLIGHT] == 0.0:
        e[TERRAIN] = pd_new + RNG_ON_GND
    dpd = pd_new - filter_get(e, k, 2)
    shift_output(e, 2, dpd + e[OUT_EPD])
    e[OUT_EPD] = 0.0
    shift_output(e, 5, e[OUT_EVD])
    e[OUT_EVD] = 0.0
    reset_block(e, ES_POS + 2, 1, r_hgt)
    e[HGT_RESET_COUNT] += 1.0


@tick_jit
def _bad_imu_check(e, cfg, t, vd_gps, k, r_vd):
    """EKF3's bad-IMU (accel aliasing) check and response; returns True while it is active.

    Detection: with a baro sample less than 0.2 s old, the height and vertical-velocity errors
    (filter state minus measurement, at the GPS time horizon) have the same sign and both exceed
    gain * R (gain 1 within 1.5 hold times of the previous detection, 4 within 2, else 9).
    Response while the *previous* detection is less than C_BAD_IMU_HOLD seconds old (as EKF3
    measures the hold time before recording the new detection, the response starts with the GPS
    sample after the first detection): the filter's vertical velocity is set to the GPS value,
    GPS and baro are fused without innovation gates, accel process noise is raised to
    C_BAD_IMU_ACC_NSE; after C_BAD_IMU_TIMEOUT seconds without a passing check the height is
    reset to the baro (at most once per timeout).
    """
    hold = cfg[C_BAD_IMU_HOLD]
    r_hgt = cfg[C_ALT_NSE] ** 2
    since = t - e[T_BAD_IMU]  # time since the previous detection
    if t - e[T_BARO_LAST] < 0.2:
        hgt_err = filter_get(e, k, 2) + e[BARO_LAST]
        vd_err = filter_get(e, k, 5) - vd_gps
        gain = 9.0 if since > 2.0 * hold else (4.0 if since > 1.5 * hold else 1.0)
        if hgt_err * vd_err > 0.0 and hgt_err**2 > gain * r_hgt and vd_err**2 > gain * r_vd:
            e[T_BAD_IMU] = t
        else:
            e[T_GOOD_IMU] = t
    bad = since < hold
    e[BAD_IMU] = 1.0 if bad else 0.0
    if bad:
        # the filter's vertical velocity is set to GPS; the output follows (output observer)
        e[OUT_EVD] += vd_gps - filter_get(e, k, 5)
        if t - e[T_GOOD_IMU] > cfg[C_BAD_IMU_TIMEOUT] and t - e[T_BARO_LAST] < 0.2:
            # bad for longer than the timeout: reset the height to the baro
            reset_height(e, r_hgt, -e[BARO_LAST], k)
            e[T_GOOD_IMU] = t
    return bad


@tick_jit
def lane_fuse_gps(e, cfg, t, pos, vel):
    """Fuse one 3-D-fix GPS sample: pos[0:2] NE [m] from the origin, vel[0:3] NED [m/s].

    In aiding mode NONE (before the first fix, or after constant-position mode started) the
    sample starts absolute aiding with a reset to GPS. Otherwise velocity (N, E, D) and position
    (N, E) are gated separately and fused sequentially. Measurement noise: the reported
    accuracies' envelopes (:func:`lane_gps_accuracy`) with the EK3_*_M_NSE floors; the
    horizontal velocity *gate* uses EK3_VELNE_M_NSE alone, as EKF3's data checks do. When
    velocity has not passed for C_POS_RETRY seconds, or the horizontal position variance
    exceeds EK3_GLITCH_RAD^2, position and velocity are reset to GPS; when only the position
    has not passed for C_POS_RETRY_VEL seconds (velocity still passing: a GPS glitch), the
    position alone is reset to GPS. While the bad-IMU response is active the gates are bypassed.
    """
    if e[ALIGNED] == 0.0 or e[FAULT] != 0.0 or e[IMU_OK] == 0.0:
        return
    k = _delay_ticks(cfg, cfg[C_GPS_DELAY])
    if e[AID_MODE] == AID_NONE:
        if not ready_to_use_gps(e, cfg):  # the boot phase's conditions (tlm_sim.ekf.lifecycle)
            return
        reset_vel_pos_to_gps(e, cfg, t, pos, vel, k)
        started_using_gps(e)
        update_flags(e, cfg, t)
        return
    r_vne = cfg[C_VELNE_NSE] ** 2
    r_vd = cfg[C_VELD_NSE] ** 2
    # the fusion's noises: the reported accuracies' envelopes, scaled for few satellites
    scale2 = e[GPS_NOISE_SCALE] ** 2
    r_vne_fuse = max(e[GPS_SACC_F], cfg[C_VELNE_NSE]) ** 2 * scale2
    r_vd_obs = max(e[GPS_SACC_F], cfg[C_VELD_NSE]) ** 2
    r_p = gps_pos_var(e, cfg)
    bad = _bad_imu_check(e, cfg, t, vel[2], k, r_vd_obs)
    yvn = vel[0] - filter_get(e, k, 3)
    yve = vel[1] - filter_get(e, k, 4)
    yvd = vel[2] - filter_get(e, k, 5)
    ypn = pos[0] - filter_get(e, k, 0)
    ype = pos[1] - filter_get(e, k, 1)
    d = NS + 1
    svn = e[P0 + (ES_VEL + 0) * d] + r_vne
    sve = e[P0 + (ES_VEL + 1) * d] + r_vne
    svd = e[P0 + (ES_VEL + 2) * d] + r_vd
    spn = e[P0 + (ES_POS + 0) * d] + r_p
    spe = e[P0 + (ES_POS + 1) * d] + r_p
    vel_tr = (yvn * yvn + yve * yve + yvd * yvd) / (cfg[C_VEL_GATE] ** 2 * (svn + sve + svd))
    pos_tr = (ypn * ypn + ype * ype) / (cfg[C_POS_GATE] ** 2 * (spn + spe))
    e[VEL_TR] = vel_tr
    e[POS_TR] = pos_tr
    e[INNOV_VN] = yvn
    e[INNOV_VE] = yve
    e[INNOV_VD] = yvd
    e[INNOV_PN] = ypn
    e[INNOV_PE] = ype
    if _gps_reset(e, cfg, t, pos, vel, k):
        update_flags(e, cfg, t)
        return
    fuse_vel = vel_tr < 1.0 or bad
    pos_pass = pos_tr < 1.0 or bad
    fuse_pos = pos_pass or e[POS_TIMEOUT] != 0.0
    if not (fuse_vel or fuse_pos):
        return
    clear_dx(e)
    if fuse_vel:
        fuse_index(e, ES_VEL + 0, yvn, r_vne_fuse)
        fuse_index(e, ES_VEL + 1, yve, r_vne_fuse)
        fuse_index(e, ES_VEL + 2, yvd, r_vd_obs * scale2)
        e[T_VEL_PASS] = t
    if fuse_pos:
        fuse_index(e, ES_POS + 0, ypn, r_p * scale2)
        fuse_index(e, ES_POS + 1, ype, r_p * scale2)
        e[T_GPS_FUSED] = t
        if pos_pass:
            e[T_POS_PASS] = t
    apply_correction(e, cfg[C_GBIAS_LIM], cfg[C_ABIAS_LIM])
    update_flags(e, cfg, t)


@tick_jit
def _gps_reset(e, cfg, t, pos, vel, k):
    """EKF3's GPS timeouts and resets before a sample is fused; returns True after a reset.

    Velocity aiding counts while a GPS velocity or position passed within C_POS_RETRY
    (EKF3's velAiding over its minTestTime, 7 s). The position times out (POS_TIMEOUT, held
    until a reset) when no position passed for C_POS_RETRY_VEL with velocity aiding,
    C_POS_RETRY without. A reset to GPS needs no velocity aiding or a good GPS
    (gpsGoodToAlign, ``GPS_GOOD``): position and velocity when no velocity passed for
    C_POS_RETRY or the position variance exceeds EK3_GLITCH_RAD^2, the position alone when it
    timed out. Otherwise a timed-out position is fused without its gate
    (:func:`lane_fuse_gps`), weighted by the reported accuracy: while GPS jamming makes the
    GPS bad the estimate is drawn towards the jammed fix instead of jumping to it."""
    vel_used = t - e[T_VEL_PASS] <= cfg[C_POS_RETRY]
    vel_aiding = vel_used or t - e[T_POS_PASS] <= cfg[C_POS_RETRY]
    retry = cfg[C_POS_RETRY_VEL] if vel_aiding else cfg[C_POS_RETRY]
    if t - e[T_POS_PASS] > retry:
        e[POS_TIMEOUT] = 1.0
    if vel_aiding and e[GPS_GOOD] == 0.0:
        return False
    d = NS + 1
    pos_var = e[P0 + (ES_POS + 0) * d] + e[P0 + (ES_POS + 1) * d]
    if not vel_used or pos_var > cfg[C_GLITCH_RAD] ** 2:
        reset_vel_pos_to_gps(e, cfg, t, pos, vel, k)
        return True
    if e[POS_TIMEOUT] != 0.0:
        reset_pos_to_gps(e, cfg, t, pos[0], pos[1], k)
        return True
    return False


@tick_jit
def lane_fuse_baro(e, cfg, t, alt):
    """Fuse a baro altitude above the origin [m, up], delayed by EK3_HGT_DELAY.

    After C_HGT_RETRY seconds of rejected samples the height is reset to the baro. While the
    bad-IMU response is active the gate is bypassed and the height variance is held at least at
    the baro measurement variance R (tlm model choice, from the reference logs: in both SITL
    accelerometer-failure flights EKF3's height innovation variance, (XKF3.IPD / (5 XKF4.SH))^2,
    is 4.2 m^2 (R = 4 plus P_pd = 0.2) before its bad-IMU response and 8 m^2 and more once it
    runs, and the height innovation then halves at every baro sample, i.e. P_pd >= R; the EKF3
    mechanism was not identified. The effect: the height follows the baro closely while the
    accelerometers are known to be bad, and the vehicle descends back to the mission altitude
    during the fault as in SITL).
    """
    if e[ALIGNED] == 0.0 or e[FAULT] != 0.0 or e[IMU_OK] == 0.0:
        return
    e[BARO_LAST] = alt
    e[T_BARO_LAST] = t
    k = _delay_ticks(cfg, cfg[C_HGT_DELAY])
    y = -alt - filter_get(e, k, 2)
    r = cfg[C_ALT_NSE] ** 2
    jj = P0 + (ES_POS + 2) * (NS + 1)
    if e[BAD_IMU] != 0.0 and e[jj] < r:
        e[jj] = r
    s = e[jj] + r
    tr = y * y / (cfg[C_HGT_GATE] ** 2 * s)
    e[HGT_TR] = tr
    e[INNOV_HGT] = y
    if tr < 1.0 or e[BAD_IMU] != 0.0:
        clear_dx(e)
        fuse_index(e, ES_POS + 2, y, r)
        apply_correction(e, cfg[C_GBIAS_LIM], cfg[C_ABIAS_LIM])
        e[T_HGT_PASS] = t
    elif t - e[T_HGT_PASS] > cfg[C_HGT_RETRY]:
        reset_height(e, r, -alt, k)
        e[T_HGT_PASS] = t


@tick_jit
def lane_fuse_mag(e, cfg, mag):
    """Fuse a body-frame magnetometer sample mag[0:3] [gauss] (3-axis, fixed earth field).

    Measurement model m_b = R^T m_e; with the earth-frame attitude error the Jacobian row of body
    axis k is (R[:, k] x m_e). All three axes are gated (EK3_MAG_I_GATE) and fused only if all
    pass. Before alignment the sample is only stored (for the initial yaw). Returns True when
    the sample was fused.
    """
    e[MAG_LX] = mag[0]
    e[MAG_LY] = mag[1]
    e[MAG_LZ] = mag[2]
    e[MAG_HAVE] = 1.0
    if e[ALIGNED] == 0.0 or e[FAULT] != 0.0 or e[IMU_OK] == 0.0:
        return False
    if e[YAW_DONE] == 0.0:  # boot phase: the first sample after tilt alignment sets the yaw
        yaw_align(e, cfg, EKF3_INIT_ROT_SD**2)
        return False
    if cfg[C_BOOT] != 0.0 and e[INFLIGHT_SEEN] == 0.0:
        return lane_fuse_heading(e, cfg)
    mn = cfg[C_MAG_N]
    me = cfg[C_MAG_E]
    md = cfg[C_MAG_D]
    r = cfg[C_MAG_NSE] ** 2
    g2 = cfg[C_MAG_GATE] ** 2
    # body axes in NED (columns of R)
    u0x, u0y, u0z = e[R00], e[R10], e[R20]
    u1x, u1y, u1z = e[R01], e[R11], e[R21]
    u2x, u2y, u2z = e[R02], e[R12], e[R22]
    y0 = mag[0] - (u0x * mn + u0y * me + u0z * md)
    y1 = mag[1] - (u1x * mn + u1y * me + u1z * md)
    y2 = mag[2] - (u2x * mn + u2y * me + u2z * md)
    # h_k = u_k x m_e
    h00 = u0y * md - u0z * me
    h01 = u0z * mn - u0x * md
    h02 = u0x * me - u0y * mn
    h10 = u1y * md - u1z * me
    h11 = u1z * mn - u1x * md
    h12 = u1x * me - u1y * mn
    h20 = u2y * md - u2z * me
    h21 = u2z * mn - u2x * md
    h22 = u2x * me - u2y * mn
    s0 = innov_var_h3(e, ES_ATT, h00, h01, h02, r)
    s1 = innov_var_h3(e, ES_ATT, h10, h11, h12, r)
    s2 = innov_var_h3(e, ES_ATT, h20, h21, h22, r)
    tr0 = y0 * y0 / (g2 * s0)
    tr1 = y1 * y1 / (g2 * s1)
    tr2 = y2 * y2 / (g2 * s2)
    e[MAG_TR] = max(tr0, max(tr1, tr2))
    e[INNOV_MX] = y0
    e[INNOV_MY] = y1
    e[INNOV_MZ] = y2
    if tr0 >= 1.0 or tr1 >= 1.0 or tr2 >= 1.0:
        return False
    clear_dx(e)
    fuse_h3(e, ES_ATT, h00, h01, h02, y0, r)
    fuse_h3(e, ES_ATT, h10, h11, h12, y1, r)
    fuse_h3(e, ES_ATT, h20, h21, h22, y2, r)
    apply_correction(e, cfg[C_GBIAS_LIM], cfg[C_ABIAS_LIM])
    return True


@tick_jit
def lane_fuse_heading(e, cfg):
    """EKF3's magnetic heading fusion (EK3_MAG_CAL 3 before the first climb's in-flight yaw
    alignment, with the boot phase): the heading of the lane's last compass sample, levelled
    with its roll and pitch, fused as a yaw measurement with noise EK3_YAW_M_NSE, gated by
    EK3_YAW_I_GATE; its test ratio is the lane's compass test ratio meanwhile, its
    innovation INNOV_YAW (measurement - prediction, rad). A yaw measurement sees the
    earth-frame attitude error's z component (h = [0, 0, 1], exact for a level vehicle).
    Returns True when fused."""
    roll, pitch, yaw = quat_to_euler(e[QW], e[QX], e[QY], e[QZ])
    y = mag_heading(e, cfg, roll, pitch) - yaw
    y = (y + math.pi) % (2.0 * math.pi) - math.pi
    r = max(cfg[C_YAW_NSE], 0.01) ** 2
    s = e[P0 + (ES_ATT + 2) * (NS + 1)] + r
    e[INNOV_YAW] = y
    e[MAG_TR] = y * y / (cfg[C_YAW_GATE] ** 2 * s)  # EKF3's yawTestRatio takes its place
    if e[MAG_TR] >= 1.0:
        return False
    clear_dx(e)
    fuse_index(e, ES_ATT + 2, y, r)
    apply_correction(e, cfg[C_GBIAS_LIM], cfg[C_ABIAS_LIM])
    return True


@tick_jit
def lane_fuse_constpos(e, cfg, t, armed):
    """Constant-position pseudo-measurement (aiding mode NONE), every C_CONSTPOS_DT seconds.

    Fuses the last known NE position with EK3_NOAID_M_NSE (C_ONGROUND_NSE while disarmed),
    bypassing the innovation gate as EKF3 does. The test ratio is still computed and stored.
    """
    if t - e[T_CONSTPOS] < cfg[C_CONSTPOS_DT] - 1e-9:
        return
    e[T_CONSTPOS] = t
    nse = cfg[C_NOAID_NSE] if armed else cfg[C_ONGROUND_NSE]
    r = nse * nse
    yn = e[CONSTPOS_N] - filter_now(e, 0)
    ye = e[CONSTPOS_E] - filter_now(e, 1)
    d = NS + 1
    s = e[P0 + ES_POS * d] + e[P0 + (ES_POS + 1) * d] + 2.0 * r
    e[POS_TR] = (yn * yn + ye * ye) / (cfg[C_POS_GATE] ** 2 * s)
    e[INNOV_PN] = yn
    e[INNOV_PE] = ye
    clear_dx(e)
    fuse_index(e, ES_POS + 0, yn, r)
    fuse_index(e, ES_POS + 1, ye, r)
    apply_correction(e, cfg[C_GBIAS_LIM], cfg[C_ABIAS_LIM])


@tick_jit
def is_finite_lane(e):
    """False if the quaternion, velocity, position or any covariance diagonal is not finite."""
    s = e[0] + e[VN] + e[VE] + e[VD] + e[PN] + e[PE] + e[PD]
    for i in range(NS):
        s += e[P0 + i * (NS + 1)]
    return math.isfinite(s)


@tick_jit
def update_flags(e, cfg, t):
    """Refresh the lane status flags (layout F_*) for time t [s]."""
    aligned = e[ALIGNED] != 0.0 and e[FAULT] == 0.0
    absolute = aligned and e[AID_MODE] == AID_ABSOLUTE
    retry = cfg[C_POS_RETRY]
    e[F_ATTITUDE] = 1.0 if aligned else 0.0
    e[F_HORIZ_VEL] = 1.0 if absolute and t - e[T_VEL_PASS] <= retry else 0.0
    e[F_HORIZ_POS] = 1.0 if absolute and t - e[T_POS_PASS] <= retry else 0.0
    e[F_VERT_VEL] = 1.0 if aligned else 0.0
    e[F_VERT_POS] = 1.0 if aligned and t - e[T_HGT_PASS] <= cfg[C_HGT_RETRY] else 0.0
    e[F_CONST_POS] = 1.0 if aligned and e[AID_MODE] == AID_NONE else 0.0
    e[F_USING_GPS] = 1.0 if absolute and t - e[T_GPS_FUSED] <= cfg[C_USING_GPS_T] else 0.0
    gps_glitch_check(e, t)
