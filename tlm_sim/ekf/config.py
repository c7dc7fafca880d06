"""EKF configuration array and per-flight EKF arrays (Python, called once per flight).

Parameter names follow ArduPilot (EK3_*); defaults are the ArduCopter EKF3 defaults
(``ardupilot-reference.md`` section 3.8). Values not covered by an EK3_* parameter use
``TLM_*`` names (earth magnetic field, assumed GPS delay, EKF timing).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from tlm_sim.ekf import layout as L
from tlm_sim.geo import earth_field_ned

GRAVITY = 9.80665  # m/s^2
DEFAULT_GPS_DELAY_MS = 120.0  # u-blox M8/F9 generation (ardupilot-reference §3.8)


def _gate_sigmas(gate_percent: float) -> float:
    """EKF3 gates are in percent of one standard deviation, with a floor of one sigma."""
    return max(0.01 * float(gate_percent), 1.0)


def gps_delay_s(params: Mapping[str, float]) -> float:
    """Assumed lag of GPS samples [s]: GPS1_DELAY_MS (or the older GPS_DELAY_MS) when > 0, else
    the driver default DEFAULT_GPS_DELAY_MS (ArduPilot's u-blox driver reports 0.22 s until the
    receiver generation is known, 0.12 s for M8/F9 receivers; SITL itself lags its samples by
    SIM_GPS1_LAG_MS = 100 ms)."""
    ms = float(params.get("GPS1_DELAY_MS", 0.0) or 0.0)
    if ms <= 0.0:
        ms = float(params.get("GPS_DELAY_MS", 0.0) or 0.0)
    if ms <= 0.0:
        ms = DEFAULT_GPS_DELAY_MS
    return ms * 1e-3


def build_ekf_config(params: Mapping[str, float]) -> np.ndarray:
    """Return the ``cfg[N_CFG]`` float64 array from ArduPilot-named parameters.

    Recognised names (unit, default): EK3_VELNE_M_NSE (m/s, 0.3), EK3_VELD_M_NSE (m/s, 0.5),
    EK3_POSNE_M_NSE (m, 0.5), EK3_ALT_M_NSE (m, 2.0), EK3_MAG_M_NSE (gauss, 0.05),
    EK3_GYRO_P_NSE (rad/s, 0.015), EK3_ACC_P_NSE (m/s^2, 0.35), EK3_GBIAS_P_NSE (rad/s^2, 0.001),
    EK3_ABIAS_P_NSE (m/s^3, 0.02), EK3_VEL_I_GATE / EK3_POS_I_GATE / EK3_HGT_I_GATE (%, 500),
    EK3_MAG_I_GATE (%, 300), EK3_GLITCH_RAD (m, 25), EK3_NOAID_M_NSE (m, 10),
    EK3_ERR_THRESH (0.2), EK3_HGT_DELAY (ms, 60), EK3_ACC_BIAS_LIM (m/s^2, 1.0),
    GPS1_DELAY_MS (ms, 0 = driver default, see :func:`gps_delay_s`), TLM_MAG_DEC_DEG (deg, 12.5),
    TLM_MAG_INC_DEG (deg, -66), TLM_MAG_INT_GA (gauss, 0.58), TLM_LOOP_HZ (Hz, 400),
    TLM_EKF_TARGET_DT (s, 0.012: covariance prediction interval target, as EKF3),
    EK3_TAU_OUTPUT (cs, 25: output observer time constant, limited to 10..50 cs as EKF3).
    """
    p = params
    c = np.zeros(L.N_CFG)
    loop_hz = float(p.get("TLM_LOOP_HZ", 400.0))
    c[L.C_DT] = 1.0 / loop_hz
    c[L.C_TARGET_DT] = float(p.get("TLM_EKF_TARGET_DT", 0.012))
    c[L.C_VELNE_NSE] = float(p.get("EK3_VELNE_M_NSE", 0.3))
    c[L.C_VELD_NSE] = float(p.get("EK3_VELD_M_NSE", 0.5))
    c[L.C_POSNE_NSE] = float(p.get("EK3_POSNE_M_NSE", 0.5))
    c[L.C_ALT_NSE] = float(p.get("EK3_ALT_M_NSE", 2.0))
    c[L.C_MAG_NSE] = float(p.get("EK3_MAG_M_NSE", 0.05))
    c[L.C_GYRO_PNSE] = float(p.get("EK3_GYRO_P_NSE", 0.015))
    c[L.C_ACC_PNSE] = float(p.get("EK3_ACC_P_NSE", 0.35))
    c[L.C_GBIAS_PNSE] = float(p.get("EK3_GBIAS_P_NSE", 0.001))
    c[L.C_ABIAS_PNSE] = float(p.get("EK3_ABIAS_P_NSE", 0.02))
    c[L.C_VEL_GATE] = _gate_sigmas(p.get("EK3_VEL_I_GATE", 500.0))
    c[L.C_POS_GATE] = _gate_sigmas(p.get("EK3_POS_I_GATE", 500.0))
    c[L.C_HGT_GATE] = _gate_sigmas(p.get("EK3_HGT_I_GATE", 500.0))
    c[L.C_MAG_GATE] = _gate_sigmas(p.get("EK3_MAG_I_GATE", 300.0))
    c[L.C_GLITCH_RAD] = float(p.get("EK3_GLITCH_RAD", 25.0))
    c[L.C_NOAID_NSE] = float(p.get("EK3_NOAID_M_NSE", 10.0))
    c[L.C_ERR_THRESH] = float(p.get("EK3_ERR_THRESH", 0.2))
    c[L.C_GPS_DELAY] = gps_delay_s(p)
    c[L.C_HGT_DELAY] = float(p.get("EK3_HGT_DELAY", 60.0)) * 1e-3
    field = earth_field_ned(
        float(p.get("TLM_MAG_DEC_DEG", 12.5)),
        float(p.get("TLM_MAG_INC_DEG", -66.0)),
        float(p.get("TLM_MAG_INT_GA", 0.58)),
    )
    c[L.C_MAG_N], c[L.C_MAG_E], c[L.C_MAG_D] = field
    c[L.C_POS_RETRY] = 7.0
    c[L.C_TILT_DRIFT] = 15.0
    c[L.C_HGT_RETRY] = 5.0
    c[L.C_USING_GPS_T] = 4.0
    c[L.C_CONSTPOS_DT] = 0.2
    c[L.C_GBIAS_LIM] = 0.5
    c[L.C_ABIAS_LIM] = float(p.get("EK3_ACC_BIAS_LIM", 1.0))
    c[L.C_ALIGN_TIME] = 0.5
    c[L.C_LANE_INIT_T] = 1.0
    c[L.C_SELECT_T] = 10.0
    c[L.C_ONGROUND_NSE] = 0.5
    c[L.C_BAD_IMU_ACC_NSE] = 5.0
    c[L.C_BAD_IMU_HOLD] = 10.0
    c[L.C_BAD_IMU_TIMEOUT] = 1.0
    c[L.C_TAU_OUTPUT] = min(max(0.01 * float(p.get("EK3_TAU_OUTPUT", 25.0)), 0.1), 0.5)
    imus = lane_imus(params)
    c[L.C_N_LANES] = len(imus)
    for i, imu in enumerate(imus):
        c[L.C_LANE_IMU + i] = imu
    max_delay = (L.NBUF - 1) * c[L.C_DT]
    if c[L.C_GPS_DELAY] > max_delay or c[L.C_HGT_DELAY] > max_delay:
        raise ValueError(f"EKF measurement delays must be <= {max_delay:.3f} s")
    return c


def lane_imus(params: Mapping[str, float], n_imu: int = 2) -> list[int]:
    """IMU instance per lane from EK3_IMU_MASK (default 3: lanes on IMU0 and IMU1)."""
    mask = int(params.get("EK3_IMU_MASK", 3))
    imus = [i for i in range(n_imu) if mask & (1 << i)]
    if not imus:
        raise ValueError("EK3_IMU_MASK selects no available IMU")
    return imus[: L.MAX_LANES]


def new_ekf(params: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
    """Allocate ``(ekf[n_lanes, N_EKF], sel[N_SEL])`` in their initial (unaligned) state.

    Equivalent to allocating the arrays and calling :func:`tlm_sim.ekf.lanes.ekf_init` with
    ``build_ekf_config(params)``.
    """
    from tlm_sim.ekf.lanes import ekf_init

    cfg = build_ekf_config(params)
    ekf = np.zeros((int(cfg[L.C_N_LANES]), L.N_EKF))
    sel = np.zeros(L.N_SEL)
    ekf_init(ekf, sel, cfg)
    return ekf, sel
