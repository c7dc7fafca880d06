"""DCM, AHR2, XKY0 and XKY1: the AHRS's DCM attitude estimator (``tlm_sim.control.dcm``) and
EKF3's EKF-GSF yaw estimator (``tlm_sim.ekf.gsf``), as a tlm flight logs them against SITL's
normal_s11 (ArduCopter 4.7.0-dev), and both estimators on analytic cases."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.conftest import flown, reference_path
from tests.ekf_synth import (
    DT,
    _rot_from_acc_yaw,
    _rotvec,
    _smooth,
    quat_conj,
    quat_mul,
    rot_to_quat,
)
from tlm_sim import fly
from tlm_sim.bundles import EkfInputs
from tlm_sim.control import dcm as D
from tlm_sim.control import dcm_layout as DL
from tlm_sim.control import layout as C
from tlm_sim.control.config import build_control_config
from tlm_sim.ekf import gsf as G
from tlm_sim.ekf import gsf_layout as GL
from tlm_sim.ekf.config import build_ekf_config, new_ekf
from tlm_sim.flightlog import SCHEMAS, read_bin
from tlm_sim.flightlog.binwriter import write_bin
from tlm_sim.params import Params
from tlm_sim.rotation import quat_to_dcm
from tlm_sim.sensors import layout as S

MESSAGES = ("DCM", "AHR2", "XKY0", "XKY1")
GRAVITY = 9.80665
W_COLS = [f"W{m}" for m in range(5)]


def _wrap180(a: np.ndarray) -> np.ndarray:
    return (np.asarray(a) + 180.0) % 360.0 - 180.0


def _nearest(t_ref: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Index into the sorted t_ref of the sample nearest each t."""
    i = np.searchsorted(t_ref, t).clip(1, len(t_ref) - 1)
    return np.where(np.abs(t_ref[i - 1] - t) < np.abs(t_ref[i] - t), i - 1, i)


def _tables(log_or_path, names):
    if hasattr(log_or_path, "tables"):
        return {n: log_or_path.tables[n] for n in names}
    return read_bin(log_or_path, types=list(names))


def _armed_window(ev) -> tuple[float, float]:
    """(arm, disarm) times [us] from the EV table."""
    return float(ev[ev.Id == 10].TimeUS.min()), float(ev[ev.Id == 11].TimeUS.max())


def _dcm_vs(tabs, ref: str) -> dict[str, np.ndarray]:
    """|DCM - ref| [deg] for Roll, Pitch, Yaw while armed (ref: ATT or SIM, nearest rows)."""
    arm, dis = _armed_window(tabs["EV"])
    dcm = tabs["DCM"]
    dcm = dcm[(dcm.TimeUS > arm) & (dcm.TimeUS < dis)]
    r = tabs[ref]
    i = _nearest(r.TimeUS.to_numpy(), dcm.TimeUS.to_numpy())
    return {f: np.abs(_wrap180(dcm[f].to_numpy() - r[f].to_numpy()[i]))
            for f in ("Roll", "Pitch", "Yaw")}


def _err_levels(tabs) -> tuple[float, float]:
    """Median DCM ErrRP and ErrYaw while armed."""
    arm, dis = _armed_window(tabs["EV"])
    dcm = tabs["DCM"]
    dcm = dcm[(dcm.TimeUS > arm) & (dcm.TimeUS < dis)]
    return float(dcm.ErrRP.median()), float(dcm.ErrYaw.median())


@pytest.fixture(scope="module")
def sitl():
    path = reference_path("normal_s11.bin")
    tabs = read_bin(path, types=[*MESSAGES, "ATT", "SIM", "EV", "FMT", "FMTU"])
    tabs["sidecar"] = json.loads(path.with_suffix(".json").read_text())
    return tabs


@pytest.fixture(scope="module")
def tlm(normal_flight):
    return _tables(normal_flight, (*MESSAGES, "ATT", "SIM", "EV", "GPS"))


# --- layout, presence, rates ---------------------------------------------------------------
def test_the_bin_has_the_four_messages_with_sitls_layout(normal_flight, sitl, tmp_path):
    fmt = sitl["FMT"].set_index("Name")
    out = tmp_path / "m1.bin"
    write_bin(normal_flight, out)
    back = read_bin(out, types=list(MESSAGES))
    for name in MESSAGES:
        s = SCHEMAS[name]
        assert s.fmt == fmt.loc[name, "Format"], name
        assert ",".join(s.columns) == fmt.loc[name, "Columns"], name
        assert list(back[name].columns) == list(sitl[name].columns), name
        assert len(back[name]) == normal_flight.n_rows(name) > 0, name


def test_rates_as_sitl_logs_them(tlm, sitl):
    rates = sitl["sidecar"]["log_message_rates"]
    arm, dis = _armed_window(tlm["EV"])
    for name in MESSAGES:
        t = tlm[name]
        per_instance = [t[t.C == c] for c in (0, 1)] if "C" in t.columns else [t]
        for part in per_instance:
            dt = np.diff(part.TimeUS.to_numpy()) * 1e-6
            assert np.median(dt) == pytest.approx(0.1, abs=1e-3), name
        span = (t.TimeUS.iloc[-1] - t.TimeUS.iloc[0]) * 1e-6
        assert len(t) / span == pytest.approx(rates[name]["rate_hz"], rel=0.05), name
    # DCM from the start, AHR2 once the EKF is the active solution, both to the end
    assert tlm["DCM"].TimeUS.iloc[0] < 0.2e6
    assert tlm["AHR2"].TimeUS.iloc[0] < 2e6
    # the yaw estimator logs from just after arming (SITL: 0.23 s) until the disarm, both lanes
    for name in ("XKY0", "XKY1"):
        t = tlm[name]
        assert arm < t.TimeUS.iloc[0] < arm + 1e6, name
        assert dis - 0.2e6 < t.TimeUS.iloc[-1] <= dis, name
        assert (t.C == 0).sum() == (t.C == 1).sum()
    assert np.array_equal(tlm["XKY0"].TimeUS.to_numpy(), tlm["XKY1"].TimeUS.to_numpy())


def test_constant_fields_are_what_sitl_logs(tlm, sitl):
    for f in ("VWN", "VWE", "VWD"):  # no wind estimate on a copter
        assert (sitl["DCM"][f] == 0.0).all() and (tlm["DCM"][f] == 0.0).all()
    first = tlm["XKY0"].iloc[0]
    sfirst = sitl["XKY0"].iloc[0]
    # the bank starts with equal weights and yaws spread evenly, from -144 deg (= 216)
    for row in (first, sfirst):
        assert [row[c] for c in W_COLS] == pytest.approx([0.2] * 5, abs=1e-6)
        ys = [row[f"Y{m}"] for m in range(5)]
        assert _wrap180(np.array(ys) - [216, 288, 0, 72, 144]) == pytest.approx([0] * 5, abs=0.5)
        # evenly spread equal weights: no composite direction, a wide spread (SITL: 15.04, the
        # firmware's sqrt(degrees(3.95 rad^2)) with its composite at 180 deg)
        assert 14.0 < row.YCS < 15.5


# --- the DCM against the EKF and the truth, as SITL's -----------------------------------------
def test_dcm_tracks_the_attitude_as_sitls_does(tlm, sitl):
    """tlm's DCM differs from the EKF attitude (ATT) and from the truth (SIM) no more than twice
    as much as SITL's does (95th percentiles while armed; SITL's DCM vs ATT: roll/pitch
    0.11 deg, yaw 2.0 deg), and its error levels are SITL's within a factor of 2."""
    for ref in ("ATT", "SIM"):
        ours = _dcm_vs(tlm, ref)
        theirs = _dcm_vs(sitl, ref)
        for f in ("Roll", "Pitch", "Yaw"):
            p_ours = np.percentile(ours[f], 95)
            p_theirs = np.percentile(theirs[f], 95)
            assert p_ours < 2.0 * max(p_theirs, 0.05), (ref, f, p_ours, p_theirs)
    for ours, theirs in zip(_err_levels(tlm), _err_levels(sitl), strict=True):
        assert 0.5 * theirs < ours < 2.0 * theirs


def test_ahr2_is_the_dcm_solution(tlm, normal_flight):
    dcm, ahr2, sim = tlm["DCM"], tlm["AHR2"], tlm["SIM"]
    i = _nearest(dcm.TimeUS.to_numpy(), ahr2.TimeUS.to_numpy())
    assert np.array_equal(dcm.TimeUS.to_numpy()[i], ahr2.TimeUS.to_numpy())
    for f in ("Roll", "Pitch", "Yaw"):  # centidegrees truncated towards zero
        assert np.abs(_wrap180(ahr2[f].to_numpy() - dcm[f].to_numpy()[i])).max() < 0.0101
    q = ahr2[["Q1", "Q2", "Q3", "Q4"]].to_numpy()
    assert np.abs(np.linalg.norm(q, axis=1) - 1.0).max() < 1e-5
    yaw_q = np.degrees(np.arctan2(2 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]),
                                  1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2)))
    assert np.abs(_wrap180(yaw_q - ahr2.Yaw.to_numpy())).max() < 0.02
    # position: within a few metres of the truth (GPS lag and noise), altitude the baro's
    j = _nearest(sim.TimeUS.to_numpy(), ahr2.TimeUS.to_numpy())
    m_per_deg = 111_319.5
    dn = (ahr2.Lat.to_numpy() - sim.Lat.to_numpy()[j]) * m_per_deg
    de = (ahr2.Lng.to_numpy() - sim.Lng.to_numpy()[j]) * m_per_deg * math.cos(
        math.radians(normal_flight.meta["home"][0]))
    assert np.percentile(np.hypot(dn, de), 95) < 3.0
    assert np.percentile(np.abs(ahr2.Alt.to_numpy() - sim.Alt.to_numpy()[j]), 95) < 2.0


# --- the yaw estimator in flight ----------------------------------------------------------------
def test_weights_sum_to_one(tlm, sitl):
    for tabs in (tlm, sitl):
        w = tabs["XKY0"][W_COLS].to_numpy()
        assert np.abs(w.sum(axis=1) - 1.0).max() < 1e-6
        assert (w > 0).all()


def test_gsf_finds_a_yaw_no_model_started_from():
    """Heading 108 deg at take-off (every hypothesis starts >= 36 deg away from it): once the
    copter accelerates along its first leg the composite yaw meets the truth, its spread is
    small and one model holds most of the weight."""
    log = fly(1, seed=3, params={"SIM_OPOS_HDG": 108.0})
    ky, sim, gps = log.tables["XKY0"], log.tables["SIM"], log.tables["GPS"]
    ky = ky[ky.C == 0]
    first = ky.iloc[0]
    assert [first[f"Y{m}"] for m in range(5)] == pytest.approx([216, 288, 0, 72, 144], abs=0.5)
    t_move = gps.TimeUS[gps.Spd > 2.0].iloc[0]  # the first leg's acceleration
    later = ky[(ky.TimeUS > t_move + 10e6) & (ky.TimeUS < t_move + 40e6)]
    i = _nearest(sim.TimeUS.to_numpy(), later.TimeUS.to_numpy())
    err = np.abs(_wrap180(later.YC.to_numpy() - sim.Yaw.to_numpy()[i]))
    assert np.median(err) < 10.0, err
    assert np.median(later.YCS) < 3.0
    assert np.median(later[W_COLS].to_numpy().max(axis=1)) > 0.5


def test_gsf_in_straight_flight_drifts_no_more_than_sitls(tlm, sitl):
    """Yaw is not observable from GPS velocity at constant speed: the composite drifts between
    the turns in both (SITL ~0.3 deg/s). Median |YC - ATT.Yaw| from 60 s after arming."""
    def median_err(tabs):
        arm, _ = _armed_window(tabs["EV"])
        ky = tabs["XKY0"]
        ky = ky[(ky.C == 0) & (ky.TimeUS > arm + 60e6)]
        i = _nearest(tabs["ATT"].TimeUS.to_numpy(), ky.TimeUS.to_numpy())
        return float(np.median(np.abs(_wrap180(ky.YC.to_numpy()
                                               - tabs["ATT"].Yaw.to_numpy()[i]))))
    ours, theirs = median_err(tlm), median_err(sitl)
    assert ours < 1.5 * theirs, (ours, theirs)


def test_gsf_resets_when_gps_returns_as_sitls():
    """gps_s12: GPS off for 34 s. The bank keeps predicting (XKY0 goes on); the first GPS
    velocity after the outage puts every weight under the floor, the bank resets and realigns
    on the next one: one 0.2-0.4 s gap in XKY0 at the GPS's return, in SITL and in tlm."""
    path = reference_path("gps_s12.bin")
    fault = json.loads(path.with_suffix(".json").read_text())["faults"][0]
    t0, t1 = fault["start_time_us"] * 1e-6, fault["end_time_us"] * 1e-6
    log = fly(1, faults=[(t0, "SIM_GPS1_ENABLE", 0), (t1, "SIM_GPS1_ENABLE", 1)], seed=12)
    for ky in (read_bin(path, types=["XKY0"])["XKY0"], log.tables["XKY0"]):
        t = ky[ky.C == 0].TimeUS.to_numpy() * 1e-6
        dt = np.diff(t)
        gaps = t[:-1][dt > 0.15]
        assert len(gaps) == 1 and t1 - 0.5 < gaps[0] < t1 + 1.0, gaps
        assert 0.2 < dt.max() < 0.45
        after = ky[(ky.C == 0) & (ky.TimeUS > (gaps[0] + 0.2) * 1e6)].iloc[0]
        ys = np.array([after[f"Y{m}"] for m in range(5)])
        assert np.abs(_wrap180(np.diff(ys)) - 72.0).max() < 25.0  # spread again


def test_no_estimator_on_a_lane_outside_ek3_gsf_run_mask():
    log = fly(1, seed=0, params={"EK3_GSF_RUN_MASK": 2})
    for name in ("XKY0", "XKY1"):
        assert set(log.tables[name].C) == {1}


# --- the yaw estimator on a synthetic flight ----------------------------------------------------
def _manoeuvres(yaw: float, duration: float = 50.0, seed: int = 0):
    """A copter holding heading ``yaw`` [rad] that sits still until 14 s, then changes its
    velocity every 10 s (4 m/s towards 30 deg, 3 m/s towards 200 deg, 4 m/s towards 290 deg,
    stop), each change a 3 s smooth step, tilting its thrust along the acceleration; armed at
    10 s. IMU deltas at the 400 Hz main loop with SITL's base noise, GPS velocity at 5 Hz lagged
    0.1 s with 5 cm/s noise. Returns (t, dang, dvel, gps_new, gps_vel, armed)."""
    rng = np.random.default_rng(seed)
    steps = [(14.0, 30.0, 4.0), (24.0, 200.0, 3.0), (34.0, 290.0, 4.0), (44.0, 0.0, 0.0)]

    def vel(t):
        v = np.zeros((t.shape[0], 3))
        prev = np.zeros(3)
        for t0, course, speed in steps:
            w = speed * np.array([math.cos(math.radians(course)),
                                  math.sin(math.radians(course)), 0.0])
            v += np.outer(_smooth((t - t0) / 3.0), w - prev)
            prev = w
        return v

    def acc(t):
        return (vel(t + 1e-4) - vel(t - 1e-4)) / 2e-4

    n = int(round(duration / DT))
    tk = np.arange(n + 1) * DT
    tm = tk[:-1] + 0.5 * DT
    r_k = _rot_from_acc_yaw(acc(tk), np.full(n + 1, yaw))
    r_m = _rot_from_acc_yaw(acc(tm), np.full(n, yaw))
    q = rot_to_quat(r_k)
    dang = _rotvec(quat_mul(quat_conj(q[:-1]), q[1:]))
    v_k = vel(tk)
    dvel = np.einsum("nji,nj->ni", r_m, v_k[1:] - v_k[:-1] - np.array([0.0, 0.0, GRAVITY * DT]))
    dang += math.radians(0.04) * rng.uniform(-1, 1, dang.shape) * DT
    dvel += 0.01 * rng.uniform(-1, 1, dvel.shape) * DT
    t = tk[1:]
    gps_new = (np.arange(n) + 1) % 80 == 0
    gps_vel = vel(t - 0.1) + rng.normal(0.0, 0.05, (n, 3))
    return t, dang, dvel, gps_new, gps_vel, t >= 10.0


def test_gsf_converges_from_between_its_hypotheses_on_a_synthetic_flight():
    """True heading 100 deg, 28 and 44 deg from the nearest initial hypotheses (72, 144): after
    the first velocity change the composite is within 5 deg of it, its spread small, the weight
    on the two models that started either side of it; the weights sum to 1 throughout."""
    t, dang, dvel, gps_new, gps_vel, armed = _manoeuvres(math.radians(100.0))
    p = Params()
    cfg = build_ekf_config(p)
    ekf, _ = new_ekf(p)
    gsf = np.zeros((1, GL.N_GSF))
    G.gsf_init(gsf, cfg)
    da = np.zeros((S.N_IMU, 3))
    dv = np.zeros((S.N_IMU, 3))
    imu_ok = np.ones(2 * S.N_IMU)
    no_mag = np.zeros(1)
    out = []
    for k in range(t.shape[0]):
        da[0], dv[0] = dang[k], dvel[k]
        new = bool(gps_new[k])  # (the estimator reads no GPS position, baro or compass)
        G.gsf_update(gsf, ekf[:1], cfg, EkfInputs(da, dv, imu_ok, new, gps_vel[k], gps_vel[k],
                                                  new, False, 0.0, False, no_mag,
                                                  bool(armed[k])))
        if k % 40 == 0 and gsf[0, GL.G_FUSING]:
            G.gsf_refresh(gsf[0])
            out.append((t[k], math.degrees(gsf[0, GL.G_YAW]),
                        math.degrees(math.sqrt(gsf[0, GL.G_YAW_VAR])),
                        *gsf[0, GL.G_W:GL.G_W + 5]))
    out = np.array(out)
    assert out[0, 0] < 10.3  # fusing from the first GPS velocity after arming
    assert np.abs(out[:, 3:].sum(axis=1) - 1.0).max() < 1e-9
    late = out[out[:, 0] > 20.0]
    assert np.abs(_wrap180(late[:, 1] - 100.0)).max() < 5.0
    assert late[:, 2].max() < 10.0
    assert late[:, 6:8].sum(axis=1).min() > 0.95  # models 3 (72 deg) and 4 (144 deg)


# --- analytic checks of the estimators' pieces -----------------------------------------------
def _rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Body -> NED matrix of ZYX Euler angles."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
            @ np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
            @ np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]]))


def _model_block(rng):
    """An estimator row whose AHRS is tilted and turned at random and whose model 0 has a random
    heading offset, velocity and covariance; returns (row, model base, P, model 0's matrix)."""
    g = np.zeros(GL.N_GSF)
    b = GL.MODEL_BASE
    off = rng.uniform(-0.05, 0.05, 3)
    p = np.diag(rng.uniform(0.2, 1.0, 3))
    p[0, 1] = p[1, 0] = off[0]
    p[0, 2] = p[2, 0] = off[1]
    p[1, 2] = p[2, 1] = off[2]
    g[b + GL.M_P:b + GL.M_P + 9] = p.ravel()
    r0 = _rpy_matrix(*rng.uniform(-0.2, 0.2, 2), rng.uniform(-3, 3))
    g[GL.G_R:GL.G_R + 9] = r0.ravel()
    a = rng.uniform(-3, 3)
    g[b + GL.M_COS], g[b + GL.M_SIN] = math.cos(a), math.sin(a)
    g[b + GL.M_VN], g[b + GL.M_VE] = rng.normal(size=2)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    return g, b, p, rz @ r0


def _yaw_of(r: np.ndarray) -> float:
    """EKFGSF's yaw of a matrix: 321 Euler yaw, or the 312 first rotation when the body x axis
    is nearer the vertical than the y axis."""
    if abs(r[2, 0]) < abs(r[2, 1]):
        return math.atan2(r[1, 0], r[0, 0])
    return math.atan2(-r[0, 1], r[1, 1])


@pytest.mark.parametrize("seed", range(5))
def test_gsf_prediction_is_f_p_ft_plus_q(seed):
    rng = np.random.default_rng(seed)
    g, b, p, rm = _model_block(rng)
    dv = rng.normal(size=3) * 0.1
    dt = 0.0125
    v0 = g[b + GL.M_VN:b + GL.M_VN + 2].copy()
    d0 = g[GL.G_R:GL.G_R + 9].reshape(3, 3) @ dv  # what gsf_step hands every model
    G._ekf_predict(g, b, d0[0], d0[1], dt)
    dvn = rm @ dv  # the model's own AHRS rotates the delta velocity
    f = np.array([[1, 0, -dvn[1]], [0, 1, dvn[0]], [0, 0, 1]])
    q = np.diag([(G.ACCEL_NOISE * dt) ** 2] * 2 + [(G.GYRO_NOISE * dt) ** 2])
    assert g[b + GL.M_P:b + GL.M_P + 9].reshape(3, 3) == pytest.approx(f @ p @ f.T + q)
    assert g[b + GL.M_VN:b + GL.M_VN + 2] == pytest.approx(v0 + dvn[:2])
    assert G._model_yaw(g, b) == pytest.approx(_yaw_of(rm))


@pytest.mark.parametrize("seed", range(5))
def test_gsf_velocity_fusion_is_a_kalman_update_and_turns_the_ahrs(seed):
    rng = np.random.default_rng(seed)
    g, b, p, rm = _model_block(rng)
    x = np.array([g[b + GL.M_VN], g[b + GL.M_VE], _yaw_of(rm)])
    z = x[:2] + rng.normal(size=2) * 0.3
    obs_var = 0.5**2
    assert G._correct(g, b, z[0], z[1], obs_var)
    h = np.array([[1.0, 0, 0], [0, 1.0, 0]])
    s = h @ p @ h.T + np.eye(2) * obs_var
    k = p @ h.T @ np.linalg.inv(s)
    x_new = x + k @ (z - x[:2])
    assert g[b + GL.M_P:b + GL.M_P + 9].reshape(3, 3) == pytest.approx(p - k @ s @ k.T)
    assert [g[b + GL.M_VN], g[b + GL.M_VE]] == pytest.approx(x_new[:2])
    # the yaw state is the AHRS's: the correction turns it about the earth vertical
    assert g[b + GL.M_COS] ** 2 + g[b + GL.M_SIN] ** 2 == pytest.approx(1.0, abs=1e-9)
    assert G._model_yaw(g, b) == pytest.approx(math.atan2(math.sin(x_new[2]), math.cos(x_new[2])))
    innov = x[:2] - z
    dens = math.exp(-0.5 * innov @ np.linalg.inv(s) @ innov) / (2 * math.pi
                                                               * math.sqrt(np.linalg.det(s)))
    assert G._density(g, b) == pytest.approx(dens)


def test_gsf_yaw_alignment_keeps_the_tilt_and_sets_the_hypotheses():
    rng = np.random.default_rng(7)
    g, _, _, _ = _model_block(rng)
    r0 = g[GL.G_R:GL.G_R + 9].reshape(3, 3).copy()
    G.gsf_reset(g)
    G._align_yaw(g)
    for m in range(5):
        b = GL.MODEL_BASE + m * GL.MODEL_STRIDE
        hyp = -math.pi + (0.5 + m) * 2 * math.pi / 5
        assert G._model_yaw(g, b) == pytest.approx(math.atan2(math.sin(hyp), math.cos(hyp)))
    assert g[GL.G_R:GL.G_R + 9].reshape(3, 3) == pytest.approx(r0)  # the tilt is G_R's


def test_gsf_weights_follow_the_likelihoods_and_stay_normalised():
    g = np.zeros(GL.N_GSF)
    G.gsf_reset(g)
    g[GL.G_RUN] = 1.0
    G.gsf_fuse_vel(g, 0.0, 0.0, 0.3)  # aligns the bank
    assert g[GL.G_FUSING] == 1.0
    for m in range(5):  # the models disagree about the velocity
        g[GL.MODEL_BASE + m * GL.MODEL_STRIDE + GL.M_VN] = 0.3 * (m - 2)
    before = g[GL.G_W:GL.G_W + 5].copy()
    G.gsf_fuse_vel(g, 0.4, -0.2, 0.3)
    dens = np.array([G._density(g, GL.MODEL_BASE + m * GL.MODEL_STRIDE) for m in range(5)])
    expected = before * dens / (before * dens).sum()
    assert g[GL.G_W:GL.G_W + 5] == pytest.approx(expected)
    assert np.argmax(g[GL.G_W:GL.G_W + 5]) == 3  # the model nearest 0.4 m/s north
    assert g[GL.G_W:GL.G_W + 5].sum() == pytest.approx(1.0, abs=1e-12)


def test_dcm_renormalisation_and_quaternion():
    d = np.zeros(DL.N_DCM)
    D.dcm_init(d)
    roll, pitch, yaw = 0.3, -0.2, 2.5
    D._from_euler(d, roll, pitch, yaw)
    r0 = d[DL.D_R:DL.D_R + 9].copy()
    d[DL.D_R:DL.D_R + 9] += np.random.default_rng(0).normal(size=9) * 1e-3
    assert D._normalize(d)
    r = d[DL.D_R:DL.D_R + 9].reshape(3, 3)
    assert r @ r.T == pytest.approx(np.eye(3), abs=1e-6)
    assert r.ravel() == pytest.approx(r0, abs=3e-3)
    D._from_euler(d, roll, pitch, yaw)
    q = D.dcm_quaternion(d)
    assert np.array(quat_to_dcm(*q)).ravel() == pytest.approx(r0, abs=1e-12)


def _static_dcm(seconds: float, tilt0: tuple[float, float], gyro_bias: np.ndarray,
                armed: bool, yaw: float = math.radians(120.0)):
    """A level copter at rest, heading ``yaw``, without GPS: the DCM started with a tilt error
    ``tilt0`` (roll, pitch) [rad] and fed a gyro with a constant bias [rad/s]."""
    p = Params()
    g = build_control_config(p)
    dt = g[C.G_DT]
    s = np.zeros(S.N_SENSOR_STATE)
    ib = S.IMU_BASE
    s[ib + S.I_ACC_OK] = s[ib + S.I_GYR_OK] = 1.0
    s[ib + S.I_ACC_F + 2] = -GRAVITY
    s[ib + S.I_GYR_F:ib + S.I_GYR_F + 3] = gyro_bias
    dec = g[C.G_MAG_DEC]
    earth = np.array([0.2 * math.cos(dec), 0.2 * math.sin(dec), 0.5])
    cy, sy = math.cos(yaw), math.sin(yaw)
    s[S.MAG_BASE + S.M_FIELD:S.MAG_BASE + S.M_FIELD + 3] = np.array(
        [[cy, sy, 0], [-sy, cy, 0], [0, 0, 1]]) @ earth
    s[S.MAG_BASE + S.M_HEALTHY] = 1.0
    dang = np.zeros((S.N_IMU, 3))
    dang[0] = gyro_bias * dt
    dvel = np.zeros((S.N_IMU, 3))
    dvel[0, 2] = -GRAVITY * dt
    imu_ok = np.array([1.0, 0.0, 1.0, 0.0])
    gps = np.zeros(S.N_GPS_EPOCH)
    d = np.zeros(DL.N_DCM)
    D.dcm_init(d)
    no_mag = np.zeros(1)
    n = int(seconds / dt)
    for k in range(n):
        t_us = (k + 1) * 2500
        if k % 40 == 0:
            s[S.MAG_BASE + S.M_T_US] = t_us
        inputs = EkfInputs(dang, dvel, imu_ok, False, gps[:3], gps[:3], False, False, 0.0,
                           False, no_mag, armed)  # (the DCM reads no position, baro, compass)
        D.dcm_update(d, g, s, inputs, gps, 0, t_us)
        if k == 0:  # the tilt error to correct (the heading is the compass's already)
            D.dcm_eulers(d)
            assert math.degrees(d[DL.D_YAW]) == pytest.approx(math.degrees(yaw), abs=0.01)
            D._from_euler(d, tilt0[0], tilt0[1], d[DL.D_YAW])
    D.dcm_eulers(d)
    return d


def test_dcm_levels_a_tilt_error_and_takes_its_heading_from_the_compass():
    d = _static_dcm(20.0, (math.radians(5.0), math.radians(-4.0)), np.zeros(3), False)
    assert abs(math.degrees(d[DL.D_ROLL])) < 0.05
    assert abs(math.degrees(d[DL.D_PITCH])) < 0.05
    assert math.degrees(d[DL.D_YAW]) == pytest.approx(120.0, abs=0.05)
    assert d[DL.D_ERR_RP] < 0.001 and d[DL.D_ERR_YAW] < 0.001


def test_dcm_learns_a_gyro_drift_at_the_ins_drift_rate():
    bias = np.radians([0.2, -0.1, 0.15])  # deg/s
    d = _static_dcm(60.0, (0.0, 0.0), bias, True)
    omega_i = d[DL.D_OMEGA_I:DL.D_OMEGA_I + 3]
    assert omega_i == pytest.approx(-bias, abs=math.radians(0.03))
    # the integrator's time constant is AHRS_RP_P / KI = 23 s (at most 0.5 deg/min per 5 s)
    assert abs(math.degrees(d[DL.D_ROLL])) < 0.3 and abs(math.degrees(d[DL.D_PITCH])) < 0.3


def test_flight_is_deterministic_with_the_estimators():
    a = flown(1, 0)
    b = fly(1, seed=0)
    for name in MESSAGES:
        assert a.tables[name].equals(b.tables[name]), name
