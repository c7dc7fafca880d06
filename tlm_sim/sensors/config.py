"""Build the sensor configuration array from a :class:`~tlm_sim.params.Params` (once per flight).

Every value comes from the parameter set (SITL names and units, converted to SI here); the
defaults live in ``tlm_sim/data/copter_defaults.parm`` and the ``TLM_*`` table only.
"""

import math

import numpy as np

from tlm_sim.boot import BOOT_GPS_DETECT_S
from tlm_sim.frames import MAX_MOTORS, frame_for
from tlm_sim.params import Params, earth_field, require_params
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.imu import lpf2p_coefficients

# SITL's IMU sample rates ("like a Pixhawk 1"): (gyro Hz, accel Hz) per instance
IMU_RATES_HZ = ((1000.0, 1000.0), (760.0, 800.0))
# sub-samples SITL averages into one published sample (gyro IMU0, IMU1, accel IMU0, IMU1):
# INS_FAST_SAMPLE (default 1) fast-samples the first IMU, 8 gyro and 4 accel sub-samples. tlm
# draws the base noise once per published sample (its amplitude fitted, TLM_INSn_NSE_SC) and
# sub-samples only the vibration sinusoids, whose phases advance per sub-sample.
IMU_SUBSAMPLES = (8.0, 1.0, 4.0, 1.0)


def _imu_config(c: np.ndarray, p: Params) -> None:
    """Per-IMU noise, bias, failure, rates and filters of IMU instances 0 and 1."""
    c[S.C_ACC_NOISE] = p["TLM_ACC_NOISE"]
    c[S.C_GYR_NOISE] = math.radians(p["TLM_GYR_NOISE"])
    for i, n in enumerate(("1", "2")):
        c[S.C_GYR_RND + i] = math.radians(p[f"SIM_GYR{n}_RND"])
        c[S.C_ACC_RND + i] = p[f"SIM_ACC{n}_RND"]
        for k, ax in enumerate("XYZ"):
            c[S.C_ACC_BIAS + 3 * i + k] = p[f"SIM_ACC{n}_BIAS_{ax}"]
            c[S.C_GYR_BIAS + 3 * i + k] = p[f"SIM_GYR{n}_BIAS_{ax}"]
            c[S.C_ACC_SCAL + 3 * i + k] = p[f"SIM_ACC{n}_SCAL_{ax}"]
            c[S.C_GYR_SCALE + 3 * i + k] = 1.0 + p[f"SIM_GYR{n}_SCALE_{ax}"] / 100.0
        c[S.C_ACC_FAIL + i] = p[f"SIM_ACCEL{n}_FAIL"]
        c[S.C_NOISE_SCALE + i] = p[f"TLM_INS{n}_NSE_SC"]
        g_hz, a_hz = IMU_RATES_HZ[i]
        c[S.C_GYR_PERIOD_US + i] = round(1e6 / g_hz)
        c[S.C_ACC_PERIOD_US + i] = round(1e6 / a_hz)
        c[S.C_GYR_LPF + 5 * i : S.C_GYR_LPF + 5 * i + 5] = lpf2p_coefficients(
            g_hz, p["INS_GYRO_FILTER"]
        )
        c[S.C_ACC_LPF + 5 * i : S.C_ACC_LPF + 5 * i + 5] = lpf2p_coefficients(
            a_hz, p["INS_ACCEL_FILTER"]
        )
        c[S.C_GYR_WALK_STEP + i] = math.radians(p["TLM_GYR_WALK"]) / math.sqrt(g_hz)
        c[S.C_ACC_WALK_STEP + i] = p["TLM_ACC_WALK"] / math.sqrt(a_hz)
        c[S.C_VIB_FLOOR_A + i] = 1.0 / (1.0 + a_hz / (2.0 * math.pi * 5.0))
        c[S.C_VIB_SQ_A + i] = 1.0 / (1.0 + a_hz / (2.0 * math.pi * 2.0))
    c[S.C_DRIFT_SPEED] = math.radians(p["SIM_DRIFT_SPEED"])
    c[S.C_DRIFT_TIME] = p["SIM_DRIFT_TIME"]
    c[S.C_INS_THR_MIN] = p["SIM_INS_THR_MIN"]
    c[S.C_ACC_FAIL_MSK] = p["SIM_ACC_FAIL_MSK"]
    c[S.C_GYR_FAIL_MSK] = p["SIM_GYR_FAIL_MSK"]
    _vibration_config(c, p)


def _vibration_config(c: np.ndarray, p: Params) -> None:
    """SITL's vibration model: motor-locked (SIM_VIB_MOT_*) and fixed-frequency (SIM_VIB_FREQ_*)
    sinusoids, amplitudes SIM_ACCn_RND / SIM_GYRn_RND (sensors.imu)."""
    c[S.C_VIB_MOT_MAX] = p["SIM_VIB_MOT_MAX"]
    for k, ax in enumerate("XYZ"):
        c[S.C_VIB_FREQ + k] = p[f"SIM_VIB_FREQ_{ax}"]
    c[S.C_VIB_ON] = 1.0 if (p["SIM_VIB_MOT_MAX"] > 0.0
                            or any(c[S.C_VIB_FREQ:S.C_VIB_FREQ + 3] != 0.0)) else 0.0
    c[S.C_VIB_MOT_MULT] = p["SIM_VIB_MOT_MULT"]
    c[S.C_VIB_MOT_HMNC] = p["SIM_VIB_MOT_HMNC"]
    # SITL's mask of the frame's motors (outputs 1..n), ORed with SIM_VIB_MOT_MASK
    n_motors = frame_for(p["FRAME_CLASS"], p["FRAME_TYPE"]).n_motors
    c[S.C_VIB_MOT_MASK] = float((1 << n_motors) - 1 | int(p["SIM_VIB_MOT_MASK"]))
    c[S.C_IMU_NSUB:S.C_IMU_NSUB + 4] = IMU_SUBSAMPLES
    # a real copter's structure (issue 40): per-axis gains, one imbalanced propeller
    for k, ax in enumerate("XYZ"):
        c[S.C_VIB_ACC_AX + k] = p[f"TLM_VIB_ACC_{ax}"]
        c[S.C_VIB_GYR_AX + k] = p[f"TLM_VIB_GYR_{ax}"]
    c[S.C_VIB_IMB] = p["TLM_VIB_IMB"]
    c[S.C_VIB_IMB_MOT] = p["TLM_VIB_IMB_MOT"] - 1.0  # -1: none
    c[S.C_ROTOR_TC] = p["TLM_ROTOR_TC"]
    c[S.C_VIB_CMD_REF] = p["TLM_VIB_CMD_REF"]
    # rotors that turn a little apart (TLM_VIB_SPREAD): motor m of n at 1 + spread x
    # (2 m / (n - 1) - 1), -spread .. +spread in motor order
    c[S.C_VIB_MOT_FMUL:S.C_VIB_MOT_FMUL + MAX_MOTORS] = 1.0
    if p["TLM_VIB_SPREAD"] > 0.0 and n_motors > 1:
        for m in range(n_motors):
            c[S.C_VIB_MOT_FMUL + m] = 1.0 + p["TLM_VIB_SPREAD"] * (2.0 * m / (n_motors - 1)
                                                                       - 1.0)
    span = p["TLM_PWM_MAX"] - p["TLM_PWM_MIN"]
    c[S.C_ROTOR_PWM] = p["TLM_PWM_MIN"] + p["TLM_SPIN_MIN"] * span
    c[S.C_ROTOR_PWM + 1] = (p["TLM_SPIN_MAX"] - p["TLM_SPIN_MIN"]) * span
    for i in range(2):
        c[S.C_ACC_SLOW + i] = 1.0 if (c[S.C_ACC_WALK_STEP + i] != 0.0
                                      or (p["TLM_VIB_IMB"] > 0.0 and c[S.C_VIB_ON] != 0.0)) else 0.0


def _gps_config(c: np.ndarray, p: Params) -> None:
    """GPS 1: enable, rate, lag, satellites, reported accuracy and dilution, errors, glitch
    offsets, jamming, lock time and (with the boot phase) the time the driver finds it."""
    c[S.C_GPS_ENABLE] = p["SIM_GPS1_ENABLE"]
    c[S.C_GPS_PERIOD_US] = round(1e6 / max(p["SIM_GPS1_HZ"], 1.0))
    c[S.C_GPS_LAG_S] = p["SIM_GPS1_LAG_MS"] / 1000.0
    c[S.C_GPS_NUMSATS] = p["SIM_GPS1_NUMSATS"]
    c[S.C_GPS_HDOP] = p["TLM_GPS_HDOP"]
    c[S.C_GPS_VDOP] = p["TLM_GPS_VDOP"]
    c[S.C_GPS_ACC] = p["SIM_GPS1_ACC"]
    for k, ax in enumerate("XYZ"):
        c[S.C_GPS_VERR + k] = p[f"SIM_GPS1_VERR_{ax}"]
    c[S.C_GPS_NOISE] = p["SIM_GPS1_NOISE"]
    for k, ax in enumerate("XYZ"):
        c[S.C_GPS_GLITCH + k] = p[f"SIM_GPS1_GLTCH_{ax}"]
    c[S.C_GPS_JAM] = p["SIM_GPS1_JAM"]
    c[S.C_GPS_LOCK_US] = 1e6 * p["SIM_GPS1_LCKTIME"]
    c[S.C_BOOT] = p["TLM_BOOT_PHASE"]
    c[S.C_GPS_DETECT_US] = round(1e6 * BOOT_GPS_DETECT_S) if p["TLM_BOOT_PHASE"] else 0.0


def _baro_config(c: np.ndarray, p: Params) -> None:
    """Barometers 1 and 2 (SIM_BARO_*, SIM_BAR2_*): noise, glitch, drift, freeze, disable; the
    board temperature warm-up (SIM_TEMP_*)."""
    for i, n in enumerate(("BARO", "BAR2")):
        c[S.C_BARO_RND + i] = p[f"SIM_{n}_RND"]
        c[S.C_BARO_GLITCH + i] = p[f"SIM_{n}_GLITCH"]
        c[S.C_BARO_DRIFT + i] = p[f"SIM_{n}_DRIFT"]
        c[S.C_BARO_FREEZE + i] = p[f"SIM_{n}_FREEZE"]
        c[S.C_BARO_DISABLE + i] = p[f"SIM_{n}_DISABLE"]
    c[S.C_TEMP_START] = p["SIM_TEMP_START"]
    c[S.C_TEMP_BRD_OFF] = p["SIM_TEMP_BRD_OFF"]
    c[S.C_TEMP_TCONST] = p["SIM_TEMP_TCONST"]


def _mag_config(c: np.ndarray, p: Params) -> None:
    """The compasses: noise, earth field, anomaly, motor interference, per-compass faults
    (mGauss -> gauss)."""
    c[S.C_MAG_RND] = p["SIM_MAG_RND"] / 1000.0
    c[S.C_MAG_EARTH : S.C_MAG_EARTH + 3] = earth_field(p)
    for k, ax in enumerate("XYZ"):
        c[S.C_MAG_ALY + k] = p[f"SIM_MAG_ALY_{ax}"] / 1000.0
        c[S.C_MAG_MOT + k] = p[f"SIM_MAG_MOT_{ax}"] / 1000.0
    c[S.C_MAG_ALY_HGT] = p["SIM_MAG_ALY_HGT"]
    for i in range(S.N_MAG):
        c[S.C_MAG_FAIL + i] = p[f"SIM_MAG{i + 1}_FAIL"]


def build_sensor_config(p: Params) -> np.ndarray:
    """Sensor configuration of a flight from its parameters (SITL names and units -> SI)."""
    require_params(p, "build_sensor_config")
    c = np.zeros(S.N_SENSOR_CFG)
    _imu_config(c, p)
    _gps_config(c, p)
    _baro_config(c, p)
    _mag_config(c, p)
    c[S.C_RC_FAIL] = p["SIM_RC_FAIL"]
    c[S.C_RC3_RANGE] = p["RC3_MIN"]
    c[S.C_RC3_RANGE + 1] = p["RC3_MAX"]
    c[S.C_HOME_ALT] = p["SIM_OPOS_ALT"]
    c[S.C_FRAME_HEIGHT] = p["TLM_FRAME_HEIGHT"]
    return c
