"""Build the sensor configuration array from ArduPilot/tlm parameters (once per flight)."""

import math
from collections.abc import Mapping

import numpy as np

from tlm_sim.geo import earth_field_ned
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.imu import lpf2p_coefficients

# SITL's IMU sample rates ("like a Pixhawk 1"): (gyro Hz, accel Hz) per instance
IMU_RATES_HZ = ((1000.0, 1000.0), (760.0, 800.0))


def build_sensor_config(p: Mapping[str, float]) -> np.ndarray:
    """Sensor configuration from parameters (SITL names and units, converted to SI)."""
    c = np.zeros(S.N_SENSOR_CFG)
    c[S.C_ACC_NOISE] = p.get("TLM_ACC_NOISE", 0.01)
    c[S.C_GYR_NOISE] = math.radians(p.get("TLM_GYR_NOISE", 0.04))
    for i, n in enumerate(("1", "2")):
        c[S.C_GYR_RND + i] = math.radians(p.get(f"SIM_GYR{n}_RND", 0.0))
        c[S.C_ACC_RND + i] = p.get(f"SIM_ACC{n}_RND", 0.0)
        for k, ax in enumerate("XYZ"):
            c[S.C_ACC_BIAS + 3 * i + k] = p.get(f"SIM_ACC{n}_BIAS_{ax}", 0.0)
            c[S.C_GYR_BIAS + 3 * i + k] = p.get(f"SIM_GYR{n}_BIAS_{ax}", 0.0)
        c[S.C_ACC_FAIL + i] = p.get(f"SIM_ACCEL{n}_FAIL", 0.0)
        c[S.C_NOISE_SCALE + i] = p.get(f"TLM_INS{n}_NSE_SC", 1.0)
        g_hz, a_hz = IMU_RATES_HZ[i]
        c[S.C_GYR_PERIOD_US + i] = round(1e6 / g_hz)
        c[S.C_ACC_PERIOD_US + i] = round(1e6 / a_hz)
        c[S.C_GYR_LPF + 5 * i : S.C_GYR_LPF + 5 * i + 5] = lpf2p_coefficients(
            g_hz, p.get("INS_GYRO_FILTER", 20.0)
        )
        c[S.C_ACC_LPF + 5 * i : S.C_ACC_LPF + 5 * i + 5] = lpf2p_coefficients(
            a_hz, p.get("INS_ACCEL_FILTER", 20.0)
        )
        c[S.C_VIB_FLOOR_A + i] = 1.0 / (1.0 + a_hz / (2.0 * math.pi * 5.0))
        c[S.C_VIB_SQ_A + i] = 1.0 / (1.0 + a_hz / (2.0 * math.pi * 2.0))
    c[S.C_DRIFT_SPEED] = math.radians(p.get("SIM_DRIFT_SPEED", 0.05))
    c[S.C_DRIFT_TIME] = p.get("SIM_DRIFT_TIME", 5.0)
    c[S.C_INS_THR_MIN] = p.get("SIM_INS_THR_MIN", 0.1)
    c[S.C_GPS_ENABLE] = p.get("SIM_GPS1_ENABLE", 1.0)
    c[S.C_GPS_PERIOD_US] = round(1e6 / max(p.get("SIM_GPS1_HZ", 5.0), 1.0))
    c[S.C_GPS_LAG_S] = p.get("SIM_GPS1_LAG_MS", 100.0) / 1000.0
    c[S.C_GPS_NUMSATS] = p.get("SIM_GPS1_NUMSATS", 10.0)
    c[S.C_GPS_HDOP] = p.get("TLM_GPS_HDOP", 1.21)
    for k, ax in enumerate("XYZ"):
        c[S.C_GPS_VERR + k] = p.get(f"SIM_GPS1_VERR_{ax}", 0.0)
    c[S.C_GPS_NOISE] = p.get("SIM_GPS1_NOISE", 0.0)
    c[S.C_BARO_RND] = p.get("SIM_BARO_RND", 0.0)
    c[S.C_BARO_GLITCH] = p.get("SIM_BARO_GLITCH", 0.0)
    c[S.C_MAG_RND] = p.get("SIM_MAG_RND", 0.0) / 1000.0  # mG -> gauss
    c[S.C_MAG_EARTH : S.C_MAG_EARTH + 3] = earth_field_ned(
        p.get("TLM_MAG_DEC_DEG", 12.65),
        p.get("TLM_MAG_INC_DEG", -65.75),
        p.get("TLM_MAG_INT_GA", 0.579),
    )
    c[S.C_RC_FAIL] = p.get("SIM_RC_FAIL", 0.0)
    c[S.C_HOME_ALT] = p.get("SIM_OPOS_ALT", 584.0)
    c[S.C_VIB_MOT_MAX] = p.get("SIM_VIB_MOT_MAX", 0.0)
    c[S.C_FRAME_HEIGHT] = p.get("TLM_FRAME_HEIGHT", 0.1)
    c[S.C_ENGINE_MUL] = p.get("SIM_ENGINE_MUL", 1.0)
    fail = p.get("SIM_ENGINE_FAIL", 0.0)
    if p.get("TLM_PROFILE", 0.0) >= 0.5:  # paper era: the index of one output, 0 = motor 1
        fail = float(1 << int(fail)) if 0 <= fail < 31 else 0.0
    c[S.C_ENGINE_MASK] = fail
    return c
