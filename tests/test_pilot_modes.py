"""The pilot's helpers as ArduCopter 4.7 defines them (design: pilot-modes-and-vibration.md,
A2-A4): stick scaling and dead zones, the mode switch, lean angles, yaw rate, climb rate, the
manual throttle curve, POSHOLD's brake angle; analytic cases and properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim.control import layout as C
from tlm_sim.control.config import build_control_config
from tlm_sim.control.pilot import stick_norm, switch_position, throttle_in
from tlm_sim.control.pilot_modes import climb_rate, lean_angles, manual_throttle, yaw_rate
from tlm_sim.params import Params

G = build_control_config(Params())
D30 = math.radians(30.0)


def test_stick_scaling_and_dead_zones():
    # RC1: 1000-2000, trim 1500, DZ 20: 1520 is still centred, 2000 is full right
    assert stick_norm(G, 0, 1520.0) == 0.0
    assert stick_norm(G, 0, 2000.0) == 1.0
    assert stick_norm(G, 0, 1000.0) == -1.0
    assert stick_norm(G, 1, 1300.0) == pytest.approx(-180.0 / 480.0)  # the reference's 40 %
    # the throttle: 0 up to RC3_MIN + RC3_DZ, 1000 at RC3_MAX; mid-stick control_in 484
    assert throttle_in(G, 1030.0) == 0.0
    assert throttle_in(G, 2000.0) == 1000.0
    assert G[C.G_THR_MID] == 484.0


def test_mode_switch_positions():
    edges = [(800.0, -1), (1230.0, 0), (1231.0, 1), (1360.0, 1), (1490.0, 2), (1620.0, 3),
             (1749.0, 4), (1750.0, 5), (2199.0, 5), (2200.0, -1)]
    for pwm, pos in edges:
        assert switch_position(pwm) == pos, pwm


def test_lean_angles_single_axis_and_diagonal():
    roll, pitch = lean_angles(0.0, 0.4, D30, D30)
    assert roll == 0.0 and math.degrees(pitch) == pytest.approx(12.0)
    # A = L = 30 deg, full diagonal: pitch 22.2, roll 20.7 (the design's example)
    roll, pitch = lean_angles(1.0, 1.0, D30, D30)
    assert math.degrees(pitch) == pytest.approx(22.2, abs=0.05)
    assert math.degrees(roll) == pytest.approx(20.7, abs=0.05)


@settings(max_examples=60, deadline=None)
@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(10, 45), st.floats(5, 45))
def test_lean_angles_stay_within_the_limit(r, p, a_deg, l_deg):
    a, lim = math.radians(a_deg), math.radians(l_deg)
    roll, pitch = lean_angles(r, p, a, lim)
    tilt = math.acos(math.cos(roll) * math.cos(pitch))
    assert tilt <= max(min(lim, a), math.radians(10.0)) + 1e-9
    assert math.copysign(1, pitch) == math.copysign(1, p) or pitch == 0.0


def test_climb_rate_dead_band_and_limits():
    assert climb_rate(G, 484.0) == 0.0
    assert climb_rate(G, 384.0) == 0.0 and climb_rate(G, 584.0) == 0.0
    assert climb_rate(G, 1000.0) == pytest.approx(2.5)
    assert climb_rate(G, 0.0) == pytest.approx(-2.5)
    # the reference flights' climb stick, 1800 us: 1.26 m/s
    assert climb_rate(G, throttle_in(G, 1800.0)) == pytest.approx(1.261, abs=1e-3)


def test_manual_throttle_curve_puts_mid_stick_at_hover():
    for hover in (0.2, 0.39, 0.5, 0.65):
        assert manual_throttle(G, G[C.G_THR_MID], hover) == pytest.approx(hover, abs=1e-12)
    assert manual_throttle(G, 0.0, 0.39) == 0.0
    assert manual_throttle(G, 1000.0, 0.39) == pytest.approx(1.0)
    xs = np.linspace(0, 1000, 101)
    ys = [manual_throttle(G, x, 0.39) for x in xs]
    assert np.all(np.diff(ys) > 0)


def test_yaw_rate_and_expo():
    assert yaw_rate(G, 1.0) == pytest.approx(math.radians(202.5))
    g = G.copy()
    g[C.G_PILOT_Y_EXPO] = 0.5
    assert yaw_rate(g, 0.5) == pytest.approx(math.radians(202.5) * 0.25 / 0.75)
    assert yaw_rate(g, 1.0) == pytest.approx(math.radians(202.5))
