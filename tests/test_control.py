"""Controller tests: square-root controller, mixer/thrust linearisation, closed-loop rate steps,
the vibration-failsafe gating and the thrust-loss check."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import reference_path
from tlm_sim import ardupilot as AP
from tlm_sim import logger as L
from tlm_sim.control import failsafe as FS
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import rate_pid, sqrt_ctrl
from tlm_sim.control.config import build_control_config
from tlm_sim.control.mixer import lift_max, mix, thrust_to_actuator
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.body import init_state, physics_step, set_airborne
from tlm_sim.dynamics.frame import build_frame, hover_command, pwm_to_command
from tlm_sim.ekf import layout as EK
from tlm_sim.params import Params
from tlm_sim.rng import new_rng

#: wind generator state for the physics calls
RNG = new_rng(0, 2)


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
    assert pwm[0] == int(pwm[0])  # whole microseconds, as the motor library outputs them
    # thrust linearisation is the exact inverse of SITL's thrust curve: 0.39 -> hover command,
    # less the fraction of a microsecond the integer PWM drops (1 us = 1/800 of the command)
    a = pwm_to_command(pwm[0], frame)
    assert hover_command(frame) - 1.0 / 800.0 - 1e-9 <= a <= hover_command(frame) + 1e-9


def test_mixer_density_and_voltage_compensation(cfg):
    """Thinner air and a higher resting-voltage estimate change the motor outputs as
    AP_Motors' compensation gain 1/(lift_max rho_ratio) does."""
    _, g = cfg
    c = np.zeros(C.N_CONTROL_STATE)
    mix(c, g, 0.0, 0.0, 0.0, 0.36, 12.6)
    base = c[C.MIX_THRUST]
    c[C.AIR_RHO_RATIO] = 0.9433  # CMAC, 604 m AMSL
    mix(c, g, 0.0, 0.0, 0.0, 0.36, 12.6)
    assert c[C.MIX_THRUST] == pytest.approx(base / 0.9433, rel=1e-9)
    c[C.AIR_RHO_RATIO] = 1.0
    c[C.THR_HOVER] = 0.36  # at the hover thrust the monitor adds TLM_BATT_SAG_HOV
    c[C.MIX_THRUST : C.MIX_THRUST + 4] = 0.36  # (the thrust of the previous tick)
    mix(c, g, 0.0, 0.0, 0.0, 0.36, 12.6)
    _, lift_est = lift_max(g, 12.6 + g[C.G_BATT_SAG_HOVER])
    _, lift_v = lift_max(g, 12.6)
    assert c[C.MIX_THRUST] == pytest.approx(base * lift_v / lift_est, rel=1e-9)
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
            physics_step(x, pwm, frame, 833e-6, t_us * 1e-6, RNG)
            t_us += 833
        out.append(math.degrees(meas[axis]))
    return np.array(out[20:])


@pytest.mark.parametrize("axis", [0, 1])
def test_rate_loop_step_response(cfg, axis):
    """A 60 deg/s roll or pitch rate step with ArduCopter's default rate gains on SITL's quad
    settles within 0.15 s without overshoot beyond 10 % (ArduPilot tunes for a well-damped rate
    loop). The rotors' momentum drag damps the body rates (~1.9 /s), so the integrator takes a
    while to supply the holding torque: ~58.6 deg/s after 1 s."""
    frame, g = cfg
    r = _rate_step(frame, g, axis, 60.0)
    assert r.max() <= 66.0
    outside = np.flatnonzero(np.abs(r - 60.0) > 6.0)
    settle = (outside.max() + 1) / 400.0 if outside.size else 0.0
    assert settle <= 0.15
    assert r[-40:].mean() == pytest.approx(60.0, abs=2.0)


def test_yaw_rate_step_is_slowed_by_rotor_drag(cfg):
    """Yaw has little authority against the rotors' momentum-drag damping (normal_s11.bin:
    yaw acceleration = 2.0 deg/s^2 per us of differential PWM - 1.92 /s x yaw rate): with
    ATC_RAT_YAW_P 0.3 the rate jumps to ~2/3 of a 60 deg/s step within 0.5 s and then creeps up
    on the small integrator (I 0.02), never overshooting."""
    frame, g = cfg
    r = _rate_step(frame, g, 2, 60.0)
    assert r.max() <= 60.0
    assert 35.0 <= r[200] <= 47.0
    assert r[-1] > r[200]


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
    eo = np.zeros(EK.N_OUT)  # the EKF's output block
    eo[EK.O_INNOV_VD] = -3.0  # tlm sign: measurement - prediction
    eo[EK.O_INNOV_HGT] = -5.0
    eo[EK.O_VEL_TR] = 16.0
    eo[EK.O_F_HORIZ_POS] = 1.0  # an absolute position, not constant-position mode
    eo[EK.O_BAD_IMU] = bad_imu
    events, ev_counts = L.event_buffers(*L.new_buffers(1.0))
    for k in range(int(seconds / 0.1) + 1):
        FS.failsafe_checks(c, g, k * 100000, eo, (events, ev_counts))
    return events[L.E_ERR][: ev_counts[L.E_ERR]]


def test_vibration_check_innovation_clause_needs_the_ekf_check():
    """With FS_EKF_THRESH 0 ArduCopter's ekf_check never filters the variances, so only the
    EKF's bad-IMU flag can turn vibration compensation on (as in the reference flights: ERR 29
    ~1 s after EKF3's bad-IMU response, not after its velocity ratio exceeds 1)."""
    assert not (_vibe_run(0.0, 0.0)[:, 1] == AP.ERR_FAILSAFE_VIBE).any()
    on = _vibe_run(0.0, 1.0)
    vibe = on[on[:, 1] == AP.ERR_FAILSAFE_VIBE]
    assert len(vibe) == 1 and vibe[0, 2] == 1 and vibe[0, 0] == pytest.approx(1.0e6)
    # with the EKF check on, the filtered ratio counts too (and the EKF failsafe also fires)
    with_check = _vibe_run(0.8, 0.0)
    assert (with_check[:, 1] == AP.ERR_FAILSAFE_VIBE).any()


def _thrust_loss_run(g, roll_cmd, thr, vd, limit_hi=0.0, seconds=1.5):
    c = _armed_state(g)
    c[C.ATT_ROLL_CMD] = roll_cmd
    c[C.THR_OUT] = thr
    c[C.LIM_THR_HI] = limit_hi
    c[C.MIX_THRUST : C.MIX_THRUST + 4] = 1.0
    q = np.array([1.0, 0.0, 0.0, 0.0])
    events, ev_counts = L.event_buffers(*L.new_buffers(1.0))
    dt = g[C.G_DT]
    hits = [k for k in range(int(seconds / dt))
            if FS.thrust_loss_check(c, dt, q, vd, (events, ev_counts), k * 2500)]
    return hits, events[L.E_ERR][: ev_counts[L.E_ERR]], c


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
    # the boost holds the check off; the motor library switches it off once a balanced mix
    # with headroom comes out of the mixer (mixer.motor_loss_monitor)
    events, ev_counts = L.event_buffers(*L.new_buffers(1.0))
    c[C.THRUST_LOSS_T] = 5.0
    assert not FS.thrust_loss_check(c, g[C.G_DT], np.array([1.0, 0, 0, 0]), 2.0,
                                    (events, ev_counts), 0)
    assert c[C.THRUST_BOOST] == 1.0 and ev_counts[L.E_ERR] == 0
    mix(c, g, 0.0, 0.0, 0.0, 0.4, 12.6)
    assert c[C.THRUST_BOOST] == 0.0


# ------------------------------------------------------------------- waypoint navigation


def _fly_path(g, points, ticks=40000):
    """Follow a path with a perfectly tracking vehicle; returns the targets per tick."""
    from tlm_sim.control.wpnav import PATH_COLS, path_start, path_update, prepare_path

    path = np.zeros((len(points), PATH_COLS))
    path[:, :3] = points
    prepare_path(path, len(points), g)
    c = np.zeros(C.N_CONTROL_STATE)
    path_start(c)
    pos = np.array(points[0], dtype=float)
    c[C.PXY_POS_T], c[C.PXY_POS_T + 1], c[C.PZ_POS_T] = pos
    rows = []
    for _ in range(ticks):
        vel = np.array([c[C.PXY_VEL_FF], c[C.PXY_VEL_FF + 1], c[C.PZ_VEL_FF]])
        heading, done = path_update(c, g, path, len(points), (pos, vel), 0.0, True)
        pos[:] = c[C.PXY_POS_T], c[C.PXY_POS_T + 1], c[C.PZ_POS_T]
        rows.append([*pos, c[C.PXY_VEL_FF], c[C.PXY_VEL_FF + 1], c[C.PZ_VEL_FF],
                     c[C.PXY_ACC_FF], c[C.PXY_ACC_FF + 1], c[C.PZ_ACC_FF], c[C.YAW_RATE_CMD],
                     heading, done])
        if done:
            break
    return np.array(rows), path


def test_corner_blend_turns_like_overlapping_s_curves(cfg):
    """At an intermediate waypoint the target does not stop: position, velocity and
    acceleration stay continuous, the speed dips to v cos(turn/2) half-way (normal_s11's 95 deg
    turn: 3.39 -> 2.31 m/s), the heading-rate feed-forward turns the heading by the corner
    angle, and the path's end is reached with a jerk-limited stop."""
    _, g = cfg
    rows, path = _fly_path(g, [(0.0, 0.0, -20.0), (14.0, 0.0, -20.0), (14.0, 14.0, -20.0),
                               (28.0, 14.0, -20.0)])
    dt = g[C.G_DT]
    v = np.hypot(rows[:, 3], rows[:, 4])
    a = rows[:, 6:9]
    assert rows[-1, -1] == 1.0
    np.testing.assert_allclose(rows[-1, :3], (28.0, 14.0, -20.0), atol=0.02)
    steps = np.abs(np.diff(rows[:, :3], axis=0)).max(axis=1)
    assert steps[:-1].max() <= v.max() * dt * 1.01
    assert steps[-1] < 0.02  # the stop ends within ~1.5 ticks' travel of the end point
    assert np.abs(np.diff(rows[:, 3:6], axis=0)).max() < 3.0 * dt  # no velocity step
    jerk = np.linalg.norm(np.diff(a, axis=0), axis=1) / dt
    assert jerk.max() < 4.0  # m/s^3: WPNAV_JERK 1 with the blend's and stop's shapes
    # the first corner: 90 deg between two 14 m legs cruising at v_leg
    v_leg = path[1, 7]
    near = np.hypot(rows[:, 0] - 14.0, rows[:, 1]) < 6.0
    assert v[near].min() == pytest.approx(v_leg * math.cos(math.radians(45.0)), rel=0.05)
    # the heading follows the velocity; its rate feed-forward integrates to the turns
    turn = rows[:, 9].sum() * dt
    assert turn == pytest.approx(0.0, abs=0.05)  # +90 then -90 deg
    first = rows[:, 1] < 7.0
    assert rows[first, 9].sum() * dt == pytest.approx(math.pi / 2.0, rel=0.05)


def test_vertical_leg_uses_the_vertical_acceleration_limit(cfg):
    """A climb (takeoff, RTL climb) accelerates at WPNAV_ACCEL_Z (1 m/s^2), not WPNAV_ACCEL,
    as AC_WPNav's S-curve takes its limits along the track (normal_s11's takeoff reaches
    2.5 m/s about 2.5 s after it starts)."""
    _, g = cfg
    rows, _ = _fly_path(g, [(0.0, 0.0, 0.0), (0.0, 0.0, -16.0)])
    acc_up = -rows[:, 8]
    assert acc_up.max() == pytest.approx(g[C.G_WP_ACCEL_Z], rel=0.02)
    t_25 = np.argmax(-rows[:, 5] >= 0.99 * g[C.G_WP_SPEED_UP]) * g[C.G_DT]
    assert 2.5 <= t_25 <= 3.6


def test_lean_limit_follows_throttle_headroom(cfg):
    """With the throttle saturated the lean target shrinks to 10 deg within a few
    ATC_ANG_LIM_TC (engine_s14.bin on the ground after the crash: 10 deg held for 25 s)."""
    from tlm_sim.control.position import althold_lean_update, xy_update

    _, g = cfg
    c = np.zeros(C.N_CONTROL_STATE)
    c[C.ALTHOLD_LEAN] = math.radians(60.0)
    for _ in range(2000):  # 5 s at full throttle
        althold_lean_update(c, g, 1.0)
    assert c[C.ALTHOLD_LEAN] < math.radians(1.0)
    c[C.PXY_POS_T] = 50.0  # far ahead
    for _ in range(400):
        xy_update(c, g, np.zeros(3), np.zeros(3), 1.0, 0.0)
    lean = math.hypot(c[C.ATT_ROLL_CMD], c[C.ATT_PITCH_CMD])
    assert lean == pytest.approx(math.radians(10.0), abs=math.radians(0.1))
    for _ in range(4000):  # hover throttle: the limit opens up to ANGLE_MAX
        althold_lean_update(c, g, 0.37)
        xy_update(c, g, np.zeros(3), np.zeros(3), 1.0, 0.0)
    assert abs(c[C.ATT_PITCH_CMD]) == pytest.approx(g[C.G_ANGLE_MAX], abs=math.radians(0.2))


def test_tilted_copter_recovers_its_thrust_axis_before_its_heading(cfg):
    """Beyond 60 deg of thrust-vector error the yaw-rate target is the measured yaw rate and
    the heading error is capped (45 deg with the SITL defaults), as AC_AttitudeControl does."""
    from tlm_sim.control.attitude import attitude_reset, attitude_update

    _, g = cfg
    assert g[C.G_YAW_ERR_MAX] == pytest.approx(math.radians(45.0))
    c = np.zeros(C.N_CONTROL_STATE)
    attitude_reset(c, 0.0, 0.0, math.radians(80.0))  # level, heading 80 deg
    roll = math.radians(90.0)  # the copter: rolled 90 deg, heading 0
    q = np.array([math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0])
    out = np.zeros(3)
    attitude_update(c, g, q, np.array([0.0, 0.0, 0.7]), out)
    assert out[2] == 0.7
    assert out[0] < -1.0  # roll back
    # the heading target was dragged to within 45 deg of the copter's
    assert abs(c[C.ATT_YAW_T]) <= math.radians(45.0) + 1e-6


# ------------------------------------------------- position jumps (EKF stopping/resuming aiding)


def test_position_error_limit_is_ac_p_2d_error_max(cfg):
    """A target far from the position estimate is moved to PSC's error_max (8.45 m for
    WPNAV_SPEED 6 m/s, PSC_POSXY_P 1, WPNAV_ACCEL 2.5 m/s^2: gps_s12.bin's PSCN/PSCE target sat
    8.45 m from the zero position estimate while the EKF had no position), along the same
    direction, and the correction asks for exactly WPNAV_SPEED on top of the feed-forward."""
    from tlm_sim.control.config import inv_sqrt_ctrl
    from tlm_sim.control.position import xy_update

    _, g = cfg
    assert g[C.G_POSXY_ERR_MAX] == pytest.approx(8.45)
    assert sqrt_ctrl(g[C.G_POSXY_ERR_MAX], g[C.G_POSXY_P], g[C.G_WP_ACCEL], 0.0) == (
        pytest.approx(g[C.G_WP_SPEED]))
    # the vertical ones ask for WPNAV_SPEED_UP / _DN (combined_s21.bin: PSCD 1.625 m below)
    assert g[C.G_POSZ_ERR_DN] == pytest.approx(1.625)
    assert g[C.G_POSZ_ERR_UP] == pytest.approx(3.625)
    assert inv_sqrt_ctrl(0.5, 1.0, 2.5) == pytest.approx(0.5)  # linear region
    c = np.zeros(C.N_CONTROL_STATE)
    c[C.ALTHOLD_LEAN] = g[C.G_ANGLE_MAX]
    c[C.PXY_POS_T], c[C.PXY_POS_T + 1] = -136.9, -2.9  # the path target before the jump
    c[C.PXY_VEL_FF], c[C.PXY_VEL_FF + 1] = -3.21, -0.07
    xy_update(c, g, np.zeros(3), np.zeros(3), -1.0, 0.0)  # estimate jumped to the origin
    t = c[C.PXY_POS_T : C.PXY_POS_T + 2]
    assert np.hypot(*t) == pytest.approx(8.45)
    assert t[1] / t[0] == pytest.approx(2.9 / 136.9)
    corr = c[C.PXY_VEL_T : C.PXY_VEL_T + 2] - c[C.PXY_VEL_FF : C.PXY_VEL_FF + 2]
    assert np.hypot(*corr) == pytest.approx(6.0)
    assert c[C.PXY_VEL_T] == pytest.approx(-9.21, abs=0.01)  # SITL's PSCN.TVN
    # the lean saturates at ANGLE_MAX towards the target (gps_s12: DesPitch -30 deg)
    assert c[C.ATT_PITCH_CMD] == pytest.approx(-g[C.G_ANGLE_MAX], abs=1e-3)


def test_track_scaler_freezes_the_path_but_keeps_the_feed_forward(cfg):
    """AC_WPNav's S-curve time: 1 while the vehicle keeps up, 0 when it is far behind, low-passed
    with WPNAV_ACCEL / WPNAV_JERK; the path target then stops while the feed-forward velocity
    keeps its value (gps_s12.bin: DPN frozen, DVN -3.21 m/s for 19 s)."""
    from tlm_sim.control.wpnav import (
        PATH_COLS,
        path_start,
        path_update,
        prepare_path,
        track_scaler,
    )

    _, g = cfg
    points = [(0.0, 0.0, -20.0), (-200.0, 0.0, -20.0)]
    path = np.zeros((2, PATH_COLS))
    path[:, :3] = points
    prepare_path(path, 2, g)
    c = np.zeros(C.N_CONTROL_STATE)
    path_start(c)
    pos = np.array(points[0])
    for _ in range(4000):  # 10 s of perfect tracking: up to cruise, scaler 1
        vel = np.array([c[C.PXY_VEL_FF], c[C.PXY_VEL_FF + 1], c[C.PZ_VEL_FF]])
        path_update(c, g, path, 2, (pos, vel), 0.0, True)
        pos[:] = c[C.PXY_POS_T], c[C.PXY_POS_T + 1], c[C.PZ_POS_T]
    assert c[C.TRACK_K] == pytest.approx(1.0)
    v_ff = c[C.PXY_VEL_FF]
    assert v_ff < -1.0
    # the vehicle now 8.45 m behind and not moving: the target slows to a stop
    pos[0] = c[C.PXY_POS_T] + 8.45
    s0 = c[C.PATH_S]
    k = []
    for _ in range(4000):
        path_update(c, g, path, 2, (pos, np.zeros(3)), 0.0, True)
        c[C.PXY_POS_T] = pos[0] - 8.45  # (as the position controller's error limit leaves it)
        k.append(c[C.TRACK_K])
    tc = g[C.G_WP_ACCEL] / g[C.G_WP_JERK]
    assert k[int(tc / g[C.G_DT])] == pytest.approx(math.exp(-1.0), abs=0.01)
    assert k[-1] < 0.02
    assert c[C.PATH_S] - s0 < 3.0 * abs(v_ff)  # about tc x speed, then stopped
    assert c[C.PXY_VEL_FF] == pytest.approx(v_ff)  # the feed-forward is kept
    assert track_scaler(c, g, pos, np.zeros(3)) < 0.02


def _psc_accel_stats(tables) -> tuple[float, float, float]:
    """(RMS of PSCN.AN - TAN and of PSCE.AE - TAE [m/s^2], max |PSCD.AD + RATE.A / 100|) of
    a log's tables."""
    pn, pe, pd_, rate = (tables[k] for k in ("PSCN", "PSCE", "PSCD", "RATE"))
    rms_n = float(np.sqrt(((pn.AN - pn.TAN) ** 2).mean()))
    rms_e = float(np.sqrt(((pe.AE - pe.TAE) ** 2).mean()))
    both = pd_.merge(rate[["TimeUS", "A"]], on="TimeUS")
    return rms_n, rms_e, float((both.AD + both.A / 100.0).abs().max())


def test_psc_actual_acceleration_is_the_controllers_as_in_sitl(normal_flight):
    """PSCN.AN / PSCE.AE are the acceleration the attitude target's lean angles ask for (at the
    AHRS yaw) and PSCD.AD the vertical controller's measured acceleration (-RATE.A / 100), as
    AC_PosControl logs them, not the truth's: in normal_s11.bin AN follows TAN within
    0.033 / 0.038 m/s^2 RMS and AD is -RATE.A / 100 row by row (truth acceleration gave
    0.82 / 0.98 m/s^2 in tlm)."""
    from tlm_sim.flightlog import read_log

    sitl = read_log(reference_path("normal_s11.bin"))
    s_n, s_e, s_d = _psc_accel_stats(getattr(sitl, "tables", sitl))
    t_n, t_e, t_d = _psc_accel_stats(normal_flight.tables)
    assert s_n < 0.05 and s_e < 0.05 and s_d < 0.01  # SITL's own definition
    assert t_n < 0.06 and t_e < 0.06
    assert t_d < 1e-6
    std_tlm = normal_flight.tables["PSCD"].AD.std()
    std_sitl = getattr(sitl, "tables", sitl)["PSCD"].AD.std()
    assert std_tlm == pytest.approx(std_sitl, rel=0.3)


@pytest.mark.parametrize("roll,pitch,yaw", [(0.0, -0.2, 0.0), (0.3, 0.0, 0.0),
                                            (0.1, -0.2, 1.0), (0.0, 0.0, 2.0)])
def test_lean_angles_to_accel_is_the_thrust_direction(roll, pitch, yaw):
    """The NE acceleration of a thrust that holds the weight at (roll, pitch, yaw) is g x its
    NE components over its vertical one: checked against the rotated body -z axis."""
    from scipy.spatial.transform import Rotation

    from tlm_sim.control.log import lean_angles_to_accel

    up = Rotation.from_euler("ZYX", [yaw, pitch, roll]).apply([0.0, 0.0, -1.0])
    want = 9.80665 * up[:2] / -up[2]
    got = [lean_angles_to_accel(roll, pitch, yaw, ax) for ax in (0, 1)]
    assert got == pytest.approx(want, abs=1e-9)
