"""``tlm generate`` draws the frame and the wind per flight: shares and ranges, their own
streams (every earlier draw of a flight unchanged), the manifest columns, the command line
(``--frame``, ``--calm-share``, ``--wind-*``, ``tlm fly --frame``) and one-line errors."""

from __future__ import annotations

import argparse
import hashlib
import json
import math
from concurrent.futures import ThreadPoolExecutor

import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tlm_process.cliutil import UsageError
from tlm_process.generate import (
    GenerateOptions,
    ScenarioConfig,
    generate,
    read_journal,
    scenario_from_manifest,
)
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.manifest import CONDITION_COLUMNS, manifest_frame
from tlm_process.generate.runner import GenerateReport
from tlm_process.generate.scenario import (
    DEFAULT_RANGES,
    DEFAULT_WIND,
    WIND_PARAMS,
    Scenario,
    flight_conditions,
    sample_scenario,
)
from tlm_process.generate.task import _config, make_job
from tlm_sim.faults import FAULT_TYPES
from tlm_sim.frames import FRAMES

#: fast scenarios: built-in missions keep their altitude profile (cached missions)
FAST = {"missions": {"builtin": 1.0}, "builtin_altitudes": "keep"}
QUADS = ("+", "x")


def _earlier(s: Scenario) -> dict:
    """What streams 0-5 decide: kind, mission, faults, flight seed, sensor noise."""
    return {"kind": s.kind, "mission": s.mission, "faults": s.faults, "seed": s.seed,
            "noise": {n: s.params[n] for n in DEFAULT_RANGES}, "dropped": s.dropped,
            "sha": s.mission_sha1}


def _digest(s: Scenario) -> str:
    return hashlib.sha1(json.dumps(_earlier(s), sort_keys=True).encode()).hexdigest()[:12]


#: _digest of flights 0-5 of seeds 7 and 2024 with the default settings, drawn by tlm 3246e40
#: (before frames and wind had streams; its wind came from the environment stream)
BEFORE = {7: ["600243abfdfb", "d69342543ef8", "c9066e9388b8", "fc81292c511b", "dde2a10954d6",
              "ec5e754c199c"],
          2024: ["11409191da95", "9f130f3d7839", "122dc1e1060c", "a103a6c3d8a3",
                 "8ece88772ace", "7627e3ccf5d5"]}


def test_the_new_streams_leave_every_earlier_draw_unchanged():
    # the vibration stream (8) replaces the SIM_GYRn_RND draws of its real-level flights
    # (tests/test_generate_vibration.py); without it every earlier draw is as before. A new
    # fault type (prop_damage, label 14) is a new choice: the types of labels 1-13 draw as
    # before
    first = [t for t in FAULT_TYPES if FAULT_TYPES[t].label <= 13]
    cfg = ScenarioConfig(vibration=None, fault_weights=dict.fromkeys(first, 1.0),
                         sequence_types=tuple(t for t in first if FAULT_TYPES[t].label > 4))
    for seed, digests in BEFORE.items():
        assert [_digest(sample_scenario(seed, i, cfg)) for i in range(6)] == digests
    assert [sample_scenario(7, i, cfg).seed for i in range(3)] == [1171815639, 1025053882,
                                                                   1964472879]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), flight=st.integers(0, 10**6),
       share=st.floats(0.0, 1.0), calm=st.floats(0.0, 1.0))
def test_frame_and_wind_settings_move_no_other_draw(seed, flight, share, calm):
    base = ScenarioConfig(**FAST)
    other = ScenarioConfig(**FAST, frames={"+": share, "x": 1.0 - share + 1e-9},
                           wind={"calm": calm, "speed": (1.0, 3.0)})
    still = ScenarioConfig(**FAST, wind=None)
    a, b, c = (sample_scenario(seed, flight, x) for x in (base, other, still))
    assert _earlier(a) == _earlier(b) == _earlier(c)
    # and the frame stream is not moved by the wind settings, nor the wind by the frames
    assert a.frame == sample_scenario(seed, flight, ScenarioConfig(**FAST, wind=None)).frame
    windy = ScenarioConfig(**FAST, wind={"calm": 0.0}, frames={"x": 1})
    w1 = sample_scenario(seed, flight, windy)
    w2 = sample_scenario(seed, flight, ScenarioConfig(**FAST, wind={"calm": 0.0}))
    assert {n: w1.params[n] for n in WIND_PARAMS.values()} == {
        n: w2.params[n] for n in WIND_PARAMS.values()}


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), flights=st.lists(st.integers(0, 10**5), min_size=1,
                                                        max_size=6, unique=True),
       frames=st.dictionaries(st.sampled_from(QUADS), st.floats(0.01, 5.0), min_size=1),
       calm=st.floats(0.0, 1.0), lo=st.floats(0.0, 6.0), width=st.floats(0.0, 4.0),
       turb=st.floats(0.0, 3.0))
def test_draws_depend_on_seed_and_flight_only(seed, flights, frames, calm, lo, width, turb):
    """Per (seed, flight): the same scenario in any order, from the job's JSON settings (as
    a worker reads them) and on one or three threads; values inside their ranges."""
    cfg = ScenarioConfig(**FAST, frames=frames,
                         wind={"calm": calm, "speed": (lo, lo + width), "turbulence": (0, turb)})
    direct = [sample_scenario(seed, i, cfg).to_dict() for i in flights]
    job_cfg = _config(make_job(0, seed, cfg, tables=None, bin_log=False)["config"])
    assert job_cfg == cfg
    for workers in (1, 3):
        with ThreadPoolExecutor(workers) as pool:
            got = list(pool.map(lambda i: sample_scenario(seed, i, job_cfg).to_dict(),
                                reversed(flights)))
        assert got[::-1] == direct
    for d in direct:
        s = Scenario.from_dict(d)
        c = s.conditions
        assert c["frame"] == s.frame and frames.get(s.frame, 0) > 0
        assert (c["frame_class"], c["frame_type"]) == (FRAMES[s.frame].frame_class,
                                                       FRAMES[s.frame].frame_type)
        if s.params["SIM_WIND_SPD"] == 0 and s.params["SIM_WIND_TURB"] == 0:
            assert c["calm"] and math.isnan(c["wind_dir"])
        else:
            assert lo - 1e-3 <= c["wind_spd"] <= lo + width + 1e-3
            assert 0 <= c["wind_dir"] <= 360 and 0 <= c["wind_turb"] <= turb + 1e-3


def _binomial_ok(count: int, n: int, p: float) -> bool:
    """Within 4 standard deviations of n p."""
    return abs(count - n * p) <= 4 * math.sqrt(n * p * (1 - p)) + 1e-9


def test_frame_and_calm_shares_are_respected():
    n = 800
    cfg = ScenarioConfig(**FAST, frames={"+": 0.3, "x": 0.7}, wind={"calm": 0.25})
    scen = [sample_scenario(3, i, cfg) for i in range(n)]
    assert _binomial_ok(sum(s.frame == "x" for s in scen), n, 0.7)
    calm = [s for s in scen if s.conditions["calm"]]
    assert _binomial_ok(len(calm), n, 0.25)
    for s in calm:  # no wind, no turbulence, no direction
        assert s.params["SIM_WIND_SPD"] == 0 and s.params["SIM_WIND_TURB"] == 0
        assert "SIM_WIND_DIR" not in s.params
    windy = pd.DataFrame([s.conditions for s in scen if not s.conditions["calm"]])
    for col, (lo, hi) in (("wind_spd", DEFAULT_WIND["speed"]),
                          ("wind_dir", DEFAULT_WIND["direction"]),
                          ("wind_turb", DEFAULT_WIND["turbulence"])):
        assert windy[col].between(lo, hi).all()
        # uniform: the mean within 4 standard errors of the middle
        assert abs(windy[col].mean() - (lo + hi) / 2) <= 4 * (hi - lo) / math.sqrt(
            12 * len(windy))


def test_defaults_cover_calm_and_windy_flights_on_both_quad_frames():
    cfg = ScenarioConfig(**FAST)
    assert {k for k, v in cfg.frames.items() if v > 0} == {"+", "x"}
    assert 0 < cfg.wind["calm"] < 1
    assert cfg.wind["speed"] == (0.0, 8.0) and cfg.wind["turbulence"] == (0.0, 2.0)
    seen = {(s.frame, s.conditions["calm"]) for s in (sample_scenario(1, i, cfg)
                                                      for i in range(40))}
    assert seen == {("+", True), ("+", False), ("x", True), ("x", False)}
    # the wind is no longer an environment range; the noise ranges are what they were
    assert not set(WIND_PARAMS.values()) & set(cfg.ranges)
    assert cfg.ranges == DEFAULT_RANGES


def test_settings_round_trip_and_older_forms():
    cfg = ScenarioConfig(frames="+,x", wind={"calm": 0.5, "speed": 4})
    assert cfg.frames["+"] == cfg.frames["x"] == 1.0 and cfg.wind["speed"] == (4.0, 4.0)
    assert ScenarioConfig.from_dict(json.loads(json.dumps(cfg.to_dict()))) == cfg
    assert ScenarioConfig(frames=["X"]).frames["x"] == 1.0
    # a wind parameter's range in ranges (older configurations) is the windy flights' range
    old = ScenarioConfig(ranges={"SIM_WIND_SPD": (0, 8), "SIM_GYR1_RND": (0, 0.5)})
    assert old.wind["speed"] == (0.0, 8.0) and old.ranges == {"SIM_GYR1_RND": (0.0, 0.5)}
    # no wind draw: the wind parameters are drawn or fixed for every flight, as before
    still = ScenarioConfig(wind=None, ranges={"SIM_WIND_SPD": (1, 2)},
                           params={"SIM_WIND_TURB": 1.0})
    s = sample_scenario(0, 0, still)
    assert 1 <= s.params["SIM_WIND_SPD"] <= 2 and s.params["SIM_WIND_TURB"] == 1.0


@pytest.mark.parametrize("kwargs, needle", [
    ({"frames": {"quad": 1}}, "frames: unknown 'quad'; choose from +, x, hexa, hexax, octa"),
    ({"frames": {"x": -1}}, "share of 'x' must be a number >= 0"),
    ({"frames": []}, "frames must name at least one frame"),
    ({"params": {"FRAME_TYPE": 1}}, "FRAME_TYPE is set by each flight's frame"),
    ({"ranges": {"FRAME_CLASS": (1, 2)}}, "FRAME_CLASS is set by each flight's frame"),
    ({"params": {"SIM_WIND_SPD": 5}}, "SIM_WIND_SPD is both drawn (wind) and fixed"),
    ({"wind": {"calm": 1.5}}, "the share of calm flights, --calm-share"),
    ({"wind": {"gusts": 1}}, "wind: unknown setting 'gusts'"),
    ({"wind": {"speed": (5, 1)}}, "wind speed (SIM_WIND_SPD) must be"),
    ({"wind": {"turbulence": (-1, 1)}}, "wind turbulence (SIM_WIND_TURB) must be"),
    ({"wind": {"direction": (0, 400)}}, "SIM_WIND_DIR = 400 is out of range"),
    ({"wind": {"speed": (0, 200)}}, "SIM_WIND_SPD = 200 is out of range"),
    ({"wind": "strong"}, "wind must be a mapping"),
    ({"wind": {"speed": (0, 5)}, "ranges": {"SIM_WIND_SPD": (0, 8)}}, "given twice"),
])
def test_bad_frame_and_wind_settings_are_one_line_errors(kwargs, needle):
    with pytest.raises(GenerateError) as err:
        ScenarioConfig(**kwargs)
    assert needle in str(err.value) and "\n" not in str(err.value)


def _args(*argv: str) -> argparse.Namespace:
    from tlm_process.commands import generate as command

    ap = argparse.ArgumentParser(prog="tlm")
    command.add_parser(ap.add_subparsers(dest="command", required=True))
    return ap.parse_args(["generate", "--flights", "1", "--out", "ds", *argv])


def _build(*argv: str) -> ScenarioConfig:
    from tlm_process.commands.generate import build_config

    return build_config(_args(*argv))


def test_command_line_frames_and_wind():
    assert _build("--frame", "x").frames == {"+": 0.0, "x": 1.0, "hexa": 0.0, "hexax": 0.0,
                                              "octa": 0.0}
    assert _build("--frame", "+, x").frames["+"] == 1.0
    assert _build("--frame", "+=0.3,x=0.7").frames["x"] == 0.7
    c = _build("--calm-share", "0", "--wind-speed", "4:8", "--wind-dir", "45",
               "--wind-turb", "1:2")
    assert c.wind == {"calm": 0.0, "speed": (4.0, 8.0), "direction": (45.0, 45.0),
                      "turbulence": (1.0, 2.0)}
    # --range of a wind parameter keeps working: the windy flights' range
    c = _build("--range", "SIM_WIND_SPD=0:3", "--range", "SIM_GYR1_RND=0:1")
    assert c.wind["speed"] == (0.0, 3.0) and c.ranges["SIM_GYR1_RND"] == (0.0, 1.0)
    assert "SIM_WIND_SPD" not in c.ranges
    # --no-env: no wind draw, as before (a --param fixes it for every flight)
    c = _build("--no-env", "--param", "SIM_WIND_SPD=5", "--param", "SIM_WIND_DIR=45")
    assert c.wind is None and c.ranges == {} and c.params["SIM_WIND_SPD"] == 5.0
    s = sample_scenario(0, 0, c)
    assert (s.params["SIM_WIND_SPD"], s.params["SIM_WIND_DIR"]) == (5.0, 45.0)


def test_config_file_frames_and_wind_and_flags_over_it(tmp_path):
    f = tmp_path / "gen.yaml"
    f.write_text("frames: {+: 0.2, x: 0.8}\nwind: {calm: 0.5, speed: [2, 6]}\n")
    c = _build("--config", str(f))
    assert (c.frames["+"], c.frames["x"]) == (0.2, 0.8)
    assert c.wind == {**DEFAULT_WIND, "calm": 0.5, "speed": (2.0, 6.0)}
    c = _build("--config", str(f), "--frame", "+", "--wind-speed", "1:2", "--calm-share", "0")
    assert c.frames["+"] == 1.0 and c.frames["x"] == 0.0
    assert c.wind["speed"] == (1.0, 2.0) and c.wind["calm"] == 0.0
    f.write_text("wind: null\n")
    assert _build("--config", str(f)).wind is None


@pytest.mark.parametrize("argv, needle", [
    (["--frame", "quad"], "frames: unknown 'quad'"),
    (["--frame", ","], "--frame expects NAME"),
    (["--frame", "+,x=1"], "give every frame a share"),
    (["--frame", "x=a"], "--frame expects NAME=SHARE"),
    (["--wind-speed", "fast"], "--wind-speed expects LOW:HIGH or one value"),
    (["--wind-speed", "5:2"], "wind speed (SIM_WIND_SPD) must be"),
    (["--wind-turb=-1:1"], "wind turbulence (SIM_WIND_TURB) must be"),
    (["--wind-dir=-400:0"], "SIM_WIND_DIR = -400 is out of range"),
    (["--calm-share", "2"], "must be a number in [0, 1]"),
    (["--wind-speed", "1:2", "--range", "SIM_WIND_SPD=0:3"],
     "give --wind-speed or --range SIM_WIND_SPD, not both"),
    (["--no-env", "--calm-share", "0.5"], "--no-env draws no wind: drop --calm-share"),
    (["--param", "SIM_WIND_SPD=5"], "--wind-speed 5 --calm-share 0"),
    (["--param", "FRAME_TYPE=1"], "--frame x"),
])
def test_bad_frame_and_wind_flags_are_one_line_errors(tmp_path, capsys, argv, needle):
    from tlm_process.cli import main

    assert main(["generate", "--flights", "1", "--out", str(tmp_path / "ds"), "--no-progress",
                 *argv]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.startswith("tlm: error:") and err.count("\n") == 1, err
    assert not (tmp_path / "ds").exists()  # refused before anything is written


def test_manifest_columns_from_journal_entries():
    """manifest_frame reads frame and wind from each flight's parameters; a record of a tlm
    before frames (no FRAME_* and no frame) is a '+' flight; a failed flight without a
    scenario has empty columns."""
    cfg = ScenarioConfig(**FAST, wind={"calm": 0.5})
    scen = [sample_scenario(4, i, cfg) for i in range(12)]
    old = {k: v for k, v in scen[0].to_dict().items() if k != "frame"}
    old["params"] = {"SIM_WIND_SPD": 3.0, "SIM_WIND_DIR": 90.0, "SIM_WIND_TURB": 0.5}
    entries = {i: {"flight": i, "status": "ok", "scenario": s.to_dict()}
               for i, s in enumerate(scen)}
    entries[12] = {"flight": 12, "status": "ok", "scenario": old}
    entries[13] = {"flight": 13, "status": "failed", "scenario": None}
    df = manifest_frame(entries).set_index("flight")
    for i, s in enumerate(scen):
        row, c = df.loc[i], s.conditions
        assert row["frame"] == s.frame and row["calm"] == c["calm"]
        assert (row["frame_class"], row["frame_type"]) == (FRAMES[s.frame].frame_class,
                                                           FRAMES[s.frame].frame_type)
        for col in ("wind_spd", "wind_turb"):
            assert row[col] == c[col]
        assert (math.isnan(row["wind_dir"]) if c["calm"]
                else row["wind_dir"] == s.params["SIM_WIND_DIR"])
    assert df["calm"].any() and not df["calm"].iloc[:12].all()
    assert tuple(df.loc[12, ["frame", "frame_class", "frame_type", "calm", "wind_spd"]]) == (
        "+", 1, 0, False, 3.0)
    assert df.loc[13, list(CONDITION_COLUMNS)].isna().all()
    assert Scenario.from_dict(old).frame == "+"
    assert str(df["frame_class"].dtype) == "Int64" and str(df["calm"].dtype) == "boolean"


def test_an_edited_frame_is_refused_when_flown_again():
    s = sample_scenario(0, 0, ScenarioConfig(**FAST, frames={"+": 1}))
    bad = Scenario.from_dict({**s.to_dict(), "frame": "x"})
    with pytest.raises(GenerateError, match="frame 'x', but its parameters"):
        bad.realise()
    assert flight_conditions({"FRAME_CLASS": 7})["frame"] is None


def test_report_counts_frames_and_wind():
    rep = GenerateReport(out=None, flights=3, frames={"+": 2, "x": 1}, calm=1, windy=2)
    assert "frames, wind       + 2, x 1; 1 calm, 2 windy" in rep.lines()


def test_a_data_set_records_frame_and_wind_and_flies_them_again(tmp_path):
    """Needs X-frame flights: the frame core must accept FRAME_TYPE 1."""
    ds = tmp_path / "ds"
    config = ScenarioConfig(kinds={"none": 1.0}, **FAST, frames={"+": 1, "x": 1},
                            wind={"calm": 0.5})
    rep = generate(GenerateOptions(out=ds, flights=4, seed=11, config=config, tables=["GPS"],
                                   executor="thread", workers=1, progress=False))
    assert (rep.ok, rep.failed) == (4, 0)
    df = pd.read_parquet(ds / "manifest.parquet").set_index("flight")
    entries, _ = read_journal(ds)
    for i in range(4):
        sc = Scenario.from_dict(entries[i]["scenario"])
        assert df.loc[i, "frame"] == sc.frame and df.loc[i, "calm"] == sc.conditions["calm"]
        spec = scenario_from_manifest(ds, i)
        for name in ("FRAME_CLASS", "FRAME_TYPE", *WIND_PARAMS.values()):
            assert spec.params[name] == sc.params.get(name, spec.params.defaults()[name])
    assert rep.frames == df["frame"].value_counts().to_dict()
    assert (rep.calm, rep.windy) == (int(df["calm"].sum()), int((~df["calm"]).sum()))
    assert set(df["frame"]) == {"+", "x"} and rep.calm and rep.windy


def test_fly_frame_flag(tmp_path, capsys):
    """``tlm fly --frame x`` flies FRAME_CLASS 1 / FRAME_TYPE 1 (needs the frame core)."""
    from tlm_process.cli import main

    out = tmp_path / "x"
    assert main(["fly", "--frame", "x", "--out", str(out), "--format", "parquet",
                 "--no-plot"]) == 0
    params = json.loads((out / "meta.json").read_text())["params"]
    assert (params["FRAME_CLASS"], params["FRAME_TYPE"]) == (1, 1)


@pytest.mark.parametrize("argv, needle", [
    (["--frame", "quad"], "--frame: unknown frame 'quad'; choose from +, x, hexa, hexax, octa"),
    (["--frame", "x", "--param", "FRAME_TYPE=0"],
     "--frame x sets FRAME_TYPE 1, but --param sets FRAME_TYPE=0"),
    (["--frame", "x", "--from-manifest", "ds", "--flight", "0"],
     "--from-manifest flies the data set's own scenario: drop --frame"),
])
def test_fly_frame_mistakes_are_one_line_errors(tmp_path, capsys, argv, needle):
    from tlm_process.cli import main

    assert main(["fly", "--out", str(tmp_path / "o"), "--no-plot", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1


def test_fly_frame_sets_the_frame_parameters():
    from tlm_process.commands.fly import _frame_params

    assert _frame_params("X", {}) == {"FRAME_CLASS": 1.0, "FRAME_TYPE": 1.0}
    assert _frame_params("+", {"FRAME_TYPE": 0.0}) == {"FRAME_CLASS": 1.0, "FRAME_TYPE": 0.0}
    assert _frame_params(None, {"FRAME_TYPE": 1.0}) == {}
    with pytest.raises(UsageError, match="--param sets FRAME_CLASS=2"):
        _frame_params("x", {"FRAME_CLASS": 2.0})


def test_params_file_fixes_its_parameters_for_every_flight(tmp_path):
    """``--params vehicle.parm`` (a ``tlm fit`` vehicle): its modelled changes are fixed
    parameters of every flight (a drawn range of the same name gives way), --param beats it,
    and its frame is left to --frame."""
    parm = tmp_path / "v.parm"
    parm.write_text("TLM_VIB_ACC_X 1.5\nSIM_ACC1_RND 5\nTLM_HOVER_THR 0.45\nFRAME_TYPE 1\n")
    cfg = _build("--params", str(parm), "--param", "TLM_HOVER_THR=0.42")
    assert cfg.params["TLM_VIB_ACC_X"] == 1.5 and cfg.params["SIM_ACC1_RND"] == 5.0
    assert cfg.params["TLM_HOVER_THR"] == 0.42
    assert "FRAME_TYPE" not in cfg.params and "SIM_ACC1_RND" not in cfg.ranges
    with pytest.raises(UsageError, match="no such file"):
        _build("--params", str(tmp_path / "missing.parm"))
