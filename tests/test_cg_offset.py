"""An unbalanced airframe. A centre of gravity off the motors' centre (TLM_CG_X / _Y): the
motors balance the thrust's moment about it unequally, as a real airframe's do (issue 40's
follow-up: log171's rear motors run ~22 us above its front ones in its steady hover). Rotors
of unequal reaction torque (TLM_YAW_ASYM): the yaw controller trims them (log171's hover: RATE
YOut +0.06, its counter-clockwise motors ~50 us above its clockwise ones). ``tlm fit`` fits
both."""

from __future__ import annotations

import warnings

import pytest

from tlm_process.fit.fit import fly_hover_stats


def _asym(**params):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = fly_hover_stats({"FRAME_TYPE": 1, **params}, seed=3, hold_s=30)
    return s["mot_roll_us"], s["mot_pitch_us"]


def _yaw(**params):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = fly_hover_stats({"FRAME_TYPE": 1, **params}, seed=3, hold_s=30)
    return s["mot_yaw_us"]


def test_balanced_airframe_runs_its_motors_alike():
    roll, pitch = _asym()
    assert abs(roll) < 1.0 and abs(pitch) < 1.0


def test_centre_of_gravity_forward_or_right_loads_those_motors_in_proportion():
    """Forward: the front motors work harder (pitch output > 0); right: the right ones (roll
    output < 0, ArduPilot's roll factor being negative on the right); twice the offset, about
    twice the asymmetry (the moment is linear in it); the other axis untouched."""
    r1, p1 = _asym(TLM_CG_X=0.005)
    r2, p2 = _asym(TLM_CG_X=0.010)
    assert p1 > 5.0 and p2 == pytest.approx(2.0 * p1, rel=0.15) and abs(r2) < 2.0
    rr, pr = _asym(TLM_CG_Y=0.010)
    assert rr < -5.0 and abs(pr) < 2.0
    rb, pb = _asym(TLM_CG_X=-0.010)
    assert pb == pytest.approx(-p2, rel=0.15)


def test_unequal_reaction_torque_is_trimmed_by_the_yaw_output():
    """Counter-clockwise rotors of more torque (TLM_YAW_ASYM > 0): the clockwise motors work
    harder (yaw output < 0 on ArduPilot's factors); linear in the asymmetry, odd in its sign,
    roll and pitch untouched; the frame at 0 is exactly the yaw factors (bit-identical)."""
    from tlm_sim.dynamics.frame import F_MOT_YAW, build_frame
    from tlm_sim.frames import frame_for
    from tlm_sim.params import Params

    assert abs(_yaw()) < 1.0
    y1, y2, yb = _yaw(TLM_YAW_ASYM=0.05), _yaw(TLM_YAW_ASYM=0.10), _yaw(TLM_YAW_ASYM=-0.10)
    assert y1 < -10.0 and y2 == pytest.approx(2.0 * y1, rel=0.15)
    assert yb == pytest.approx(-y2, rel=0.15)
    r, p = _asym(TLM_YAW_ASYM=0.10)
    assert abs(r) < 2.0 and abs(p) < 2.0
    layout = frame_for(1, 1)
    f0 = build_frame(Params({"FRAME_TYPE": 1}))
    assert [f0[F_MOT_YAW + i] for i in range(4)] == [m.yaw_factor for m in layout.motors]
    f1 = build_frame(Params({"FRAME_TYPE": 1, "TLM_YAW_ASYM": 0.1}))
    assert [f1[F_MOT_YAW + i] for i in range(4)] == pytest.approx(
        [m.yaw_factor * (1.0 + 0.1 * m.yaw_factor) for m in layout.motors])
