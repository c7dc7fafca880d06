"""Pilot-flown flights in generated data sets (issue 42): ``--pilot-share`` draws stick
scripts (modes, patterns) instead of missions, with faults drawn as for missions, inside the
script's flying time; the data set's records fly them again."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from tlm_process.cli import main
from tlm_process.generate import read_dataset_table
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.pilot_flights import (
    PATTERNS,
    PILOT_MODES,
    draw_pilot,
    pilot_script,
    validate_pilot,
)
from tlm_process.generate.scenario import ScenarioConfig, sample_scenario
from tlm_sim import ardupilot as AP
from tlm_sim import fly
from tlm_sim.mission.sticks import StickScript


def test_default_draws_no_pilot_flights():
    cfg = ScenarioConfig()
    assert cfg.pilot["share"] == 0.0
    assert all(sample_scenario(1, k, cfg).mission["source"] != "pilot" for k in range(20))


def test_pilot_share_draws_scripts_and_times_faults_within_them():
    cfg = ScenarioConfig(pilot={"share": 1.0})
    seen_modes, seen_patterns = set(), set()
    for k in range(40):
        sc = sample_scenario(2, k, cfg)
        m = sc.mission
        assert m["source"] == "pilot"
        draw = m["pilot"]
        seen_modes.add(draw["mode"])
        seen_patterns.add(draw["pattern"])
        rows, origin, descent = pilot_script(draw)
        assert rows[0] == {"t": 1.0, "gcs_mode": draw["mode"]}  # the ground station's mode
        for f in sc.faults["faults"]:
            assert origin <= f["start"] and f["end"] <= descent
        spec = sc.realise()
        assert isinstance(spec.sticks, StickScript)
        assert spec.sticks.gcs_modes()[0, 1] == {v: k for k, v in AP.MODE_NAMES.items()}[
            draw["mode"]]
    assert seen_modes == set(PILOT_MODES) and seen_patterns == set(PATTERNS)


def test_patterns_move_the_sticks_they_name():
    rng = np.random.default_rng(0)
    cfg = validate_pilot({"share": 1.0, "patterns": {"box": 1}})
    d = draw_pilot(rng, cfg)
    moves = [tuple(s[:3]) for s in d["segments"][:4]]
    assert [tuple(np.sign(m)) for m in moves] == [(0, 1, 0), (1, 0, 0), (0, -1, 0), (-1, 0, 0)]
    assert all(0.2 <= max(abs(v) for v in m) <= 0.6 for m in moves)


def test_freestyle_moves_every_stick_at_once():
    cfg = validate_pilot({"share": 1.0, "patterns": {"freestyle": 1}})
    moves = np.array([s[:3] for k in range(20)
                      for s in draw_pilot(np.random.default_rng(k), cfg)["segments"]])
    assert np.all(np.abs(moves) <= 0.6)
    assert np.mean(np.all(moves != 0.0, axis=1)) > 0.95  # three sticks at once
    for axis in range(3):  # both ways on each
        assert moves[:, axis].min() < -0.3 and moves[:, axis].max() > 0.3


@pytest.mark.parametrize("bad, msg", [
    ({"share": 1.5}, "share"), ({"modes": {"ACRO": 1}}, "ACRO is not drawn"),
    ({"patterns": {"circle": 1}}, "unknown 'circle'"), ({"stick": [0.2, 1.5]}, "at most 1"),
    ({"speed": 3}, "unknown setting"),
])
def test_bad_pilot_settings(bad, msg):
    with pytest.raises(GenerateError, match=msg):
        ScenarioConfig(pilot=bad)


def test_a_generated_pilot_flight_flies_its_faults_and_lands():
    cfg = ScenarioConfig(pilot={"share": 1.0, "modes": {"LOITER": 1}, "patterns": {"box": 1}},
                         kinds={"single": 1.0}, fault_weights={"gps_glitch": 1.0})
    sc = sample_scenario(4, 0, cfg)
    spec = sc.realise()
    log = fly(spec.mission, spec.schedule, spec.params, spec.seed, spec.profile,
              sticks=spec.sticks)
    assert log.meta["end_reason"] == "landed" and log.meta["mission"] == "pilot"
    assert [r["type"] for r in log.faults] == ["gps_glitch"]
    assert (log.tables["MODE"]["ModeNum"] == AP.MODE_LOITER).any()


def test_a_generated_stabilize_flight_holds_its_height_by_the_pilots_hand():
    """STABILIZE only when a configuration gives it a share: the pilot's hand climbs to the
    drawn height, holds it through the pattern (a fault drawn in it) and lands; auto-disarm."""
    cfg = ScenarioConfig(pilot={"share": 1.0, "modes": {"STABILIZE": 1},
                                "patterns": {"lines": 1}, "duration": [40, 60]},
                         kinds={"single": 1.0}, fault_weights={"gps_glitch": 1.0})
    sc = sample_scenario(5, 0, cfg)
    draw = sc.mission["pilot"]
    assert draw["mode"] == "STABILIZE"
    rows, origin, descent = pilot_script(draw)
    assert {"t": 19.0, "height": draw["alt"]} in rows and {"t": descent, "throttle": "land"} in rows
    spec = sc.realise()
    log = fly(spec.mission, spec.schedule, spec.params, spec.seed, spec.profile,
              sticks=spec.sticks)
    assert log.meta["end_reason"] == "landed"
    assert set(log.tables["MODE"]["ModeNum"]) == {AP.MODE_STABILIZE}
    ctun = log.tables["CTUN"]
    held = ctun[(ctun.TimeUS > origin * 1e6) & (ctun.TimeUS < descent * 1e6)]["Alt"]
    assert abs(held.mean() - draw["alt"]) < 0.5 and held.max() - held.min() < 1.5
    assert log.tables["ARM"]["Method"].iloc[-1] in (AP.ARM_METHOD_DISARMDELAY,
                                                    AP.ARM_METHOD_RUDDER)


def test_tlm_generate_pilot_share_and_fly_from_manifest(tmp_path, capsys):
    ds = tmp_path / "ds"
    code = main(["generate", "--flights", "2", "--seed", "3", "--out", str(ds), "--pilot-share",
                 "1", "--no-progress", "--workers", "1", "--tables", "GPS,CTUN,RCIN"])
    assert code == 0
    man = pd.read_parquet(ds / "manifest.parquet")
    assert man["mission"].str.startswith("pilot-").all()
    assert "pilot-flown (stick scripts" in (ds / "README.md").read_text()
    header = json.loads((ds / "manifest.json").read_text())
    assert header["settings"]["scenario"]["pilot"]["share"] == 1.0
    out = tmp_path / "again"
    assert main(["fly", "--from-manifest", str(ds), "--flight", "1", "--out", str(out),
                 "--format", "csv", "--no-plot"]) == 0
    again = pd.read_csv(out / "CTUN.csv")
    capsys.readouterr()
    mine = read_dataset_table(ds, "CTUN").query("flight == 1")
    assert len(mine) == len(again) > 1000
    assert np.allclose(mine["Alt"].to_numpy(), again["Alt"].to_numpy(), atol=1e-4)
