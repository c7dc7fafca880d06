"""The tlm command line: fly writes ArduPilot-named tables and faults.json, fault schedules
(paper, file, shorthand) reach the flight, user mistakes are one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from tlm_process.cli import COMMANDS, main
from tlm_process.cli import _fault_lines as summary_lines
from tlm_sim import builtin_mission
from tlm_sim.faults import FaultSchedule
from tlm_sim.flightlog import SCHEMAS
from tlm_sim.geo import latlon_to_ne


def test_fly_writes_tables_and_summary(tmp_path, capsys):
    out = tmp_path / "f"
    assert main(["fly", "--mission", "2", "--seed", "7", "--out", str(out), "--no-plot"]) == 0
    text = capsys.readouterr().out
    assert "waypoints reached" in text and "final mode" in text
    for name in ("GPS", "IMU", "RATE", "VIBE", "MODE", "ATT"):
        csv = pd.read_csv(out / f"{name}.csv")
        assert tuple(csv.columns) == SCHEMAS[name].columns
        pq = pd.read_parquet(out / f"{name}.parquet")
        assert len(pq) == len(csv) > 0
    imu = pd.read_csv(out / "IMU.csv")
    assert sorted(imu.I.unique()) == [0, 1]
    assert (out / "summary.json").exists()
    assert json.loads((out / "faults.json").read_text()) == {"faults": []}


def test_fly_csv_only_and_param_and_in_flight_change(tmp_path):
    out = tmp_path / "g"
    rc = main(["fly", "--out", str(out), "--format", "csv", "--no-plot",
               "--param", "WPNAV_SPEED=500", "--set", "60:SIM_GPS1_ENABLE=0"])
    assert rc == 0
    assert (out / "GPS.csv").exists() and not (out / "GPS.parquet").exists()
    gps = pd.read_csv(out / "GPS.csv")
    late = gps[gps.TimeUS > 61e6]
    assert set(late.Status) == {1} and set(late.NSats) == {3}


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["fly", "--out", "X", "--param", "WPNAV_SPED=5"], "did you mean WPNAV_SPEED"),
        (["fly", "--out", "X", "--param", "TLM_MASS=-1"], "TLM_MASS"),
        (["fly", "--out", "X", "--param", "WPNAV_SPEED"], "NAME=VALUE"),
        (["fly", "--out", "X", "--format", "xlsx"], "unknown format"),
        (["fly", "--out", "X", "--mission-file", "/nonexistent/m.waypoints"], "No such file"),
        (["fly", "--out", "X", "--seed", "-3"], "seed"),
        (["fly", "--out", "X", "--set", "1e308:SIM_GPS1_ENABLE=0"], "the longest this flight"),
        (["fly", "--out", "X", "--set", "nan:SIM_GPS1_ENABLE=0"], "between 0 and"),
        (["fly", "--out", "X", "--set", "99999:SIM_GPS1_ENABLE=0"], "between 0 and"),
        (["fly", "--out", "X", "--set", "100:FRAME_CLASS=2"], "cannot change in flight"),
        (["fly", "--out", "X", "--from-manifest", "ds", "--flight", "0", "--seed", "5"],
         "drop --seed"),
        (["fly", "--out", "X", "--from-manifest", "ds", "--flight", "0", "--mission", "3"],
         "drop --mission"),
        (["fly", "--out", "X", "--from-manifest", "ds", "--flight", "0", "--profile", "paper"],
         "drop --profile"),
        (["fly", "--out", "X", "--flight", "2"], "--flight N picks a flight of --from-manifest"),
        (["fly", "--out", "X", "--mission", "2", "--mission-file", "m.txt"], "exclusive"),
    ],
)
def test_user_mistakes_are_one_line_errors(tmp_path, capsys, argv, needle):
    argv = [a if a != "X" else str(tmp_path / "o") for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("argv", [["fly"], ["demo"], ["generate", "--flights", "1"],
                                  ["convert", "x.bin"], ["process", "x"], ["evaluate", "x"],
                                  ["crosscheck", "x.bin"]], ids=lambda a: a[0])
def test_an_empty_out_is_refused_not_the_current_folder(tmp_path, monkeypatch, capsys, argv):
    """``--out "$DIR"`` with DIR unset: refused, nothing written in the current folder."""
    monkeypatch.chdir(tmp_path)
    for empty in ("", " "):
        with pytest.raises(SystemExit) as done:
            main([*argv, "--out", empty])
        assert done.value.code == 2
        assert "argument --out: an empty path" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_unwritable_output_folder(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["fly", "--out", str(blocker / "sub")]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_help_runs_as_a_console_command():
    r = subprocess.run([sys.executable, "-m", "tlm_process.cli", "fly", "--help"],
                       capture_output=True, text=True, check=True)
    assert "--mission" in r.stdout and "--format" in r.stdout
    for text in ("--faults", "--fault SPEC", "--profile", "TYPE:START-END", "TYPE:START+DUR",
                 "wpN", '"faults": [{"fault": "gps"'):
        assert text in r.stdout


@pytest.mark.parametrize("command", [[], *([c] for c in COMMANDS)], ids=["tlm", *COMMANDS])
def test_every_help_is_plain_text(command, capsys):
    """``tlm --help`` says what tlm is and lists every command; no help shows docstring markup
    (reST roles or double backquotes)."""
    with pytest.raises(SystemExit) as done:
        main([*command, "--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith(f"usage: tlm {' '.join(command)}".rstrip())
    for markup in ("``", ":func:", ":class:", ":mod:", ":data:", ":meth:"):
        assert markup not in text
    if not command:
        assert "ArduPilot" in text and "'tlm COMMAND --help'" in text
        assert all(name in text for name in COMMANDS)

# --------------------------------------------------------------------------------------------
# Faults
# --------------------------------------------------------------------------------------------

def _read_flight(out):
    """faults.json records and meta.json of a written flight."""
    faults = json.loads((out / "faults.json").read_text())
    meta = json.loads((out / "meta.json").read_text())
    assert list(faults) == ["faults"]
    assert faults["faults"] == meta["faults"]
    return faults["faults"], meta


def _fault_lines(text: str) -> list[str]:
    return [ln for ln in text.splitlines() if ln.startswith("fault ")]


def test_paper_sequence_writes_four_records_inside_the_flight(tmp_path, capsys):
    out = tmp_path / "p"
    rc = main(["fly", "--mission", "2", "--faults", "paper", "--seed", "3", "--out", str(out),
               "--format", "csv", "--no-plot"])
    assert rc == 0
    records, meta = _read_flight(out)
    schedule = FaultSchedule.paper(3)
    assert [r["label"] for r in records] == [1, 2, 3, 4]
    assert [r["type"] for r in records] == ["gps", "accel", "engine", "rc"]
    m = meta["meta"]
    t_prev = m["armed_s"] * 1e6
    for r, fault in zip(records, schedule, strict=True):
        # the schedule drawn with the flight's seed, applied at the next loop tick
        assert r["start"] == fault.start.value and r["end"] == fault.end.value
        assert 0 <= r["start_time_us"] - fault.start.value * 1e6 < 0.01e6
        assert 0 <= r["end_time_us"] - fault.end.value * 1e6 < 0.01e6
        assert t_prev < r["start_time_us"] < r["end_time_us"] < m["duration_s"] * 1e6
        assert r["end_by"] == "schedule"
        assert r["duration_s"] == pytest.approx((r["end_time_us"] - r["start_time_us"]) * 1e-6)
        t_prev = r["end_time_us"]
    lines = _fault_lines(capsys.readouterr().out)
    assert len(lines) == 4
    for i, (ln, r) in enumerate(zip(lines, records, strict=True)):
        assert ln.split()[:5] == ["fault", str(i + 1), r["type"], "label", str(r["label"])]
        assert f"start {r['start_time_us'] * 1e-6:7.1f} s" in ln
        assert f"duration {r['duration_s']:5.1f} s" in ln


def test_shorthand_waypoint_trigger_and_paper_profile(tmp_path, capsys):
    out = tmp_path / "w"
    rc = main(["fly", "--mission", "2", "--out", str(out), "--format", "csv", "--no-plot",
               "--profile", "paper", "--fault", "gps:wp5-wp8", "--fault", "accel:120+20"])
    assert rc == 0
    records, meta = _read_flight(out)
    assert meta["meta"]["profile"] == "paper"
    assert meta["params"]["RC_FS_TIMEOUT"] == 0.5 and meta["params"]["TLM_PROFILE"] == 1
    gps, accel = records
    assert (gps["type"], gps["label"], gps["start"], gps["end"]) == ("gps", 1, "wp5", "wp8")
    # the GPS fault begins and ends where the vehicle reaches waypoints 5 and 8 (within
    # WPNAV_RADIUS 2 m plus one SIM sample); neighbouring waypoints are ~14 m apart
    wps = builtin_mission(2).waypoints
    for edge, k in (("start", 5), ("end", 8)):
        lat, lon = wps[k - 1][0], wps[k - 1][1]
        n, e = latlon_to_ne(np.array([gps[f"{edge}_true_lat"]]),
                            np.array([gps[f"{edge}_true_lon"]]), lat, lon)
        assert float(np.hypot(n, e)[0]) < 3.0
    g = pd.read_csv(out / "GPS.csv")
    inside = g[(g.TimeUS > gps["start_time_us"] + 0.5e6) & (g.TimeUS < gps["end_time_us"])]
    after = g[g.TimeUS > gps["end_time_us"] + 0.5e6]
    assert len(inside) and set(inside.Status) == {1}
    assert len(after) and (after.Status >= 3).all()  # 3D fix or better again
    assert (accel["start"], accel["end"]) == (120, 140)
    assert accel["duration_s"] == pytest.approx(20.0, abs=0.01)
    assert len(_fault_lines(capsys.readouterr().out)) == 2


def test_yaml_schedule_file(tmp_path, capsys):
    sched = tmp_path / "faults.yaml"
    sched.write_text(
        "faults:\n"
        "  - fault: engine\n"
        "    start: 60\n"
        "    end: 75\n"
        "    params_start: {SIM_ENGINE_MUL: 0.5}\n"
        "  - fault: rc\n"
        "    start: wp10\n")
    out = tmp_path / "y"
    assert main(["fly", "--mission", "3", "--faults", str(sched), "--out", str(out),
                 "--format", "csv", "--no-plot"]) == 0
    records, meta = _read_flight(out)
    engine, rc = records
    assert (engine["type"], engine["label"]) == ("engine", 3)
    assert engine["params_start"] == {"SIM_ENGINE_MUL": 0.5}
    assert engine["params_end"] == {"SIM_ENGINE_MUL": 1.0}
    assert (rc["type"], rc["label"], rc["start"], rc["end"]) == ("rc", 4, "wp10", None)
    # no end: held until the log ends (the radio failsafe's RTL lands and disarms)
    assert rc["end_by"] == "flight end"
    last_us = max(pd.read_csv(out / "ATT.csv").TimeUS.max(), pd.read_csv(out / "IMU.csv")
                  .TimeUS.max())
    assert rc["end_time_us"] >= last_us
    assert meta["meta"]["landed"] is True
    lines = _fault_lines(capsys.readouterr().out)
    assert len(lines) == 2 and "held to the end of the log" in lines[1]


BAD_SCHEDULES = {
    "overlap": (["--fault", "gps:60-110", "--fault", "accel:100-130"], "must not overlap"),
    "end before start": (["--fault", "gps:110-60"], "end 60 s is before start 110 s"),
    "after the flight": (["--fault", "gps:5000-5100"], "after the end of the flight"),
    "beyond the mission": (["--fault", "engine:wp40-wp200"], "beyond the mission's last"),
    "unknown fault": (["--fault", "gsp:60-110"], "did you mean 'gps'?"),
    "bad shorthand": (["--fault", "gps"], "expected TYPE:START-END"),
    "bad duration": (["--fault", "accel:wp5+10"], "needs a start time"),
    "both options": (["--faults", "paper", "--fault", "gps:60-110"], "exclusive"),
    "with --set": (["--fault", "gps:60-110", "--set", "10:SIM_GPS1_ENABLE=0"], "--set cannot"),
    "unknown profile": (["--faults", "paper", "--profile", "papr"], "unknown profile 'papr'"),
    "no such file": (["--faults", "{tmp}/none.json"], "cannot read fault schedule"),
    "file type": (["--faults", "{tmp}/f.txt"], "unsupported fault schedule file type"),
    "unknown key": (["--faults", "{tmp}/key.yaml"], "did you mean 'start'?"),
    "broken yaml": (["--faults", "{tmp}/broken.yml"], "invalid YAML"),
    "broken json": (["--faults", "{tmp}/broken.json"], "invalid JSON"),
    "held, then another": (["--faults", "{tmp}/held.json"], "has no end"),
    "file unknown fault": (["--faults", "{tmp}/type.json"], "did you mean 'engine'?"),
}


@pytest.mark.parametrize("extra, needle", BAD_SCHEDULES.values(), ids=BAD_SCHEDULES)
def test_bad_schedules_are_one_line_errors_before_flying(tmp_path, capsys, extra, needle):
    (tmp_path / "f.txt").write_text("gps:60-110\n")
    (tmp_path / "key.yaml").write_text("faults:\n  - {fault: gps, strat: 60}\n")
    (tmp_path / "broken.yml").write_text("faults: [\n")
    (tmp_path / "broken.json").write_text('{"faults": [}')
    (tmp_path / "held.json").write_text(json.dumps({"faults": [
        {"fault": "rc", "start": 60}, {"fault": "gps", "start": 80, "end": 90}]}))
    (tmp_path / "type.json").write_text(json.dumps({"faults": [
        {"fault": "engin", "start": 60, "end": 90}]}))
    out = tmp_path / "o"
    argv = ["fly", "--mission", "2", "--out", str(out)]
    argv += [a.format(tmp=tmp_path) for a in extra]
    assert main(argv) == 2
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert needle in err and len(err.splitlines()) == 1 and err.startswith("tlm: error: ")
    assert captured.out == "" and not out.exists()  # checked before flying


def test_fault_lines_say_late_held_and_never_started():
    # no flight: a log stand-in with the records fly() would make when the accel fault's
    # waypoints are reached after the engine fault's times (so those fire late, at once)
    schedule = FaultSchedule.from_shorthand(["accel:wp40-wp44", "engine:200-215", "rc:230-"])
    changes = [{"fault": 0, "edge": "start", "time_us": 250_600_000},
               {"fault": 0, "edge": "end", "time_us": 280_000_000},
               {"fault": 1, "edge": "start", "time_us": 280_000_000},
               {"fault": 1, "edge": "end", "time_us": 280_000_000},
               {"fault": 2, "edge": "start", "time_us": None}]

    def rec(kind, label, t0, t1, end_by="schedule"):
        return {"type": kind, "label": label, "start_time_us": t0, "end_time_us": t1,
                "end_by": end_by, "duration_s": (t1 - t0) * 1e-6}

    log = SimpleNamespace(meta={"param_changes": changes}, faults=[
        rec("accel", 2, 250_600_000, 280_000_000), rec("engine", 3, 280_000_000, 280_000_000)])
    first, second, third = summary_lines(log, schedule)
    assert first == ("fault 1 accel  label 2  start   250.6 s  end   280.0 s  duration  29.4 s")
    assert second.startswith("fault 2 engine label 3  start   280.0 s  end   280.0 s  duration "
                             "  0.0 s (late: start due 200 s, end due 215 s;")
    assert third == "fault 3 rc     label 4  never started (the flight ended first)"
    held = SimpleNamespace(meta={"param_changes": changes[:1]},
                           faults=[rec("accel", 2, 250_600_000, 300_000_000, "flight end")])
    only = FaultSchedule.from_shorthand(["accel:wp40-"])
    assert summary_lines(held, only)[0].endswith("(held to the end of the log)")
    assert summary_lines(held, None) == []


def test_demo_flies_the_paper_sequence(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out)]) == 0
    records, meta = _read_flight(out)
    assert [r["label"] for r in records] == [1, 2, 3, 4]
    assert all(r["end_by"] == "schedule" for r in records)
    assert meta["meta"]["mission"] == builtin_mission(1).name and meta["meta"]["seed"] == 1
    assert (out / "GPS.csv").exists() and (out / "GPS.parquet").exists()
    assert (out / "flight.bin").exists()
    text = capsys.readouterr().out
    assert len(_fault_lines(text)) == 4
    # the TLM pipeline ran on the flight: labelled tables with every class present
    gps = pd.read_parquet(out / "tlm" / "GPS.parquet")
    assert sorted(gps.label.unique()) == [0, 1, 2, 3, 4]
    assert "rows per class" in text and (out / "tlm" / "report.json").exists()
