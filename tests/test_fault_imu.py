"""IMU faults (issue 19): gyro sample loss (label 5, SIM_GYR_FAIL_MSK), accelerometer sample
loss (13, SIM_ACC_FAIL_MSK), vibration (10, SIM_VIB_* with SIM_ACCn_RND / SIM_GYRn_RND), and
the accel/gyro scale errors (SIM_ACCn_SCAL, SIM_GYRn_SCALE).

Signature tests fly the gyro_s42 and vibration_s48 references (reconstructed from their logs,
each flown once) and measure tlm and SITL the same way; behaviour tests check the kernels and
the EKF/controller reaction directly.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_process.fault_metrics import Flight
from tlm_process.reference import time_window
from tlm_sim import ardupilot as AP
from tlm_sim.params import ParamError, Params
from tlm_sim.rng import new_streams
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.config import build_sensor_config

TYPES = ["IMU", "VIBE", "CTUN", "ATT", "XKF1", "XKF4", "SIM", "MODE", "EV", "ERR", "MSG"]
REL = 0.35  # issue 19: each signature within 35 % of SITL's


# ------------------------------------------------------------------------------ measurements


def _imu(tables: dict, i: int) -> pd.DataFrame:
    t = tables["IMU"]
    return t[t.I.to_numpy(int) == i].sort_values("TimeUS")


def gyro_signature(tables: dict, t0: float, t1: float) -> dict[str, float]:
    """The gyro-loss facts of the reference README, measured in a log (TimeUS t0/t1: the
    fault's set and clear)."""
    f = Flight(tables)
    i0, i1 = _imu(tables, 0), _imu(tables, 1)
    tt = i0.TimeUS.to_numpy(float)
    gh = i0.GH.to_numpy(float)
    off = np.flatnonzero((tt >= t0) & (gh == 0.0))
    on = np.flatnonzero((tt > tt[off[0]]) & (gh == 1.0)) if len(off) else []
    w = time_window(i0, t0 + 0.2e6, t1 - 0.2e6)
    pre = time_window(i0, t0 - 20e6, t0)
    gyr = ["GyrX", "GyrY", "GyrZ"]
    tp, err = f.ekf_error()
    ew = (tp >= t0) & (tp <= t1)
    x4 = time_window(tables["XKF4"], t0, t1 + 30e6)
    return {
        "gh0_off_s": (tt[off[0]] - t0) * 1e-6 if len(off) else math.nan,
        "gh0_on_s": (tt[on[0]] - t0) * 1e-6 if len(on) else math.nan,
        "gh0_max_in": float(w.GH.max()),
        "gyr0_std_in": float(w[gyr].std().max()),
        "gyr0_std_before": float(pre[gyr].std().max()),
        "gh1_min_in": float(time_window(i1, t0, t1).GH.min()),
        "ah_min_in": float(min(time_window(i0, t0, t1).AH.min(),
                               time_window(i1, t0, t1).AH.min())),
        "err_count": float(len(time_window(f.err, t0, t1 + 5e6))),
        "lane_changes": float(len(x4.PI.unique()) - 1) if "PI" in x4 else 0.0,
        "ekf_err_max_m": float(err[ew].max()),
        "roll_max_deg": float(np.abs(f.roll[f.sel(t0, t1)]).max()),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    }


def vibration_signature(tables: dict, t0: float, t1: float) -> dict[str, float]:
    """The vibration facts of the reference README, measured in a log."""
    f = Flight(tables)
    v = tables["VIBE"]
    out: dict[str, float] = {}
    for i in (0, 1):
        vi = v[v.IMU.to_numpy(int) == i]
        w = time_window(vi, t0, t1)
        out[f"vibe{i}_mean"] = float(w[["VibeX", "VibeY", "VibeZ"]].to_numpy().mean())
        out[f"vibe{i}_max"] = float(w[["VibeX", "VibeY", "VibeZ"]].to_numpy().max())
        out[f"vibe{i}_xz_diff"] = float(np.abs(w.VibeX - w.VibeZ).mean())
        quiet = pd.concat([time_window(vi, t0 - 20e6, t0), time_window(vi, t1 + 2e6, t1 + 20e6)])
        out[f"vibe{i}_out_max"] = float(quiet[["VibeX", "VibeY", "VibeZ"]].to_numpy().max())
        out[f"clip{i}"] = float(w.Clip.max() - time_window(vi, 0, t0).Clip.max())
    i0 = _imu(tables, 0)
    out["accz_std_in"] = float(time_window(i0, t0, t1).AccZ.std())
    out["accz_std_before"] = float(time_window(i0, t0 - 20e6, t0).AccZ.std())
    ctun = tables["CTUN"]
    out["tho_in"] = float(time_window(ctun, t0 + 3e6, t1).ThO.mean())
    out["tho_before"] = float(time_window(ctun, t0 - 20e6, t0).ThO.mean())
    out["roll_max_deg"] = float(np.abs(f.roll[f.sel(t0, t1)]).max())
    tp, err = f.ekf_error()
    out["ekf_err_max_m"] = float(err[(tp >= t0) & (tp <= t1)].max())
    out["err_count"] = float(len(time_window(f.err, t0, t1 + 5e6)))
    out["auto_kept"] = f.mode_kept(AP.MODE_AUTO, t0, t1)
    return out


@lru_cache(maxsize=4)
def _pair(name: str) -> tuple[dict[str, Any], dict[str, Any], tuple[float, float],
                              tuple[float, float]]:
    """(SITL tables, tlm tables, SITL window, tlm window) of a reference flight re-flown."""
    from tlm_process.crosscheck.scenario import reconstruct
    from tlm_sim import fly
    from tlm_sim.flightlog import read_bin

    path = reference_path(f"{name}.bin")
    sc = reconstruct(str(path))
    fault = sc.faults[0]
    ref = read_bin(str(path), types=TYPES)
    log = fly(sc.mission, sc.schedule, sc.params, seed=sc.seed)
    w_ref = (float(fault["start_time_us"]), float(fault["end_time_us"]))
    w_tlm = (sc.to_tlm_us(w_ref[0]), sc.to_tlm_us(w_ref[1]))
    return ref, log.tables, w_ref, w_tlm


def _signatures(name: str, measure) -> tuple[dict[str, float], dict[str, float]]:
    ref, tlm, w_ref, w_tlm = _pair(name)
    return measure(ref, *w_ref), measure(tlm, *w_tlm)


def _close(a: float, b: float, floor: float = 0.0) -> bool:
    return abs(a - b) <= max(REL * abs(b), floor)


# ------------------------------------------------------------------- gyro loss (gyro_s42)


def test_gyro_loss_signature_matches_gyro_s42():
    """IMU 0's gyro stops: GH 0 from the first IMU record after the set (IMU at 25 Hz) to the
    clear, its logged gyro frozen (std exactly 0), IMU 1 healthy, no ERR, no lane switch, no
    mode change, EKF and attitude undisturbed (the lanes and controllers use IMU 1's gyro)."""
    ref, tlm = _signatures("gyro_s42", gyro_signature)
    for s in (ref, tlm):
        assert 0.0 <= s["gh0_off_s"] <= 0.045  # the first 25 Hz record after the set
        assert abs(s["gh0_on_s"] - 30.0) <= 0.045
        assert s["gh0_max_in"] == 0.0 and s["gyr0_std_in"] == 0.0
        assert s["gyr0_std_before"] > 5e-4
        assert s["gh1_min_in"] == 1.0 and s["ah_min_in"] == 1.0
        assert s["err_count"] == 0.0 and s["lane_changes"] == 0.0 and s["auto_kept"] == 1.0
        assert s["ekf_err_max_m"] <= 0.2
        assert s["roll_max_deg"] <= 0.3
    assert _close(tlm["gyr0_std_before"], ref["gyr0_std_before"])


def test_every_gyro_masked_is_refused():
    """SITL's firmware waits for a gyro sample forever when every gyro is masked (the
    simulation freezes): tlm refuses the value wherever it comes from."""
    from tlm_sim.faults import Fault, FaultScheduleError, Trigger
    from tlm_sim.flight import build_schedule

    with pytest.raises(ParamError, match="SIM_GYR_FAIL_MSK = 3 masks every gyro"):
        Params({"SIM_GYR_FAIL_MSK": 3})
    with pytest.raises(ParamError, match="masks every gyro"):
        build_schedule(Params(), [(100.0, "SIM_GYR_FAIL_MSK", 1), (110.0, "SIM_GYR_FAIL_MSK", 7)])
    with pytest.raises(FaultScheduleError, match="masks every gyro"):
        Fault("gyro", Trigger("time", 60), Trigger("time", 90),
              params_start={"SIM_GYR_FAIL_MSK": 3})
    for ok in (1, 2, 4, 5):  # bit 2 (IMU 3) names no gyro of tlm's
        assert build_sensor_config(Params({"SIM_GYR_FAIL_MSK": ok}))[S.C_GYR_FAIL_MSK] == ok


# ------------------------------------------------------------------- vibration (vibration_s48)


def test_vibration_signature_matches_vibration_s48():
    """Motor-rpm sinusoids of SIM_ACCn_RND on every axis: VIBE ~6 (IMU 1's, not fast-sampled,
    above IMU 0's), the same on X, Y and Z, quiet outside the window, no clipping; the logged
    (20 Hz filtered, 25 Hz) AccZ hardly moves; attitude, throttle, EKF and mode unchanged, no
    vibration failsafe (no ERR 29)."""
    ref, tlm = _signatures("vibration_s48", vibration_signature)
    for k in ("vibe0_mean", "vibe1_mean", "vibe0_max", "vibe1_max", "accz_std_in", "tho_in"):
        assert _close(tlm[k], ref[k]), (k, tlm[k], ref[k])
    for s in (ref, tlm):
        assert s["vibe1_mean"] > s["vibe0_mean"] > 4.0
        assert s["vibe0_xz_diff"] < 0.05 and s["vibe1_xz_diff"] < 0.05
        assert s["vibe0_out_max"] < 0.02 and s["vibe1_out_max"] < 0.02
        assert s["clip0"] == 0.0 and s["clip1"] == 0.0
        assert s["accz_std_before"] < 0.05 < s["accz_std_in"] < 0.4
        assert abs(s["tho_in"] - s["tho_before"]) < 0.01
        assert s["err_count"] == 0.0 and s["auto_kept"] == 1.0
        assert s["ekf_err_max_m"] < 0.5


# ------------------------------------------------------------------------- kernel level


def _quiet(extra: dict | None = None) -> np.ndarray:
    """Sensor configuration without base noise and gyro drift (exact readings)."""
    return build_sensor_config(Params({"TLM_ACC_NOISE": 0.0, "TLM_GYR_NOISE": 0.0,
                                       "SIM_DRIFT_SPEED": 0.0, **(extra or {})}))


def _run_imu(cfg: np.ndarray, ticks: int, pwm=1400.0, throttle: float = 0.4, seed: int = 7,
             s: np.ndarray | None = None, t0: int = 0, sf=(0.5, -0.3, -9.80665),
             w=(0.1, -0.2, 0.05)):
    """imu_sample over ``ticks`` physics ticks (833 us) from a fixed truth state; returns
    (sensor state, rng, per-tick raw accel and gyro of both IMUs (ticks, 2, 3) each)."""
    from tlm_sim.dynamics import layout as X
    from tlm_sim.sensors.imu import imu_init, imu_sample

    x = np.zeros(X.N_STATE)
    x[X.SQW] = 1.0
    x[X.SFX:X.SFX + 3] = sf
    x[X.SWX:X.SWX + 3] = w
    if s is None:
        s = np.zeros(S.N_SENSOR_STATE)
        imu_init(s, cfg, 0.0)
    rng = new_streams(seed, S.N_NOISE_STREAMS)
    motors = np.full(4, pwm) if np.isscalar(pwm) else np.asarray(pwm, float)
    acc = np.zeros((ticks, 2, 3))
    gyr = np.zeros((ticks, 2, 3))
    for k in range(ticks):
        imu_sample(s, x, cfg, float(t0 + (k + 1) * 833), throttle, motors, rng)
        for i in range(2):
            b = S.IMU_BASE + i * S.IMU_STRIDE
            acc[k, i] = s[b + S.I_LAST_ACC:b + S.I_LAST_ACC + 3]
            gyr[k, i] = s[b + S.I_LAST_GYR:b + S.I_LAST_GYR + 3]
    return s, rng, acc, gyr


def _last(s: np.ndarray, i: int, slot: int) -> np.ndarray:
    b = S.IMU_BASE + i * S.IMU_STRIDE + slot
    return s[b:b + 3].copy()


def test_scale_then_bias_as_sitls_pipeline():
    """§2.2: accel = truth / SIM_ACCn_SCAL (per non-zero axis) + SIM_ACCn_BIAS; gyro =
    truth x (1 + SIM_GYRn_SCALE / 100) + SIM_GYRn_BIAS; per IMU, the other untouched."""
    sf, w = np.array([0.5, -0.3, -9.80665]), np.array([0.1, -0.2, 0.05])
    cfg = _quiet({"SIM_ACC2_SCAL_X": 2.0, "SIM_ACC2_SCAL_Z": 0.5, "SIM_ACC2_BIAS_X": 0.25,
                  "SIM_GYR2_SCALE_Y": 50.0, "SIM_GYR2_SCALE_Z": -20.0, "SIM_GYR2_BIAS_Y": 0.01,
                  "SIM_ACC1_SCAL_Y": -1.0, "SIM_GYR1_SCALE_X": 10.0})
    s, _, _, _ = _run_imu(cfg, 10)
    np.testing.assert_allclose(_last(s, 1, S.I_LAST_ACC),
                               [0.5 / 2.0 + 0.25, -0.3, -9.80665 / 0.5], rtol=1e-12)
    np.testing.assert_allclose(_last(s, 1, S.I_LAST_GYR),
                               [0.1, -0.2 * 1.5 + 0.01, 0.05 * 0.8], rtol=1e-12)
    np.testing.assert_allclose(_last(s, 0, S.I_LAST_ACC), [0.5, 0.3, -9.80665], rtol=1e-12)
    np.testing.assert_allclose(_last(s, 0, S.I_LAST_GYR), [0.11, -0.2, 0.05], rtol=1e-12)
    base, _, _, _ = _run_imu(_quiet(), 10)
    np.testing.assert_array_equal(_last(base, 0, S.I_LAST_ACC), sf)
    np.testing.assert_array_equal(_last(base, 1, S.I_LAST_GYR), w)


def test_masked_sensors_stop_hold_and_resume_at_their_rate():
    """SIM_GYR_FAIL_MSK / SIM_ACC_FAIL_MSK: the masked sensor produces nothing (no samples,
    no noise draws), holds its last sample, is unhealthy at the next take; when the bit
    clears it samples at its rate again (its timer catches up, no burst)."""
    from tlm_sim.sensors.imu import imu_take_deltas

    cfg = build_sensor_config(Params())
    s, _, _, _ = _run_imu(cfg, 120)
    dang, dvel = np.zeros((2, 3)), np.zeros((2, 3))
    for i in range(2):
        imu_take_deltas(s, i, 0.0025, dang, dvel)
    held_g = _last(s, 0, S.I_GYR_F)
    held_a = _last(s, 1, S.I_ACC_F)
    masked = build_sensor_config(Params({"SIM_GYR_FAIL_MSK": 1, "SIM_ACC_FAIL_MSK": 2}))
    s, rng, _, _ = _run_imu(masked, 600, s=s, t0=120 * 833, seed=8)
    assert s[S.IMU_BASE + S.I_GYR_COUNT] == 0.0  # IMU 0 gyro: nothing
    assert s[S.IMU_BASE + S.IMU_STRIDE + S.I_ACC_COUNT] == 0.0  # IMU 1 accel: nothing
    assert s[S.IMU_BASE + S.I_ACC_COUNT] > 0 and s[S.IMU_BASE + S.IMU_STRIDE + S.I_GYR_COUNT] > 0
    np.testing.assert_array_equal(_last(s, 0, S.I_GYR_F), held_g)
    np.testing.assert_array_equal(_last(s, 1, S.I_ACC_F), held_a)
    ok = [imu_take_deltas(s, i, 0.0025, dang, dvel) for i in range(2)]
    assert ok == [1.0, 0.0]
    b0, b1 = S.IMU_BASE, S.IMU_BASE + S.IMU_STRIDE
    assert (s[b0 + S.I_GYR_OK], s[b0 + S.I_ACC_OK]) == (0.0, 1.0)
    assert (s[b1 + S.I_GYR_OK], s[b1 + S.I_ACC_OK]) == (1.0, 0.0)
    # the stopped gyro drew no noise: its stream is where it started
    np.testing.assert_array_equal(rng[S.RNG_GYRO], new_streams(8, S.N_NOISE_STREAMS)[S.RNG_GYRO])
    t_clear = 720 * 833
    s, _, _, _ = _run_imu(cfg, 1200, s=s, t0=t_clear)  # 1 s after the clear
    n_gyr = s[b0 + S.I_GYR_COUNT]
    n_acc = s[b1 + S.I_ACC_COUNT]
    assert abs(n_gyr - 1200 * 833e-6 * 1000) <= 2 and abs(n_acc - 1200 * 833e-6 * 800) <= 2
    assert s[b0 + S.I_NEXT_GYR_US] > (720 + 1200) * 833


def _vibration(acc: np.ndarray) -> np.ndarray:
    """(IMU, axis) RMS of the raw accel minus its mean."""
    return np.sqrt(((acc - acc.mean(axis=0)) ** 2).mean(axis=0))


def test_vibration_model():
    """SITL's vibration (§2.2 stage 5): nothing without SIM_ACCn_RND (not even noise draws);
    motor-locked sinusoids of amplitude RND x MULT, the same on every axis, summed over the
    motors (RMS ~ A sqrt(N / 2) for IMU 1, a little less for the fast-sampled IMU 0), more
    with harmonics, none with the motors off; fixed-frequency ones only on their axis."""
    base_cfg = _quiet()
    _, rng0, acc0, _ = _run_imu(base_cfg, 6000)
    _, rng1, acc1, _ = _run_imu(_quiet({"SIM_VIB_MOT_MAX": 350.0}), 6000)
    np.testing.assert_array_equal(acc0, acc1)
    np.testing.assert_array_equal(rng0, rng1)
    pwm = [1590.0, 1600.0, 1580.0, 1610.0]
    _, _, acc, _ = _run_imu(_quiet({"SIM_VIB_MOT_MAX": 350.0, "SIM_ACC1_RND": 4.8,
                                 "SIM_ACC2_RND": 4.8}), 6000, pwm=pwm)
    rms = _vibration(acc)
    assert np.ptp(acc[:, 1, :] - acc[:, 1, :].mean(axis=0), axis=1).max() < 1e-9  # all axes
    assert 5.5 < rms[1, 0] < 8.0 and 4.5 < rms[0, 0] < rms[1, 0]
    _, _, acc_h, _ = _run_imu(_quiet({"SIM_VIB_MOT_MAX": 350.0, "SIM_ACC2_RND": 4.8,
                                   "SIM_VIB_MOT_HMNC": 3, "SIM_VIB_MOT_MULT": 0.5}), 6000,
                           pwm=pwm)
    assert _vibration(acc_h)[0, 0] < 1e-9  # IMU 0 has no amplitude
    assert 0.8 * math.sqrt(2) < _vibration(acc_h)[1, 0] / (rms[1, 0] * 0.5) < 1.2 * math.sqrt(2)
    _, _, acc_off, _ = _run_imu(_quiet({"SIM_VIB_MOT_MAX": 350.0, "SIM_ACC2_RND": 4.8}), 2000,
                             pwm=1050.0, throttle=0.05)
    assert _vibration(acc_off).max() < 1e-9  # motors off (throttle below SIM_INS_THR_MIN)
    _, _, acc_f, _ = _run_imu(_quiet({"SIM_VIB_FREQ_X": 37.0, "SIM_ACC2_RND": 2.0}), 6000)
    v = _vibration(acc_f)[1]
    assert v[1] < 1e-9 and v[2] < 1e-9
    assert 0.9 < v[0] / (2.0 / math.sqrt(2)) < 1.1


def test_gyro_vibration_replaces_the_second_noise_term():
    """Without SIM_VIB_*, SIM_GYRn_RND is uniform noise x throttle (RMS amp / sqrt(3)); with
    SIM_VIB_* it is the vibration amplitude amp = radians(RND) x throttle (four motor
    sinusoids: RMS about amp sqrt(2)) and that noise term is gone."""
    amp = math.radians(10.0) * 0.4
    pwm = [1590.0, 1600.0, 1580.0, 1610.0]
    _, _, _, g = _run_imu(_quiet({"SIM_GYR2_RND": 10.0}), 6000, pwm=pwm)
    assert 0.9 < _vibration(g)[1, 0] / (amp / math.sqrt(3)) < 1.1
    _, _, _, g = _run_imu(_quiet({"SIM_GYR2_RND": 10.0, "SIM_VIB_MOT_MAX": 350.0}), 6000,
                          pwm=pwm)
    assert 0.6 < _vibration(g)[1, 0] / (amp * math.sqrt(2)) < 1.3
    assert _vibration(g)[0, 0] < 1e-9  # IMU 0: no SIM_GYR1_RND


# ------------------------------------------------------------------ flights: accel samples


@lru_cache(maxsize=2)
def _accel_mask_flight(mask: int):
    from tlm_sim import fly

    log = fly(1, [(120.0, "SIM_ACC_FAIL_MSK", mask), (150.0, "SIM_ACC_FAIL_MSK", 0)], seed=5)
    return log.tables


def test_accel_sample_loss_marks_the_imu_unhealthy_and_the_ekf_uses_the_other():
    """SIM_ACC_FAIL_MSK 1: IMU 0's accel stops (AH 0, logged accel frozen) from the first record
    after the set to the clear; IMU 1 untouched; the EKF lanes take IMU 1's delta velocities
    (integrating IMU 0's held sample would drift metres in 30 s), so no lane switch, no ERR,
    the flight goes on as without the fault."""
    t = _accel_mask_flight(1)
    i0, i1 = _imu(t, 0), _imu(t, 1)
    w0 = time_window(i0, 120.05e6, 149.95e6)
    assert (w0.AH == 0).all() and (w0.GH == 1).all()
    assert w0[["AccX", "AccY", "AccZ"]].std().max() == 0.0
    assert (time_window(i0, 0, 119.95e6).AH == 1).all() and (time_window(i0, 150.05e6, 1e12).AH
                                                             == 1).all()
    assert (i1.AH == 1).all() and (i1.GH == 1).all()
    assert time_window(i1, 120e6, 150e6).AccZ.std() > 0.01
    f = Flight(t)
    tp, err = f.ekf_error()
    assert err[(tp >= 120e6) & (tp <= 160e6)].max() < 0.5
    assert len(time_window(f.err, 120e6, 160e6)) == 0
    assert f.mode_kept(AP.MODE_AUTO, 120e6, 150e6) == 1.0
    x4 = time_window(t["XKF4"], 120e6, 160e6)
    assert "PI" not in x4 or x4.PI.nunique() == 1


def test_every_accel_masked_flies_on_held_samples():
    """SIM_ACC_FAIL_MSK 3 (SITL's behaviour not established, §13): both IMUs AH 0 with frozen
    accels; the EKF integrates the held samples (EKF3 keeps reading its stale first usable
    accel), GPS and baro keep it bounded, and the flight is completed."""
    t = _accel_mask_flight(3)
    for i in (0, 1):
        w = time_window(_imu(t, i), 120.05e6, 149.95e6)
        assert (w.AH == 0).all() and w[["AccX", "AccY", "AccZ"]].std().max() == 0.0
    f = Flight(t)
    assert not math.isnan(f.disarm_us)
    assert f.h[f.sel(120e6, 150e6)].min() > 5.0
