"""``tlm generate`` draws every fault type: ``--faults`` presets, ``sequence`` flights,
magnitudes drawn from user ranges; ``--faults paper`` draws what the default drew before."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tlm_process.cli import build_parser
from tlm_process.commands.generate import build_config
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.scenario import (
    PAPER_TYPES,
    ScenarioConfig,
    fault_params,
    fault_preset,
    magnitude_knobs,
    new_types,
    sample_scenario,
)
from tlm_sim.faults import FAULT_TYPES, Fault, Trigger
from tlm_sim.geo import HOME_CMAC
from tlm_sim.params import is_modelled

#: types whose parameters tlm models (every type: test_every_fault_type_is_modelled)
FLYABLE = tuple(t for t, ft in FAULT_TYPES.items()
                if all(is_modelled(p) for p in ft.params_start))


def test_every_fault_type_is_modelled():
    assert FLYABLE == tuple(FAULT_TYPES)


def test_default_draws_every_type():
    cfg = ScenarioConfig()
    assert ScenarioConfig.from_dict({"faults": "all"}) == cfg
    assert {t for t, w in cfg.fault_weights.items() if w > 0} == set(FAULT_TYPES)
    seen = {t for i in range(300) for t in sample_scenario(5, i, cfg).fault_types}
    assert seen == set(FAULT_TYPES)


def test_paper_preset_draws_only_the_papers_four_types_with_their_parameters():
    cfg = ScenarioConfig.from_dict({"faults": "paper"})
    assert cfg.kinds["sequence"] == 0.0
    assert {t for t, w in cfg.fault_weights.items() if w > 0} == set(PAPER_TYPES)
    for i in range(60):
        s = sample_scenario(5, i, cfg)
        assert s.kind in ("none", "single", "paper")
        for f in s.faults.get("faults", []):
            assert f["fault"] in PAPER_TYPES and "params_start" not in f


def test_presets():
    assert set(fault_preset("all")["fault_weights"]) == set(FAULT_TYPES)
    assert fault_preset("all")["kinds"] == {"none": 0.2, "single": 0.4, "paper": 0.2,
                                            "sequence": 0.2}
    assert set(fault_preset("new")["fault_weights"]) == set(new_types()) == set(
        fault_preset("new")["sequence_types"])
    assert fault_preset("single")["kinds"] == {"none": 0.2, "single": 0.8}
    p = fault_preset("Battery, gps_glitch")
    assert p["fault_weights"] == {"battery": 1.0, "gps_glitch": 1.0}
    assert p["sequence_types"] == ["gps_glitch", "battery"] and p["sequence_len"] == [2, 2]
    assert fault_preset(["engine"])["kinds"] == {"none": 0.2, "single": 0.8}
    with pytest.raises(GenerateError, match="unknown fault type 'warp'"):
        fault_preset("warp,gps")


def test_file_keys_override_the_file_preset_and_the_flag_overrides_the_file(tmp_path):
    cfg = ScenarioConfig.from_dict({"faults": "gps,rc", "kinds": {"single": 1.0}})
    assert cfg.kinds["single"] == 1.0 and cfg.kinds["none"] == 0.0
    f = tmp_path / "gen.yaml"
    f.write_text("faults: gps,engine\nfault_weights: {engine: 1}\n")
    args = build_parser().parse_args(["generate", "--flights", "1", "--out", "x", "--config",
                                      str(f)])
    assert {t for t, w in build_config(args).fault_weights.items() if w} == {"engine"}
    args = build_parser().parse_args(["generate", "--flights", "1", "--out", "x", "--config",
                                      str(f), "--faults", "engine,rc", "--kinds", "single=1"])
    cfg = build_config(args)
    assert {t for t, w in cfg.fault_weights.items() if w} == {"engine", "rc"}
    assert cfg.kinds["single"] == 1.0 and cfg.kinds["sequence"] == 0.0


def test_sequence_flights_fly_distinct_types_in_paper_timing():
    cfg = ScenarioConfig(kinds={"sequence": 1.0}, sequence_types=("gps", "engine", "rc"),
                         sequence_len=(2, 3), fault_weights={"gps": 1, "engine": 1, "rc": 1})
    lengths = set()
    for i in range(40):
        s = sample_scenario(2, i, cfg)
        types = s.fault_types
        lengths.add(len(types))
        assert s.kind == "sequence" and len(set(types)) == len(types) and 2 <= len(types) <= 3
        assert set(types) <= {"gps", "engine", "rc"}
        assert "rc" not in types[:-1]  # the RC failsafe ends the mission: it comes last
        t = 20.0
        for f in s.faults["faults"]:
            assert 15 - 0.11 <= f["start"] - t <= 25 + 0.11
            t = f["end"]
    assert lengths == {2, 3}
    with pytest.raises(GenerateError, match="sequence_len starts at 3"):
        ScenarioConfig(kinds={"sequence": 1.0}, sequence_types=("gps", "rc"),
                       sequence_len=(3, 4))


@pytest.mark.parametrize("ftype", sorted(magnitude_knobs()))
def test_every_knob_maps_to_the_types_parameters(ftype):
    """fault_params gives parameters a Fault of the type accepts (name and range), clearing
    each to its type's end value or tlm's default."""
    from tlm_sim.params import Params

    cfg = ScenarioConfig()
    rng = np.random.default_rng(0)
    from tlm_process.generate.scenario import _draw_magnitudes

    start, end = fault_params(ftype, _draw_magnitudes(rng, ftype, cfg), HOME_CMAC[0])
    assert set(start) == set(end)
    defaults = Params.defaults()
    for n, v in end.items():
        assert v == FAULT_TYPES[ftype].params_end.get(n, defaults[n])
    if all(is_modelled(n) for n in start):
        f = Fault(ftype, Trigger("time", 50), Trigger("time", 80), start, end)
        assert dict(f.params_start) == pytest.approx(start)


def test_knob_values():
    start, end = fault_params("gps_glitch", {"offset_m": 43.0, "bearing_deg": 0.0}, -35.36)
    assert start["SIM_GPS1_GLTCH_X"] == pytest.approx(43.0 / 111319.49, abs=1e-7)
    assert start["SIM_GPS1_GLTCH_Y"] == 0.0 and end == {"SIM_GPS1_GLTCH_X": 0.0,
                                                        "SIM_GPS1_GLTCH_Y": 0.0}
    start, _ = fault_params("gps_glitch", {"offset_m": 43.0, "bearing_deg": 90.0}, -35.36)
    assert start["SIM_GPS1_GLTCH_Y"] == pytest.approx(
        43.0 / (111319.49 * math.cos(math.radians(35.36))), abs=1e-7)
    assert fault_params("compass", {"instance": 2, "mode": 2}, 0.0) == (
        {"SIM_MAG2_FAIL": 2.0}, {"SIM_MAG2_FAIL": 0.0})
    assert fault_params("baro", {"instance": "both"}, 0.0)[0] == {"SIM_BARO_DISABLE": 1.0,
                                                                  "SIM_BAR2_DISABLE": 1.0}
    assert fault_params("baro", {"instance": 2}, 0.0)[0] == {"SIM_BAR2_DISABLE": 1.0}
    assert fault_params("gyro", {"instance": "both"}, 0.0)[0] == {"SIM_GYR_FAIL_MSK": 3.0}
    assert fault_params("accel_samples", {"instance": 2}, 0.0)[0] == {"SIM_ACC_FAIL_MSK": 2.0}
    assert fault_params("motor_partial", {"mul": 0.5}, 0.0) == (
        {"SIM_ENGINE_MUL": 0.5}, {"SIM_ENGINE_MUL": 1.0})
    assert fault_params("battery", {"volt": 10.2}, 0.0) == (
        {"SIM_BATT_VOLTAGE": 10.2}, {"SIM_BATT_VOLTAGE": 12.6})
    assert fault_params("vibration", {"amplitude": 4.8}, 0.0)[0] == {
        "SIM_ACC1_RND": 4.8, "SIM_ACC2_RND": 4.8, "SIM_VIB_MOT_MAX": 350.0}
    assert fault_params("gps", {}, 0.0) is None


def test_magnitudes_are_drawn_from_the_configured_ranges_on_their_own_stream():
    kinds = {"single": 1.0}
    weights = {"motor_partial": 1.0, "battery": 1.0}
    a = ScenarioConfig(kinds=kinds, fault_weights=weights)
    b = ScenarioConfig(kinds=kinds, fault_weights=weights,
                       magnitudes={"motor_partial": {"mul": [0.55, 0.6]},
                                   "battery": {"volt": 10.0}})
    seen = set()
    for i in range(30):
        sa, sb = sample_scenario(4, i, a), sample_scenario(4, i, b)
        (fa,), (fb,) = sa.faults["faults"], sb.faults["faults"]
        assert (fa["fault"], fa["start"], fa["end"]) == (fb["fault"], fb["start"], fb["end"])
        seen.add(fa["fault"])
        if fa["fault"] == "motor_partial":
            assert 0.4 <= fa["params_start"]["SIM_ENGINE_MUL"] <= 0.8
            assert 0.55 <= fb["params_start"]["SIM_ENGINE_MUL"] <= 0.6
        else:
            assert 9.9 <= fa["params_start"]["SIM_BATT_VOLTAGE"] <= 10.4
            assert fb["params_start"]["SIM_BATT_VOLTAGE"] == 10.0
        assert sample_scenario(4, i, a) == sa  # deterministic per seed
    assert seen == {"motor_partial", "battery"}


@pytest.mark.parametrize("bad, needle", [
    ({"warp": {}}, "no knobs for 'warp'"),
    ({"battery": {"amps": [1, 2]}}, "unknown knob 'amps'"),
    ({"motor_partial": {"mul": [0.5, 1.5]}}, r"must lie in \[0, 1\]"),
    ({"baro": {"instance": [3]}}, "must be one or more of 1, 2, both"),
    ({"battery": {"volt": [11, 10]}}, "low <= high"),
])
def test_bad_magnitudes_are_one_line_errors(bad, needle):
    with pytest.raises(GenerateError, match=needle):
        ScenarioConfig(magnitudes=bad)


def test_unmodelled_types_are_refused_up_front(monkeypatch):
    """A type whose parameters tlm does not model (as SIM_GYR_FAIL_MSK once was) is refused
    when the settings are read, not when a flight draws it."""
    import tlm_sim.params

    real = tlm_sim.params.is_modelled
    monkeypatch.setattr(tlm_sim.params, "is_modelled",
                        lambda name: name != "SIM_GYR_FAIL_MSK" and real(name))
    with pytest.raises(GenerateError, match="fault type gyro: tlm does not model"):
        ScenarioConfig.from_dict({"faults": "all"})


def test_every_type_can_be_drawn_once_modelled():
    cfg = ScenarioConfig.from_dict({"faults": list(FLYABLE), "kinds": {"single": 1.0}})
    seen = {sample_scenario(9, i, cfg).fault_types[0] for i in range(200)}
    assert seen == set(FLYABLE)


@pytest.mark.slow
def test_generate_writes_labels_of_new_fault_types(tmp_path):
    import pandas as pd

    from tlm_process.generate import GenerateOptions, generate

    types = ["motor_partial", "battery", "vibration"]
    cfg = ScenarioConfig.from_dict({"faults": types, "kinds": {"sequence": 1.0},
                                    "missions": {"builtin": 1.0}, "ranges": {}})
    rep = generate(GenerateOptions(out=tmp_path / "ds", flights=2, seed=3, config=cfg,
                                   tables=["GPS"], workers=1, progress=False))
    assert rep.failed == 0
    faults = pd.read_parquet(tmp_path / "ds" / "faults.parquet")
    assert set(faults["type"]) <= set(types) and len(faults) >= 4
    assert set(faults["label"]) <= {FAULT_TYPES[t].label for t in types}
