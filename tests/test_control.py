"""Controller tests: square-root controller, mixer/thrust linearisation, closed-loop rate steps,
the vibration-failsafe gating and the thrust-loss check."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim.control import failsafe as FS
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import rate_pid, sqrt_ctrl
from tlm_sim.control.config import build_control_config
from tlm_sim.control.mixer import mix, thrust_to_actuator
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.body import init_state, physics_step, set_airborne
from tlm_sim.dynamics.frame import build_frame, hover_command, pwm_to_command
from tlm_sim.params import Params


@pytest.fixture(scope="module")
def cfg():
    p = Params()
    return build_frame(p), build_control_config(p)


@given(st.floats(-50, 50), st.floats(0.1, 10), st.floats(0.1, 20))
@settings(max_examples=200, deadline=None)
def test_sqrt_ctrl_odd_bounded_and_never_overshoots(e, p, a):
    dt = 0.0025
    out = sqrt_ctrl(e, p, a, dt)
    assert out == pytest.approx(-sqrt_ctrl(-e, p, a, dt))
    assert abs(out) * dt <= abs(e) + 1e-12  # one step never passes the target
    assert abs(out) <= p * abs(e) + 1e-9  # never steeper than the linear law
    if e != 0:
        assert math.copysign(1, out) == math.copysign(1, e)


def test_sqrt_ctrl_continuous_at_the_switch():
    p, a = 4.5, 10.0
    lin = a / (p * p)
    assert sqrt_ctrl(lin * (1 - 1e-9), p, a, 0.0) == pytest.approx(
        sqrt_ctrl(lin * (1 + 1e-9), p, a, 0.0)
    )


def test_mixer_hover_is_symmetric_and_inverts_the_motor_model(cfg):
    frame, g = cfg
    c = np.zeros(C.N_CONTROL_STATE)
    mix(c, g, 0.0, 0.0, 0.0, 0.39, 12.8)  # at MOT_BAT_VOLT_MAX: no voltage compensation
    pwm = c[C.MIX_PWM : C.MIX_PWM + 4]
    assert np.ptp(pwm) == 0.0
    # thrust linearisation is the exact inverse of SITL's thrust curve: 0.39 -> hover command
    a = pwm_to_command(pwm[0], frame)
    assert a == pytest.approx(hover_command(frame), abs=1e-9)
    assert not c[C.LIM_RP] and not c[C.LIM_THR_LO] and not c[C.LIM_THR_HI]


def test_mixer_signs(cfg):
    _, g = cfg
    c = np.zeros(C.N_CONTROL_STATE)
    mix(c, g, 0.1, 0.0, 0.0, 0.4, 12.6)  # roll right: left motor (2) up, right motor (1) down
    assert c[C.MIX_PWM + 1] > c[C.MIX_PWM + 0]
    mix(c, g, 0.0, 0.1, 0.0, 0.4, 12.6)  # pitch up: front motor (3) up
    assert c[C.MIX_PWM + 2] > c[C.MIX_PWM + 3]
    mix(c, g, 0.0, 0.0, 0.1, 0.4, 12.6)  # yaw right: CCW motors (1, 2) up
    assert c[C.MIX_PWM + 0] > c[C.MIX_PWM + 2]


@given(st.floats(-2, 2), st.floats(-2, 2), st.floats(-2, 2), st.floats(0, 1))
@settings(max_examples=200, deadline=None)
def test_mixer_outputs_stay_in_range(cfg, r, p, y, t):
    _, g = cfg
    c = np.zeros(C.N_CONTROL_STATE)
    mix(c, g, r, p, y, t, 12.0)
    assert np.all(c[C.MIX_THRUST : C.MIX_THRUST + 4] >= 0.0)
    assert np.all(c[C.MIX_THRUST : C.MIX_THRUST + 4] <= 1.0)
    assert np.all(c[C.MIX_PWM : C.MIX_PWM + 4] >= 1000.0 + 150.0 - 1e-9)
    assert np.all(c[C.MIX_PWM : C.MIX_PWM + 4] <= 1950.0 + 1e-9)


def test_thrust_to_actuator_monotone(cfg):
    _, g = cfg
    a = [thrust_to_actuator(g, t, 1.0, 1.0) for t in np.linspace(0, 1, 101)]
    assert np.all(np.diff(a) > 0)


def _rate_step(frame, g, axis, target_deg, n_ticks=400):
    """Closed-loop rate PIDs + mixer + SITL physics at hover; returns the rate trace [deg/s]."""
    x = np.zeros(X.N_STATE)
    init_state(x, frame, 0.0)
    set_airborne(x, frame, 50.0, hover_command(frame))
    c = np.zeros(C.N_CONTROL_STATE)
    pwm = np.zeros(4)
    t_us = 0
    out = []
    for tick in range(n_ticks):
        tgt = math.radians(target_deg) if tick >= 20 else 0.0
        meas = (x[X.WX], x[X.WY], x[X.WZ])
        o = [
            rate_pid(c, g, k, tgt if k == axis else 0.0, meas[k], c[C.LIM_RP] != 0)
            for k in range(3)
        ]
        mix(c, g, o[0], o[1], o[2], 0.39, 12.6)
        pwm[:] = c[C.MIX_PWM : C.MIX_PWM + 4]
        for _ in range(3):
            physics_step(x, pwm, frame, 833e-6, t_us * 1e-6)
            t_us += 833
        out.append(math.degrees(meas[axis]))
    return np.array(out[20:])


@pytest.mark.parametrize("axis, settle_s", [(0, 0.15), (1, 0.15), (2, 0.8)])
def test_rate_loop_step_response(cfg, axis, settle_s):
    """A 60 deg/s body-rate step with ArduCopter's default rate gains on SITL's quad settles
    without overshoot beyond 10 % (ArduPilot tunes for a well-damped rate loop)."""
    frame, g = cfg
    r = _rate_step(frame, g, axis, 60.0)
    assert r.max() <= 66.0
    outside = np.flatnonzero(np.abs(r - 60.0) > 6.0)
    settle = (outside.max() + 1) / 400.0 if outside.size else 0.0
    assert settle <= settle_s
    assert r[-40:].mean() == pytest.approx(60.0, abs=1.0)


# ------------------------------------------------------------------- failsafe checks


def _armed_state(g):
    c = np.zeros(C.N_CONTROL_STATE)
    c[C.ARMED] = 1.0
    c[C.THR_HOVER] = 0.39
    c[C.VIBE_FAIL_T] = -1.0
    return c


def _vibe_run(thresh, bad_imu, seconds=3.0):
    """ERR rows from the 10 Hz checks with an EKF reporting sinking-and-low innovations and a
    velocity test ratio of 4, with or without its bad-IMU flag."""
    g = build_control_config(Params({"FS_EKF_THRESH": thresh}))
    c = _armed_state(g)
    nav = np.zeros(FS.N_NAV)
    nav[FS.NAV_INNOV_VD] = -3.0  # tlm sign: measurement - prediction
    nav[FS.NAV_INNOV_HGT] = -5.0
    nav[FS.NAV_VEL_TR] = 16.0
    nav[FS.NAV_POS_OK] = 1.0
    nav[FS.NAV_BAD_IMU] = bad_imu
    err = np.zeros((16, 3))
    counts = np.zeros(1, dtype=np.int64)
    for k in range(int(seconds / 0.1) + 1):
        FS.failsafe_checks(c, g, k * 100000, nav, err, counts, 0)
    return err[: counts[0]]


def test_vibration_check_innovation_clause_needs_the_ekf_check():
    """With FS_EKF_THRESH 0 ArduCopter's ekf_check never filters the variances, so only the
    EKF's bad-IMU flag can turn vibration compensation on (as in the reference flights: ERR 29
    ~1 s after EKF3's bad-IMU response, not after its velocity ratio exceeds 1)."""
    assert not (_vibe_run(0.0, 0.0)[:, 1] == FS.ERR_FAILSAFE_VIBE).any()
    on = _vibe_run(0.0, 1.0)
    vibe = on[on[:, 1] == FS.ERR_FAILSAFE_VIBE]
    assert len(vibe) == 1 and vibe[0, 2] == 1 and vibe[0, 0] == pytest.approx(1.0e6)
    # with the EKF check on, the filtered ratio counts too (and the EKF failsafe also fires)
    with_check = _vibe_run(0.8, 0.0)
    assert (with_check[:, 1] == FS.ERR_FAILSAFE_VIBE).any()


def _thrust_loss_run(g, roll_cmd, thr, vd, limit_hi=0.0, seconds=1.5):
    c = _armed_state(g)
    c[C.ATT_ROLL_CMD] = roll_cmd
    c[C.THR_OUT] = thr
    c[C.LIM_THR_HI] = limit_hi
    c[C.MIX_THRUST : C.MIX_THRUST + 4] = 1.0
    q = np.array([1.0, 0.0, 0.0, 0.0])
    err = np.zeros((8, 3))
    counts = np.zeros(1, dtype=np.int64)
    dt = g[C.G_DT]
    hits = [k for k in range(int(seconds / dt))
            if FS.thrust_loss_check(c, dt, q, vd, err, counts, 0, k * 2500)]
    return hits, err[: counts[0]], c


def test_thrust_loss_check_fires_after_one_second_of_full_throttle_descent(cfg):
    _, g = cfg
    hits, err, c = _thrust_loss_run(g, math.radians(5.0), 0.95, 2.0)
    assert len(hits) == 1 and hits[0] == pytest.approx(1.0 / g[C.G_DT] - 1, abs=1)
    assert err.tolist() == [[hits[0] * 2500, 25, 1]]
    assert c[C.THRUST_BOOST] == 1.0
    assert _thrust_loss_run(g, 0.0, 0.5, 2.0, limit_hi=1.0)[0]  # saturated counts as full
    assert not _thrust_loss_run(g, math.radians(20.0), 0.95, 2.0)[0]  # leaning: not thrust
    assert not _thrust_loss_run(g, 0.0, 0.95, -1.0)[0]  # climbing
    assert not _thrust_loss_run(g, 0.0, 0.8, 2.0)[0]  # throttle in reserve
    assert not _thrust_loss_run(g, 0.0, 0.2, 2.0, limit_hi=1.0)[0]  # below 25 %
    # the boost holds the check off until the motors have headroom again
    c[C.MIX_THRUST : C.MIX_THRUST + 4] = 0.5
    FS.thrust_loss_check(c, g[C.G_DT], np.array([1.0, 0, 0, 0]), 2.0, err, np.zeros(1, np.int64),
                         0, 0)
    assert c[C.THRUST_BOOST] == 0.0
