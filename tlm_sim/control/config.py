"""Build the controller configuration array from a :class:`~tlm_sim.params.Params` (once per
flight).

ArduPilot units are converted to SI here (cm -> m, cdeg -> rad, cm/s -> m/s); filter cut-offs
become first-order filter alphas at the main-loop rate (SCHED_LOOP_RATE). Every value comes
from the parameter set; ``tlm params`` lists units and defaults.
"""

import math

import numpy as np

from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.boot import BOOT_ARM_ATTEMPTS_S, BOOT_DRIVER_S, PREARM_FIRST_S
from tlm_sim.control import layout as C
from tlm_sim.control.arming import ARM_RETRY_S, ARM_TIMEOUT_S
from tlm_sim.dynamics.atmosphere import RHO0, air_density, air_density_gradient
from tlm_sim.ekf.config import gps_delay_s
from tlm_sim.frames import frame_for
from tlm_sim.params import Params, require_params

_AXES = ("RLL", "PIT", "YAW")


#: AC_PosControl's throttle cutoff (POSCONTROL_THROTTLE_CUTOFF_FREQ_HZ): the motors low-pass the
#: throttle the position controller gives them at this frequency [Hz]
THROTTLE_CUTOFF_HZ = 2.0
#: AP_Motors' throttle slew-rate filter (AP_MOTORS_SLEW_FILTER_CUTOFF) [Hz]
SLEW_FILTER_CUTOFF_HZ = 50.0


def lpf_alpha(cutoff_hz: float, dt: float) -> float:
    """First-order low-pass alpha for a cut-off frequency (1 = no filtering when cut-off is 0)."""
    if cutoff_hz <= 0.0:
        return 1.0
    return dt / (dt + 1.0 / (2.0 * math.pi * cutoff_hz))


def _attitude(g: np.ndarray, p: Params, dt: float) -> None:
    """Rate PIDs, angle P gains, acceleration and slew limits, input shaping, lean angle."""
    for k, ax in enumerate(_AXES):
        g[C.G_RAT_P + k] = p[f"ATC_RAT_{ax}_P"]
        g[C.G_RAT_I + k] = p[f"ATC_RAT_{ax}_I"]
        g[C.G_RAT_D + k] = p[f"ATC_RAT_{ax}_D"]
        g[C.G_RAT_FF + k] = p[f"ATC_RAT_{ax}_FF"]
        g[C.G_RAT_IMAX + k] = p[f"ATC_RAT_{ax}_IMAX"]
        g[C.G_RAT_FLTT + k] = lpf_alpha(p[f"ATC_RAT_{ax}_FLTT"], dt)
        g[C.G_RAT_FLTE + k] = lpf_alpha(p[f"ATC_RAT_{ax}_FLTE"], dt)
        g[C.G_RAT_FLTD + k] = lpf_alpha(p[f"ATC_RAT_{ax}_FLTD"], dt)
        g[C.G_ANG_P + k] = p[f"ATC_ANG_{ax}_P"]
    # ATC_ACCEL_*_MAX [cdeg/s^2]: the input shaping uses them as they are; the angle
    # controller's square-root law uses half of them, constrained to 40..720 deg/s^2 (roll,
    # pitch) or 10..120 deg/s^2 (yaw) (AC_AttitudeControl's *_CONTROLLER_MIN/MAX_RADSS). With
    # the defaults 1100/1100/270 deg/s^2: 550/550/120.
    for k, (ax, lo, hi) in enumerate((("R", 40.0, 720.0), ("P", 40.0, 720.0), ("Y", 10.0, 120.0))):
        deg = max(p[f"ATC_ACCEL_{ax}_MAX"] / 100.0, 0.0)
        g[C.G_ACCEL_MAX + k] = math.radians(deg)
        g[C.G_ANG_ACCEL + k] = math.radians(min(max(0.5 * deg, lo), hi)) if deg > 0 else 0.0
    g[C.G_INPUT_TC] = max(p["ATC_INPUT_TC"], 0.05)
    g[C.G_SLEW_YAW] = math.radians(p["ATC_SLEW_YAW"] / 100.0)
    g[C.G_ANGLE_MAX] = math.radians(p["ANGLE_MAX"] / 100.0)
    g[C.G_THR_MIX_MIN] = p["ATC_THR_MIX_MIN"]
    g[C.G_THR_MIX_MAX] = p["ATC_THR_MIX_MAX"]
    g[C.G_ACCEL_XY_MAX] = GRAVITY_MSS * math.tan(g[C.G_ANGLE_MAX])
    tc = p["ATC_ANG_LIM_TC"]
    g[C.G_ANG_LIM_ALPHA] = 1.0 if tc <= 0.0 else dt / (dt + tc)


def _position(g: np.ndarray, p: Params, dt: float) -> None:
    """Horizontal and vertical position controllers (PSC_*)."""
    g[C.G_POSXY_P] = p["PSC_POSXY_P"]
    g[C.G_VELXY_P] = p["PSC_VELXY_P"]
    g[C.G_VELXY_I] = p["PSC_VELXY_I"]
    g[C.G_VELXY_D] = p["PSC_VELXY_D"]
    g[C.G_VELXY_IMAX] = p["PSC_VELXY_IMAX"] / 100.0
    g[C.G_VELXY_FLTE] = lpf_alpha(p["PSC_VELXY_FLTE"], dt)
    g[C.G_VELXY_FLTD] = lpf_alpha(p["PSC_VELXY_FLTD"], dt)
    g[C.G_POSZ_P] = p["PSC_POSZ_P"]
    g[C.G_VELZ_P] = p["PSC_VELZ_P"]
    g[C.G_ACCZ_P] = p["PSC_ACCZ_P"]
    g[C.G_ACCZ_I] = p["PSC_ACCZ_I"]
    g[C.G_ACCZ_IMAX] = p["PSC_ACCZ_IMAX"]
    g[C.G_ACCZ_FLTE] = lpf_alpha(p["PSC_ACCZ_FLTE"], dt)


def _navigation(g: np.ndarray, p: Params) -> None:
    """Waypoint navigation, RTL and landing (WPNAV_*, RTL_*, LAND_*, TLM_WP_LEG_K)."""
    g[C.G_WP_SPEED] = p["WPNAV_SPEED"] / 100.0
    g[C.G_WP_ACCEL] = p["WPNAV_ACCEL"] / 100.0
    g[C.G_WP_SPEED_UP] = p["WPNAV_SPEED_UP"] / 100.0
    g[C.G_WP_SPEED_DN] = p["WPNAV_SPEED_DN"] / 100.0
    g[C.G_WP_ACCEL_Z] = p["WPNAV_ACCEL_Z"] / 100.0
    g[C.G_WP_RADIUS] = max(p["WPNAV_RADIUS"] / 100.0, 0.05)
    g[C.G_WP_JERK] = p["WPNAV_JERK"]
    g[C.G_WP_LEG_K] = p["TLM_WP_LEG_K"]
    g[C.G_RTL_ALT] = p["RTL_ALT"] / 100.0
    g[C.G_RTL_SPEED] = p["RTL_SPEED"] / 100.0
    g[C.G_RTL_LOIT_TIME] = p["RTL_LOIT_TIME"] / 1000.0
    g[C.G_RTL_CONE_SLOPE] = p["RTL_CONE_SLOPE"]
    g[C.G_RTL_CLIMB_MIN] = p["RTL_CLIMB_MIN"] / 100.0
    g[C.G_LAND_SPEED] = p["LAND_SPEED"] / 100.0
    g[C.G_LAND_SPEED_HIGH] = p["LAND_SPEED_HIGH"] / 100.0
    g[C.G_LAND_ALT_LOW] = p["LAND_ALT_LOW"] / 100.0
    g[C.G_ARM_TIME] = p["TLM_ARM_TIME"]
    _driver(g, p)


def _driver(g: np.ndarray, p: Params) -> None:
    """The driver's GUIDED switch and arm attempts, the pre-arm checks (ARMING_*,
    GPS_HDOP_GOOD, BATT_ARM_VOLT; tlm_sim.control.arming): SITL's boot times with
    TLM_BOOT_PHASE 1, TLM_ARM_TIME without."""
    boot = p["TLM_BOOT_PHASE"] != 0.0
    g[C.G_BOOT] = 1.0 if boot else 0.0
    g[C.G_DRIVER_T] = BOOT_DRIVER_S if boot else p["TLM_ARM_TIME"]
    first = BOOT_ARM_ATTEMPTS_S[0] if boot else p["TLM_ARM_TIME"]
    g[C.G_ARM_FIRST] = first
    g[C.G_ARM_SECOND] = BOOT_ARM_ATTEMPTS_S[1] if boot else first + ARM_RETRY_S
    g[C.G_ARM_GIVE_UP] = first + ARM_TIMEOUT_S
    # AP_Arming::update's 1 Hz, on the reference logs' phase (x.449 s)
    g[C.G_PREARM_FIRST] = PREARM_FIRST_S if boot else PREARM_FIRST_S % 1.0
    g[C.G_ARMING_CHECK] = p["ARMING_CHECK"]
    g[C.G_ACC_THRESH] = p["ARMING_ACCTHRESH"]
    g[C.G_HDOP_GOOD] = p["GPS_HDOP_GOOD"] / 100.0
    g[C.G_BATT_ARM_VOLT] = p["BATT_ARM_VOLT"]


def _motors(g: np.ndarray, p: Params) -> None:
    """Motor matrix of the frame, thrust curve, spin and PWM range, voltage and air density
    compensation (MOT_*)."""
    g[C.G_MOT_EXPO] = p["MOT_THST_EXPO"]
    g[C.G_MOT_HOVER] = p["MOT_THST_HOVER"]
    g[C.G_MOT_SPIN_ARM] = p["MOT_SPIN_ARM"]
    g[C.G_MOT_SPIN_MIN] = p["MOT_SPIN_MIN"]
    g[C.G_MOT_SPIN_MAX] = p["MOT_SPIN_MAX"]
    g[C.G_MOT_PWM_MIN] = p["MOT_PWM_MIN"] or 1000.0  # 0 = the RC3 range, 1000-2000 in SITL
    g[C.G_MOT_PWM_MAX] = p["MOT_PWM_MAX"] or 2000.0
    g[C.G_MOT_BAT_MAX] = p["MOT_BAT_VOLT_MAX"]
    g[C.G_MOT_BAT_MIN] = p["MOT_BAT_VOLT_MIN"]
    g[C.G_MOT_YAW_HEADROOM] = p["MOT_YAW_HEADROOM"] / 1000.0
    layout = frame_for(p["FRAME_CLASS"], p["FRAME_TYPE"])
    g[C.G_N_MOTORS] = layout.n_motors
    for slot, factors in zip((C.G_MIX_ROLL, C.G_MIX_PITCH, C.G_MIX_YAW), layout.mixer_factors(),
                             strict=True):
        g[slot:slot + layout.n_motors] = factors
    g[C.G_HOVER_LEARN] = p["MOT_HOVER_LEARN"]
    g[C.G_BATT_SAG_HOVER] = p["TLM_BATT_SAG_HOV"]
    g[C.G_BATT_RES0] = p["TLM_BATT_SAG_HOV"] / p["TLM_REF_CURR"]
    # the barometer's air density ratio for the motors' density compensation: the 1976
    # atmosphere at the home altitude (field elevation) plus the height above it
    home_alt = p["SIM_OPOS_ALT"]
    g[C.G_RHO_RATIO_HOME] = air_density(home_alt) / RHO0
    g[C.G_RHO_RATIO_GRAD] = air_density_gradient(home_alt) / RHO0
    dt = g[C.G_DT]
    g[C.G_THR_FILT_A] = lpf_alpha(THROTTLE_CUTOFF_HZ, dt)
    g[C.G_SLEW_FILT_A] = lpf_alpha(SLEW_FILTER_CUTOFF_HZ, dt)


def _failsafes(g: np.ndarray, p: Params) -> None:
    """Radio, EKF, vibration, crash and battery failsafes (FS_*, RC_FS_TIMEOUT, EK3_HRT_FILT,
    BATT_*)."""
    g[C.G_FS_THR_ENABLE] = p["FS_THR_ENABLE"]
    g[C.G_RC_FS_TIMEOUT] = p["RC_FS_TIMEOUT"]
    g[C.G_FS_CRASH_CHECK] = p["FS_CRASH_CHECK"]
    g[C.G_HRT_OMEGA] = 2.0 * math.pi * min(max(p["EK3_HRT_FILT"], 0.1), 30.0)
    g[C.G_FS_VIBE_ENABLE] = p["FS_VIBE_ENABLE"]
    g[C.G_FS_EKF_THRESH] = p["FS_EKF_THRESH"]
    g[C.G_FS_EKF_ACTION] = p["FS_EKF_ACTION"]
    g[C.G_FS_THR_VALUE] = p["FS_THR_VALUE"]
    g[C.G_BATT_CAPACITY] = p["BATT_CAPACITY"]
    g[C.G_BATT_LOW_VOLT] = p["BATT_LOW_VOLT"]
    g[C.G_BATT_CRT_VOLT] = p["BATT_CRT_VOLT"]
    g[C.G_BATT_LOW_TIMER] = p["BATT_LOW_TIMER"]
    g[C.G_BATT_LOW_MAH] = p["BATT_LOW_MAH"]
    g[C.G_BATT_CRT_MAH] = p["BATT_CRT_MAH"]
    g[C.G_BATT_FS_LOW_ACT] = p["BATT_FS_LOW_ACT"]
    g[C.G_BATT_FS_CRT_ACT] = p["BATT_FS_CRT_ACT"]
    filt = p["FS_EKF_FILT"]
    g[C.G_FS_EKF_ALPHA] = 1.0 if filt <= 0.0 else 0.1 / (0.1 + 1.0 / (2.0 * math.pi * filt))


def _dcm(g: np.ndarray, p: Params) -> None:
    """The DCM estimator's gains and GPS use, the declination and the assumed GPS lag."""
    g[C.G_AHRS_RP_P] = p["AHRS_RP_P"]
    g[C.G_AHRS_YAW_P] = p["AHRS_YAW_P"]
    g[C.G_AHRS_GPS_GAIN] = p["AHRS_GPS_GAIN"]
    g[C.G_AHRS_GPS_MINSATS] = p["AHRS_GPS_MINSATS"]
    g[C.G_AHRS_GPS_USE] = p["AHRS_GPS_USE"]
    g[C.G_MAG_DEC] = math.radians(p["TLM_MAG_DEC_DEG"])
    g[C.G_GPS_LAG] = gps_delay_s(p)


#: AC_Loiter's position correction limits (LOITER_POS_CORRECTION_MAX, LOITER_VEL_CORRECTION_MAX)
LOITER_POS_CORRECTION_MAX_M = 2.0
LOITER_VEL_CORRECTION_MAX_MS = 2.0
_STICKS = ("ROLL", "PITCH", "THROTTLE", "YAW")


def _pilot(g: np.ndarray, p: Params) -> None:
    """The receiver and the pilot's modes (RCn_*, RCMAP_*, FLTMODE*, PILOT_*, THR_DZ, LOIT_*,
    PHLD_*, ARMING_RUDDER, DISARM_DELAY; tlm_sim.control.pilot). G_PILOT itself is set by
    :func:`tlm_sim.flight.fly` when the flight has RC input to fly from."""
    for k, name in enumerate(_STICKS):
        ch = int(p[f"RCMAP_{name}"])
        g[C.G_RC_MAP + k] = ch - 1
        g[C.G_RC_MIN + k] = p[f"RC{ch}_MIN"]
        g[C.G_RC_MAX + k] = p[f"RC{ch}_MAX"]
        g[C.G_RC_TRIM + k] = p[f"RC{ch}_TRIM"]
        g[C.G_RC_DZ + k] = p[f"RC{ch}_DZ"]
        g[C.G_RC_REV + k] = p[f"RC{ch}_REVERSED"]
    for k in range(6):
        g[C.G_FLTMODE + k] = p[f"FLTMODE{k + 1}"]
    g[C.G_FLTMODE_CH] = p["FLTMODE_CH"] - 1.0
    up = p["PILOT_SPEED_UP"] / 100.0
    dn = (p["PILOT_SPEED_DN"] or p["PILOT_SPEED_UP"]) / 100.0
    accel = p["PILOT_ACCEL_Z"] / 100.0
    g[C.G_PILOT_SPEED_UP] = up
    g[C.G_PILOT_SPEED_DN] = dn
    g[C.G_PILOT_ACCEL_Z] = accel
    g[C.G_PILOT_JERK_Z] = p["PSC_JERK_Z"]
    g[C.G_PILOT_POSZ_ERR_UP] = inv_sqrt_ctrl(up, p["PSC_POSZ_P"], accel)
    g[C.G_PILOT_POSZ_ERR_DN] = inv_sqrt_ctrl(dn, p["PSC_POSZ_P"], accel)
    g[C.G_PILOT_Y_RATE] = math.radians(p["PILOT_Y_RATE"])
    g[C.G_PILOT_Y_EXPO] = p["PILOT_Y_EXPO"]
    g[C.G_PILOT_Y_TC] = p["PILOT_Y_RATE_TC"]
    g[C.G_THR_DZ] = min(max(p["THR_DZ"], 0.0), 400.0)
    # RC_Channel::get_control_mid of the throttle (an integer: 484 for 1000-2000, DZ 30)
    lo = g[C.G_RC_MIN + 2] + g[C.G_RC_DZ + 2]
    hi = g[C.G_RC_MAX + 2]
    mid = 0.5 * (g[C.G_RC_MIN + 2] + hi)
    g[C.G_THR_MID] = float(int(1000.0 * (mid - lo) / (hi - lo))) if hi > lo else 500.0
    g[C.G_TKOFF_ALT] = p["PILOT_TKOFF_ALT"] / 100.0
    g[C.G_TKOFF_SLEW] = p["TKOFF_SLEW_TIME"]
    g[C.G_TKOFF_THR_MAX] = p["TKOFF_THR_MAX"]
    g[C.G_ARMING_RUDDER] = p["ARMING_RUDDER"]
    g[C.G_DISARM_DELAY] = p["DISARM_DELAY"]
    g[C.G_THR_MIX_MAN] = p["ATC_THR_MIX_MAN"]
    # AC_Loiter::get_angle_max_cd: LOIT_ANG_MAX, or 2/3 of ANGLE_MAX when 0 (tlm's position
    # controller leans to ANGLE_MAX: PSC_ANGLE_MAX is not modelled)
    angle_max = p["ANGLE_MAX"] / 100.0
    loit = p["LOIT_ANG_MAX"]
    g[C.G_LOIT_ANG_MAX] = math.radians(min(loit, angle_max) if loit > 0.0 else angle_max * 2 / 3)
    g[C.G_LOIT_SPEED] = max(p["LOIT_SPEED"], 20.0) / 100.0
    g[C.G_LOIT_ACC_MAX] = min(p["LOIT_ACC_MAX"] / 100.0,
                              GRAVITY_MSS * math.tan(math.radians(angle_max)))
    g[C.G_LOIT_BRK_ACCEL] = p["LOIT_BRK_ACCEL"] / 100.0
    g[C.G_LOIT_BRK_JERK] = p["LOIT_BRK_JERK"] / 100.0
    g[C.G_LOIT_BRK_DELAY] = p["LOIT_BRK_DELAY"]
    g[C.G_LOIT_ERR_MAX] = min(LOITER_POS_CORRECTION_MAX_M, inv_sqrt_ctrl(
        LOITER_VEL_CORRECTION_MAX_MS, p["PSC_POSXY_P"], g[C.G_LOIT_ACC_MAX]))
    g[C.G_PHLD_BRAKE_RATE] = max(p["PHLD_BRAKE_RATE"], 4.0)
    g[C.G_PHLD_BRAKE_ANGLE] = p["PHLD_BRAKE_ANGLE"]
    g[C.G_ACRO_RP_RATE] = math.radians(p["ACRO_RP_RATE"])
    g[C.G_ACRO_RP_EXPO] = p["ACRO_RP_EXPO"]
    g[C.G_ACRO_Y_RATE] = math.radians(p["ACRO_Y_RATE"])
    g[C.G_ACRO_Y_EXPO] = p["ACRO_Y_EXPO"]
    g[C.G_ACRO_TC] = p["ACRO_RP_RATE_TC"]
    g[C.G_ACRO_TC + 1] = p["ACRO_RP_RATE_TC"]
    g[C.G_ACRO_TC + 2] = p["ACRO_Y_RATE_TC"]
    g[C.G_ACRO_TRAINER] = p["ACRO_TRAINER"]
    g[C.G_ACRO_BAL] = p["ACRO_BAL_ROLL"]
    g[C.G_ACRO_BAL + 1] = p["ACRO_BAL_PITCH"]
    g[C.G_ACRO_THR_MID] = p["ACRO_THR_MID"]


def build_control_config(p: Params) -> np.ndarray:
    """Controller configuration of a flight from its parameters (ArduCopter names -> SI)."""
    require_params(p, "build_control_config")
    dt = 1.0 / p["SCHED_LOOP_RATE"]
    g = np.zeros(C.N_CONTROL_CFG)
    g[C.G_DT] = dt
    _attitude(g, p, dt)
    _position(g, p, dt)
    _navigation(g, p)
    _motors(g, p)
    _failsafes(g, p)
    _dcm(g, p)
    _pilot(g, p)
    g[C.G_YAW_ERR_MAX] = yaw_error_max(g[C.G_RAT_P + 2], g[C.G_ANG_P + 2], g[C.G_ACCEL_MAX + 2])
    g[C.G_POSXY_ERR_MAX] = inv_sqrt_ctrl(g[C.G_WP_SPEED], g[C.G_POSXY_P], g[C.G_WP_ACCEL])
    g[C.G_POSZ_ERR_UP] = inv_sqrt_ctrl(g[C.G_WP_SPEED_UP], g[C.G_POSZ_P], g[C.G_WP_ACCEL_Z])
    g[C.G_POSZ_ERR_DN] = inv_sqrt_ctrl(g[C.G_WP_SPEED_DN], g[C.G_POSZ_P], g[C.G_WP_ACCEL_Z])
    return g


def inv_sqrt_ctrl(output: float, p: float, accel: float) -> float:
    """Error at which the square-root controller (gain p, acceleration accel) outputs
    ``output``: AC_P_2D's error_max, beyond which AC_PosControl moves its target towards the
    vehicle. For the position controller with WPNAV_SPEED 6 m/s, PSC_POSXY_P 1 and WPNAV_ACCEL
    2.5 m/s^2 it is 8.45 m, the distance at which gps_s12.bin's PSCN/PSCE target sits from the
    position estimate while the EKF has no position (inf: no limit)."""
    if output <= 0.0:
        return math.inf
    if accel <= 0.0:
        return output / p if p > 0.0 else math.inf
    if p <= 0.0:
        return output * output / (2.0 * accel)
    if output <= accel / p:
        return output / p
    return output * output / (2.0 * accel) + accel / (2.0 * p * p)


def yaw_error_max(rate_p: float, angle_p: float, accel_max: float) -> float:
    """Largest heading error [rad] the attitude controller acts on: the error whose square-root
    controller output (ATC_ANG_YAW_P, half the yaw acceleration limit, kept within 10..120
    deg/s^2) saturates the yaw-rate loop (a rate error of 1/ATC_RAT_YAW_P), at most 45 deg
    (AC_AttitudeControl's heading error limit). With the SITL defaults: 45 deg, which is the
    heading error engine_s14.bin holds for 25 s on the ground after the crash (DesYaw 337 vs
    Yaw 291 deg)."""
    cap = math.radians(45.0)
    if rate_p <= 0.0 or angle_p <= 0.0:
        return cap
    out = 1.0 / rate_p
    d = min(max(0.5 * accel_max, math.radians(10.0)), math.radians(120.0))
    err = out / angle_p if out <= d / angle_p else out * out / (2.0 * d) + d / (2.0 * angle_p**2)
    return min(err, cap)
