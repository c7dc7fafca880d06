"""Scenario sampling of ``tlm generate``: draws from the run seed only, shares, λ, recipes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tlm_process.generate.errors import GenerateError
from tlm_process.generate.scenario import (
    DEFAULT_RANGES,
    REAL_VIBRATION,
    Scenario,
    ScenarioConfig,
    flight_conditions,
    mission_from_recipe,
    new_types,
    sample_scenario,
)
from tlm_sim.flight import max_duration_s


def _holds(sc: Scenario) -> list[float]:
    return [f["end"] - f["start"] for f in sc.faults["faults"]]


def test_flight_i_depends_only_on_seed_and_index():
    cfg = ScenarioConfig()
    forward = [sample_scenario(7, i, cfg) for i in range(12)]
    backward = [sample_scenario(7, i, cfg) for i in reversed(range(12))][::-1]
    assert [s.to_dict() for s in forward] == [s.to_dict() for s in backward]
    assert len({s.seed for s in forward}) == 12
    assert sample_scenario(8, 3, cfg).to_dict() != forward[3].to_dict()
    # a fresh config object with the same settings draws the same flight
    assert sample_scenario(7, 5, ScenarioConfig.from_dict(cfg.to_dict())) == forward[5]


def test_aspects_draw_from_separate_streams():
    """Changing the mission mix moves no fault time, seed or wind draw."""
    a, b = ScenarioConfig(), ScenarioConfig(missions={"builtin": 1.0})
    for i in range(20):
        sa, sb = sample_scenario(3, i, a), sample_scenario(3, i, b)
        assert sb.mission["source"] == "builtin"
        assert (sa.kind, sa.faults, sa.params, sa.seed) == (sb.kind, sb.faults, sb.params, sb.seed)


def test_kinds_shares_and_fault_structure():
    cfg = ScenarioConfig()
    scen = [sample_scenario(11, i, cfg) for i in range(300)]
    counts = {k: sum(s.kind == k for s in scen) for k in ("none", "single", "paper", "sequence")}
    for kind, share in cfg.kinds.items():  # binomial, 4 standard deviations
        assert abs(counts[kind] - 300 * share) <= 4 * math.sqrt(300 * share * (1 - share))
    orders = set()
    for s in scen:
        types = s.fault_types
        if s.kind == "none":
            assert types == []
        elif s.kind == "single":
            assert len(types) == 1
            start = s.faults["faults"][0]["start"]
            assert 20 + 15 <= start <= 20 + 240
        elif s.kind == "sequence":
            assert 2 <= len(types) <= 4 and len(set(types)) == len(types)
            assert set(types) <= set(new_types())
        else:
            assert sorted(types) == ["accel", "engine", "gps", "rc"] and types[-1] == "rc"
            orders.add(tuple(types))
            t = 20.0
            for f in s.faults["faults"]:
                assert 15 - 0.11 <= f["start"] - t <= 25 + 0.11  # gap, 0.1 s rounding
                t = f["end"]
        assert all(20 - 0.1 <= h <= 40 + 0.1 for h in _holds(s))
        assert s.dropped == 0
        real = flight_conditions(s.params)["vibration"] == "real"
        for name, (lo, hi) in DEFAULT_RANGES.items():
            if real and name in REAL_VIBRATION:  # a real airframe's replaces the draw
                lo, hi = REAL_VIBRATION[name]
            assert lo <= s.params[name] <= hi
    assert len(orders) == 6  # GPS/accel/engine shuffled, RC last


def test_lambda_scales_holds_and_keeps_gaps():
    one, two = ScenarioConfig(kinds={"paper": 1}), ScenarioConfig(kinds={"paper": 1}, lam=2.0)
    for i in range(10):
        a, b = sample_scenario(5, i, one), sample_scenario(5, i, two)
        assert a.fault_types == b.fault_types and a.seed == b.seed and b.lam == 2.0
        for ha, hb in zip(_holds(a), _holds(b), strict=True):
            assert abs(hb - 2 * ha) <= 0.15
        fa, fb = a.faults["faults"], b.faults["faults"]
        assert fa[0]["start"] == fb[0]["start"]
        gaps_a = [fa[k]["start"] - fa[k - 1]["end"] for k in range(1, 4)]
        gaps_b = [fb[k]["start"] - fb[k - 1]["end"] for k in range(1, 4)]
        assert np.allclose(gaps_a, gaps_b, atol=0.11)


def test_faults_past_the_flight_end_are_dropped():
    cfg = ScenarioConfig(kinds={"paper": 1}, lam=20.0)
    s = sample_scenario(2, 0, cfg)
    assert s.dropped >= 1 and len(s.fault_types) == 4 - s.dropped
    spec = s.realise()
    spec.schedule.validate(spec.mission.n_waypoints, max_duration_s(spec.mission, spec.params))


def test_scenario_round_trips_through_json_and_realises():
    s = sample_scenario(1, 4, ScenarioConfig(missions={"random": 1}, kinds={"single": 1}))
    back = Scenario.from_dict(json.loads(json.dumps(s.to_dict())))
    assert back == s
    spec = back.realise()
    assert spec.seed == s.seed and spec.profile == "current"
    assert spec.schedule.to_dict() == s.faults
    assert {k: spec.params[k] for k in s.params} == s.params
    # random missions the Algorithm 1 way: ~90 waypoints on a 1.1-1.3 km loop, 15-25 m
    m = spec.mission
    assert 88 <= m.n_waypoints <= 92 and 1100 <= m.path_length_m <= 1300
    assert m.waypoints[:, 2].min() >= 14.5 and m.waypoints[:, 2].max() <= 25.5


def test_builtin_shapes_get_a_fresh_altitude_profile():
    from tlm_sim.mission import builtin_mission

    base = builtin_mission(2)
    m = mission_from_recipe({"source": "builtin", "id": 2, "alt_seed": 9,
                             "alt_range": [15.0, 25.0]})
    assert np.array_equal(m.waypoints[:, :2], base.waypoints[:, :2])
    assert not np.array_equal(m.waypoints[:, 2], base.waypoints[:, 2])
    assert mission_from_recipe({"source": "builtin", "id": 2}) == base


def test_tampered_mission_is_detected():
    s = sample_scenario(1, 0, ScenarioConfig())
    bad = Scenario.from_dict({**s.to_dict(), "mission_sha1": "0" * 16})
    with pytest.raises(GenerateError, match="another tlm version"):
        bad.realise()


@pytest.mark.parametrize("kwargs, needle", [
    ({"kinds": {"none": -1}}, "share of 'none'"),
    ({"kinds": {"nothing": 1}}, "unknown 'nothing'"),
    ({"kinds": {"none": 0}}, "at least one share"),
    ({"lam": 0.0}, "lambda must be"),
    ({"lam": -1.0}, "lambda must be"),
    ({"ranges": {"SIM_WIND_SPD": (5, 1)}}, "range of SIM_WIND_SPD"),
    ({"ranges": {"SIM_WIND_SPEED": (0, 1)}}, "unknown parameter"),
    ({"params": {"SIM_WIND_SPD": 1}}, "both drawn"),
    # parameters tlm does not model are refused, drawn or fixed (they would change nothing)
    ({"ranges": {"SIM_BAR3_RND": (0, 0.2)}}, "SIM_BAR3_RND is not modelled"),
    ({"params": {"SIM_BAR3_DISABLE": 1}}, "SIM_BAR3_DISABLE is not modelled"),
    ({"profile": "old"}, "unknown profile"),
    ({"hold_s": (0, 0)}, "hold_s"),
])
def test_bad_settings_are_one_line_errors(kwargs, needle):
    with pytest.raises(GenerateError, match=needle) as err:
        ScenarioConfig(**kwargs)
    assert "\n" not in str(err.value)


def test_default_draws_are_modelled_parameters():
    """Every parameter the sampler draws by default changes a flight (SIM_BAR2_RND, read by
    nothing, was drawn for every flight)."""
    from tlm_sim.params import is_modelled

    assert all(is_modelled(n) for n in DEFAULT_RANGES)
    ScenarioConfig()  # the default configuration validates
