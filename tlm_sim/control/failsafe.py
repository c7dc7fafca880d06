"""Copter's EKF-driven checks: height-rate filter, vibration failsafe, EKF failsafe, crash check,
thrust-loss check.

Reference §3.2 (ekf_check, FS_EKF_THRESH), §3.6 (crash check) and ArduCopter's vibration
failsafe (FS_VIBE_ENABLE):

* Height-rate filter: EKF3 runs a third-order complementary filter on its output height, fed by
  the corrected vertical acceleration, with all three poles at omega = 2 pi EK3_HRT_FILT
  (Widnall & Sinha's baro-inertial vertical channel). Its rate is what the altitude controller
  uses while vibration compensation is on: it follows the height (baro) even when the
  accelerometers are wrong, because its integrator absorbs a constant acceleration error.
* Vibration failsafe (10 Hz, after ekf_check): the check fails while the EKF reports itself
  vibration affected (its bad-IMU response is active), or while its vertical velocity and
  height innovations are both positive (EKF3 sign: prediction - measurement, i.e. the EKF
  believes it is sinking faster and is lower than the sensors say) and ekf_check's low-passed
  velocity test ratio (square root) is > 1. That filtered ratio is only maintained while
  ekf_check runs its variance comparison, i.e. with FS_EKF_THRESH > 0: ArduCopter's ekf_check
  returns before filtering when the check is disabled, which leaves the variances invalid for
  the vibration check. With FS_EKF_THRESH 0 (the reference flights) only the bad-IMU flag can
  trigger it -- in the reference accelerometer logs ERR 29 comes ~1 s after the EKF's bad-IMU
  response starts, not 1 s after the velocity test ratio first exceeds 1.
  Failing for 1 s switches vibration compensation on (ERR 29/1); 15 s without a failure
  switches it off (ERR 29/0).
* EKF failsafe (10 Hz, off when FS_EKF_THRESH <= 0): over threshold when the filtered position
  test ratio and one of velocity/compass are >= FS_EKF_THRESH, or two of velocity/compass are
  (velocity >= 2x counts twice); the checks also fail without an absolute position. Ten failing
  checks in a row (1 s, after the checks have passed once) -> ERR 16/2, ERR 17/1 and the
  FS_EKF_ACTION; passing checks count down and clear it (ERR 16/0, 17/0).

* Thrust-loss check (every tick, reference section 3.6): armed, not landed, thrust boost off,
  and for 1 s: lean target < 15 deg, throttle in >= 90 % or at the upper limit (and >= 25 %),
  the EKF descending, attitude error < 30 deg -> ERR 25/1 ("Potential Thrust Loss (n)", n the
  motor the mixer's motor-loss monitor names) and the motors' thrust boost on. The boost holds
  the check off until the motor library no longer needs it. On frames of six or more motors it
  lets the mixer take the lost motor out of its limits (tlm_sim.control.mixer); on a quad it
  changes nothing in tlm (ArduPilot's motor-loss compensation needs six or more motors).

The checks read the primary lane's status from the EKF's output block ``eo``
(``tlm_sim.ekf.layout`` O_*, :func:`tlm_sim.ekf.lanes.ekf_output_nav`); innovations are tlm's
sign (measurement - prediction), converted here.
"""

import math

from tlm_sim import ardupilot as AP
from tlm_sim._jit import tick_jit
from tlm_sim.control import events as E
from tlm_sim.control import layout as C
from tlm_sim.ekf import layout as EK
from tlm_sim.rotation import quat_to_euler

CHECK_DT_S = 0.1  # ekf_check / vibration check period
VIBE_TRIGGER_S = 1.0
VIBE_CLEAR_S = 15.0
EKF_CHECK_ITERATIONS = 10
CRASH_CHECK_S = 2.0
CRASH_LEAN_COS = math.cos(math.radians(15.0))
THRUST_LOSS_S = 1.0  # THRUST_LOSS_CHECK_TRIGGER_SEC
THRUST_LOSS_LEAN = math.radians(15.0)  # THRUST_LOSS_CHECK_ANGLE_DEVIATION_CD
THRUST_LOSS_MIN_THR = 0.9  # THRUST_LOSS_CHECK_MINIMUM_THROTTLE
ATT_ERR_MAX = math.radians(30.0)  # CRASH_CHECK_ANGLE_DEVIATION_DEG

# failsafe_checks results
FS_NONE = 0
FS_EKF_LAND = 1  # EKF failsafe: switch to LAND (no position control)
FS_EKF_ALTHOLD = 2  # EKF failsafe with FS_EKF_ACTION 2


@tick_jit
def vertical_cf_reset(c, pd, vd):
    """Start the height-rate filter at an EKF height pd [m, down] and rate vd [m/s, down]."""
    c[C.VCF_POS] = pd
    c[C.VCF_VEL] = vd
    c[C.VCF_ACC] = 0.0


@tick_jit
def vertical_cf_update(c, g, pd, acc_down, dt):
    """One step of the third-order height-rate filter (backward Euler, poles at G_HRT_OMEGA).

    pd: EKF height, down [m]; acc_down: kinematic vertical acceleration from the IMU, down
    [m/s^2]; dt [s]. Leaves the rate in c[VCF_VEL] (down, m/s).
    """
    w = g[C.G_HRT_OMEGA]
    err = pd - c[C.VCF_POS]
    c[C.VCF_ACC] += err * w * w * w * dt
    c[C.VCF_VEL] += (acc_down + c[C.VCF_ACC] + err * 3.0 * w * w) * dt
    c[C.VCF_POS] += (c[C.VCF_VEL] + err * 3.0 * w) * dt


@tick_jit
def ekf_position_ok(eo):
    """True while the primary lane has an absolute horizontal position (not constant-position
    mode): what ArduCopter's checks ask of the AHRS."""
    return eo[EK.O_F_HORIZ_POS] != 0.0 and eo[EK.O_F_CONST_POS] == 0.0


@tick_jit
def _vibration_check(c, g, t_s, eo, ev, t_us):
    if g[C.G_FS_VIBE_ENABLE] == 0.0:
        if c[C.VIBE_COMP] != 0.0:
            c[C.VIBE_COMP] = 0.0
            E.log_err(ev, t_us, AP.ERR_FAILSAFE_VIBE, AP.ERR_CODE_RESOLVED)
        return
    # EKF3 innovations are prediction - measurement: both positive = "sinking and low"; the
    # filtered velocity ratio is only valid while ekf_check filters it (FS_EKF_THRESH > 0)
    innov = (g[C.G_FS_EKF_THRESH] > 0.0 and -eo[EK.O_INNOV_VD] > 0.0
             and -eo[EK.O_INNOV_HGT] > 0.0 and c[C.EKF_VEL_TR_F] > 1.0)
    failing = innov or eo[EK.O_BAD_IMU] != 0.0
    if failing:
        c[C.VIBE_LAST_FAIL_T] = t_s
        if c[C.VIBE_FAIL_T] < 0.0:
            c[C.VIBE_FAIL_T] = t_s
        if c[C.VIBE_COMP] == 0.0 and t_s - c[C.VIBE_FAIL_T] >= VIBE_TRIGGER_S - 1e-6:
            c[C.VIBE_COMP] = 1.0
            E.log_err(ev, t_us, AP.ERR_FAILSAFE_VIBE, AP.ERR_CODE_FAILSAFE)
    else:
        c[C.VIBE_FAIL_T] = -1.0
        if c[C.VIBE_COMP] != 0.0 and t_s - c[C.VIBE_LAST_FAIL_T] >= VIBE_CLEAR_S - 1e-6:
            c[C.VIBE_COMP] = 0.0
            E.log_err(ev, t_us, AP.ERR_FAILSAFE_VIBE, AP.ERR_CODE_RESOLVED)


@tick_jit
def _ekf_check(c, g, eo, ev, t_us):
    """ekf_check at 10 Hz; returns FS_* when the EKF failsafe fires this cycle.

    With FS_EKF_THRESH <= 0 it only clears the failsafe and returns before filtering the test
    ratios (as ArduCopter's ekf_check does).
    """
    thresh = g[C.G_FS_EKF_THRESH]
    if thresh <= 0.0:
        c[C.EKF_FAIL_COUNT] = 0.0
        if c[C.EKF_FAILSAFE] != 0.0:
            c[C.EKF_FAILSAFE] = 0.0
            E.log_err(ev, t_us, AP.ERR_FAILSAFE_EKFINAV, AP.ERR_CODE_RESOLVED)
        return FS_NONE
    a = g[C.G_FS_EKF_ALPHA]
    c[C.EKF_VEL_TR_F] += a * (math.sqrt(max(eo[EK.O_VEL_TR], 0.0)) - c[C.EKF_VEL_TR_F])
    c[C.EKF_POS_TR_F] += a * (math.sqrt(max(eo[EK.O_POS_TR], 0.0)) - c[C.EKF_POS_TR_F])
    vel = c[C.EKF_VEL_TR_F]
    pos = c[C.EKF_POS_TR_F]
    mag = math.sqrt(max(eo[EK.O_MAG_TR], 0.0))
    n_over = 0
    if mag >= thresh:
        n_over += 1
    if vel >= thresh:
        n_over += 1
    if vel >= 2.0 * thresh:
        n_over += 1
    over = (pos >= thresh and n_over > 0) or n_over >= 2
    passed = not over and ekf_position_ok(eo)
    if passed:
        c[C.EKF_CHECK_OK_ONCE] = 1.0
        if c[C.EKF_FAIL_COUNT] > 0.0:
            c[C.EKF_FAIL_COUNT] -= 1.0
            if c[C.EKF_FAIL_COUNT] == 0.0 and c[C.EKF_FAILSAFE] != 0.0:
                c[C.EKF_FAILSAFE] = 0.0
                E.log_err(ev, t_us, AP.ERR_EKFCHECK, AP.ERR_CODE_RESOLVED)
                E.log_err(ev, t_us, AP.ERR_FAILSAFE_EKFINAV,
                           AP.ERR_CODE_RESOLVED)
        return FS_NONE
    if c[C.EKF_CHECK_OK_ONCE] == 0.0 or c[C.EKF_FAILSAFE] != 0.0:
        return FS_NONE
    c[C.EKF_FAIL_COUNT] += 1.0
    if c[C.EKF_FAIL_COUNT] < EKF_CHECK_ITERATIONS:
        return FS_NONE
    c[C.EKF_FAIL_COUNT] = EKF_CHECK_ITERATIONS
    c[C.EKF_FAILSAFE] = 1.0
    E.log_err(ev, t_us, AP.ERR_EKFCHECK, AP.ERR_CODE_EKF_BAD_VARIANCE)
    E.log_err(ev, t_us, AP.ERR_FAILSAFE_EKFINAV, AP.ERR_CODE_FAILSAFE)
    action = g[C.G_FS_EKF_ACTION]
    if action == 2.0:
        return FS_EKF_ALTHOLD
    if action == 1.0 or action == 3.0:
        return FS_EKF_LAND
    return FS_NONE


@tick_jit
def failsafe_checks(c, g, t_us, eo, ev):
    """The 10 Hz EKF and vibration checks (armed only, in that order); returns an FS_* action."""
    t_s = t_us * 1e-6
    c[C.EKF_POS_OK] = 1.0 if ekf_position_ok(eo) else 0.0
    if t_s < c[C.CHECK_TIMER]:
        return FS_NONE
    c[C.CHECK_TIMER] = t_s + CHECK_DT_S - 1e-7
    if c[C.ARMED] == 0.0:
        c[C.VIBE_FAIL_T] = -1.0
        return FS_NONE
    fs = _ekf_check(c, g, eo, ev, t_us)
    _vibration_check(c, g, t_s, eo, ev, t_us)
    return fs


@tick_jit
def crash_check(c, g, dt, cos_tilt, roll, pitch, ground_speed):
    """ArduCopter's crash check; returns True when the vehicle should disarm.

    Armed, not landed, FS_CRASH_CHECK on, and for 2 s: |1 Hz low-passed acceleration| < 3 m/s^2,
    lean > 15 deg, attitude error > 30 deg (here: the angle between commanded and estimated
    roll/pitch), ground speed < 10 m/s. roll/pitch: EKF attitude [rad]; ground_speed [m/s].
    """
    if g[C.G_FS_CRASH_CHECK] == 0.0 or c[C.LANDED] != 0.0:
        c[C.CRASH_TIMER] = 0.0
        return False
    a_lp = math.sqrt(c[C.ALP] ** 2 + c[C.ALP + 1] ** 2 + c[C.ALP + 2] ** 2)
    if cos_tilt >= CRASH_LEAN_COS or a_lp >= 3.0 or ground_speed >= 10.0:
        c[C.CRASH_TIMER] = 0.0
        return False
    er = c[C.ATT_ROLL_CMD] - roll
    ep = c[C.ATT_PITCH_CMD] - pitch
    if er * er + ep * ep <= math.radians(30.0) ** 2:
        c[C.CRASH_TIMER] = 0.0
        return False
    c[C.CRASH_TIMER] += dt
    return c[C.CRASH_TIMER] >= CRASH_CHECK_S


@tick_jit
def thrust_loss_check(c, dt, q, vd, ev, t_us):
    """ArduCopter's thrust-loss check, once per main-loop tick (after the mixer).

    q: EKF attitude quaternion body -> NED; vd: EKF down velocity [m/s]. Uses the attitude
    targets (ATT_ROLL_CMD/ATT_PITCH_CMD), the throttle into the attitude controller (THR_OUT,
    before angle boost) and the mixer's upper throttle limit. Logs ERR 25/1 and sets
    THRUST_BOOST when the symptoms last THRUST_LOSS_S; returns True on that tick. Nothing is
    checked while the boost is on: the mixer's motor-loss monitor switches it off
    (:func:`tlm_sim.control.mixer.motor_loss_monitor`).
    """
    if c[C.THRUST_BOOST] != 0.0:  # the motor library switches it off (mixer.motor_loss_monitor)
        return False
    tr = c[C.ATT_ROLL_CMD]
    tp = c[C.ATT_PITCH_CMD]
    thr = c[C.THR_OUT]
    if (c[C.ARMED] == 0.0 or c[C.LANDED] != 0.0 or tr * tr + tp * tp > THRUST_LOSS_LEAN**2
            or (thr < THRUST_LOSS_MIN_THR and c[C.LIM_THR_HI] == 0.0) or thr < 0.25
            or not vd > 0.0):
        c[C.THRUST_LOSS_T] = 0.0
        return False
    roll, pitch, _ = quat_to_euler(q[0], q[1], q[2], q[3])
    er = tr - roll
    ep = tp - pitch
    if er * er + ep * ep >= ATT_ERR_MAX**2:
        c[C.THRUST_LOSS_T] = 0.0
        return False
    c[C.THRUST_LOSS_T] += dt
    if c[C.THRUST_LOSS_T] < THRUST_LOSS_S - 1e-9:
        return False
    c[C.THRUST_LOSS_T] = 0.0
    c[C.THRUST_BOOST] = 1.0
    E.log_err(ev, t_us, AP.ERR_THRUST_LOSS_CHECK, AP.ERR_CODE_FAILSAFE)
    return True
