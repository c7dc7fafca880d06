"""Frames as data (tlm_sim.frames): the table against sitl-faults.md §6.3, the lookups and their
errors, the parameters that pick a frame, the physics and the mixer of every frame, and which
arm SIM_ENGINE_FAIL's bit 0 cuts on each."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim.control import layout as C
from tlm_sim.control.config import build_control_config
from tlm_sim.control.mixer import mix
from tlm_sim.dynamics import (
    GRAVITY_MSS,
    build_frame,
    command_to_pwm,
    hover_command,
    init_state,
    motor_forces,
    set_airborne,
)
from tlm_sim.dynamics import frame as F
from tlm_sim.dynamics import layout as X
from tlm_sim.flight import build_schedule
from tlm_sim.flightlog.binwriter import frame_string
from tlm_sim.frames import FRAMES, MAX_MOTORS, FrameError, frame_for, frame_for_model
from tlm_sim.params import ParamError, Params

FRAME_PARAMS = {name: {"FRAME_CLASS": f.frame_class, "FRAME_TYPE": f.frame_type}
                for name, f in FRAMES.items()}


# ----------------------------------------------------------------------------- the table
def test_quad_matrices_are_the_autopilots():
    """sitl-faults.md §6.3, AP_MotorsMatrix's QUAD PLUS and X tables (roll, pitch, yaw)."""
    plus = FRAMES["+"].mixer_factors()
    assert plus == ((-0.5, 0.5, 0.0, 0.0), (0.0, 0.0, 0.5, -0.5), (0.5, 0.5, -0.5, -0.5))
    x = FRAMES["x"].mixer_factors()
    assert x == ((-0.5, 0.5, 0.5, -0.5), (0.5, -0.5, 0.5, -0.5), (0.5, 0.5, -0.5, -0.5))
    assert [m.test_order for m in FRAMES["+"].motors] == [2, 4, 1, 3]
    assert [m.test_order for m in FRAMES["x"].motors] == [1, 3, 4, 2]
    assert (FRAMES["+"].label, FRAMES["x"].label) == ("QUAD/PLUS", "QUAD/X")


@pytest.mark.parametrize("name", list(FRAMES))
def test_every_frame_is_balanced_and_normalised(name):
    """Each axis's largest factor is 0.5; the factors sum to zero on every axis (a hover needs
    no roll, pitch or yaw demand), and so do the arm moments and the yaw factors."""
    f = FRAMES[name]
    assert 4 <= f.n_motors <= MAX_MOTORS
    assert sorted(m.test_order for m in f.motors) == list(range(1, f.n_motors + 1))
    for axis in f.mixer_factors():
        assert max(abs(v) for v in axis) == 0.5
        assert sum(axis) == pytest.approx(0.0, abs=1e-12)
    arms = np.array(f.arm_unit())
    assert np.allclose(np.hypot(arms[:, 0], arms[:, 1]), 1.0)
    assert np.allclose(arms.sum(axis=0), 0.0, atol=1e-12)
    assert sum(m.yaw_factor for m in f.motors) == 0


def test_lookups_by_parameters_and_by_sitl_model():
    assert frame_for(1, 0).name == "+" and frame_for(1.0, 1.0).name == "x"
    assert frame_for(2, 1).name == "hexax" and frame_for(3, 0).name == "octa"
    for model, name in (("+", "+"), ("quad", "+"), ("X", "x"), ("x", "x"), ("hexa", "hexa"),
                        ("hexax", "hexax"), ("HexaX", "hexax"), ("octa", "octa")):
        assert frame_for_model(model).name == name, model
    with pytest.raises(FrameError, match="FRAME_CLASS 3 with FRAME_TYPE 1 .* 1/0 \\(\\+\\)"):
        frame_for(3, 1)
    for bad in ("octa-quad", "heli", "y6", ""):
        with pytest.raises(FrameError, match="not a frame tlm simulates"):
            frame_for_model(bad)


def test_frame_parameters_pick_a_frame_and_cannot_change_in_flight():
    assert Params({"FRAME_TYPE": 1})["FRAME_TYPE"] == 1
    with pytest.raises(ParamError, match="FRAME_CLASS 3 with FRAME_TYPE 1"):
        Params({"FRAME_CLASS": 3, "FRAME_TYPE": 1})
    with pytest.raises(ParamError, match="FRAME_CLASS"):
        Params({"FRAME_CLASS": 4})
    with pytest.raises(ValueError, match="FRAME_TYPE cannot change in flight"):
        build_schedule(Params(), [(100.0, "FRAME_TYPE", 1.0)])
    build_schedule(Params({"FRAME_TYPE": 1}), [(100.0, "FRAME_TYPE", 1.0)])  # no change: fine
    assert frame_string({"FRAME_CLASS": 1.0, "FRAME_TYPE": 1.0}) == "Frame: QUAD/X"
    assert frame_string({"FRAME_CLASS": 2.0, "FRAME_TYPE": 0.0}) == "Frame: HEXA/PLUS"
    assert frame_string(None) == "Frame: QUAD/PLUS"


# ----------------------------------------------------------------------------- physics
def _forces(name: str, pwm: np.ndarray) -> tuple[float, ...]:
    frame = build_frame(Params(FRAME_PARAMS[name]))
    x = np.zeros(X.N_STATE)
    init_state(x, frame, 0.0)
    set_airborne(x, frame, 50.0, hover_command(frame))
    return motor_forces(x, pwm, frame, 0.0)  # dt 0: the commands jump to pwm (no slew)


def _hover_pwm(name: str) -> np.ndarray:
    frame = build_frame(Params(FRAME_PARAMS[name]))
    pwm = np.zeros(MAX_MOTORS)
    pwm[:FRAMES[name].n_motors] = command_to_pwm(hover_command(frame), frame)
    return pwm


@pytest.mark.parametrize("name", list(FRAMES))
def test_every_frame_hovers_at_the_hover_command(name):
    """All motors at the hover command carry the weight (at the reference air density; 50 m up
    the air is 0.4 % thinner) with no net torque, whatever the number of motors: each motor's
    area is the frame's over n, as SITL's Frame::init, so every frame lifts what the "+" quad
    lifts."""
    frame = build_frame(Params(FRAME_PARAMS[name]))
    assert frame[F.F_N_MOTORS] == FRAMES[name].n_motors
    fx, fy, fz, tx, ty, tz, _ = _forces(name, _hover_pwm(name))
    weight = frame[F.F_MASS] * GRAVITY_MSS
    assert -fz == pytest.approx(weight, rel=0.01)
    assert fz == pytest.approx(_forces("+", _hover_pwm("+"))[2], rel=1e-12)
    assert max(abs(fx), abs(fy), abs(tx), abs(ty), abs(tz)) < 1e-9


@pytest.mark.parametrize(("name", "roll", "pitch"), [
    ("+", 1, 0),  # motor 1: right arm -> the right side drops (roll right)
    ("x", 1, -1),  # motor 1: front-right arm -> roll right and nose down
    ("hexa", 0, -1),  # motor 1: front arm
    ("hexax", 1, 0),  # motor 1: right arm
    ("octa", 0, -1),  # motor 1: front arm
])
def test_engine_fail_bit_0_cuts_motor_1_on_its_arm(name, roll, pitch):
    """SIM_ENGINE_FAIL bit 0 is SERVO1, motor 1 of the frame (sitl-faults.md §6.3): cutting it
    from hover tips the copter towards that arm; the lost reaction torque yaws it against
    the motor's spin (motor 1 is CCW on the quads, CW on hexa and octa)."""
    pwm = _hover_pwm(name)
    pwm[0] = 1000.0
    _, _, _, tx, ty, tz, _ = _forces(name, pwm)
    assert np.sign(round(tx, 9)) == roll and np.sign(round(ty, 9)) == pitch
    assert np.sign(tz) == -FRAMES[name].motors[0].yaw_factor


# ----------------------------------------------------------------------------- mixer
def _mix(name: str, roll: float, pitch: float, yaw: float) -> np.ndarray:
    g = build_control_config(Params(FRAME_PARAMS[name]))
    c = np.zeros(C.N_CONTROL_STATE)
    mix(c, g, roll, pitch, yaw, 0.4, 12.8)
    return c[C.MIX_THRUST:C.MIX_THRUST + MAX_MOTORS].copy()


@given(st.sampled_from(list(FRAMES)), st.floats(-0.2, 0.2), st.floats(-0.2, 0.2),
       st.floats(-0.1, 0.1))
@settings(max_examples=60, deadline=None)
def test_mixer_moments_follow_the_demand_on_every_frame(name, roll, pitch, yaw):
    """Unsaturated, the mixer's thrust change per motor times its arm gives a body moment
    along the demand (roll right: the left motors push harder), and its spin-weighted sum
    follows the yaw demand; motors beyond the frame stay at 0."""
    f = FRAMES[name]
    n = f.n_motors
    d = _mix(name, roll, pitch, yaw) - _mix(name, 0.0, 0.0, 0.0)
    assert np.all(_mix(name, roll, pitch, yaw)[n:] == 0.0)
    arms = np.array(f.arm_unit())
    spin = np.array([m.yaw_factor for m in f.motors])
    moment_roll = -float(d[:n] @ arms[:, 1])  # thrust up at +y (right) rolls left
    moment_pitch = float(d[:n] @ arms[:, 0])  # thrust up at +x (front) pitches up
    moment_yaw = float(d[:n] @ spin)
    for moment, demand in ((moment_roll, roll), (moment_pitch, pitch), (moment_yaw, yaw)):
        if abs(demand) > 1e-3:
            assert math.copysign(1.0, moment) == math.copysign(1.0, demand)
        else:
            assert abs(moment) < 1e-2


# ----------------------------------------------------------------------------- the API
def test_fly_takes_a_frame_by_name():
    """``fly(frame="x")`` is ``fly(params={"FRAME_TYPE": 1})``; the frame is in the meta; a
    frame that params contradict, or an unknown one, is a ValueError before any flying."""
    from tlm_sim import fly

    by_name = fly(1, frame="x", seed=3)
    by_params = fly(1, params=Params({"FRAME_TYPE": 1}), seed=3)
    assert by_name.meta["frame"] == by_params.meta["frame"] == "x"
    assert by_name.tables["RCOU"].equals(by_params.tables["RCOU"])
    assert fly(1, seed=3).meta["frame"] == "+"
    assert fly(1, frame="x", params={"FRAME_TYPE": 1, "WPNAV_SPEED": 500}).meta["frame"] == "x"
    with pytest.raises(ValueError, match="params set FRAME_TYPE = 0"):
        fly(1, frame="x", params={"FRAME_TYPE": 0})
    with pytest.raises(ValueError, match="unknown frame 'y6'"):
        fly(1, frame="y6")
