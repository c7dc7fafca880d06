"""A centre of gravity off the motors' centre (TLM_CG_X / _Y): the motors balance the
thrust's moment about it unequally, as a real airframe's do (issue 40's follow-up: log171's
rear motors run ~22 us above its front ones in its steady hover); ``tlm fit`` fits it."""

from __future__ import annotations

import warnings

import pytest

from tlm_process.fit.fit import fly_hover_stats


def _asym(**params):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = fly_hover_stats({"FRAME_TYPE": 1, **params}, seed=3, hold_s=30)
    return s["mot_roll_us"], s["mot_pitch_us"]


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
