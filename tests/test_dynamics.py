"""Physics of SITL's "+" quad (tlm_sim.dynamics) against ardupilot-reference.md §1."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim.dynamics import (
    GRAVITY_MSS,
    PHYSICS_DT_S,
    air_density,
    air_density_gradient,
    build_frame,
    command_to_pwm,
    frame_copy,
    hover_command,
    init_state,
    physics_step,
    pressure_temperature,
    pwm_to_command,
    resting_voltage,
    run_ticks,
    set_airborne,
    settle_wind,
    update_wind,
    yaw_of,
)
from tlm_sim.dynamics import frame as F
from tlm_sim.dynamics import layout as X
from tlm_sim.dynamics.wind import lowpass_alpha
from tlm_sim.params import Params
from tlm_sim.rng import new_rng

G = GRAVITY_MSS
DT = PHYSICS_DT_S
#: wind generator state for the physics calls (turbulence tests use their own)
RNG = new_rng(0, 2)


def new_state(frame: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    x = np.zeros(X.N_STATE)
    init_state(x, frame, yaw)
    return x


def airborne(frame: np.ndarray, height: float, command: float) -> np.ndarray:
    x = new_state(frame)
    set_airborne(x, frame, height, command)
    return x


def pwm_all(value: float) -> np.ndarray:
    return np.full(4, float(value))


def hover_pwm(frame: np.ndarray) -> np.ndarray:
    return pwm_all(command_to_pwm(hover_command(frame), frame))


def quat_to_dcm(x: np.ndarray) -> np.ndarray:
    w, i, j, k = x[X.QW], x[X.QX], x[X.QY], x[X.QZ]
    return np.array(
        [
            [1 - 2 * (j * j + k * k), 2 * (i * j - w * k), 2 * (i * k + w * j)],
            [2 * (i * j + w * k), 1 - 2 * (i * i + k * k), 2 * (j * k - w * i)],
            [2 * (i * k - w * j), 2 * (j * k + w * i), 1 - 2 * (i * i + j * j)],
        ]
    )


def euler(x: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw [rad] (ZYX) of the attitude in x."""
    r = quat_to_dcm(x)
    return (
        math.atan2(r[2, 1], r[2, 2]),
        -math.asin(max(-1.0, min(1.0, r[2, 0]))),
        math.atan2(r[1, 0], r[0, 0]),
    )


def set_euler(x: np.ndarray, roll: float, pitch: float, yaw: float) -> None:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    x[X.QW] = cr * cp * cy + sr * sp * sy
    x[X.QX] = sr * cp * cy - cr * sp * sy
    x[X.QY] = cr * sp * cy + sr * cp * sy
    x[X.QZ] = cr * cp * sy - sr * sp * cy


@pytest.fixture(scope="module")
def frame() -> np.ndarray:
    return build_frame(Params())


# --------------------------------------------------------------------------- atmosphere
def test_atmosphere_matches_1976_standard() -> None:
    p0, t0 = pressure_temperature(0.0)
    assert p0 == pytest.approx(101325.0)
    assert t0 == pytest.approx(288.15)
    assert air_density(0.0) == pytest.approx(1.225)
    assert air_density(593.0) == pytest.approx(1.1568, abs=5e-5)
    assert air_density(584.0) == pytest.approx(1.1578, abs=5e-5)
    p, t = pressure_temperature(1000.0)
    assert p == pytest.approx(89876.0, rel=2e-4)  # 1976 table, 1 km geometric
    assert t == pytest.approx(281.66, abs=0.02)
    h = 700.0
    fd = (air_density(h + 0.01) - air_density(h - 0.01)) / 0.02
    assert air_density_gradient(h) == pytest.approx(fd, rel=1e-6)


# --------------------------------------------------------------------------- frame
def test_derived_constants_match_reference_table(frame: np.ndarray) -> None:
    """§1.3 'Numbers for the default frame'."""
    assert frame[F.F_RHO_REF] == pytest.approx(1.1568, abs=5e-5)
    assert frame[F.F_D_REF] == pytest.approx(29.42, abs=5e-3)
    assert frame[F.F_D_MOM] == pytest.approx(6.49, abs=5e-3)
    assert frame[F.F_AREA_CD] == pytest.approx(0.1743, abs=5e-5)
    assert frame[F.F_MDRAG_COEF] == 0.2  # not scaled down: D_mom < D_ref
    assert frame[F.F_HOVER_POWER] == pytest.approx(354.2, abs=0.05)
    assert frame[F.F_HOVER_VOUT] == pytest.approx(24.08, abs=5e-3)
    assert 4 * frame[F.F_AREA_EFF] == pytest.approx(0.08771, abs=5e-6)
    assert frame[F.F_AREA_EFF] == pytest.approx(0.02193, abs=5e-6)
    assert frame[F.F_AREA_TRUE] == pytest.approx(0.09625, abs=5e-6)
    assert frame[F.F_VEL_MAX] == pytest.approx(38.56, abs=5e-3)
    assert frame[F.F_IXX] == pytest.approx(0.02297, abs=5e-6)
    assert frame[F.F_IYY] == frame[F.F_IXX]
    assert frame[F.F_IZZ] == pytest.approx(0.04594, abs=5e-6)
    assert frame[F.F_ROT_DAMP] == pytest.approx(0.0582, abs=5e-5)
    assert frame[F.F_PWM_LO] == 1150.0
    assert frame[F.F_PWM_HI] == 1950.0
    k_m = frame[F.F_MDRAG_COEF] * math.sqrt(frame[F.F_RHO_REF] * frame[F.F_AREA_TRUE])
    assert k_m == pytest.approx(0.0667, abs=5e-5)
    t_max = 0.5 * frame[F.F_RHO_REF] * frame[F.F_AREA_EFF] * frame[F.F_VEL_MAX] ** 2
    assert t_max == pytest.approx(18.86, abs=5e-3)
    assert 4 * t_max / (frame[F.F_MASS] * G) == pytest.approx(2.56, abs=5e-3)
    # hover command solves (1-e)a + e a^2 = 0.39 (the table's 0.5505 is a rounding slip:
    # it gives 0.3897); hover PWM ~1590 us
    a_h = hover_command(frame)
    assert 0.35 * a_h + 0.65 * a_h * a_h == pytest.approx(0.39, abs=1e-12)
    assert a_h == pytest.approx(0.5508, abs=1e-4)
    assert command_to_pwm(a_h, frame) == pytest.approx(1590.0, abs=1.0)
    # per-motor hover current at 12.6 V: 7.0 A
    i_motor = frame[F.F_POWER_FACTOR] * frame[F.F_MASS] * G / 4 / 12.6
    assert i_motor == pytest.approx(7.0, abs=0.05)


def test_motor_table_and_parameters() -> None:
    f = build_frame(Params({"TLM_DIAG": 0.5, "TLM_IXX": 0.1, "TLM_IYY": 0.2, "TLM_IZZ": 0.3}))
    assert list(f[F.F_MOT_X : F.F_MOT_X + 4]) == [0.0, 0.0, 0.5, -0.5]
    assert list(f[F.F_MOT_Y : F.F_MOT_Y + 4]) == [0.5, -0.5, 0.0, 0.0]
    assert list(f[F.F_MOT_YAW : F.F_MOT_YAW + 4]) == [1.0, 1.0, -1.0, -1.0]
    assert (f[F.F_IXX], f[F.F_IYY], f[F.F_IZZ]) == (0.1, 0.2, 0.3)
    assert build_frame(Params({"SIM_BATT_CAP_AH": 2.0}))[F.F_BATT_CAP_AH] == 2.0
    assert build_frame(Params({"TLM_BATT_CAP_AH": 3.0}))[F.F_BATT_CAP_AH] == 3.0
    # a huge momentum-drag coefficient is scaled down to the reference drag, areaCd -> 0
    g = build_frame(Params({"TLM_MDRAG_COEF": 2.0}))
    assert g[F.F_AREA_CD] == 0.0
    assert g[F.F_MDRAG_COEF] == pytest.approx(2.0 * g[F.F_D_REF] / g[F.F_D_MOM])


def test_pwm_command_mapping(frame: np.ndarray) -> None:
    assert pwm_to_command(1000.0, frame) == 0.0
    assert pwm_to_command(1150.0, frame) == 0.0
    assert pwm_to_command(1550.0, frame) == pytest.approx(0.5)
    assert pwm_to_command(1950.0, frame) == 1.0
    assert pwm_to_command(2100.0, frame) == 1.0
    for a in (0.0, 0.3, 0.5508, 1.0):
        assert pwm_to_command(command_to_pwm(a, frame), frame) == pytest.approx(a)


def test_slew_limit(frame: np.ndarray) -> None:
    x = airborne(frame, 50.0, 0.0)
    pwm = pwm_all(2000.0)
    step = frame[F.F_SLEW_MAX] * DT  # 0.125 per tick: full range in 8 ticks (6.7 ms)
    for k in range(1, 9):
        physics_step(x, pwm, frame, DT, 0.0, RNG)
        assert x[X.M1] == pytest.approx(min(1.0, k * step), abs=1e-12)
    physics_step(x, pwm, frame, DT, 0.0, RNG)
    assert x[X.M1] == 1.0
    physics_step(x, pwm_all(1000.0), frame, DT, 0.0, RNG)
    assert x[X.M1] == pytest.approx(1.0 - step)


# --------------------------------------------------------------------------- equilibrium
def test_hover_equilibrium(frame: np.ndarray) -> None:
    x = airborne(frame, 10.0, hover_command(frame))
    p0 = x[X.PN : X.PD + 1].copy()
    pwm = hover_pwm(frame)
    t = 0.0
    for _ in range(1200):
        t = run_ticks(x, pwm, frame, DT, t, 1, RNG)
        assert math.sqrt(x[X.AN] ** 2 + x[X.AE] ** 2 + x[X.AD] ** 2) < 0.05
    assert np.linalg.norm(x[X.PN : X.PD + 1] - p0) < 0.01
    # the accelerometer reads -g on z, nothing else; no rotation
    assert x[X.FZ] == pytest.approx(-G, abs=0.05)
    assert abs(x[X.FX]) < 1e-9 and abs(x[X.FY]) < 1e-9
    assert np.all(np.abs(x[X.WX : X.WZ + 1]) < 1e-12)  # rounding of the momentum-drag torque
    assert x[X.ON_GROUND] == 0.0
    # at the reference density the hover command gives exactly the weight
    for i in range(4):
        assert x[X.T1 + i] == pytest.approx(frame[F.F_MASS] * G / 4, rel=2e-3)


def test_hover_at_reference_density_is_exact(frame: np.ndarray) -> None:
    height = frame[F.F_REF_ALT] - frame[F.F_HOME_ALT] - frame[F.F_FRAME_HEIGHT]
    x = airborne(frame, height, hover_command(frame))
    run_ticks(x, hover_pwm(frame), frame, DT, 0.0, 10, RNG)
    assert abs(x[X.AD]) < 1e-9


# --------------------------------------------------------------------------- free fall
def test_free_fall_without_drag_matches_half_g_t2(frame: np.ndarray) -> None:
    f = frame_copy(frame, F_AREA_CD=0.0)
    x = airborne(f, 100.0, 0.0)
    z0 = x[X.PD]
    n = 1800  # 1.5 s
    run_ticks(x, pwm_all(1000.0), f, DT, 0.0, n, RNG)
    t = n * DT
    drop = x[X.PD] - z0
    assert drop == pytest.approx(0.5 * G * t * t, rel=0.01)
    assert x[X.VD] == pytest.approx(G * t, rel=1e-9)
    # weightless: an accelerometer in free fall reads zero
    assert np.allclose(x[X.FX : X.FZ + 1], 0.0, atol=1e-9)
    assert x[X.AD] == pytest.approx(G)


def test_free_fall_with_drag_matches_quadratic_drag_solution(frame: np.ndarray) -> None:
    x = airborne(frame, 100.0, 0.0)
    z0 = x[X.PD]
    n = 3000  # 2.5 s, about 28 m: drag is a third of the weight at the end
    run_ticks(x, pwm_all(1000.0), frame, DT, 0.0, n, RNG)
    t = n * DT
    rho = air_density(frame[F.F_HOME_ALT] - 0.5 * (z0 + x[X.PD]))
    k = frame[F.F_AREA_CD] * 0.5 * rho / frame[F.F_MASS]
    drop = math.log(math.cosh(math.sqrt(G * k) * t)) / k
    assert x[X.PD] - z0 == pytest.approx(drop, rel=0.01)
    assert x[X.PD] - z0 < 0.97 * 0.5 * G * t * t  # drag is really acting
    assert x[X.VD] == pytest.approx(math.sqrt(G / k) * math.tanh(math.sqrt(G * k) * t), rel=0.01)


# --------------------------------------------------------------------------- rotation
@settings(max_examples=12, deadline=None)
@given(
    st.tuples(
        st.floats(-8.0, 8.0, allow_nan=False),
        st.floats(-8.0, 8.0, allow_nan=False),
        st.floats(-8.0, 8.0, allow_nan=False),
    )
)
def test_torque_free_spin_conserves_angular_momentum(rates: tuple[float, float, float]) -> None:
    # no rotor thrust (so no inflow torques) and no rotational damping: torque-free body
    f = frame_copy(build_frame(Params()), F_ROT_DAMP=0.0, F_AREA_EFF=0.0, F_GYRO=1.0)
    x = airborne(f, 5000.0, 0.0)
    x[X.WX], x[X.WY], x[X.WZ] = rates
    inertia = np.array([f[F.F_IXX], f[F.F_IYY], f[F.F_IZZ]])

    def momentum_earth() -> np.ndarray:
        return quat_to_dcm(x) @ (inertia * x[X.WX : X.WZ + 1])

    l0 = momentum_earth()
    run_ticks(x, pwm_all(1000.0), f, DT, 0.0, 100_000, RNG)
    assert x[X.ON_GROUND] == 0.0
    q = x[X.QW : X.QZ + 1]
    assert abs(np.dot(q, q) - 1.0) < 1e-12
    l1 = momentum_earth()
    assert np.linalg.norm(l1 - l0) <= 1e-9 * max(np.linalg.norm(l0), 1e-3)


def test_spin_without_gyroscopic_term_keeps_body_rates(frame: np.ndarray) -> None:
    """SITL-exact mode (F_GYRO = 0): no w x Iw term, constant body rates when torque-free."""
    f = frame_copy(frame, F_ROT_DAMP=0.0, F_AREA_EFF=0.0, F_GYRO=0.0)
    x = airborne(f, 5000.0, 0.0)
    x[X.WX], x[X.WY], x[X.WZ] = 1.0, -2.0, 3.0
    run_ticks(x, pwm_all(1000.0), f, DT, 0.0, 5000, RNG)
    assert list(x[X.WX : X.WZ + 1]) == [1.0, -2.0, 3.0]


def test_rotational_damping(frame: np.ndarray) -> None:
    f = frame_copy(frame, F_AREA_EFF=0.0)
    x = airborne(f, 5000.0, 0.0)
    x[X.WZ] = 2.0
    n = 12000  # 10 s
    run_ticks(x, pwm_all(1000.0), f, DT, 0.0, n, RNG)
    assert x[X.WZ] == pytest.approx(2.0 * math.exp(-f[F.F_ROT_DAMP] * n * DT), rel=1e-3)


def test_constant_rate_rotates_attitude(frame: np.ndarray) -> None:
    f = frame_copy(frame, F_ROT_DAMP=0.0, F_AREA_EFF=0.0)
    x = airborne(f, 5000.0, 0.0)
    x[X.WZ] = 1.0
    n = 1200
    run_ticks(x, pwm_all(1000.0), f, DT, 0.0, n, RNG)
    assert yaw_of(x) == pytest.approx(n * DT, abs=1e-9)


def test_differential_thrust_rolls_and_pitches_the_right_way(frame: np.ndarray) -> None:
    a_h = hover_command(frame)
    base = command_to_pwm(a_h, frame)
    # motor 1 (right arm) faster -> right side lifts -> roll left (negative)
    x = airborne(frame, 20.0, a_h)
    pwm = pwm_all(base)
    pwm[0] += 40.0
    run_ticks(x, pwm, frame, DT, 0.0, 120, RNG)
    assert x[X.WX] < -0.5
    assert euler(x)[0] < 0.0
    assert abs(x[X.WY]) < 0.01 * abs(x[X.WX])  # only gyroscopic coupling with the yaw rate
    # motor 3 (front) faster -> nose up (positive pitch)
    x = airborne(frame, 20.0, a_h)
    pwm = pwm_all(base)
    pwm[2] += 40.0
    run_ticks(x, pwm, frame, DT, 0.0, 120, RNG)
    assert x[X.WY] > 0.5
    assert euler(x)[1] > 0.0
    assert abs(x[X.WX]) < 0.01 * abs(x[X.WY])


@pytest.mark.parametrize("profile", [0.0, 1.0])
def test_yaw_torque_sign(frame: np.ndarray, profile: float) -> None:
    """CCW motors 1 and 2 faster, CW motors 3 and 4 slower -> nose right (§1.6)."""
    f = frame_copy(frame, F_PROFILE=profile)
    a_h = hover_command(f)
    x = airborne(f, 20.0, a_h)
    pwm = pwm_all(command_to_pwm(a_h, f))
    pwm[:2] += 30.0
    pwm[2:] -= 30.0
    run_ticks(x, pwm, f, DT, 0.0, 240, RNG)
    assert x[X.WZ] > 0.05
    assert euler(x)[2] > 0.0
    assert abs(x[X.WX]) < 1e-9 and abs(x[X.WY]) < 1e-9


def test_paper_era_yaw_torque_is_stronger(frame: np.ndarray) -> None:
    """Paper era: tau = k a radians(40) s; now: tau = k a 0.05 d T(a) (§1.6).

    At hover one motor gives 0.38 N m then against 0.071 N m now (5.4x); for a differential
    command the ratio of the slopes is radians(40) / (0.05 d (T_h + a_h dT/da)) = 2.2.
    """
    rates = []
    for profile in (0.0, 1.0):
        f = frame_copy(frame, F_PROFILE=profile)
        a_h = hover_command(f)
        x = airborne(f, 20.0, a_h)
        pwm = pwm_all(command_to_pwm(a_h, f))
        pwm[:2] += 8.0
        pwm[2:] -= 8.0
        run_ticks(x, pwm, f, DT, 0.0, 12, RNG)
        rates.append(x[X.WZ])
    a_h = hover_command(frame)
    e = frame[F.F_EXPO]
    t_h = frame[F.F_MASS] * G / 4
    dt_da = t_h * ((1 - e) + 2 * e * a_h) / frame[F.F_HOVER_THR]
    slope_now = 0.05 * frame[F.F_DIAG] * (t_h + a_h * dt_da)
    assert rates[1] / rates[0] == pytest.approx(math.radians(40.0) / slope_now, rel=0.05)
    assert math.radians(40.0) * a_h / (0.05 * frame[F.F_DIAG] * a_h * t_h) > 5.0


# --------------------------------------------------------------------------- aerodynamics
def test_climb_inflow_and_momentum_drag_reduce_thrust(frame: np.ndarray) -> None:
    a_h = hover_command(frame)
    x = airborne(frame, 20.0, a_h)
    x[X.VD] = -5.0  # climbing at 5 m/s: air flows into the discs
    physics_step(x, hover_pwm(frame), frame, DT, 0.0, RNG)
    x0 = airborne(frame, 20.0, a_h)
    physics_step(x0, hover_pwm(frame), frame, DT, 0.0, RNG)
    assert x[X.T1] < x0[X.T1]
    assert x[X.AD] > 0.5  # decelerating the climb
    # forward flight: body drag plus momentum drag oppose the airspeed
    x = airborne(frame, 20.0, a_h)
    x[X.VN] = 10.0
    physics_step(x, hover_pwm(frame), frame, DT, 0.0, RNG)
    body_drag = frame[F.F_AREA_CD] * 0.5 * x[X.RHO] * 100.0
    assert body_drag == pytest.approx(10.0, rel=0.05)  # "~10 N at 10 m/s"
    assert -x[X.FX] * frame[F.F_MASS] > body_drag


# --------------------------------------------------------------------------- ground
def test_rest_on_pad(frame: np.ndarray) -> None:
    x = new_state(frame, math.radians(353.0))
    assert x[X.PD] == -frame[F.F_FRAME_HEIGHT]
    run_ticks(x, pwm_all(1000.0), frame, DT, 0.0, 2400, RNG)
    assert x[X.PD] == -frame[F.F_FRAME_HEIGHT]
    assert x[X.ON_GROUND] == 1.0
    assert x[X.IMPACT_COUNT] == 0.0
    assert np.allclose(x[X.FX : X.FZ + 1], [0.0, 0.0, -G], atol=1e-12)
    assert x[X.AD] == 0.0
    assert yaw_of(x) == pytest.approx(math.radians(353.0) - 2 * math.pi)


def test_ground_impact_is_recorded_and_vehicle_does_not_sink(frame: np.ndarray) -> None:
    h = 20.0
    x = airborne(frame, h, 0.0)
    t = 0.0
    while x[X.ON_GROUND] == 0.0:
        t = run_ticks(x, pwm_all(1000.0), frame, DT, t, 1, RNG)
        assert t < 10.0
    rho = air_density(frame[F.F_HOME_ALT] + 0.5 * h)
    v_term = math.sqrt(frame[F.F_MASS] * G / (0.5 * rho * frame[F.F_AREA_CD]))
    v_hit = v_term * math.sqrt(1.0 - math.exp(-2.0 * G * h / v_term**2))
    assert x[X.IMPACT_SPEED] == pytest.approx(v_hit, rel=0.02)
    assert x[X.IMPACT_COUNT] == 1.0
    assert x[X.PD] == -frame[F.F_FRAME_HEIGHT]
    assert x[X.VD] == 0.0
    run_ticks(x, pwm_all(1000.0), frame, DT, t, 1200, RNG)
    assert x[X.PD] == -frame[F.F_FRAME_HEIGHT]
    assert x[X.IMPACT_COUNT] == 1.0
    assert x[X.FZ] == pytest.approx(-G)


def test_touchdown_levels_attitude_keeping_yaw(frame: np.ndarray) -> None:
    x = airborne(frame, 0.05, 0.0)
    set_euler(x, math.radians(20.0), math.radians(-10.0), math.radians(30.0))
    x[X.VD] = 1.0
    x[X.WX] = 1.0
    run_ticks(x, pwm_all(1000.0), frame, DT, 0.0, 120, RNG)
    assert x[X.ON_GROUND] == 1.0
    roll, pitch, yaw = euler(x)
    assert abs(roll) < 1e-12 and abs(pitch) < 1e-12
    assert yaw == pytest.approx(math.radians(30.0), abs=2e-3)
    assert np.all(x[X.WX : X.WZ + 1] == 0.0)
    assert x[X.VN] == 0.0 and x[X.VE] == 0.0


def test_lift_off_when_thrust_exceeds_weight(frame: np.ndarray) -> None:
    x = new_state(frame)
    t = run_ticks(x, hover_pwm(frame), frame, DT, 0.0, 1200, RNG)
    assert x[X.ON_GROUND] == 1.0  # hover thrust only balances the weight
    run_ticks(x, pwm_all(1800.0), frame, DT, t, 2400, RNG)
    assert x[X.ON_GROUND] == 0.0
    assert -x[X.PD] - frame[F.F_FRAME_HEIGHT] > 1.0
    assert x[X.VD] < -1.0


# --------------------------------------------------------------------------- battery
def test_infinite_battery_holds_voltage_and_counts_charge(frame: np.ndarray) -> None:
    height = frame[F.F_REF_ALT] - frame[F.F_HOME_ALT] - frame[F.F_FRAME_HEIGHT]
    x = airborne(frame, height, hover_command(frame))
    n = 2400
    run_ticks(x, hover_pwm(frame), frame, DT, 0.0, n, RNG)
    assert x[X.BATT_V] == 12.6
    assert x[X.BATT_I] == pytest.approx(28.1, abs=0.05)  # §1.3: 28.1 A at hover
    assert x[X.BATT_AH] == pytest.approx(x[X.BATT_I] * n * DT / 3600.0, rel=1e-3)


def test_finite_battery_sags_under_load(frame: np.ndarray) -> None:
    f = build_frame(Params({"SIM_BATT_CAP_AH": 1.0}))
    x = airborne(f, 100.0, hover_command(f))
    assert x[X.BATT_V] == 12.6
    assert x[X.BATT_REM_AH] == pytest.approx(1.0)
    pwm = hover_pwm(f)
    run_ticks(x, pwm, f, DT, 0.0, 240, RNG)  # 0.2 s: filter settled on the I R drop
    v_early = x[X.BATT_V]
    assert v_early == pytest.approx(12.6 - x[X.BATT_I] * 0.01, abs=0.02)
    used = x[X.BATT_AH]
    t = 0.2
    for _ in range(100):  # 10 s more of open-loop hover command
        i0 = x[X.BATT_I]
        t = run_ticks(x, pwm, f, DT, t, 120, RNG)
        used += 0.5 * (i0 + x[X.BATT_I]) * 120 * DT / 3600.0
    assert x[X.BATT_AH] == pytest.approx(used, rel=1e-3)
    assert x[X.BATT_REM_AH] == pytest.approx(1.0 - x[X.BATT_AH], rel=1e-9)
    v_rest = resting_voltage(100.0 * x[X.BATT_REM_AH], 12.6)
    assert x[X.BATT_VREST] == pytest.approx(v_rest)
    assert v_rest < 12.6 - 0.05
    assert x[X.BATT_V] == pytest.approx(v_rest - x[X.BATT_I] * 0.01, abs=0.01)
    assert x[X.BATT_V] < v_early - 0.05
    # thrust per command scales with (V / V_max)^2: the open-loop vehicle now sinks
    scale = (x[X.BATT_V] / 12.6) ** 2 * x[X.RHO] / f[F.F_RHO_REF]
    assert x[X.T1] == pytest.approx(f[F.F_MASS] * G / 4 * scale, rel=2e-3)
    assert x[X.VD] > 0.5


def test_battery_voltage_parameter_change_and_dead_battery(frame: np.ndarray) -> None:
    f = frame.copy()
    x = airborne(f, 50.0, hover_command(f))
    f[F.F_BATT_VOLT] = 11.0  # SIM_BATT_VOLTAGE changed in flight: re-initialised
    physics_step(x, hover_pwm(f), f, DT, 0.0, RNG)
    assert x[X.BATT_V] == 11.0
    run_ticks(x, hover_pwm(f), f, DT, 0.0, 10, RNG)
    assert x[X.AD] > 0.2 * G  # thrust scales with (11/12.6)^2
    f[F.F_BATT_VOLT] = 1.0  # below 10 % of max voltage: motors stop
    run_ticks(x, hover_pwm(f), f, DT, 0.0, 2, RNG)
    assert np.all(x[X.T1 : X.T1 + 4] == 0.0)
    assert x[X.BATT_I] == 0.0


# --------------------------------------------------------------------------- wind
#: SITL's slew-filter time constant at the default SIM_WIND_TC = 5 s: cut-off 1/TC Hz [s]
WIND_RC_TC5 = 5.0 / (2.0 * math.pi)


def wind_state(f: np.ndarray, height: float, settled: bool = True) -> np.ndarray:
    """A vehicle ``height`` [m] above ground, its wind filters settled at the parameters (or,
    ``settled=False``, as at boot: 0 m/s, 0 deg)."""
    x = airborne(f, height, 0.0)
    if settled:
        settle_wind(x, f)
    return x


@pytest.mark.parametrize(
    ("kind", "height", "expected"),
    [
        (0.0, 15.0, 5.0),  # square-root law: 10 * sqrt(15 / 60)
        (0.0, 60.0, 10.0),
        (0.0, 150.0, 10.0),
        (0.0, 0.0, 0.0),
        (1.0, 15.0, 10.0),  # no profile
        (2.0, 160.0, 11.0),  # linear: 10 + (160 - 60) * 0.01
        (2.0, 30.0, 9.7),  # the linear law reduces the wind below T_ALT
        (2.0, -1000.0, 0.0),  # ... and never below 0
    ],
)
def test_wind_height_profile(kind: float, height: float, expected: float) -> None:
    f = build_frame(Params({"SIM_WIND_SPD": 10.0, "SIM_WIND_T": kind}))
    x = wind_state(f, height)
    update_wind(x, f, 10.0, RNG)
    # from the south (180 deg): the air moves north
    assert x[X.WIND_N] == pytest.approx(expected, abs=1e-9)
    assert abs(x[X.WIND_E]) < 1e-9 and x[X.WIND_D] == 0.0


def test_wind_profile_height_is_height_above_ground() -> None:
    """SITL's height_agl: 0 on the pad (PD = -frame height), so the square-root law gives no
    mean wind on the ground; 15 m above the pad a quarter of T_ALT."""
    f = build_frame(Params({"SIM_WIND_SPD": 10.0}))
    x = new_state(f)
    settle_wind(x, f)
    update_wind(x, f, 10.0, RNG)
    assert (x[X.WIND_N], x[X.WIND_E], x[X.WIND_D]) == (0.0, 0.0, 0.0)
    x[X.PD] = -f[F.F_FRAME_HEIGHT] - 15.0
    update_wind(x, f, 10.0 + 2 * DT, RNG)
    assert x[X.WIND_N] == pytest.approx(5.0)


def test_mean_wind_starts_5_s_after_boot() -> None:
    f = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_DIR": 90.0, "SIM_WIND_T": 1.0}))
    x = wind_state(f, 100.0)
    update_wind(x, f, 4.9, RNG)  # no mean wind during the first 5 s, filters frozen
    assert (x[X.WIND_N], x[X.WIND_E], x[X.WIND_D]) == (0.0, 0.0, 0.0)
    assert x[X.WIND_SLEW_T] == 0.0
    update_wind(x, f, 5.0, RNG)
    assert (x[X.WIND_N], x[X.WIND_E], x[X.WIND_D]) == (0.0, 0.0, 0.0)
    update_wind(x, f, 5.0 + DT, RNG)  # from the east: the air moves west
    assert x[X.WIND_E] == pytest.approx(-8.0)
    assert abs(x[X.WIND_N]) < 1e-9
    # vertical direction 90 deg: a pure updraft (NED down negative)
    g = build_frame(Params({"SIM_WIND_SPD": 3.0, "SIM_WIND_DIR_Z": 90.0, "SIM_WIND_T": 1.0}))
    x = wind_state(g, 100.0)
    update_wind(x, g, 10.0, RNG)
    assert x[X.WIND_D] == pytest.approx(-3.0)
    assert abs(x[X.WIND_N]) < 1e-9 and abs(x[X.WIND_E]) < 1e-9


def test_lowpass_alpha_is_ardupilots() -> None:
    assert lowpass_alpha(0.01, 1.0) == pytest.approx(0.01 / (0.01 + 1.0 / (2.0 * math.pi)))
    assert lowpass_alpha(0.01, 0.0) == 1.0  # no cut-off: no filtering
    assert lowpass_alpha(0.0, 1.0) == 0.0


def slew_run(f: np.ndarray, duration_s: float, t0: float = 6.0) -> tuple[np.ndarray, float]:
    """Physics steps of the wind from ``t0`` for ``duration_s``, filters starting at zero with
    their last update at ``t0`` (no start-up jump); returns the state and the end time."""
    x = wind_state(f, 100.0, settled=False)
    x[X.WIND_SLEW_T] = t0
    t = t0
    for _ in range(round(duration_s / DT)):
        t += DT
        update_wind(x, f, t, RNG)
    return x, t


@pytest.mark.parametrize("tc", [5.0, 20.0])
def test_wind_slew_time_constant_is_tc_over_2pi(tc: float) -> None:
    """SITL's slew filter has cut-off 1/TC Hz: after TC/(2 pi) (0.80 s at TC = 5 s) the speed
    has covered 1 - 1/e of a step, not after TC."""
    f = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_DIR": 90.0, "SIM_WIND_T": 1.0,
                            "SIM_WIND_TC": tc}))
    rc = tc / (2.0 * math.pi)
    x, _ = slew_run(f, rc)
    assert x[X.WIND_SPD_F] == pytest.approx(8.0 * (1.0 - math.exp(-1.0)), rel=0.005)
    x, _ = slew_run(f, 5.0 * rc)
    assert x[X.WIND_SPD_F] == pytest.approx(8.0 * (1.0 - math.exp(-5.0)), rel=0.001)


def test_wind_slew_advances_every_second_physics_step() -> None:
    """The filters advance only when more than 1 ms has passed since their last update: every
    second 833 us step, by the filter gain of 1666 us."""
    f = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_T": 1.0}))
    x = wind_state(f, 100.0, settled=False)
    t0 = 6.0
    x[X.WIND_SLEW_T] = t0
    a = lowpass_alpha(2 * DT, 1.0 / 5.0)
    expected = 0.0
    for k in range(1, 11):
        update_wind(x, f, t0 + k * DT, RNG)
        if k % 2 == 0:
            expected += (8.0 - expected) * a
            assert x[X.WIND_SLEW_T] == t0 + k * DT
        assert x[X.WIND_SPD_F] == pytest.approx(expected, rel=1e-9, abs=0.0), k


@pytest.mark.parametrize("tc", [0.0, 0.05, 0.1])
def test_wind_tc_is_floored_at_0_1_s(tc: float) -> None:
    f = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_T": 1.0, "SIM_WIND_TC": tc}))
    x, _ = slew_run(f, 2 * DT)
    assert x[X.WIND_SPD_F] == pytest.approx(8.0 * lowpass_alpha(2 * DT, 10.0), rel=1e-9)


def test_wind_filters_start_at_zero_and_jump_after_the_delay() -> None:
    """At boot the filters are at 0 m/s and 0 deg with their last update at t = 0; the first
    update after the 5 s delay spans those 5 s (86 % of the way at TC = 5 s)."""
    f = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_DIR": 90.0, "SIM_WIND_T": 1.0}))
    x = new_state(f)
    assert (x[X.WIND_SPD_F], x[X.WIND_DIR_F], x[X.WIND_DIRZ_F], x[X.WIND_SLEW_T]) == (
        0.0, 0.0, 0.0, 0.0)
    set_airborne(x, f, 100.0, 0.0)
    t = 5.0 + DT
    update_wind(x, f, t, RNG)
    a = lowpass_alpha(t, 1.0 / 5.0)
    assert a == pytest.approx(0.8627, abs=1e-4)
    assert x[X.WIND_SPD_F] == pytest.approx(8.0 * a)
    assert x[X.WIND_DIR_F] == pytest.approx(90.0 * a)


def test_wind_direction_slews_from_0_on_the_wrapped_error() -> None:
    """SITL's direction filter starts at 0 deg: towards the default 180 deg (a wrapped error of
    +180, ArduPilot's wrap_180 keeps +180) it swings through east; it works on the error
    wrapped into (-180, 180] and keeps the result there."""
    f = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_T": 1.0}))
    x, t = slew_run(f, WIND_RC_TC5)
    d = x[X.WIND_DIR_F]
    assert d == pytest.approx(180.0 * (1.0 - math.exp(-1.0)), rel=0.005)
    # the air, coming from ~114 deg (ESE), moves towards the west-north-west
    assert x[X.WIND_N] == pytest.approx(-x[X.WIND_SPD_F] * math.cos(math.radians(d)))
    assert x[X.WIND_E] == pytest.approx(-x[X.WIND_SPD_F] * math.sin(math.radians(d)))
    assert x[X.WIND_E] < 0.0 < x[X.WIND_N]
    for _ in range(round(14.0 * WIND_RC_TC5 / DT)):
        t += DT
        update_wind(x, f, t, RNG)
        assert -180.0 < x[X.WIND_DIR_F] <= 180.0
    assert x[X.WIND_DIR_F] == pytest.approx(180.0, abs=1e-3)
    # from 170 deg towards -170 deg: the short way, through 180 into (-180, 180]
    g = build_frame(Params({"SIM_WIND_SPD": 8.0, "SIM_WIND_T": 1.0, "SIM_WIND_DIR": -170.0}))
    x = wind_state(g, 100.0, settled=False)
    x[X.WIND_DIR_F] = 170.0
    x[X.WIND_SLEW_T] = 6.0
    update_wind(x, g, 6.0 + 2 * DT, RNG)
    a = lowpass_alpha(2 * DT, 0.2)
    assert x[X.WIND_DIR_F] == pytest.approx(170.0 + 20.0 * a)
    x[X.WIND_DIR_F] = 179.0
    x[X.WIND_SLEW_T] = 6.0
    update_wind(x, g, 6.0 + 4.0, RNG)  # a 4 s step: alpha ~0.83
    a = lowpass_alpha(4.0, 0.2)
    assert x[X.WIND_DIR_F] == pytest.approx(179.0 + 11.0 * a - 360.0)


def test_wind_pushes_hovering_vehicle_downwind() -> None:
    f = build_frame(Params({"SIM_WIND_SPD": 10.0, "SIM_WIND_DIR": 180.0, "SIM_WIND_T": 1.0}))
    x = airborne(f, 100.0, hover_command(f))
    settle_wind(x, f)
    run_ticks(x, hover_pwm(f), f, DT, 10.0, 2400, RNG)
    assert x[X.VN] > 1.0 and x[X.PN] > 1.0  # drifting north, with the air
    assert x[X.VAIR_X] < 0.0  # the air comes from ahead (body x = north at yaw 0)


def run_turbulent(seed: int, n: int = 3000) -> np.ndarray:
    f = build_frame(Params({"SIM_WIND_SPD": 5.0, "SIM_WIND_TURB": 2.0}))
    x = airborne(f, 50.0, hover_command(f))
    rng = new_rng(seed, 2)
    out = np.empty((n, X.N_STATE))
    pwm = hover_pwm(f)
    t = 5.0
    for k in range(n):
        t = run_ticks(x, pwm, f, DT, t, 1, rng)
        out[k] = x
    return out


def test_turbulence_is_deterministic_with_a_seed() -> None:
    a = run_turbulent(7)
    b = run_turbulent(7)
    c = run_turbulent(8)
    assert np.array_equal(a, b)
    assert not np.array_equal(a[:, X.WIND_N], c[:, X.WIND_N])
    assert np.std(a[:, X.WIND_D]) > 0.5


def test_turbulence_statistics_are_sitls() -> None:
    """SITL's gusts: g <- 0.98 g + 0.02 (10 TURB) N(0,1) every 1200 Hz step, i.e. a stationary
    std of 0.2 TURB / sqrt(1 - 0.98^2) = 1.005 TURB and a correlation time of -1/ln 0.98 = 49.5
    steps = 41 ms; the horizontal gust's azimuth is drawn afresh every step (its N and E
    components are uncorrelated from one step to the next). No mean wind (SIM_WIND_SPD 0)."""
    turb = 2.0
    f = build_frame(Params({"SIM_WIND_TURB": turb}))
    x = wind_state(f, 30.0)
    rng = new_rng(3, 2)
    n_warm, n = 1000, 240_000
    gh = np.empty(n)
    gv = np.empty(n)
    wn = np.empty(n)
    wd = np.empty(n)
    t = 10.0
    for k in range(n_warm + n):
        t += DT
        update_wind(x, f, t, rng)
        if k >= n_warm:
            i = k - n_warm
            gh[i], gv[i], wn[i], wd[i] = x[X.GUST_H], x[X.GUST_V], x[X.WIND_N], x[X.WIND_D]
    std_expected = 0.2 * turb / math.sqrt(1.0 - 0.98**2)
    assert std_expected == pytest.approx(1.005 * turb, rel=1e-3)
    for g in (gh, gv):
        assert np.std(g) == pytest.approx(std_expected, rel=0.05)
        phi = np.corrcoef(g[:-1], g[1:])[0, 1]
        tau_ms = -DT / math.log(phi) * 1e3
        assert tau_ms == pytest.approx(41.2, rel=0.1)
    np.testing.assert_array_equal(wd, -gv)  # the vertical gust is the whole vertical wind
    # per-step random azimuth: the north component has the gust's power spread over N and E
    # (std / sqrt 2) and forgets itself from one step to the next
    assert np.std(wn) == pytest.approx(std_expected / math.sqrt(2.0), rel=0.05)
    assert abs(np.corrcoef(wn[:-1], wn[1:])[0, 1]) < 0.02


def test_correlated_gusts_have_their_std_and_correlation_time() -> None:
    """TLM_TURB_TC (issue 40): north, east and down gusts each a first-order Gauss-Markov
    process of standard deviation SIM_WIND_TURB and correlation time TLM_TURB_TC, independent
    of each other; 0 keeps SITL's gusts (the test above)."""
    turb, tc = 1.5, 0.5
    f = build_frame(Params({"SIM_WIND_TURB": turb, "TLM_TURB_TC": tc}))
    x = wind_state(f, 30.0)
    rng = new_rng(5, 2)
    stride = 12  # 100 Hz of the 1200 Hz steps
    n = 120_000
    g = np.empty((n // stride, 3))
    t = 10.0
    for k in range(n):
        t += DT
        update_wind(x, f, t, rng)
        if k % stride == 0:
            g[k // stride] = (-x[X.WIND_N], -x[X.WIND_E], -x[X.WIND_D])
    lag = round(tc / (stride * DT))  # one time constant, in kept samples
    for j in range(3):
        assert np.std(g[:, j]) == pytest.approx(turb, rel=0.15)
        phi = np.corrcoef(g[:-lag, j], g[lag:, j])[0, 1]
        assert phi == pytest.approx(math.exp(-1.0), abs=0.1)
    assert abs(np.corrcoef(g[:, 0], g[:, 1])[0, 1]) < 0.15


def test_turbulence_before_the_start_delay_when_airborne() -> None:
    """The turbulence is not delayed (only the mean wind is): airborne at 1 s the gusts blow,
    on their own."""
    f = build_frame(Params({"SIM_WIND_SPD": 5.0, "SIM_WIND_TURB": 2.0, "SIM_WIND_T": 1.0}))
    x = wind_state(f, 10.0)
    rng = new_rng(4, 2)
    for k in range(1, 50):
        update_wind(x, f, k * DT, rng)
    assert x[X.GUST_H] != 0.0 and x[X.GUST_V] != 0.0
    assert x[X.WIND_D] == -x[X.GUST_V]
    assert math.hypot(x[X.WIND_N], x[X.WIND_E]) == pytest.approx(abs(x[X.GUST_H]))


@pytest.mark.parametrize(("hagl", "gusts"), [(0.0, False), (0.0009, False), (0.0011, True)])
def test_turbulence_only_when_airborne(hagl: float, gusts: bool) -> None:
    """Gusts (and their random draws) only above 1 mm over the ground (SITL's on_ground())."""
    f = build_frame(Params({"SIM_WIND_TURB": 3.0}))
    x = new_state(f)
    x[X.PD] = -f[F.F_FRAME_HEIGHT] - hagl
    rng = new_rng(1, 2)
    before = rng.copy()
    update_wind(x, f, 6.0, rng)
    assert (x[X.GUST_H] != 0.0) == gusts and (x[X.GUST_V] != 0.0) == gusts
    assert (x[X.WIND_D] != 0.0) == gusts
    assert (not np.array_equal(rng, before)) == gusts


def test_no_turbulence_on_the_ground() -> None:
    f = build_frame(Params({"SIM_WIND_TURB": 3.0}))
    x = new_state(f)
    rng = new_rng(1, 2)
    before = rng.copy()
    run_ticks(x, pwm_all(1000.0), f, DT, 0.0, 8000, rng)
    assert x[X.GUST_H] == 0.0 and x[X.GUST_V] == 0.0
    assert (x[X.WIND_N], x[X.WIND_E], x[X.WIND_D]) == (0.0, 0.0, 0.0)
    assert np.array_equal(rng, before)


def test_air_density_cache_tracks_altitude(frame: np.ndarray) -> None:
    x = airborne(frame, 0.5, 1.0)
    pwm = pwm_all(1950.0)
    t = 0.0
    for _ in range(40):
        t = run_ticks(x, pwm, frame, DT, t, 120, RNG)
        # RHO was set at the start of the last tick, before it moved by VD * DT
        exact = air_density(frame[F.F_HOME_ALT] - (x[X.PD] - x[X.VD] * DT))
        assert x[X.RHO] == pytest.approx(exact, rel=1e-7)
    assert -x[X.PD] > 30.0


# --------------------------------------------------------------------------- sensor smoothing
def test_sensors_see_the_truth_in_flight(frame: np.ndarray) -> None:
    """Away from the ground SITL's sensor smoothing has converged: the shadow the IMU, GPS and
    baro read is the truth."""
    x = airborne(frame, 30.0, hover_command(frame))
    pwm = hover_pwm(frame)
    pwm[0] += 40.0  # roll and climb a little
    run_ticks(x, pwm, frame, DT, 0.0, 1200, RNG)
    assert x[X.SMOOTH_ACTIVE] == 0.0
    for a, b in ((X.SPN, X.PN), (X.SVN, X.VN), (X.SFX, X.FX), (X.SWX, X.WX)):
        assert np.array_equal(x[a : a + 3], x[b : b + 3])
    assert np.array_equal(x[X.SQW : X.SQZ + 1], x[X.QW : X.QZ + 1])


def test_impact_shows_in_the_sensors_as_sitl_smooths_it(frame: np.ndarray) -> None:
    """At a ground impact the truth stops instantly (SITL's NO_MOVEMENT contact); the sensors'
    view follows with a 0.1 s time constant, so the accelerometer reads the deceleration
    (engine_s14.bin: -96 m/s^2 on z in the first 25 Hz IMU row after "SIM Hit ground at 12.7
    m/s"), overshoots (+10.7), is back near -9.3 after 1 s and settles at -g, while the truth
    reads -g at once."""
    x = airborne(frame, 8.0, 0.0)
    set_euler(x, math.radians(20.0), math.radians(-15.0), 0.0)
    t = 0.0
    while x[X.ON_GROUND] == 0.0:
        t = run_ticks(x, pwm_all(1000.0), frame, DT, t, 1, RNG)
    v_hit = x[X.IMPACT_SPEED]
    assert v_hit > 11.0
    fz, wx, sd = [], [], []
    for _ in range(2400):
        t = run_ticks(x, pwm_all(1000.0), frame, DT, t, 1, RNG)
        fz.append(x[X.SFZ])
        wx.append(x[X.SWX])
        sd.append(-x[X.SPD] - frame[F.F_FRAME_HEIGHT])
        assert x[X.FZ] == pytest.approx(-G)  # the truth: at rest on the ground
    fz = np.array(fz)
    # about v / tc of deceleration (limited per axis at 14 g), spread over the body axes
    assert fz.min() < -0.6 * v_hit / 0.1
    assert fz.min() >= -14.0 * G * math.sqrt(3.0) - G
    assert fz.max() > 0.0  # the underdamped overshoot
    assert fz[-1] == pytest.approx(-G, abs=0.05)
    # the gyro sees the levelling of the 20/15 deg attitude spread over ~0.1 s
    assert np.abs(wx).max() > math.radians(20.0) / 0.3
    # and the height the baro and GPS see dips below the ground before settling
    assert min(sd) < -0.3 and abs(sd[-1]) < 0.01


def test_rotor_momentum_drag_damps_the_body_rates(frame: np.ndarray) -> None:
    """The momentum drag acts at each motor, so SITL's torque sum r_i x F_i turns it into a
    rate damping: for a yaw rate w, each rotor moves sideways at w d and feels k_m sqrt(T) w d
    at the lever d. With hover thrust that is ~1.9 /s: normal_s11.bin's yaw response fits
    d(yaw rate)/dt = 2.0 deg/s^2 per us of differential PWM - 1.92 /s x yaw rate."""
    height = frame[F.F_REF_ALT] - frame[F.F_HOME_ALT] - frame[F.F_FRAME_HEIGHT]
    x = airborne(frame, height, hover_command(frame))
    x[X.WZ] = 1.0
    n = 600
    run_ticks(x, hover_pwm(frame), frame, DT, 0.0, n, RNG)
    thrust = frame[F.F_MASS] * G / 4.0
    k_m = frame[F.F_MDRAG_COEF] * math.sqrt(x[X.RHO] * frame[F.F_AREA_TRUE])
    damp = 4.0 * k_m * math.sqrt(thrust) * frame[F.F_DIAG] ** 2 / frame[F.F_IZZ]
    assert damp == pytest.approx(1.92, abs=0.05)
    assert x[X.WZ] == pytest.approx(math.exp(-(damp + frame[F.F_ROT_DAMP]) * n * DT), rel=0.02)


def test_wind_settled_step_skip_is_exact() -> None:
    """A settled slew-filter step is skipped (WIND_STILL_DT) only while it would change
    nothing: with the cache and with it cleared before every step, the filters, the air
    velocity and the cache's own trigger agree bit for bit, through settling, a target change
    in flight (SIM_WIND_DIR, then SIM_WIND_SPD) and a filter state written from outside."""
    f = build_frame(Params({"SIM_WIND_SPD": 0.0, "SIM_WIND_DIR": 180.0, "SIM_WIND_T": 1.0}))
    a = wind_state(f, 100.0, settled=False)
    b = a.copy()
    fa, fb = f.copy(), f.copy()
    skipped = 0
    slots = [X.WIND_SPD_F, X.WIND_DIR_F, X.WIND_DIRZ_F, X.WIND_N, X.WIND_E, X.WIND_D,
             X.WIND_SLEW_T]
    for k in range(1, 90000):  # 75 s of 833 us steps: settled after ~35 s
        t = k * DT
        if k == 60000:
            fa[F.F_WIND_DIR] = fb[F.F_WIND_DIR] = 90.0
        if k == 70000:
            fa[F.F_WIND_SPD] = fb[F.F_WIND_SPD] = 6.0
        if k == 80000:
            a[X.WIND_DIR_F] = b[X.WIND_DIR_F] = 170.0
        still = a[X.WIND_STILL_DT]
        update_wind(a, fa, t, RNG)
        skipped += still > 0.0 and a[X.WIND_STILL_DT] == still
        b[X.WIND_STILL_DT] = -1.0
        update_wind(b, fb, t, RNG)
        assert [a[s] for s in slots] == [b[s] for s in slots], k
    assert skipped > 10000  # the cache did act
