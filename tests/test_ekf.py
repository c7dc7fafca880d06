"""Navigation EKF: kernels against filterpy / dense algebra, accuracy on a synthetic flight,
GPS-loss timeouts, constant-position mode, GPS return reset, and IMU-lane switching."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.ekf_synth import DT, G, fly_ekf, make_flight, quat_angle_deg
from tlm_sim.bundles import EkfInputs
from tlm_sim.ekf import build_ekf_config, ekf_output, new_ekf
from tlm_sim.ekf import layout as L
from tlm_sim.ekf.core import (
    apply_correction,
    clear_dx,
    fuse_h3,
    fuse_index,
    output_track,
    predict_covariance,
    propagate,
    quat_to_rot,
    set_quat_euler,
)
from tlm_sim.ekf.fusion import _bad_imu_check, lane_fuse_baro, reset_vel_pos_to_gps
from tlm_sim.ekf.lanes import ekf_update, quat_to_euler
from tlm_sim.params import Params, earth_field
from tlm_sim.sensors import layout as S
from tlm_sim.sensors.config import build_sensor_config
from tlm_sim.sensors.mag import healthy_compasses

NS = L.NS


def _get_p(e: np.ndarray) -> np.ndarray:
    return e[L.P0 : L.P0 + NS * NS].reshape(NS, NS).copy()


def _set_p(e: np.ndarray, p: np.ndarray) -> None:
    e[L.P0 : L.P0 + NS * NS] = p.ravel()


def _random_spd(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    a = rng.normal(size=(n, n)) * scale
    return a @ a.T + np.eye(n) * scale * scale * 0.1


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _filter_vp(e: np.ndarray) -> np.ndarray:
    """The filter's velocity (3) and position (3): the output plus the output tracking error."""
    out = np.concatenate([e[L.VN : L.VN + 3], e[L.PN : L.PN + 3]])
    err = np.concatenate([e[L.OUT_EVN : L.OUT_EVN + 3], e[L.OUT_EPN : L.OUT_EPN + 3]])
    return out + err


def _lane(params: dict | None = None) -> np.ndarray:
    ekf, _ = new_ekf(Params(params))
    e = ekf[0].copy()
    e[L.QW] = 1.0
    quat_to_rot(e)
    return e


# ----------------------------------------------------------------------------- layout / config


def test_layout_blocks_do_not_overlap():
    blocks = {
        "nominal": (0, L.N_NOMINAL),
        "rot": (L.R00, 9),
        "P": (L.P0, NS * NS),
        "acc": (L.ACC_DVN, 4),
        "scr_a": (L.SCR_A, 9 * NS),
        "scr_c": (L.SCR_C, NS),
        "scr_dx": (L.SCR_DX, NS),
        "buf_ofs": (L.BUF_OFS, 6),
        "buf": (L.BUF0, L.NBUF * L.BUF_ROW),
    }
    used = np.zeros(L.N_EKF, dtype=int)
    for start, n in blocks.values():
        used[start : start + n] += 1
    scalars = [
        v
        for k, v in vars(L).items()
        if k.isupper() and isinstance(v, int) and L.ALIGNED <= v < L.BUF_OFS
    ]
    for v in set(scalars):
        used[v] += 1
    assert used.max() == 1
    assert used.min() == 1  # no gaps either
    assert L.N_CFG == max(slot.stop for slot in L.CONFIG)


def test_config_defaults_and_overrides():
    c = build_ekf_config(Params())
    assert c[L.C_DT] == pytest.approx(0.0025)
    assert c[L.C_VELNE_NSE] == 0.3 and c[L.C_VELD_NSE] == 0.5 and c[L.C_POSNE_NSE] == 0.5
    assert c[L.C_ALT_NSE] == 2.0 and c[L.C_MAG_NSE] == 0.05
    assert c[L.C_GYRO_PNSE] == 0.015 and c[L.C_ACC_PNSE] == 0.35
    assert (c[L.C_VEL_GATE], c[L.C_POS_GATE], c[L.C_HGT_GATE], c[L.C_MAG_GATE]) == (5, 5, 5, 3)
    assert c[L.C_GPS_DELAY] == pytest.approx(0.12) and c[L.C_HGT_DELAY] == pytest.approx(0.06)
    field = c[L.C_MAG_N : L.C_MAG_D + 1]
    assert np.linalg.norm(field) == pytest.approx(0.579)  # TLM_MAG_INT_GA
    assert field[2] < 0.0  # inclination -65.75 deg: field points up
    assert math.degrees(math.atan2(field[1], field[0])) == pytest.approx(12.65)
    # the EKF assumes exactly the field the simulated compass measures, for any setting
    for p in (Params(), Params({"TLM_MAG_DEC_DEG": -3.0, "TLM_MAG_INT_GA": 0.4})):
        scfg = build_sensor_config(p)
        assert list(build_ekf_config(p)[L.C_MAG_N : L.C_MAG_D + 1]) == list(
            scfg[S.C_MAG_EARTH : S.C_MAG_EARTH + 3])
    assert c[L.C_N_LANES] == 2 and list(c[L.C_LANE_IMU : L.C_LANE_IMU + 2]) == [0, 1]
    c2 = build_ekf_config(Params({"EK3_POS_I_GATE": 100, "GPS1_DELAY_MS": 120, "EK3_IMU_MASK": 2}))
    assert c2[L.C_POS_GATE] == 1.0  # percent of one sigma
    assert c2[L.C_GPS_DELAY] == pytest.approx(0.12)
    assert c2[L.C_N_LANES] == 1 and c2[L.C_LANE_IMU] == 1
    ekf, sel = new_ekf(Params({"EK3_IMU_MASK": 2}))
    assert ekf.shape == (1, L.N_EKF) and ekf[0, L.IMU_INDEX] == 1.0
    # GPS_DELAY_MS is the older name of GPS1_DELAY_MS (an alias)
    delayed = Params({"GPS1_DELAY_MS": 0, "GPS_DELAY_MS": 150})
    assert build_ekf_config(delayed)[L.C_GPS_DELAY] == 0.15
    with pytest.raises(ValueError):
        build_ekf_config(Params({"GPS1_DELAY_MS": 1000}))
    assert c[L.C_TAU_OUTPUT] == pytest.approx(0.25)  # EK3_TAU_OUTPUT 25 cs
    assert build_ekf_config(Params({"EK3_TAU_OUTPUT": 10}))[L.C_TAU_OUTPUT] == pytest.approx(0.1)


# ----------------------------------------------------------------------------- kernels


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    t=st.floats(0.005, 0.05),
    dv=st.floats(0.0, 1.0),
)
def test_sparse_covariance_prediction_equals_dense_product(seed, t, dv):
    """predict_covariance == F P F^T + Q with the full 15x15 F of the error-state model."""
    rng = np.random.default_rng(seed)
    e = _lane()
    q = rng.normal(size=4)
    e[L.QW : L.QW + 4] = q / np.linalg.norm(q)
    quat_to_rot(e)
    r = e[L.R00 : L.R22 + 1].reshape(3, 3).copy()
    s = rng.normal(size=3) * dv
    e[L.ACC_DVN : L.ACC_DVD + 1] = s
    e[L.ACC_DT] = t
    p = _random_spd(rng, NS, 0.05)
    _set_p(e, p)
    qa, qv, qg, qb = 1e-6, 2e-5, 1e-9, 3e-8
    predict_covariance(e, qa, qv, qg, qb)
    f = np.eye(NS)
    f[0:3, 9:12] = -r * t
    f[3:6, 0:3] = -_skew(s)
    f[3:6, 12:15] = -r * t
    f[6:9, 3:6] = np.eye(3) * t
    qd = np.diag([qa] * 3 + [qv] * 3 + [0.0] * 3 + [qg] * 3 + [qb] * 3)
    want = f @ p @ f.T + qd
    got = _get_p(e)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)
    assert np.array_equal(got, got.T)  # exactly symmetric
    assert e[L.ACC_DT] == 0.0 and not e[L.ACC_DVN : L.ACC_DVD + 1].any()


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    ticks=st.integers(1, 8),
    sigma_a=st.floats(0.0, 2.0),
    n_steps=st.integers(1, 30),
)
def test_linear_constant_velocity_block_matches_filterpy(seed, ticks, sigma_a, n_steps):
    """Velocity/position block with a constant-velocity model == filterpy's KalmanFilter.

    The lane is predicted by the real kernels (IMU propagation with zero specific force net of
    gravity, output observer, sparse covariance prediction) and updated by sequential scalar
    fusions with the batch correction; filterpy runs the same linear model with Joseph-form
    updates. The filter state is the output plus the output tracking error.
    """
    rng = np.random.default_rng(seed)
    e = _lane()
    x0 = rng.normal(size=6) * 3.0  # v (3), p (3)
    e[L.VN : L.VN + 3] = x0[:3]
    e[L.PN : L.PN + 3] = x0[3:]
    p = np.zeros((NS, NS))
    p[3:9, 3:9] = _random_spd(rng, 6, 0.7)
    _set_p(e, p)
    kf = KalmanFilter(dim_x=6, dim_z=1)
    kf.x = x0.reshape(6, 1).copy()
    kf.P = p[3:9, 3:9].copy()
    t = ticks * DT
    kf.F = np.eye(6)
    kf.F[3:6, 0:3] = np.eye(3) * t
    kf.Q = np.diag([(sigma_a * t) ** 2] * 3 + [0.0] * 3)
    dang = np.zeros((2, 3))
    dvel = np.zeros((2, 3))
    dvel[0, 2] = -G * DT
    for _ in range(n_steps):
        for _k in range(ticks):
            propagate(e, dang, dvel, 0, 0, DT)
            output_track(e, DT, 0.25, 0, False)  # moves the output, never the filter state
        predict_covariance(e, 0.0, (sigma_a * e[L.ACC_DT]) ** 2, 0.0, 0.0)
        kf.predict()
        clear_dx(e)
        for _m in range(int(rng.integers(1, 4))):
            j = int(rng.integers(0, 6))
            r = float(rng.uniform(0.01, 4.0))
            z = float(kf.x[j, 0] + rng.normal() * 2.0)
            fuse_index(e, L.ES_VEL + j, z - _filter_vp(e)[j], r)
            h = np.zeros((1, 6))
            h[0, j] = 1.0
            kf.update(np.array([[z]]), R=r, H=h)
        apply_correction(e, 1e9, 1e9)
        np.testing.assert_allclose(_filter_vp(e), kf.x[:, 0], rtol=0, atol=1e-9)
        np.testing.assert_allclose(_get_p(e)[3:9, 3:9], kf.P, rtol=0, atol=1e-9)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 3))
def test_sparse_h_update_matches_filterpy(seed, n):
    """fuse_h3 (3 non-zero Jacobian entries, e.g. a magnetometer axis) == filterpy's update."""
    rng = np.random.default_rng(seed)
    e = _lane()
    p = _random_spd(rng, NS, 0.3)
    _set_p(e, p)
    kf = KalmanFilter(dim_x=NS, dim_z=1)
    kf.x = np.zeros((NS, 1))
    kf.P = p.copy()
    clear_dx(e)
    for _ in range(n):
        hv = rng.normal(size=3)
        innov = float(rng.normal())
        r = float(rng.uniform(0.001, 1.0))
        # the innovation refers to the nominal state; filterpy's x is the correction so far
        fuse_h3(e, L.ES_ATT, hv[0], hv[1], hv[2], innov, r)
        h = np.zeros((1, NS))
        h[0, 0:3] = hv
        kf.update(np.array([[innov]]), R=r, H=h)
    np.testing.assert_allclose(e[L.SCR_DX : L.SCR_DX + NS], kf.x[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(_get_p(e), kf.P, rtol=0, atol=1e-9)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), j=st.integers(0, NS - 1))
def test_bad_imu_response_does_not_learn_the_accel_bias(seed, j):
    """EKF3 zeroes the delta-velocity-bias Kalman gains of its fusions while ``badIMUdata``:
    the bias does not move, P -= K H P with those gain rows zero, then made symmetric. Without
    the response the update is the ordinary one (the bias moves)."""
    rng = np.random.default_rng(seed)
    p = _random_spd(rng, NS, 0.3)
    innov, r = float(rng.normal()), float(rng.uniform(0.01, 1.0))
    e = _lane()
    _set_p(e, p)
    e[L.BAD_IMU] = 1.0
    clear_dx(e)
    fuse_index(e, j, innov, r)
    k = p[:, j] / (p[j, j] + r)
    k[L.ES_BA:] = 0.0
    khp = np.outer(k, p[j, :])
    expect = p - 0.5 * (khp + khp.T)
    np.testing.assert_allclose(e[L.SCR_DX : L.SCR_DX + NS], k * innov, rtol=0, atol=1e-12)
    np.testing.assert_allclose(_get_p(e), expect, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(_get_p(e)[L.ES_BA:, L.ES_BA:], p[L.ES_BA:, L.ES_BA:])
    e[L.BAD_IMU] = 0.0
    _set_p(e, p)
    clear_dx(e)
    fuse_index(e, j, innov, r)
    assert np.abs(e[L.SCR_DX + L.ES_BA : L.SCR_DX + NS]).max() > 0.0


# ----------------------------------------------------------------------------- alignment


def test_alignment_at_rest_recovers_tilt_and_yaw():
    params = Params()
    cfg = build_ekf_config(params)
    ekf, sel = new_ekf(params)
    roll, pitch, yaw = math.radians(5.0), math.radians(-3.0), math.radians(100.0)
    e = np.zeros(L.N_EKF)
    set_quat_euler(e, roll, pitch, yaw)
    r = e[L.R00 : L.R22 + 1].reshape(3, 3)
    dang = np.zeros((2, 3))
    dvel = np.tile(r.T @ np.array([0.0, 0.0, -G]) * DT, (2, 1))
    mag = healthy_compasses(r.T @ earth_field(params))
    gps = np.zeros(3)
    for k in range(400):
        ekf_update(ekf, sel, cfg, (k + 1) * 2500, EkfInputs(
            dang, dvel, np.ones(2),
            False, gps, gps, False, False, 0.0, k % 40 == 0, mag, False,
        ))  # fmt: skip
    out = np.zeros(L.N_OUT)
    ekf_output(ekf, sel, out)
    assert out[L.O_F_ATTITUDE] == 1.0
    assert out[L.O_F_CONST_POS] == 1.0 and out[L.O_F_HORIZ_POS] == 0.0  # no GPS yet
    assert math.degrees(abs(out[L.O_ROLL] - roll)) < 0.05
    assert math.degrees(abs(out[L.O_PITCH] - pitch)) < 0.05
    assert math.degrees(abs(out[L.O_YAW] - yaw)) < 0.1
    assert quat_to_euler(*out[L.O_QW : L.O_QZ + 1])[2] == pytest.approx(out[L.O_YAW])


# ----------------------------------------------------------------------------- synthetic flights


def _run(flight, params):
    params = Params(params)
    cfg = build_ekf_config(params)
    ekf, sel = new_ekf(params)
    out, lanes_pos = fly_ekf(flight, ekf, sel, cfg)
    return ekf, sel, out, lanes_pos


@pytest.fixture(scope="module")
def clean_flight():
    return make_flight(100.0, seed=1)


@pytest.mark.parametrize(
    ("delay_ms", "pos_rms_max", "att_rms_max"),
    [(100.0, 0.1, 0.2), (200.0, 1.0, 1.0)],  # matched delay; default 0.2 s vs 0.1 s true lag
)
def test_synthetic_flight_accuracy(clean_flight, delay_ms, pos_rms_max, att_rms_max):
    f = clean_flight
    ekf, sel, out, _ = _run(f, {"GPS1_DELAY_MS": delay_ms})
    t = f.t_us * 1e-6
    m = t > 15.0
    pos_err = np.linalg.norm(out[:, L.O_PN : L.O_PN + 3] - f.pos, axis=1)
    att_err = quat_angle_deg(out[:, L.O_QW : L.O_QZ + 1], f.quat)
    vel_err = np.linalg.norm(out[:, L.O_VN : L.O_VN + 3] - f.vel, axis=1)
    assert np.sqrt(np.mean(pos_err[m] ** 2)) < pos_rms_max
    assert np.sqrt(np.mean(att_err[m] ** 2)) < att_rms_max
    assert np.sqrt(np.mean(vel_err[m] ** 2)) < 0.2
    assert att_err[m].max() < 2.0
    # gyro bias learned on both lanes (lane 1 has a different bias)
    for lane in range(2):
        err_deg = np.degrees(ekf[lane, L.BGX : L.BGZ + 1] - f.gyro_bias[lane])
        assert np.abs(err_deg).max() < 0.05, err_deg
    # healthy, GPS in use, no lane switch, innovations consistent
    assert out[-1, L.O_F_HORIZ_POS] == 1.0 and out[-1, L.O_F_USING_GPS] == 1.0
    assert out[-1, L.O_PRIMARY] == 0.0 and sel[L.SEL_CHANGES] == 0.0
    assert out[m, L.O_SQRT_VEL].max() < 0.5 and out[m, L.O_SQRT_POS].max() < 0.5


def test_gps_loss_timeouts_constant_position_and_reset():
    flight = make_flight(100.0, seed=1)
    t = flight.t_us * 1e-6
    gps_fix = flight.gps_fix & ~((t >= 40.0) & (t < 65.0))
    flight.gps_fix = gps_fix
    ekf, _, out, _ = _run(flight, {"GPS1_DELAY_MS": 100.0})
    fixes = np.nonzero(flight.gps_new & gps_fix)[0]
    last = fixes[fixes < int(40.0 / DT)][-1]
    back = fixes[fixes > int(40.0 / DT)][0]
    t_last = t[last]
    hpos = out[:, L.O_F_HORIZ_POS]
    cpos = out[:, L.O_F_CONST_POS]
    ticks = np.arange(t.size)
    during = (ticks > last) & (ticks < back)
    dt_lost = t - t_last
    # 0-7 s: still absolute aiding; from 7 s: horizontal position and velocity invalid
    assert np.all(hpos[during & (dt_lost <= 6.99)] == 1.0)
    assert np.all(hpos[during & (dt_lost >= 7.01)] == 0.0)
    assert np.all(out[during & (dt_lost >= 7.01), L.O_F_HORIZ_VEL] == 0.0)
    # from 15 s: constant-position mode
    assert np.all(cpos[during & (dt_lost <= 14.99)] == 0.0)
    assert np.all(cpos[during & (dt_lost >= 15.01)] == 1.0)
    assert np.all(out[during & (dt_lost >= 4.01), L.O_F_USING_GPS] == 0.0)
    # stopping aiding resets the horizontal velocity to zero (EKF3's ResetVelocity outside
    # absolute aiding; gps_s12.bin: XKF1 VN -3.12 -> 0.0006 m/s at "stopped aiding")
    first = np.nonzero(cpos == 1.0)[0]
    first = first[first > last][0]
    assert np.abs(out[first - 1, L.O_VN : L.O_VN + 2]).max() > 0.5
    assert np.abs(out[first, L.O_VN : L.O_VN + 2]).max() < 0.05
    # pinned near the last position while the vehicle flies on: large error before GPS returns
    err = np.linalg.norm(out[:, L.O_PN : L.O_PN + 2] - flight.pos[:, :2], axis=1)
    assert err[back - 1] > 10.0
    # the first GPS sample after the loss resets position and velocity, flags valid again; the
    # reset moves the output history too, which keeps only its sub-metre tracking error
    assert err[back] < 1.0
    gps_now = flight.gps_pos[back, :2]
    assert np.linalg.norm(out[back, L.O_PN : L.O_PN + 2] - gps_now) < 1.5
    vel_err = np.linalg.norm(out[back, L.O_VN : L.O_VN + 3] - flight.vel[back])
    assert vel_err < 0.2
    assert hpos[back] == 1.0 and cpos[back] == 0.0 and out[back, L.O_F_USING_GPS] == 1.0
    # first fix, entering constant-position mode, return from it
    assert ekf[0, L.POS_RESET_COUNT] == 3.0
    # (the constant-position phase leaves tilt and bias errors that take some seconds to go:
    # 0.25 m RMS after the return since that phase starts from EKF3's reset variances)
    assert np.sqrt(np.mean(err[back:] ** 2)) < 0.3


def test_accel_failure_switches_primary_lane():
    flight = make_flight(80.0, seed=2)
    t = flight.t_us * 1e-6
    fail = t >= 50.0
    flight.dvel[fail, 0, :] = 1.0 * DT  # SIM_ACCEL1_FAIL = 1: accel reads (1, 1, 1) m/s^2
    ekf, sel, out, lanes_pos = _run(flight, {"GPS1_DELAY_MS": 100.0})
    prim = out[:, L.O_PRIMARY]
    assert np.all(prim[~fail] == 0.0)
    k_switch = int(np.argmax(prim == 1.0))
    assert 50.0 < t[k_switch] < 52.0
    assert np.all(prim[k_switch:] == 1.0)
    assert sel[L.SEL_CHANGES] == 1.0 and out[-1, L.O_PRIMARY_CHANGES] == 1.0
    assert sel[L.SEL_T_SWITCH] == pytest.approx(t[k_switch])
    # the failed lane goes wrong (bounded by its bad-IMU response); the output follows lane 1
    lane0_err = np.linalg.norm(lanes_pos[:, 0] - flight.pos, axis=1)
    assert lane0_err[fail].max() > 3.0
    assert ekf[0, L.BAD_IMU] == 1.0 and ekf[1, L.BAD_IMU] == 0.0
    err = np.linalg.norm(out[:, L.O_PN : L.O_PN + 3] - flight.pos, axis=1)
    assert err[k_switch:].max() < 0.5
    assert ekf[1, L.HEALTHY] == 1.0 and ekf[1, L.SCORE] < 0.1


def test_both_accels_failed_bad_imu_response_bounds_the_error():
    """Paper case (SIM_ACCEL1_FAIL = SIM_ACCEL2_FAIL = 1): no good lane; EKF3's bad-IMU response
    (vertical velocity from GPS, gates bypassed, 5 m/s^2 accel noise) keeps the estimate bounded,
    where pure inertial integration of the wrong specific force would be off by ~3 km."""
    flight = make_flight(90.0, seed=4)
    t = flight.t_us * 1e-6
    fail = t >= 50.0
    flight.dvel[fail, :, :] = 1.0 * DT
    ekf, sel, out, _ = _run(flight, {"GPS1_DELAY_MS": 100.0})
    assert np.all(ekf[:, L.BAD_IMU] == 1.0)
    assert sel[L.SEL_CHANGES] <= 6.0  # both lanes equally wrong (SITL switched 4-6 times)
    err = np.linalg.norm(out[:, L.O_PN : L.O_PN + 3] - flight.pos, axis=1)
    assert 2.0 < err[fail].max() < 15.0
    vel_err = np.linalg.norm(out[:, L.O_VN : L.O_VN + 3] - flight.vel, axis=1)
    assert np.median(vel_err[t > 55.0]) < 4.0  # saw-tooth: vD reset to GPS at 5 Hz
    assert out[-1, L.O_F_HORIZ_POS] == 1.0
    # no accel-bias learning while the response is active (EKF3: gains zero while badIMUdata)
    assert np.abs(ekf[:, L.BAX : L.BAX + 3]).max() < 0.05


def test_a_stopped_imu_is_replaced_by_the_first_healthy_one_without_a_lane_switch():
    """EKF3's readIMUData (sitl-faults.md §2.3): a lane whose IMU stops delivering takes the
    deltas of the first IMU that does, silently; no lane switch, the lane stays healthy and on
    track (its own IMU's held deltas are not integrated: they would be garbage here)."""
    flight = make_flight(30.0, seed=3)
    t = flight.t_us * 1e-6
    stop = t >= 20.0
    flight.imu_ok[stop, 0] = 0.0
    flight.dang[stop, 0, :] = 0.3 * DT  # what a stopped IMU would hand over: never used
    flight.dvel[stop, 0, :] = 5.0 * DT
    ekf, sel, out, lanes_pos = _run(flight, {"GPS1_DELAY_MS": 100.0})
    assert sel[L.SEL_CHANGES] == 0.0 and np.all(out[:, L.O_PRIMARY] == 0.0)
    assert ekf[0, L.IMU_OK] == 1.0 and ekf[0, L.HEALTHY] == 1.0
    # lane 0 keeps its bias states (learnt for IMU 0, whose synthetic gyro bias differs from
    # IMU 1's by 0.45 deg/s; EKF3 would swap in a separately learnt bias) and stays on track
    np.testing.assert_allclose(lanes_pos[stop, 0], lanes_pos[stop, 1], atol=0.5)
    assert np.linalg.norm(out[-1, L.O_PN:L.O_PN + 3] - flight.pos[-1]) < 0.5


def test_lane_imu_sources():
    """(gyro, accel) a lane integrates: its own, else the first delivering; every accel
    stopped: its own held one; every gyro stopped: none (-1)."""
    from tlm_sim.ekf.lanes import lane_imu_sources

    ok = np.ones(4)  # accel 0, accel 1, gyro 0, gyro 1
    assert lane_imu_sources(0, ok, 2) == (0, 0) and lane_imu_sources(1, ok, 2) == (1, 1)
    assert lane_imu_sources(0, np.array([1.0, 1.0, 0.0, 1.0]), 2) == (1, 0)  # gyro 0 stopped
    assert lane_imu_sources(0, np.array([0.0, 1.0, 1.0, 1.0]), 2) == (0, 1)  # accel 0 stopped
    assert lane_imu_sources(1, np.array([0.0, 0.0, 1.0, 1.0]), 2) == (1, 1)  # all accels: own
    assert lane_imu_sources(1, np.array([1.0, 1.0, 0.0, 0.0]), 2)[0] == -1  # all gyros
    assert lane_imu_sources(0, np.array([0.0, 1.0]), 2) == (1, 1)  # short imu_ok: both follow


# ----------------------------------------------------------------------------- output observer


def _resting_lane(params: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(lane row, cfg): aligned, level, at rest at the origin, empty ring buffer."""
    cfg = build_ekf_config(Params(params))
    e = _lane(params)
    e[L.ALIGNED] = 1.0
    e[L.IMU_OK] = 1.0
    e[L.T_BAD_IMU] = -1e9
    e[L.T_BARO_LAST] = -1e9
    return e, cfg


def test_output_observer_follows_the_filter_with_ek3_tau_output():
    """A correction of the filter's vertical velocity reaches the output through EKF3's PI
    tracking loop (tau 0.25 s): ~2/3 after one tau, settled after a few seconds; the filter
    state (output + tracking error) never moves, and its height integrates its velocity."""
    e, cfg = _resting_lane()
    tau = cfg[L.C_TAU_OUTPUT]
    assert tau == pytest.approx(0.25)
    e[L.OUT_EVD] = 1.0  # e.g. the bad-IMU response set the filter's vD 1 m/s above the output
    dang = np.zeros((2, 3))
    dvel = np.zeros((2, 3))
    dvel[0, 2] = -G * DT  # at rest: the specific force cancels gravity
    vd, pd_filter = [], []
    for _ in range(int(10.0 / DT)):
        propagate(e, dang, dvel, 0, 0, DT)
        output_track(e, DT, tau, 0, False)
        vd.append(e[L.VD])
        pd_filter.append(e[L.PD] + e[L.OUT_EPD])
        assert e[L.VD] + e[L.OUT_EVD] == pytest.approx(1.0, abs=1e-12)
    vd = np.array(vd)
    k_tau = int(tau / DT) - 1
    assert 0.55 < vd[k_tau] < 0.75
    assert abs(vd[int(2.0 / DT)] - 1.0) < 0.1  # the integral term overshoots a little
    assert abs(vd[-1] - 1.0) < 0.01
    np.testing.assert_allclose(pd_filter[-1], 10.0, rtol=1e-3)  # 1 m/s for 10 s


def test_resets_move_output_and_filter_together():
    """A GPS reset sets the filter state to GPS and shifts the output by the same jump (EKF3
    shifts its output history), so the output tracking error survives the reset."""
    e, cfg = _resting_lane()
    e[L.OUT_EVN] = 0.3
    e[L.OUT_EPN] = -0.7
    reset_vel_pos_to_gps(e, cfg, 1.0, np.array([50.0, -20.0, 0.0]), np.array([2.0, 1.0, -0.5]), 0)
    assert e[L.OUT_EVN] == 0.3 and e[L.OUT_EPN] == -0.7
    np.testing.assert_allclose(_filter_vp(e), [2.0, 1.0, -0.5, 50.0, -20.0, 0.0], atol=1e-12)
    assert e[L.PN] == pytest.approx(50.7) and e[L.VN] == pytest.approx(1.7)


def test_bad_imu_response_starts_with_the_gps_sample_after_the_first_detection():
    """EKF3 tests the hold time against the previous detection before recording a new one: the
    first detection changes nothing, the next GPS sample sets the filter's vD to GPS (the output
    keeps its value and follows through the observer), then the threshold drops to 1 sigma."""
    e, cfg = _resting_lane()
    r_vd = cfg[L.C_VELD_NSE] ** 2
    e[L.PD] = -10.0  # the EKF believes 10 m up, sinking at 5 m/s ...
    e[L.VD] = 5.0
    e[L.BARO_LAST] = 20.0  # ... the baro says 20 m, GPS says climbing at 5 m/s
    e[L.T_BARO_LAST] = 10.0
    e[L.T_GOOD_IMU] = 9.8  # the previous GPS sample passed
    assert not _bad_imu_check(e, cfg, 10.0, -5.0, 0, r_vd)
    assert e[L.T_BAD_IMU] == 10.0 and e[L.BAD_IMU] == 0.0 and e[L.OUT_EVD] == 0.0
    e[L.T_BARO_LAST] = 10.2
    assert _bad_imu_check(e, cfg, 10.2, -5.0, 0, r_vd)
    assert e[L.BAD_IMU] == 1.0 and e[L.T_BAD_IMU] == 10.2
    assert e[L.VD] == 5.0 and e[L.VD] + e[L.OUT_EVD] == pytest.approx(-5.0)
    # 3 m / 1 m/s errors: below the first (3 sigma) threshold, above the 1-sigma one now used
    e2, _ = _resting_lane()
    e2[L.PD], e2[L.BARO_LAST], e2[L.VD] = -10.0, 13.0, 1.0
    e2[L.T_BARO_LAST] = 5.0
    _bad_imu_check(e2, cfg, 5.0, 0.0, 0, r_vd)
    assert e2[L.T_BAD_IMU] < 0.0
    e[L.PD], e[L.BARO_LAST], e[L.VD], e[L.OUT_EVD] = -10.0, 13.0, 1.0, 0.0
    e[L.T_BARO_LAST] = 10.4
    _bad_imu_check(e, cfg, 10.4, 0.0, 0, r_vd)
    assert e[L.T_BAD_IMU] == 10.4


def test_bad_imu_response_holds_the_height_variance_at_the_baro_noise():
    """While the response is active a baro sample pulls the height half way (P_pd >= R), as the
    reference logs' EKF3 innovations show; otherwise the settled variance gives a small gain."""
    moves = []
    for bad in (0.0, 1.0):
        e, cfg = _resting_lane()
        e[L.P0 + (L.ES_POS + 2) * (NS + 1)] = 0.16
        e[L.BAD_IMU] = bad
        lane_fuse_baro(e, cfg, 1.0, 4.0)  # baro 4 m above the estimate
        moves.append(-(e[L.PD] + e[L.OUT_EPD]))
    assert moves[0] == pytest.approx(4.0 * 0.16 / 4.16)
    assert moves[1] == pytest.approx(2.0)
