"""The EKF's evidence messages XKF2, XKF3, XKF5, XKQ, XKV1 and XKV2 (``tlm_sim.ekf.log``)
against EKF3's definitions and the SITL reference logs.

Reference facts used (measured on ``normal_s11.bin`` / ``gps_s12.bin``, ArduCopter 4.7-dev):

* XKF2, XKF3, XKQ: 10 Hz on both cores (C 0, 1); XKF5: 10 Hz, XKV1/XKV2: 2 Hz, primary core
  only (EKF3's Log_Write_XKF5 / Log_Write_State_Variances return for the other cores).
* Cruise (above 10 m) innovation standard deviations, core 0: IVN 0.0104, IVE 0.0120,
  IPN 0.0100, IPE 0.0108, IPD 0.0084 m(/s), IMX 1.44, IMY 0.71 mGauss; IVD 0.0019 m/s (below
  the 0.01 resolution of the field) and IMZ 0 (EKF3 truncates |IMZ| < 1 mGauss to 0). tlm's
  (mission 1, seed 0): 0.0129, 0.0146, 0.0117, 0.0136, 0.0088, 1.30, 1.27; IVD 0.0035, IMZ
  0.45. The tests allow a factor 2 either way: the measured ratios are 0.9-1.8 (IMY 1.8, tlm's
  filter has no body-field states to absorb a compass offset; the GPS ones 1.05-1.26 from the
  two GPS noise models), and a wrong unit or a state instead of an innovation is off by far
  more.
* Cruise means: SITL's are up to 0.0105 m/s (IVN, one resolution step) for std 0.0106; tlm's
  up to 0.0067. "Zero-mean": |mean| below 2 resolution steps and below the std.
* XKV1/XKV2 cruise medians (SITL / tlm): quaternion variance sum 1.26e-4 / 0.92e-4, velocity
  0.0089 / 0.0093, position 0.027 / 0.029, height 0.113 / 0.116 (m, m/s squared), delta-angle
  bias 3.9e-11 / 3.8e-11 rad^2, delta-velocity bias NE 1.5e-7 / 1.0e-7 and D 1.9e-8 / 1.8e-8
  (m/s)^2; factor 2 again.
* GPS loss (gps_s12: 88.61-122.61 s; tlm: SIM_GPS1_ENABLE 0 at 120 s, 1 at 154 s): the
  velocity/position innovations freeze (no GPS fused), XKV1.V07 grows ~860x (tlm ~700x) in
  13 s; in constant-position mode the position innovations are the filter's drift from the
  last position (max |IP_NE| 15.9 m; tlm 22.7 m; correlation of IPN with the XKF1.PN drift
  0.998 / 0.999: the sign is predicted minus measured); on GPS return the velocity innovations
  jump (max |IV_NE| 0.54 / 0.85 m/s in 1.5 s) and the position innovations are back below 1 m
  (0.18 / 0.59 m) 2-4 s later.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest

from tests.conftest import flown, reference_path
from tests.ekf_synth import DT, G
from tlm_sim import fly
from tlm_sim import logger as LG
from tlm_sim.bundles import EkfInputs
from tlm_sim.ekf import build_ekf_config, new_ekf
from tlm_sim.ekf import layout as L
from tlm_sim.ekf.core import apply_correction, clear_dx, filter_now, set_quat_euler
from tlm_sim.ekf.lanes import ekf_update
from tlm_sim.ekf.log import log_ekf_evidence
from tlm_sim.flightlog import read_bin
from tlm_sim.flightlog.binwriter import write_bin
from tlm_sim.params import Params, earth_field
from tlm_sim.rotation import quat_to_euler
from tlm_sim.sensors.mag import healthy_compasses

MESSAGES = ("XKF2", "XKF3", "XKF5", "XKQ", "XKV1", "XKV2")
PER_LANE = ("XKF2", "XKF3", "XKQ")  # both cores; the others the primary only
GPS_FAULT = [(120, "SIM_GPS1_ENABLE", 0), (154, "SIM_GPS1_ENABLE", 1)]
GPS_INNOV = ("IVN", "IVE", "IPN", "IPE", "IPD")
FACTOR = 2.0  # allowed tlm/SITL ratio of spreads and variance levels (see the module doc)


@lru_cache(maxsize=4)
def _tables(path: str) -> dict[str, pd.DataFrame]:
    return read_bin(path, types=[*MESSAGES, "XKF1", "GPS", "FMT"])


@pytest.fixture(scope="module")
def tlm_bin(tmp_path_factory) -> str:
    """Mission 1, seed 0, written as a .bin (what an analyst reads)."""
    p = tmp_path_factory.mktemp("ekfmsg") / "normal.bin"
    write_bin(flown(1, 0), p)
    return str(p)


@pytest.fixture(scope="module")
def gps_bin(tmp_path_factory) -> str:
    """Mission 1, seed 0, GPS off from 120 s to 154 s."""
    p = tmp_path_factory.mktemp("ekfmsg") / "gps.bin"
    write_bin(fly(1, faults=GPS_FAULT, seed=0), p)
    return str(p)


def _rate(df: pd.DataFrame) -> float:
    t = df.TimeUS.to_numpy() * 1e-6
    return (len(t) - 1) / (t[-1] - t[0])


def _cruise(t: dict[str, pd.DataFrame], name: str, c: int) -> pd.DataFrame:
    """Rows of ``name`` (core c) while XKF1 of that core is more than 10 m above the origin."""
    m = t[name][t[name].C == c]
    k = t["XKF1"][t["XKF1"].C == 0]
    alt = np.interp(m.TimeUS, k.TimeUS, -k.PD)
    return m[alt > 10.0]


# ----------------------------------------------------------------------------- presence, layout


def test_rates_and_cores_as_sitl(tlm_bin):
    ref = _tables(str(reference_path("normal_s11.bin")))
    t = _tables(tlm_bin)
    for name in MESSAGES:
        cores = (0, 1) if name in PER_LANE else (0,)
        assert sorted(ref[name].C.unique()) == list(cores), name
        assert sorted(t[name].C.unique()) == list(cores), name
        for c in cores:
            r_ref, r = _rate(ref[name][ref[name].C == c]), _rate(t[name][t[name].C == c])
            assert abs(r / r_ref - 1.0) < 0.1, (name, c, r, r_ref)


def test_fields_and_formats_equal_sitl(tlm_bin):
    ref = _tables(str(reference_path("normal_s11.bin")))
    t = _tables(tlm_bin)
    for name in MESSAGES:
        assert list(t[name].columns) == list(ref[name].columns), name
        fr, ft = ref["FMT"], t["FMT"]
        row_r, row_t = fr[fr.Name == name].iloc[0], ft[ft.Name == name].iloc[0]
        assert (row_t.Format, row_t.Columns, row_t.Length) == (
            row_r.Format, row_r.Columns, row_r.Length), name


def test_values_finite(tlm_bin, gps_bin):
    for path in (tlm_bin, gps_bin):
        t = _tables(path)
        for name in MESSAGES:
            assert np.isfinite(t[name].to_numpy(dtype=float)).all(), name


# ----------------------------------------------------------------------------- normal flight


def test_innovations_zero_mean_and_of_sitl_magnitude(tlm_bin):
    ref = _tables(str(reference_path("normal_s11.bin")))
    t = _tables(tlm_bin)
    for c in (0, 1):
        mine, theirs = _cruise(t, "XKF3", c), _cruise(ref, "XKF3", c)
        assert len(mine) > 3000
        for f in GPS_INNOV + ("IVD",):
            m, s = mine[f].mean(), mine[f].std()
            assert abs(m) < 0.02 and abs(m) < s, (c, f, m, s)
        for f in GPS_INNOV + ("IMX", "IMY"):
            ratio = mine[f].std() / theirs[f].std()
            assert 1.0 / FACTOR < ratio < FACTOR, (c, f, ratio)
        # below the field's 0.01 m/s resolution in both; compass Z below SITL's truncation
        assert 0.0 < mine.IVD.std() < 0.01 and theirs.IVD.std() < 0.01
        assert mine.IMZ.abs().max() <= 2.0
        assert (mine.IYAW == 0).all() and (mine.IVT == 0).all()
        assert (mine.ErSc >= 0).all() and (mine.RErr.abs() <= 1.0).all()


def test_xkq_is_xkf1_attitude(tlm_bin):
    t = _tables(tlm_bin)
    for c in (0, 1):
        q = t["XKQ"][t["XKQ"].C == c]
        k = t["XKF1"][t["XKF1"].C == c]
        assert (q.TimeUS.to_numpy() == k.TimeUS.to_numpy()).all()
        qq = q[["Q1", "Q2", "Q3", "Q4"]].to_numpy()
        np.testing.assert_allclose(np.linalg.norm(qq, axis=1), 1.0, atol=1e-6)
        e = np.degrees(np.array([quat_to_euler(*r) for r in qq]))
        np.testing.assert_allclose(e[:, 0], k.Roll, atol=0.011)
        np.testing.assert_allclose(e[:, 1], k.Pitch, atol=0.011)
        dy = (e[:, 2] - k.Yaw.to_numpy() + 180.0) % 360.0 - 180.0
        assert np.abs(dy).max() < 0.011


def test_variances_positive_and_of_sitl_level(tlm_bin):
    ref = _tables(str(reference_path("normal_s11.bin")))
    t = _tables(tlm_bin)
    v1, v2 = t["XKV1"], t["XKV2"]
    aligned = v1.V04 > 0.0
    assert aligned.mean() > 0.95  # zero before alignment only, as SITL's
    q = v1.loc[aligned, ["V00", "V01", "V02", "V03"]]
    assert (q >= 0).all().all() and (q.sum(axis=1) > 0).all()
    for f in [f"V{i:02d}" for i in range(4, 12)]:
        assert (v1.loc[aligned, f] > 0).all(), f
    for f in ("V12", "V13", "V14", "V15"):
        assert (v2.loc[aligned.to_numpy(), f] > 0).all(), f
    assert (v2[[f"V{i}" for i in range(16, 24)]] == 0).all().all()  # states tlm has not
    cr1, cr2 = _cruise(ref, "XKV1", 0), _cruise(ref, "XKV2", 0)
    ct1, ct2 = _cruise(t, "XKV1", 0), _cruise(t, "XKV2", 0)
    qsum = [d[["V00", "V01", "V02", "V03"]].sum(axis=1).median() for d in (ct1, cr1)]
    assert 1.0 / FACTOR < qsum[0] / qsum[1] < FACTOR, qsum
    for a, b, fields in ((ct1, cr1, range(4, 12)), (ct2, cr2, range(12, 16))):
        for i in fields:
            f = f"V{i:02d}"
            ratio = a[f].median() / b[f].median()
            assert 1.0 / FACTOR < ratio < FACTOR, (f, ratio)


def test_states_and_output_errors(tlm_bin):
    """XKF2's earth field is the one the filter uses (and SITL learns: 232, 52, -528
    mGauss); XKF5's terrain state is the ground at take-off, HAGL the height above it, the
    output tracking errors millimetres (SITL: eVel 1.2e-3, ePos 2.0e-3 mean in cruise)."""
    ref = _tables(str(reference_path("normal_s11.bin")))
    t = _tables(tlm_bin)
    x2 = t["XKF2"][t["XKF2"].MN != 0]
    field = np.asarray(earth_field(Params())) * 1000.0
    for f, v in zip(("MN", "ME", "MD"), field, strict=True):
        assert np.abs(x2[f] - v).max() <= 0.5, f
        r = ref["XKF2"][ref["XKF2"].MN != 0][f].median()
        assert abs(v - r) < 0.05 * abs(r) + 1.0, (f, v, r)
    assert (x2[["MX", "MY", "MZ", "VWN", "VWE", "IDX", "IDY", "IS"]] == 0).all().all()
    assert x2[["AX", "AY", "AZ"]].abs().max().max() < 0.1
    x5 = _cruise(t, "XKF5", 0)
    k = t["XKF1"][t["XKF1"].C == 0]
    alt = np.interp(x5.TimeUS, k.TimeUS, -k.PD)
    np.testing.assert_allclose(x5.HAGL, alt + x5.offset, atol=0.05)
    assert (x5.offset.abs() < 0.2).all() and (x5.Herr == 0.5).all()
    for f, sitl in (("eVel", 1.2e-3), ("ePos", 2.0e-3)):
        assert 1.0 / FACTOR < x5[f].mean() / sitl < FACTOR, f
    assert (x5.eAng == 0).all()
    assert (x5[["NI", "FIX", "FIY", "AFI", "RI", "rng"]] == 0).all().all()


# ----------------------------------------------------------------------------- GPS fault


def _gps_loss(t: dict[str, pd.DataFrame]) -> tuple[float, float]:
    """(start, end) [s] of the GPS outage after the first fix (GPS.Status < 3)."""
    g = t["GPS"]
    g = g[g.TimeUS > g[g.Status >= 3].TimeUS.min()]
    bad = g[g.Status < 3].TimeUS * 1e-6
    return float(bad.min()), float(bad.max())


def _gps_signature(t: dict[str, pd.DataFrame]) -> dict[str, float]:
    t0, t1 = _gps_loss(t)
    x = t["XKF3"][t["XKF3"].C == 0]
    ts = x.TimeUS * 1e-6
    k = t["XKF1"][t["XKF1"].C == 0]
    tk = k.TimeUS * 1e-6
    dead = x[(ts > t0 + 0.5) & (ts < t0 + 14.5)]
    v = t["XKV1"]
    tv = v.TimeUS * 1e-6
    growth = v[(tv > t0 + 12.5)].V07.iloc[0] / v[tv < t0].V07.iloc[-1]
    cp = x[(ts > t0 + 15.5) & (ts < t1)]
    tc = cp.TimeUS * 1e-6
    drift_n = np.interp(tc, tk, k.PN) - np.interp(t0 + 15.2, tk, k.PN)
    back = x[(ts > t1) & (ts < t1 + 1.5)]
    later = x[(ts > t1 + 2.0) & (ts < t1 + 4.0)]
    return {
        "frozen": max(dead[f].nunique() for f in ("IVN", "IVE", "IVD", "IPN", "IPE")),
        "v07_growth": growth,
        "constpos_max": float(np.hypot(cp.IPN, cp.IPE).max()),
        "sign_corr": float(np.corrcoef(cp.IPN, drift_n)[0, 1]),
        "return_vel": float(np.hypot(back.IVN, back.IVE).max()),
        "later_pos": float(np.hypot(later.IPN, later.IPE).max()),
    }


def test_gps_loss_shows_in_xkf3_as_in_sitl(gps_bin):
    ref = _gps_signature(_tables(str(reference_path("gps_s12.bin"))))
    mine = _gps_signature(_tables(gps_bin))
    for sig in (ref, mine):
        assert sig["frozen"] == 1  # no GPS fused: the innovations keep their last values
        assert sig["v07_growth"] > 100.0
        assert sig["constpos_max"] > 5.0
        assert sig["sign_corr"] > 0.95  # predicted minus measured
        assert sig["return_vel"] > 0.2 and sig["later_pos"] < 1.0
    for key in ("v07_growth", "constpos_max", "return_vel"):
        assert 1.0 / FACTOR < mine[key] / ref[key] < FACTOR, (key, mine[key], ref[key])


# ----------------------------------------------------------------------------- the filter's own


def _aided_lanes() -> tuple[np.ndarray, np.ndarray, np.ndarray, int, np.ndarray]:
    """Two lanes aligned at rest (yaw 100 deg) and aiding with GPS at the origin for 3 s."""
    params = Params()
    cfg = build_ekf_config(params)
    ekf, sel = new_ekf(params)
    e = np.zeros(L.N_EKF)
    set_quat_euler(e, math.radians(4.0), math.radians(-2.0), math.radians(100.0))
    r = e[L.R00 : L.R22 + 1].reshape(3, 3)
    dang = np.zeros((2, 3))
    dvel = np.tile(r.T @ np.array([0.0, 0.0, -G]) * DT, (2, 1))
    mag = healthy_compasses(r.T @ earth_field(params))
    z = np.zeros(3)
    k = 0
    for k in range(1, 1600):
        gps = k > 400 and k % 40 == 0
        ekf_update(ekf, sel, cfg, float(k * 2500), EkfInputs(
            dang, dvel, np.ones(4), gps, z, z, True, k % 40 == 20, 0.0, k % 40 == 0, mag, True))
    return ekf, sel, cfg, k, dvel


def test_xkf3_holds_the_innovations_of_the_last_fusion():
    """A GPS sample 2 m north and 0.3 m/s east of the filter: XKF3 logs EKF3's predicted
    minus measured, i.e. -2 m and -0.3 m/s, on both lanes; XKF2/XKF5 from the lane states."""
    ekf, sel, cfg, k, dvel = _aided_lanes()
    dang = np.zeros((2, 3))
    mag = healthy_compasses(np.zeros(3))
    k += 1
    before = [filter_now(ekf[i], 0) for i in range(2)]
    ekf_update(ekf, sel, cfg, float(k * 2500), EkfInputs(
        dang, dvel, np.ones(4), True, np.array([2.0, 0.0, 0.0]), np.array([0.0, 0.3, 0.0]), True,
        False, 0.0, False, mag, True))
    bufs, counts = LG.new_buffers(1.0)
    log_ekf_evidence((bufs, counts), k * 2500, ekf, sel, cfg)
    x3 = bufs[LG.K_XKF3][: counts[LG.K_XKF3]]
    assert counts[LG.K_XKF3] == 2 and counts[LG.K_XKF2] == 2 and counts[LG.K_XKQ] == 2
    assert counts[LG.K_XKF5] == 1 and counts[LG.K_XKV1] == 1 and counts[LG.K_XKV2] == 1
    c3 = LG.XKF3_COLS
    for ln in range(2):
        assert x3[ln, c3.C] == ln
        assert x3[ln, c3.IPN] == pytest.approx(before[ln] - 2.0, abs=1e-3)
        assert x3[ln, c3.IPN] == pytest.approx(-2.0, abs=0.05)
        assert x3[ln, c3.IVE] == pytest.approx(-0.3, abs=0.05)
        assert x3[ln, c3.ErSc] == ekf[ln, L.SCORE]
    x2 = bufs[LG.K_XKF2][0]
    assert x2[LG.XKF2_COLS.AX] == ekf[0, L.BAX]
    np.testing.assert_allclose(x2[LG.XKF2_COLS.MN:LG.XKF2_COLS.MD + 1],
                               cfg[L.C_MAG_N:L.C_MAG_D + 1] * 1000.0)
    x5 = bufs[LG.K_XKF5][0]
    e = ekf[0]
    assert x5[LG.XKF5_COLS.HAGL] == pytest.approx(e[L.TERRAIN] - filter_now(e, 2))
    assert x5[LG.XKF5_COLS.ePos] == pytest.approx(np.linalg.norm(e[L.OUT_EPN:L.OUT_EPN + 3]))


def test_xkv_maps_the_error_states_onto_ekf3s():
    """XKV1/XKV2 in EKF3's 24-state order: the quaternion variances are the earth-frame
    attitude covariance carried through the filter's own attitude correction (its Jacobian by
    finite differences of ``apply_correction``), velocity/position as they are, the biases
    in EKF3's per-prediction units (times the average prediction interval, 12.5 ms here)."""
    ekf, sel, cfg, k, _ = _aided_lanes()
    e = ekf[0]
    bufs, counts = LG.new_buffers(1.0)
    log_ekf_evidence((bufs, counts), k * 2500, ekf, sel, cfg)
    v1, v2 = bufs[LG.K_XKV1][0], bufs[LG.K_XKV2][0]
    p = e[L.P0:L.P0 + L.NS * L.NS].reshape(L.NS, L.NS)
    jac = np.zeros((4, 3))
    eps = 1e-7
    for j in range(3):
        w = e.copy()
        clear_dx(w)
        w[L.SCR_DX + j] = eps
        apply_correction(w, 1.0, 1.0)
        jac[:, j] = (w[L.QW:L.QZ + 1] - e[L.QW:L.QZ + 1]) / eps
    pq = jac @ p[:3, :3] @ jac.T
    c1, c2 = LG.XKV1_COLS, LG.XKV2_COLS
    np.testing.assert_allclose(v1[c1.V00:c1.V03 + 1], np.diag(pq), rtol=1e-4)
    assert sum(v1[c1.V00:c1.V03 + 1]) == pytest.approx(0.25 * np.trace(p[:3, :3]), rel=1e-9)
    np.testing.assert_allclose(v1[c1.V04:c1.V09 + 1], np.diag(p)[3:9])
    dt = e[L.DT_EKF_AVG]
    assert dt == pytest.approx(0.0125, abs=1e-4)
    np.testing.assert_allclose([v1[c1.V10], v1[c1.V11], v2[c2.V12]], np.diag(p)[9:12] * dt**2)
    np.testing.assert_allclose(v2[c2.V13:c2.V15 + 1], np.diag(p)[12:15] * dt**2)
    assert (v2[c2.V16:c2.V23 + 1] == 0).all()
    # the 0.5 s timer: no second pair within 0.49 s, one after
    log_ekf_evidence((bufs, counts), k * 2500 + 400000, ekf, sel, cfg)
    assert counts[LG.K_XKV1] == 1
    log_ekf_evidence((bufs, counts), k * 2500 + 500000, ekf, sel, cfg)
    assert counts[LG.K_XKV1] == 2 and counts[LG.K_XKV2] == 2
