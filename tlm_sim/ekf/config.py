"""EKF configuration array and per-flight EKF arrays (Python, called once per flight).

Parameter names follow ArduPilot (EK3_*); every value comes from a
:class:`~tlm_sim.params.Params` (defaults: ``tlm_sim/data/copter_defaults.parm``, the reference
SITL logs' set; ``tlm params EK3_`` lists them). The earth magnetic field is the one the
simulated compass measures (:func:`tlm_sim.params.earth_field`).
"""

from __future__ import annotations

import numpy as np

from tlm_sim.boot import BOOT_EKF_START_S
from tlm_sim.ekf import layout as L
from tlm_sim.params import ParamError, Params, earth_field, require_params

DEFAULT_GPS_DELAY_MS = 120.0  # u-blox M8/F9 generation (ardupilot-reference §3.8)
#: EKF3's covariance prediction target interval [s] (a constant in ArduPilot, not a parameter)
EKF_TARGET_DT_S = 0.012


def _gate_sigmas(gate_percent: float) -> float:
    """EKF3 gates are in percent of one standard deviation, with a floor of one sigma."""
    return max(0.01 * float(gate_percent), 1.0)


def gps_delay_s(params: Params) -> float:
    """Assumed lag of GPS samples [s]: GPS1_DELAY_MS (the older GPS_DELAY_MS is its alias) when
    > 0, else the driver default DEFAULT_GPS_DELAY_MS (ArduPilot's u-blox driver reports 0.22 s
    until the receiver generation is known, 0.12 s for M8/F9 receivers; SITL itself lags its
    samples by SIM_GPS1_LAG_MS = 100 ms)."""
    ms = float(params["GPS1_DELAY_MS"])
    return (ms if ms > 0.0 else DEFAULT_GPS_DELAY_MS) * 1e-3


def _noise_and_gates(c: np.ndarray, p: Params) -> None:
    """Measurement and process noises, innovation gates, glitch radius, lane switch threshold."""
    c[L.C_VELNE_NSE] = p["EK3_VELNE_M_NSE"]
    c[L.C_VELD_NSE] = p["EK3_VELD_M_NSE"]
    c[L.C_POSNE_NSE] = p["EK3_POSNE_M_NSE"]
    c[L.C_ALT_NSE] = p["EK3_ALT_M_NSE"]
    c[L.C_MAG_NSE] = p["EK3_MAG_M_NSE"]
    c[L.C_GYRO_PNSE] = p["EK3_GYRO_P_NSE"]
    c[L.C_ACC_PNSE] = p["EK3_ACC_P_NSE"]
    c[L.C_GBIAS_PNSE] = p["EK3_GBIAS_P_NSE"]
    c[L.C_ABIAS_PNSE] = p["EK3_ABIAS_P_NSE"]
    c[L.C_VEL_GATE] = _gate_sigmas(p["EK3_VEL_I_GATE"])
    c[L.C_POS_GATE] = _gate_sigmas(p["EK3_POS_I_GATE"])
    c[L.C_HGT_GATE] = _gate_sigmas(p["EK3_HGT_I_GATE"])
    c[L.C_MAG_GATE] = _gate_sigmas(p["EK3_MAG_I_GATE"])
    c[L.C_GLITCH_RAD] = p["EK3_GLITCH_RAD"]
    c[L.C_NOAID_NSE] = p["EK3_NOAID_M_NSE"]
    c[L.C_ERR_THRESH] = p["EK3_ERR_THRESH"]


def _ekf3_constants(c: np.ndarray) -> None:
    """Timeouts and limits EKF3 hard-codes (no parameters, ardupilot-reference §3.8)."""
    c[L.C_POS_RETRY] = 7.0
    c[L.C_POS_RETRY_VEL] = 10.0
    c[L.C_TILT_DRIFT] = 15.0
    # hgtRetryTimeMode0_ms: with GPS vertical velocity fused (EK3_SRC1_VELZ 3) EKF3 waits 10 s
    # (5 s only without it) before a rejected height is reset, or a height that stopped
    # arriving is declared invalid (baro_s44.bin: both baros off, CTUN.Alt 0 from +10.19 s)
    c[L.C_HGT_RETRY] = 10.0
    c[L.C_USING_GPS_T] = 4.0
    c[L.C_CONSTPOS_DT] = 0.2
    c[L.C_GBIAS_LIM] = 0.5
    c[L.C_ALIGN_TIME] = 0.5
    c[L.C_LANE_INIT_T] = 1.0
    c[L.C_SELECT_T] = 10.0
    # EKF3's cores fuse a measurement at their own prediction steps, a few IMU samples
    # apart; tlm's lanes fuse on the same tick. The relative errors see the primary's new
    # score this much later than the other lanes' (tlm model choice, from gps_glitch_s46:
    # XKF3.RErr dips by ~0.3-1 at each GPS sample while the scores fall, and the lane
    # switches at the second rejected sample)
    c[L.C_SCORE_LAG] = 3 * c[L.C_DT]
    c[L.C_ONGROUND_NSE] = 0.5
    c[L.C_BAD_IMU_ACC_NSE] = 5.0
    c[L.C_BAD_IMU_HOLD] = 10.0
    c[L.C_BAD_IMU_TIMEOUT] = 1.0
    c[L.C_MAG_FAIL_T] = 10.0
    c[L.C_MAG_SWITCH_T0] = 30.0
    c[L.C_INFLIGHT_HGT] = 1.5


def build_ekf_config(params: Params) -> np.ndarray:
    """Return the ``cfg[N_CFG]`` float64 array of a flight from its parameters.

    Reads EK3_* (noises, gates, delays, EK3_IMU_MASK lanes, EK3_TAU_OUTPUT limited to 10..50
    cs as EKF3, EK3_GPS_CHECK / EK3_CHECK_SCALE), GPS1_DELAY_MS (:func:`gps_delay_s`),
    SCHED_LOOP_RATE (the prediction step), TLM_BOOT_PHASE (:mod:`tlm_sim.ekf.lifecycle`) and
    the earth field; units and defaults: ``tlm params EK3_``.
    """
    p = require_params(params, "build_ekf_config")
    c = np.zeros(L.N_CFG)
    c[L.C_DT] = 1.0 / p["SCHED_LOOP_RATE"]
    c[L.C_TARGET_DT] = EKF_TARGET_DT_S
    _noise_and_gates(c, p)
    c[L.C_GPS_DELAY] = gps_delay_s(p)
    c[L.C_HGT_DELAY] = p["EK3_HGT_DELAY"] * 1e-3
    c[L.C_MAG_N], c[L.C_MAG_E], c[L.C_MAG_D] = earth_field(p)
    _ekf3_constants(c)
    c[L.C_ABIAS_LIM] = p["EK3_ACC_BIAS_LIM"]
    c[L.C_TAU_OUTPUT] = min(max(0.01 * p["EK3_TAU_OUTPUT"], 0.1), 0.5)
    c[L.C_GSF_RUN_MASK] = p["EK3_GSF_RUN_MASK"]
    imus = lane_imus(p)
    c[L.C_N_LANES] = len(imus)
    for i, imu in enumerate(imus):
        c[L.C_LANE_IMU + i] = imu
    c[L.C_BOOT] = p["TLM_BOOT_PHASE"]
    c[L.C_EKF_START] = BOOT_EKF_START_S if p["TLM_BOOT_PHASE"] else 0.0
    c[L.C_GPS_CHECK] = p["EK3_GPS_CHECK"]
    c[L.C_CHECK_SCALE] = 0.01 * p["EK3_CHECK_SCALE"]
    c[L.C_YAW_NSE] = p["EK3_YAW_M_NSE"]
    c[L.C_YAW_GATE] = _gate_sigmas(p["EK3_YAW_I_GATE"])
    max_delay = (L.NBUF - 1) * c[L.C_DT]
    if c[L.C_GPS_DELAY] > max_delay or c[L.C_HGT_DELAY] > max_delay:
        raise ParamError(f"EKF measurement delays must be <= {max_delay:.3f} s")
    return c


def lane_imus(params: Params, n_imu: int = 2) -> list[int]:
    """IMU instance per lane from EK3_IMU_MASK (bit i: a lane on IMU i)."""
    mask = int(params["EK3_IMU_MASK"])
    imus = [i for i in range(n_imu) if mask & (1 << i)]
    if not imus:
        raise ParamError(f"EK3_IMU_MASK = {mask} selects no IMU tlm simulates (bits 0 and 1)")
    return imus[: L.MAX_LANES]


def new_ekf(params: Params) -> tuple[np.ndarray, np.ndarray]:
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
