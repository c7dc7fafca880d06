"""Build the controller configuration array from ArduPilot parameters (once per flight).

ArduPilot units are converted to SI here (cm -> m, cdeg -> rad, cm/s -> m/s); filter cut-offs
become first-order filter alphas at the 400 Hz main-loop rate (SCHED_LOOP_RATE).
"""

import math
from collections.abc import Mapping

import numpy as np

from tlm_sim.control import layout as C
from tlm_sim.dynamics.atmosphere import RHO0, air_density, air_density_gradient

LOOP_HZ = 400.0


def lpf_alpha(cutoff_hz: float, dt: float) -> float:
    """First-order low-pass alpha for a cut-off frequency (1 = no filtering when cut-off is 0)."""
    if cutoff_hz <= 0.0:
        return 1.0
    return dt / (dt + 1.0 / (2.0 * math.pi * cutoff_hz))


def build_control_config(p: Mapping[str, float], loop_hz: float | None = None) -> np.ndarray:
    """Controller configuration from parameters (ArduCopter names, defaults as the SITL logs)."""
    hz = loop_hz or p.get("SCHED_LOOP_RATE", LOOP_HZ)
    dt = 1.0 / hz
    g = np.zeros(C.N_CONTROL_CFG)
    g[C.G_DT] = dt
    rat_defaults = {
        "RLL": (0.135, 0.135, 0.0036, 0.0, 0.5, 20.0, 0.0, 20.0),
        "PIT": (0.135, 0.135, 0.0036, 0.0, 0.5, 20.0, 0.0, 20.0),
        "YAW": (0.3, 0.02, 0.0, 0.0, 0.5, 20.0, 2.5, 20.0),
    }
    for k, ax in enumerate(("RLL", "PIT", "YAW")):
        dp, di, dd, dff, dimax, dfltt, dflte, dfltd = rat_defaults[ax]
        g[C.G_RAT_P + k] = p.get(f"ATC_RAT_{ax}_P", dp)
        g[C.G_RAT_I + k] = p.get(f"ATC_RAT_{ax}_I", di)
        g[C.G_RAT_D + k] = p.get(f"ATC_RAT_{ax}_D", dd)
        g[C.G_RAT_FF + k] = p.get(f"ATC_RAT_{ax}_FF", dff)
        g[C.G_RAT_IMAX + k] = p.get(f"ATC_RAT_{ax}_IMAX", dimax)
        g[C.G_RAT_FLTT + k] = lpf_alpha(p.get(f"ATC_RAT_{ax}_FLTT", dfltt), dt)
        g[C.G_RAT_FLTE + k] = lpf_alpha(p.get(f"ATC_RAT_{ax}_FLTE", dflte), dt)
        g[C.G_RAT_FLTD + k] = lpf_alpha(p.get(f"ATC_RAT_{ax}_FLTD", dfltd), dt)
    for k, ax in enumerate(("RLL", "PIT", "YAW")):
        g[C.G_ANG_P + k] = p.get(f"ATC_ANG_{ax}_P", 4.5)
    # ATC_ACCEL_*_MAX [cdeg/s^2], constrained as the attitude controller does
    for k, (ax, d, lo, hi) in enumerate(
        (("R", 110000.0, 40.0, 720.0), ("P", 110000.0, 40.0, 720.0), ("Y", 27000.0, 10.0, 120.0))
    ):
        deg = p.get(f"ATC_ACCEL_{ax}_MAX", d) / 100.0
        g[C.G_ACCEL_MAX + k] = math.radians(min(max(deg, lo), hi) if deg > 0 else hi)
    g[C.G_INPUT_TC] = max(p.get("ATC_INPUT_TC", 0.15), 0.05)
    g[C.G_SLEW_YAW] = math.radians(p.get("ATC_SLEW_YAW", 6000.0) / 100.0)
    g[C.G_ANGLE_MAX] = math.radians(p.get("ANGLE_MAX", 3000.0) / 100.0)
    g[C.G_ACCEL_XY_MAX] = 9.80665 * math.tan(g[C.G_ANGLE_MAX])
    g[C.G_POSXY_P] = p.get("PSC_POSXY_P", 1.0)
    g[C.G_VELXY_P] = p.get("PSC_VELXY_P", 2.0)
    g[C.G_VELXY_I] = p.get("PSC_VELXY_I", 1.0)
    g[C.G_VELXY_D] = p.get("PSC_VELXY_D", 0.25)
    g[C.G_VELXY_IMAX] = p.get("PSC_VELXY_IMAX", 1000.0) / 100.0
    g[C.G_VELXY_FLTE] = lpf_alpha(p.get("PSC_VELXY_FLTE", 5.0), dt)
    g[C.G_VELXY_FLTD] = lpf_alpha(p.get("PSC_VELXY_FLTD", 5.0), dt)
    g[C.G_POSZ_P] = p.get("PSC_POSZ_P", 1.0)
    g[C.G_VELZ_P] = p.get("PSC_VELZ_P", 5.0)
    g[C.G_ACCZ_P] = p.get("PSC_ACCZ_P", 0.5)
    g[C.G_ACCZ_I] = p.get("PSC_ACCZ_I", 1.0)
    g[C.G_ACCZ_D] = p.get("PSC_ACCZ_D", 0.0)
    g[C.G_ACCZ_IMAX] = p.get("PSC_ACCZ_IMAX", 800.0)
    g[C.G_ACCZ_FLTE] = lpf_alpha(p.get("PSC_ACCZ_FLTE", 20.0), dt)
    g[C.G_WP_SPEED] = p.get("WPNAV_SPEED", 600.0) / 100.0
    g[C.G_WP_ACCEL] = p.get("WPNAV_ACCEL", 250.0) / 100.0
    g[C.G_WP_SPEED_UP] = p.get("WPNAV_SPEED_UP", 250.0) / 100.0
    g[C.G_WP_SPEED_DN] = p.get("WPNAV_SPEED_DN", 150.0) / 100.0
    g[C.G_WP_ACCEL_Z] = p.get("WPNAV_ACCEL_Z", 100.0) / 100.0
    g[C.G_WP_RADIUS] = max(p.get("WPNAV_RADIUS", 200.0) / 100.0, 0.05)
    g[C.G_WP_JERK] = p.get("WPNAV_JERK", 1.0)
    g[C.G_RTL_ALT] = p.get("RTL_ALT", 2000.0) / 100.0
    g[C.G_RTL_SPEED] = p.get("RTL_SPEED", 0.0) / 100.0
    g[C.G_RTL_LOIT_TIME] = p.get("RTL_LOIT_TIME", 5000.0) / 1000.0
    g[C.G_RTL_CONE_SLOPE] = p.get("RTL_CONE_SLOPE", 3.0)
    g[C.G_RTL_CLIMB_MIN] = p.get("RTL_CLIMB_MIN", 0.0) / 100.0
    g[C.G_LAND_SPEED] = p.get("LAND_SPEED", 50.0) / 100.0
    g[C.G_LAND_SPEED_HIGH] = p.get("LAND_SPEED_HIGH", 0.0) / 100.0
    g[C.G_LAND_ALT_LOW] = p.get("LAND_ALT_LOW", 1000.0) / 100.0
    g[C.G_MOT_EXPO] = p.get("MOT_THST_EXPO", 0.65)
    g[C.G_MOT_HOVER] = p.get("MOT_THST_HOVER", 0.39)
    g[C.G_MOT_SPIN_ARM] = p.get("MOT_SPIN_ARM", 0.1)
    g[C.G_MOT_SPIN_MIN] = p.get("MOT_SPIN_MIN", 0.15)
    g[C.G_MOT_SPIN_MAX] = p.get("MOT_SPIN_MAX", 0.95)
    g[C.G_MOT_PWM_MIN] = p.get("MOT_PWM_MIN", 1000.0) or 1000.0
    g[C.G_MOT_PWM_MAX] = p.get("MOT_PWM_MAX", 2000.0) or 2000.0
    g[C.G_MOT_BAT_MAX] = p.get("MOT_BAT_VOLT_MAX", 12.8)
    g[C.G_MOT_BAT_MIN] = p.get("MOT_BAT_VOLT_MIN", 9.6)
    g[C.G_MOT_YAW_HEADROOM] = p.get("MOT_YAW_HEADROOM", 200.0) / 1000.0
    g[C.G_FS_THR_ENABLE] = p.get("FS_THR_ENABLE", 1.0)
    g[C.G_RC_FS_TIMEOUT] = p.get("RC_FS_TIMEOUT", 1.0)
    g[C.G_FS_THR_VALUE] = p.get("FS_THR_VALUE", 975.0)
    g[C.G_ARM_TIME] = p.get("TLM_ARM_TIME", 10.0)
    g[C.G_HOVER_LEARN] = p.get("MOT_HOVER_LEARN", 2.0)
    g[C.G_WP_LEG_K] = p.get("TLM_WP_LEG_K", 0.946)
    g[C.G_THR_MIX_MIN] = p.get("ATC_THR_MIX_MIN", 0.1)
    g[C.G_THR_MIX_MAX] = p.get("ATC_THR_MIX_MAX", 0.5)
    g[C.G_FS_CRASH_CHECK] = p.get("FS_CRASH_CHECK", 1.0)
    g[C.G_DISARM_DELAY] = p.get("DISARM_DELAY", 10.0)
    g[C.G_HRT_OMEGA] = 2.0 * math.pi * min(max(p.get("EK3_HRT_FILT", 2.0), 0.1), 30.0)
    g[C.G_FS_VIBE_ENABLE] = p.get("FS_VIBE_ENABLE", 1.0)
    g[C.G_FS_EKF_THRESH] = p.get("FS_EKF_THRESH", 0.8)
    g[C.G_FS_EKF_ACTION] = p.get("FS_EKF_ACTION", 1.0)
    filt = p.get("FS_EKF_FILT", 5.0)
    g[C.G_FS_EKF_ALPHA] = 1.0 if filt <= 0.0 else 0.1 / (0.1 + 1.0 / (2.0 * math.pi * filt))
    # the barometer's air density ratio for the motors' density compensation: the 1976
    # atmosphere at the home altitude (field elevation) plus the height above it
    home_alt = p.get("SIM_OPOS_ALT", 584.0)
    g[C.G_RHO_RATIO_HOME] = air_density(home_alt) / RHO0
    g[C.G_RHO_RATIO_GRAD] = air_density_gradient(home_alt) / RHO0
    g[C.G_BATT_SAG_HOVER] = p.get("TLM_BATT_SAG_HOV", 0.075)
    tc = p.get("ATC_ANG_LIM_TC", 1.0)
    g[C.G_ANG_LIM_ALPHA] = 1.0 if tc <= 0.0 else dt / (dt + tc)
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
