"""RATE.AOutSlew (issue 23): the motors' throttle slew rate as ArduPilot computes it
(AP_MotorsMulticopter::update_throttle_filter: the throttle low-passed at 2 Hz and clamped,
a 7-point DerivativeFilter on its changes, |slope| low-passed at 50 Hz), against the reference
SITL logs."""

from __future__ import annotations

import json
import math
from functools import lru_cache

import numpy as np
import pytest

from tests.conftest import REFERENCE, reference_path
from tlm_sim.control import layout as C
from tlm_sim.control.config import build_control_config
from tlm_sim.control.mixer import _slew_sample, _slew_slope, throttle_slew_update
from tlm_sim.params import Params

LEVEL = np.array([1.0, 0.0, 0.0, 0.0])


def _state() -> np.ndarray:
    return np.zeros(C.N_CONTROL_STATE)


def test_derivative_filter_is_exact_on_a_ramp_with_uneven_times():
    c = _state()
    assert _slew_slope(c) == 0.0  # nothing yet
    times = [1000.0, 3500.0, 6000.0, 7500.0, 11000.0, 13500.0, 16000.0, 17000.0, 20500.0]
    for k, t in enumerate(times):
        _slew_sample(c, 0.2 + 3e-5 * t, t)
        if k < 5:  # ArduPilot's check: slots 5 and 6 still both empty -> 0
            assert _slew_slope(c) == 0.0
    assert _slew_slope(c) == pytest.approx(3e-5, rel=1e-9)
    assert _slew_slope(c) == pytest.approx(3e-5, rel=1e-9)  # no new sample: the last slope
    _slew_sample(c, 0.5, 20500.0)  # a repeated time is ignored
    assert c[C.SLEW_NEW] == 0.0


def test_filtered_throttle_at_a_limit_freezes_the_slew_rate():
    """Once the filtered throttle sits at 1.0 it no longer changes, no sample comes, and the
    rate settles on the last slope (engine_s14.bin: 79.5 /s through the tumble, 0.346 /s on the
    ground)."""
    g = build_control_config(Params())
    c = _state()
    c[C.ARMED] = 1.0
    c[C.SUBMODE] = C.SUB_WP
    c[C.THR_IN_RAW] = 0.4
    t = 0.0
    for _ in range(2000):  # 5 s at 400 Hz
        t += 2500.0
        throttle_slew_update(c, g, t, LEVEL)
    assert c[C.THR_FILT] == pytest.approx(0.4, abs=1e-6)
    assert c[C.THR_SLEW_RATE] < 1e-4
    c[C.THR_IN_RAW] = 3.0  # far above full throttle: the filter climbs to 1.0 in ~0.1 s
    rates = []
    for _ in range(400):
        t += 2500.0
        throttle_slew_update(c, g, t, LEVEL)
        rates.append(c[C.THR_SLEW_RATE])
    assert c[C.THR_FILT] == 1.0
    assert rates[-1] == pytest.approx(rates[-100], rel=1e-9) and rates[-1] > 5.0
    # disarmed: the filter is 0
    c[C.ARMED] = 0.0
    throttle_slew_update(c, g, t + 2500.0, LEVEL)
    assert c[C.THR_FILT] == 0.0


def test_angle_boost_of_the_motors_input():
    """The motors get the unclamped demand x 1/cos(tilt), the cosine floored at 0.1 and faded to
    0 past 84 deg: at 60 deg of roll the filter heads for twice the demand."""
    g = build_control_config(Params())
    c = _state()
    c[C.ARMED] = 1.0
    c[C.SUBMODE] = C.SUB_WP
    c[C.THR_IN_RAW] = 0.3
    q = np.array([math.cos(math.radians(30.0)), math.sin(math.radians(30.0)), 0.0, 0.0])
    for k in range(4000):
        throttle_slew_update(c, g, 2500.0 * (k + 1), q)
    assert c[C.THR_FILT] == pytest.approx(0.6, abs=1e-6)
    c[C.SUBMODE] = C.SUB_GROUND_IDLE  # ground idle: no throttle
    for k in range(4000, 8000):
        throttle_slew_update(c, g, 2500.0 * (k + 1), q)
    assert c[C.THR_FILT] == pytest.approx(0.0, abs=1e-6)


@lru_cache(maxsize=4)
def _flights(name: str):
    """(SITL RATE, tlm RATE, SITL fault, tlm fault, SITL arm us, tlm arm us) of a reference."""
    from tlm_sim.flightlog import read_bin
    from tools.fidelity_faults import fly_like_reference

    path = reference_path(f"{name}.bin")
    ref = read_bin(str(path), types=["RATE", "EV"])
    flight = fly_like_reference(REFERENCE, name)
    side = json.loads(path.with_suffix(".json").read_text())

    def arm(t):
        return float(t["EV"][t["EV"].Id == 10].TimeUS.iloc[0])

    faults = (side["faults"][0], flight["tlm_faults"][0]) if side["faults"] else (None, None)
    return ref["RATE"], flight["tlm"]["RATE"], *faults, arm(ref), arm(flight["tlm"])


def _window(rate, a_us: float, b_us: float):
    return rate[(rate.TimeUS >= a_us) & (rate.TimeUS <= b_us)].AOutSlew


@pytest.mark.slow
def test_cruise_slew_rate_like_sitl():
    """normal_s11, 20-60 s after arming (cruise): SITL median 0.0008 /s, p95 0.0026; tlm
    0.0005, 0.0023."""
    sitl, tlm, _, _, a_s, a_t = _flights("normal_s11")
    s, t = _window(sitl, a_s + 20e6, a_s + 60e6), _window(tlm, a_t + 20e6, a_t + 60e6)
    assert (t > 0.0).all()
    assert t.quantile(0.95) == pytest.approx(s.quantile(0.95), rel=0.3)
    assert t.median() == pytest.approx(s.median(), rel=0.5)
    assert t.max() < 0.01


@pytest.mark.slow
def test_engine_fault_slew_rate_like_sitl():
    """engine_s14: the tumble pins the rate at the last rise to full throttle (SITL 79.5 /s,
    tlm 78.7), the ground phase at the last small rise (SITL 0.346, tlm 0.45)."""
    sitl, tlm, fs, ft, _, _ = _flights("engine_s14")
    s = _window(sitl, fs["start_time_us"] + 1e6, fs["start_time_us"] + 2.4e6)
    t = _window(tlm, ft["start_time_us"] + 1e6, ft["start_time_us"] + 2.4e6)
    assert t.median() == pytest.approx(s.median(), rel=0.1)
    s = _window(sitl, fs["start_time_us"] + 6e6, fs["end_time_us"])
    t = _window(tlm, ft["start_time_us"] + 6e6, ft["end_time_us"])
    assert s.std() == 0.0 and t.std() == 0.0  # frozen: the filtered throttle sits at 1
    assert t.median() == pytest.approx(s.median(), abs=0.2)


@pytest.mark.slow
def test_accel_fault_slew_rate_like_sitl():
    """accel_s13: throttle to full and swinging after the fault; 0-3 s median SITL 4.3 /s,
    tlm 4.0; the window's p95 4.7 and 4.0."""
    sitl, tlm, fs, ft, _, _ = _flights("accel_s13")
    s = _window(sitl, fs["start_time_us"], fs["start_time_us"] + 3e6)
    t = _window(tlm, ft["start_time_us"], ft["start_time_us"] + 3e6)
    assert t.median() == pytest.approx(s.median(), rel=0.25)
    s = _window(sitl, fs["start_time_us"], fs["end_time_us"])
    t = _window(tlm, ft["start_time_us"], ft["end_time_us"])
    assert t.quantile(0.95) == pytest.approx(s.quantile(0.95), rel=0.3)
