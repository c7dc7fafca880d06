"""EKF3's start-up on the ground, lane by lane: what must happen before a lane uses GPS.

With ``TLM_BOOT_PHASE`` 1 (cfg ``C_BOOT``) a lane goes through EKF3's sequence
(AP_NavEKF3_Control.cpp, _VehicleStatus.cpp), each step a change of its own state:

1. *initialised* at ``C_EKF_START`` (EKF3's InitialiseFilter): tilt from the averaged
   accelerometers, yaw from the compass, the attitude variance EKF3's 0.1 rad per axis;
2. *tilt alignment complete* once the attitude variance about each horizontal axis is below
   (5 deg)^2 (checkAttitudeAlignmentStatus; EKF3's tiltErrorVariance read per axis, which from
   its initial 0.1^2 gives SITL's 1.35 s), as the constant-position and height fusion bring it
   down;
3. *initial yaw alignment complete* at the next compass sample: the yaw is set from the
   compass again (a yaw reset, EV 62) and compass fusion starts -- as heading fusion
   (EK3_MAG_CAL 3: EK3_YAW_M_NSE, :func:`tlm_sim.ekf.fusion.lane_fuse_heading`) until the
   first climb's in-flight yaw alignment, then 3-axis (the reference logs' XKF3: IYAW only on
   the ground, IMX..IMZ from then on; XKFS.MAG_FUSION 1, then 2);
4. the GPS checks of calcGpsGoodToAlign on every 3-D-fix sample (EK3_GPS_CHECK: satellites,
   HDOP, speed and position accuracy, compass yaw, and on the ground drift and speeds;
   thresholds scaled by EK3_CHECK_SCALE, x1.3 once passed); *origin set* when they have
   passed for 10 s (gpsGoodToAlign, cleared by 5 s without a passing sample);
5. *is using GPS* at the first GPS sample once the origin is set, tilt and yaw are aligned and
   the gyro biases are learnt (checkGyroCalStatus: every gyro bias standard deviation below
   0.15 deg/s, from the lane's own covariance: the heading fusion's yaw information makes the
   z bias the last, ~36 s after the yaw alignment as in SITL) -- readyToUseGPS.

With ``TLM_BOOT_PHASE`` 0 the lanes are ready at once: tilt and yaw aligned at alignment, the
GPS good and the biases counted as learnt, so the first GPS sample is used and sets the origin
(the behaviour tlm had before the boot phase). Later aiding changes are the same in both:
"stopped aiding" when GPS has been lost for the tilt-drift time, "is using GPS" when it is back.

Each event sets a bit of the lane's LIFE_EVENTS; the flight loop turns them into text log
rows (:func:`tlm_sim.control.arming.lifecycle_texts`) and the MSG text is rendered after the
flight (:mod:`tlm_sim.flightlog.texts`).
"""

from __future__ import annotations

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.ekf.core import reset_block, set_quat_euler
from tlm_sim.ekf.layout import (
    AID_ABSOLUTE,
    AID_MODE,
    BIAS_LEARNED,
    C_BOOT,
    C_CHECK_SCALE,
    C_GPS_CHECK,
    C_MAG_E,
    C_MAG_N,
    ES_ATT,
    ES_BG,
    GPS_CHK_FAILS,
    GPS_DRIFT,
    GPS_GOOD,
    GPS_PREV_E,
    GPS_PREV_N,
    GPS_SACC_F,
    GPS_VH_F,
    GPS_VZ_F,
    IN_FLIGHT,
    LIFE_EVENTS,
    MAG_LX,
    MAG_LY,
    MAG_LZ,
    MAG_TR,
    NS,
    ORIGIN_OK,
    P0,
    QW,
    QX,
    QY,
    QZ,
    T_GPS_CHK_FAIL,
    T_GPS_CHK_PASS,
    TILT_DONE,
    YAW_DONE,
)
from tlm_sim.rotation import quat_to_euler
from tlm_sim.sensors.layout import (
    GE_HACC,
    GE_HDOP,
    GE_NSATS,
    GE_PE,
    GE_PN,
    GE_VACC,
    GE_VD,
    GE_VE,
    GE_VN,
)

# lifecycle events: bits of LIFE_EVENTS (ardupilot.EKF_EVT_*, the texts' order within a tick)

#: EKF3's initial attitude uncertainty (CovarianceInit: rotation vector variance 0.1^2)
EKF3_INIT_ROT_SD = 0.1  # rad
#: tilt alignment complete below this tilt error variance (checkAttitudeAlignmentStatus),
#: per horizontal axis
TILT_ALIGN_VAR = math.radians(5.0) ** 2  # rad^2
#: gyro biases learnt below this standard deviation (checkGyroCalStatus: 0.15 deg/s)
BIAS_LEARNED_VAR = math.radians(0.15) ** 2  # (rad/s)^2
GPS_GOOD_PASS_S = 10.0  # the checks must pass this long (continuously) to set gpsGoodToAlign
GPS_GOOD_FAIL_S = 5.0  # ... and fail this long (no passing sample) to clear it
DRIFT_TC_S = 10.0  # position drift decay time constant

# EK3_GPS_CHECK bits (AP_NavEKF3_core.h MASK_GPS_*) and their thresholds at EK3_CHECK_SCALE 100
GPS_CHK_NSATS = 1  # fewer than 6 satellites
GPS_CHK_HDOP = 2  # HDOP above 2.5
GPS_CHK_SPD_ERR = 4  # speed accuracy above 1 m/s
GPS_CHK_POS_ERR = 8  # horizontal accuracy above 5 m or vertical above 7.5 m
GPS_CHK_YAW_ERR = 16  # compass innovations above their gate
GPS_CHK_POS_DRIFT = 32  # on the ground: filtered position drift above 3 m
GPS_CHK_VERT_SPD = 64  # on the ground: filtered vertical speed above 0.3 m/s
GPS_CHK_HORIZ_SPD = 128  # on the ground: filtered horizontal speed above 0.3 m/s


@tick_jit
def life_event(e, bit):
    """Record lifecycle event ``bit`` (ardupilot.EKF_EVT_*) of lane e for the text log."""
    e[LIFE_EVENTS] = float(int(e[LIFE_EVENTS]) | bit)


@tick_jit
def mag_heading(e, cfg, roll, pitch):
    """Heading [rad] the lane's last compass sample gives at the attitude (roll, pitch) [rad]:
    the body field levelled, against the earth field's declination."""
    mx = e[MAG_LX]
    my = e[MAG_LY]
    mz = e[MAG_LZ]
    cr = math.cos(roll)
    sr = math.sin(roll)
    cp = math.cos(pitch)
    sp = math.sin(pitch)
    mlx = cp * mx + sp * (sr * my + cr * mz)
    mly = cr * my - sr * mz
    return math.atan2(cfg[C_MAG_E], cfg[C_MAG_N]) - math.atan2(mly, mlx)


@tick_jit
def lane_started(e, cfg):
    """At alignment (EKF3's InitialiseFilter): the initialised event; with the boot phase off
    the lane is also tilt and yaw aligned, its GPS good and its gyro biases learnt."""
    life_event(e, AP.EKF_EVT_INIT)
    if cfg[C_BOOT] == 0.0:
        e[TILT_DONE] = 1.0
        e[YAW_DONE] = 1.0
        e[GPS_GOOD] = 1.0
        e[BIAS_LEARNED] = 1.0
        life_event(e, AP.EKF_EVT_TILT)
        life_event(e, AP.EKF_EVT_YAW)
    else:
        e[TILT_DONE] = 0.0
        e[YAW_DONE] = 0.0
        e[BIAS_LEARNED] = 0.0


@tick_jit
def lane_alignment_checks(e, cfg):
    """After a covariance prediction, with the boot phase: tilt alignment (horizontal attitude
    variance below (5 deg)^2) and gyro bias learning (every bias variance below
    (0.15 deg/s)^2, re-evaluated as EKF3 does)."""
    if cfg[C_BOOT] == 0.0:
        return
    d = NS + 1
    if e[TILT_DONE] == 0.0:
        if max(e[P0 + ES_ATT * d], e[P0 + (ES_ATT + 1) * d]) < TILT_ALIGN_VAR:
            e[TILT_DONE] = 1.0
            life_event(e, AP.EKF_EVT_TILT)
    learnt = (e[P0 + ES_BG * d] <= BIAS_LEARNED_VAR and e[P0 + (ES_BG + 1) * d]
              <= BIAS_LEARNED_VAR and e[P0 + (ES_BG + 2) * d] <= BIAS_LEARNED_VAR)
    e[BIAS_LEARNED] = 1.0 if learnt else 0.0


@tick_jit
def yaw_align(e, cfg, init_yaw_var):
    """EKF3's initial yaw alignment (magYawResetRequest once the tilt is aligned): the yaw is
    set from the compass sample just read (roll and pitch kept), its variance reset to
    init_yaw_var [rad^2]; the lane then fuses the compass. Returns True when it aligned."""
    if e[TILT_DONE] == 0.0:
        return False
    roll, pitch, _ = quat_to_euler(e[QW], e[QX], e[QY], e[QZ])
    set_quat_euler(e, roll, pitch, mag_heading(e, cfg, roll, pitch))
    reset_block(e, ES_ATT + 2, 1, init_yaw_var)
    e[YAW_DONE] = 1.0
    life_event(e, AP.EKF_EVT_YAW)
    return True


@tick_jit
def _gps_check_fails(e, cfg, t, gps):
    """EK3_GPS_CHECK bits failing on this sample (calcGpsGoodToAlign's tests), updating the
    drift and ground-speed filters. EKF3's drift sum starts from the first sample here."""
    gps_pn, gps_pe = gps[GE_PN], gps[GE_PE]
    vn, ve, vd = gps[GE_VN], gps[GE_VE], gps[GE_VD]
    nsats, hdop, hacc, vacc = gps[GE_NSATS], gps[GE_HDOP], gps[GE_HACC], gps[GE_VACC]
    mask = int(cfg[C_GPS_CHECK])
    scale = cfg[C_CHECK_SCALE] * (1.3 if e[GPS_GOOD] != 0.0 else 1.0)
    on_ground = e[IN_FLIGHT] == 0.0
    first = e[T_GPS_CHK_FAIL] < 0.0
    dt = 0.0 if first else min(max(t - max(e[T_GPS_CHK_FAIL], e[T_GPS_CHK_PASS]), 0.01),
                               DRIFT_TC_S)
    if not first:
        e[GPS_DRIFT] += math.sqrt((gps_pn - e[GPS_PREV_N]) ** 2 + (gps_pe - e[GPS_PREV_E]) ** 2)
    e[GPS_PREV_N] = gps_pn
    e[GPS_PREV_E] = gps_pe
    e[GPS_DRIFT] = min(e[GPS_DRIFT] * (1.0 - dt / DRIFT_TC_S), 10.0)
    fails = 0
    if on_ground:
        e[GPS_VZ_F] = min(max(0.1 * vd + 0.9 * e[GPS_VZ_F], -10.0), 10.0)
        e[GPS_VH_F] = min(max(0.1 * math.sqrt(vn * vn + ve * ve) + 0.9 * e[GPS_VH_F], -10.0),
                          10.0)
        if e[GPS_DRIFT] > 3.0 * scale:
            fails |= GPS_CHK_POS_DRIFT
        if abs(e[GPS_VZ_F]) > 0.3 * scale:
            fails |= GPS_CHK_VERT_SPD
        if abs(e[GPS_VH_F]) > 0.3 * scale:
            fails |= GPS_CHK_HORIZ_SPD
    if hacc > 5.0 * scale or vacc > 7.5 * scale:
        fails |= GPS_CHK_POS_ERR
    if e[GPS_SACC_F] > 1.0 * scale:
        fails |= GPS_CHK_SPD_ERR
    if hdop > 2.5:
        fails |= GPS_CHK_HDOP
    if nsats < 6.0:
        fails |= GPS_CHK_NSATS
    if e[MAG_TR] > 1.0:
        fails |= GPS_CHK_YAW_ERR
    return fails & mask


@tick_jit
def lane_gps_checks(e, cfg, t, gps):
    """One 3-D-fix GPS sample through EKF3's readGpsData checks: the GPS quality tests and
    gpsGoodToAlign (10 s of passing, 5 s of failing to clear it), on the ground and in flight
    (a bad GPS stops resets to it, :func:`tlm_sim.ekf.fusion.lane_fuse_gps`); with the boot
    phase also the origin, set once when the GPS is good (EKF_EVT_ORIGIN). gps: the epoch
    (``tlm_sim.sensors.layout`` GE_*: position NE [m], velocity NED [m/s], satellites, HDOP,
    horizontal / vertical accuracy [m])."""
    fails = _gps_check_fails(e, cfg, t, gps)
    e[GPS_CHK_FAILS] = fails
    if e[T_GPS_CHK_FAIL] < 0.0:
        e[T_GPS_CHK_FAIL] = t  # EKF3 counts its first check as a failure
    elif fails != 0:
        e[T_GPS_CHK_FAIL] = t
    if fails == 0:
        e[T_GPS_CHK_PASS] = t
    if e[GPS_GOOD] == 0.0 and t - e[T_GPS_CHK_FAIL] > GPS_GOOD_PASS_S:
        e[GPS_GOOD] = 1.0
    elif e[GPS_GOOD] != 0.0 and t - e[T_GPS_CHK_PASS] > GPS_GOOD_FAIL_S:
        e[GPS_GOOD] = 0.0
    if e[GPS_GOOD] != 0.0 and e[ORIGIN_OK] == 0.0 and cfg[C_BOOT] != 0.0:
        e[ORIGIN_OK] = 1.0
        life_event(e, AP.EKF_EVT_ORIGIN)


@tick_jit
def ready_to_use_gps(e, cfg):
    """EKF3's readyToUseGPS for a lane with a new GPS sample: origin set, tilt and yaw aligned,
    gyro biases learnt and the GPS good (always so with the boot phase off, where the sample
    sets the origin)."""
    return ((e[ORIGIN_OK] != 0.0 or cfg[C_BOOT] == 0.0) and e[TILT_DONE] != 0.0
            and e[YAW_DONE] != 0.0 and e[BIAS_LEARNED] != 0.0 and e[GPS_GOOD] != 0.0)


@tick_jit
def started_using_gps(e):
    """The lane starts absolute aiding with GPS: the origin is set with the first sample when
    the boot phase is off (EKF3 sets it from GPS before using it), then EKF_EVT_USING_GPS."""
    if e[ORIGIN_OK] == 0.0:
        e[ORIGIN_OK] = 1.0
        life_event(e, AP.EKF_EVT_ORIGIN)
    e[AID_MODE] = AID_ABSOLUTE
    life_event(e, AP.EKF_EVT_USING_GPS)
