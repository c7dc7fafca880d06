"""Output folders and files are safe (issue 22, "Data safety"): a command never mixes its
output with what a folder already holds, refuses a non-empty folder unless told
``--overwrite`` (and then replaces only what tlm wrote, whole), and checks that its outputs can
be written before its work."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from tests.conftest import reference_path
from tlm_process.cli import main
from tlm_process.cliutil import OUT_MARK, UsageError, check_writable_file, prepare_out

FLY = ["fly", "--mission", "1", "--format", "csv", "--no-plot"]


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def test_prepare_out_rules(tmp_path):
    fresh = prepare_out(tmp_path / "a" / "b", "fly")
    assert (fresh / OUT_MARK).read_text() == "fly\n"
    (fresh / "GPS.csv").write_text("old")
    (fresh / "sub").mkdir()
    (fresh / "sub" / "x").write_text("old")
    with pytest.raises(UsageError, match="not empty .*--overwrite"):
        prepare_out(fresh, "fly")
    assert (fresh / "GPS.csv").exists()
    prepare_out(fresh, "convert", overwrite=True)  # replaced whole: nothing of the old run
    assert sorted(p.name for p in fresh.iterdir()) == [OUT_MARK]
    assert (fresh / OUT_MARK).read_text() == "convert\n"
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("precious")
    with pytest.raises(UsageError, match="not written by tlm .* will not delete"):
        prepare_out(mine, "fly", overwrite=True)
    assert (mine / "notes.txt").read_text() == "precious"
    (tmp_path / "file").write_text("x")
    with pytest.raises(UsageError, match="is a file"):
        prepare_out(tmp_path / "file", "fly")
    hidden = tmp_path / "hidden"
    hidden.mkdir()
    (hidden / ".keep").write_text("")
    prepare_out(hidden, "fly")  # hidden entries do not make a folder non-empty


def test_fly_refuses_a_used_folder_and_overwrite_replaces_it_whole(tmp_path, capsys):
    out = tmp_path / "flight"
    assert main([*FLY, "--out", str(out)]) == 0
    first = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    (out / "trajectory.png").write_bytes(b"from an earlier run with a plot")
    capsys.readouterr()
    assert main([*FLY, "--seed", "3", "--out", str(out)]) == 2
    assert "not empty" in _one_line_error(capsys)
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir() if p.name in first} == first
    assert main([*FLY, "--seed", "3", "--out", str(out), "--overwrite"]) == 0
    assert not (out / "trajectory.png").exists()  # nothing of the earlier run is left
    assert (out / "GPS.csv").is_file() and (out / "faults.json").is_file()


def test_fly_into_a_data_set_or_foreign_folder_is_one_line(tmp_path, capsys):
    ds = tmp_path / "ds"
    ds.mkdir()
    (ds / "manifest.json").write_text("{}")
    (ds / "flights").mkdir()
    assert main([*FLY, "--out", str(ds)]) == 2
    _one_line_error(capsys)
    assert sorted(p.name for p in ds.iterdir()) == ["flights", "manifest.json"]
    assert main([*FLY, "--out", str(ds), "--overwrite"]) == 2
    assert "not written by tlm" in _one_line_error(capsys)
    assert (ds / "manifest.json").exists()


def test_convert_refuses_a_used_folder(tmp_path, capsys):
    src = reference_path("normal_s11.bin")
    out = tmp_path / "conv"
    assert main(["convert", str(src), "--out", str(out), "--types", "GPS"]) == 0
    capsys.readouterr()
    assert main(["convert", str(src), "--out", str(out), "--types", "ATT"]) == 2
    _one_line_error(capsys)
    assert main(["convert", str(src), "--out", str(out), "--types", "ATT",
                 "--overwrite"]) == 0
    assert not list(out.glob("*GPS*")) and list(out.glob("*ATT*"))


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_unwritable_outputs_fail_before_the_work(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        t0 = time.perf_counter()
        assert main(["crosscheck", str(reference_path("normal_s11.bin")),
                     "--json", str(locked / "r.json")]) == 2
        assert time.perf_counter() - t0 < 5.0  # refused before flying
        assert "--json" in _one_line_error(capsys)
    finally:
        locked.chmod(0o700)


def test_check_writable_file(tmp_path):
    check_writable_file(tmp_path / "new.json", "--json")
    with pytest.raises(UsageError, match="is a folder"):
        check_writable_file(tmp_path, "--json")
    with pytest.raises(UsageError, match="no such folder"):
        check_writable_file(tmp_path / "missing" / "r.json", "--json")
    ro = tmp_path / "ro.json"
    ro.write_text("{}")
    ro.chmod(0o400)
    if os.geteuid() != 0:
        with pytest.raises(UsageError, match="permission denied"):
            check_writable_file(ro, "--json")


def test_crosscheck_json_into_a_missing_folder_fails_at_once(tmp_path, capsys):
    t0 = time.perf_counter()
    assert main(["crosscheck", str(reference_path("normal_s11.bin")),
                 "--json", str(tmp_path / "no" / "r.json")]) == 2
    assert time.perf_counter() - t0 < 5.0
    assert "no such folder" in _one_line_error(capsys)
    assert not Path(tmp_path / "no").exists()


@pytest.mark.parametrize("bad", [["--workers", "0"], ["--dask-local", "0"],
                                 ["--scheduler", "bogus"], ["--executor", "thread",
                                                            "--workers", "-1"]])
def test_generate_checks_every_option_before_writing_a_data_set(tmp_path, capsys, bad):
    """A bad executor option is refused before the data set is created, so the corrected
    command is not refused as 'a data set made with other settings'."""
    out = tmp_path / "ds"
    assert main(["generate", "--flights", "1", "--out", str(out), *bad]) == 2
    _one_line_error(capsys)
    assert not out.exists()


def test_generate_reaches_the_scheduler_before_writing(tmp_path, capsys):
    out = tmp_path / "ds"
    assert main(["generate", "--flights", "1", "--out", str(out), "--scheduler",
                 "tcp://127.0.0.1:1", "--connect-timeout", "1"]) == 2
    assert "cannot reach the Dask scheduler" in _one_line_error(capsys)
    assert not out.exists()


@pytest.mark.parametrize("content", [b"", b"hello, not a log\n"])
def test_crosscheck_of_a_file_that_is_no_log_is_one_line(tmp_path, capsys, content):
    f = tmp_path / "x.bin"
    f.write_bytes(content)
    assert main(["crosscheck", str(f)]) == 2
    assert "not an ArduPilot DataFlash log" in _one_line_error(capsys)


def test_info_checks_its_json_first_and_lists_each_fault_once(tmp_path, capsys):
    src = reference_path("combined_s21.bin")
    assert main(["info", str(src), "--json", str(tmp_path / "no" / "i.json")]) == 2
    assert "--json" in _one_line_error(capsys)
    assert main(["info", str(src), "--json", str(tmp_path / "i.json")]) == 0
    import json

    faults = json.loads((tmp_path / "i.json").read_text())["faults"]
    assert [f["type"] for f in faults] == ["gps", "accel", "engine", "rc"]
    assert {f["source"] for f in faults} == {"PARM, sidecar"}
    assert capsys.readouterr().out.count("(label 1)") == 1


def test_a_data_set_from_a_newer_tlm_is_refused_everywhere(tmp_path, capsys):
    """One rule for every reader (issue 22): a generated data set or a processed one whose
    format version is newer than this tlm's is refused in one line (generate, fly
    --from-manifest, process, evaluate)."""
    import json

    ds = tmp_path / "ds"
    assert main(["generate", "--flights", "1", "--out", str(ds), "--workers", "1",
                 "--no-progress", "--kinds", "none=1", "--tables", "GPS"]) == 0
    processed = tmp_path / "p"
    assert main(["process", str(ds), "--out", str(processed), "--quiet", "--tables", "GPS"]) == 0
    capsys.readouterr()
    header = json.loads((ds / "manifest.json").read_text())
    header["format_version"] += 1
    (ds / "manifest.json").write_text(json.dumps(header))
    for argv in (["fly", "--from-manifest", str(ds), "--flight", "0", "--out",
                  str(tmp_path / "f")],
                 ["process", str(ds), "--out", str(tmp_path / "p2")],
                 ["generate", "--flights", "1", "--out", str(ds)]):
        assert main(argv) == 2, argv
        assert "newer tlm" in _one_line_error(capsys) or argv[0] == "generate"
    rep = json.loads((processed / "report.json").read_text())
    rep["version"] += 1
    (processed / "report.json").write_text(json.dumps(rep))
    assert main(["evaluate", str(processed), "--models", "ZeroR", "--table", "GPS"]) == 2
    assert "newer tlm" in _one_line_error(capsys)


def test_an_impossible_target_fault_ratio_is_refused_and_leaves_nothing(tmp_path):
    """A target fault share that needs lambda > 10 is refused (it used to choose 26 without
    a word), and the refused run leaves no data set behind, so the corrected run goes."""
    from tlm_process.generate import GenerateError, GenerateOptions, ScenarioConfig, generate

    out = tmp_path / "ds"
    config = ScenarioConfig(kinds={"none": 0.9, "single": 0.1})
    opts = dict(out=out, flights=1, config=config, tables=["GPS"], workers=1,
                executor="thread", progress=False, pilot_flights=3, pilot_rounds=1)
    with pytest.raises(GenerateError, match="needs lambda = .* more than the 10"):
        generate(GenerateOptions(**opts, target_fault_ratio=0.9))
    assert not out.exists()
    assert generate(GenerateOptions(**opts)).ok == 1


def test_constant_training_features_are_reported(tmp_path, capsys):
    """Min-max scaling maps a feature constant in the training flights to 0 everywhere: tlm
    process says which (stderr and report.json) instead of doing it silently."""
    import json

    from tlm_process.pipeline import MinMaxScaler

    flight = tmp_path / "f"
    assert main([*FLY, "--out", str(flight)]) == 0
    capsys.readouterr()
    assert main(["process", str(flight), "--out", str(tmp_path / "ds"), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "GPS NSats" in err and "scale to 0 everywhere" in err
    rep = json.loads((tmp_path / "ds" / "report.json").read_text())
    assert "NSats" in rep["scaling"]["constant_features"]["GPS"]
    import pandas as pd

    df = pd.DataFrame({"flight": ["a", "a", "b"], "x": [1.0, 1.0, 5.0], "y": [1.0, 2.0, 3.0]})
    assert MinMaxScaler.fit({"T": df}, ["a"]).constant_features() == {"T": ["x"]}
    assert MinMaxScaler.fit({"T": df}, ["a", "b"]).constant_features() == {}


def test_data_sets_carry_a_card(tmp_path, capsys):
    """tlm generate and tlm process write DS/README.md: how it was made, counts, labels and
    every table's columns with units (issue 22)."""
    ds = tmp_path / "ds"
    assert main(["generate", "--flights", "2", "--out", str(ds), "--workers", "1",
                 "--no-progress", "--faults", "paper", "--kinds", "paper=1",
                 "--tables", "GPS,IMU,RATE,VIBE"]) == 0
    card = (ds / "README.md").read_text()
    assert "* flights: 2 asked, 2 written (complete)" in card
    assert "* kinds: paper 2" in card and "| 3 | `engine` | Engine |" in card
    assert "### `GPS.parquet/`" in card and "| `Spd` | m/s |" in card
    out = tmp_path / "p"
    assert main(["process", str(ds), "--out", str(out), "--quiet"]) == 0
    card = (out / "README.md").read_text()
    assert "| 1 | GPS |" in card and "### `IMU.parquet`" in card
    assert "| `GyrX` | rad/s | feature, min-max scaled" in card
    import json

    from tlm_process.pipeline.card import dataset_card

    rep = json.loads((out / "report.json").read_text())
    n_gps = rep["counts"]["GPS"]["1"]
    assert "| 1 | GPS | GPS 1 streams 'no fix'" in card and f"{n_gps:,}" in card
    assert dataset_card(rep).split("## Labels")[1] == card.split("## Labels")[1]


def test_a_fault_ending_at_an_unreachable_waypoint_is_warned(tmp_path, capsys):
    """An engine cut meant to end at waypoint 48 (the copter sits on the ground, so it never
    gets there) lasts to the end of the log: tlm says so on stderr; the summary says 'never
    disarmed', not 'disarmed None s'. tlm fly --help no longer suggests it."""
    assert main([*FLY, "--fault", "engine:wp40-wp48", "--out", str(tmp_path / "f")]) == 0
    cap = capsys.readouterr()
    assert "warning: fault 1 (engine) was to end at waypoint 48" in cap.err
    assert "never disarmed" in cap.out and "None" not in cap.out
    with pytest.raises(SystemExit):
        main(["fly", "--help"])
    assert "engine:wp40-wp48" not in capsys.readouterr().out


def test_process_reads_fault_records_from_the_log_itself(tmp_path, capsys):
    """tlm process takes a lone .bin: tlm's own (its fault MSG lines) and SITL's (its SIM_*
    parameter changes), with the same labels as with the records beside it (issue 22)."""
    import json
    import shutil

    flight = tmp_path / "f"
    assert main(["fly", "--faults", "paper", "--format", "bin", "--no-plot",
                 "--out", str(flight)]) == 0
    lone = tmp_path / "lone"
    lone.mkdir()
    shutil.copy(flight / "flight.bin", lone / "flight.bin")
    sitl = tmp_path / "sitl"
    sitl.mkdir()
    shutil.copy(reference_path("combined_s21.bin"), sitl / "combined_s21.bin")
    counts = {}
    for name, src in (("with", flight / "flight.bin"), ("lone", lone / "flight.bin"),
                      ("sitl", sitl / "combined_s21.bin"),
                      ("sidecar", reference_path("combined_s21.bin"))):
        out = tmp_path / f"p-{name}"
        assert main(["process", str(src), "--out", str(out), "--quiet", "--tables", "GPS"]) == 0
        counts[name] = json.loads((out / "report.json").read_text())["counts"]["GPS"]
    assert counts["with"] == counts["lone"] and counts["sitl"] == counts["sidecar"]
    assert all(int(counts["lone"][str(k)]) > 50 for k in (1, 2, 3, 4))


@pytest.mark.parametrize("command", ["fly", "convert", "process", "crosscheck", "evaluate",
                                     "evaluate --test-on"])
def test_overwrite_never_deletes_an_input_inside_the_output_folder(tmp_path, capsys, command):
    """An input that is the output folder or lies in it is refused (one line, exit 2) before
    --overwrite empties the folder; the input is still there afterwards."""
    import shutil

    out = tmp_path / "out"
    out.mkdir()
    (out / OUT_MARK).write_text(f"{command.split()[0]}\n")  # a folder tlm wrote
    log = out / "rc_s15.bin"
    shutil.copy(reference_path("rc_s15.bin"), log)
    shutil.copy(reference_path("rc_s15.json"), out / "rc_s15.json")
    parm = out / "p.parm"
    parm.write_text("WPNAV_SPEED 600\n")
    (out / "report.json").write_text("{}")
    argv = {"fly": ["fly", "--params", str(parm)],
            "convert": ["convert", str(log)],
            "process": ["process", str(log)],
            "crosscheck": ["crosscheck", str(log)],
            "evaluate": ["evaluate", str(out)],
            "evaluate --test-on": ["evaluate", str(tmp_path / "elsewhere"), "--test-on",
                                   str(log)]}[command]
    (tmp_path / "elsewhere").mkdir()
    before = sorted(p.name for p in out.iterdir())
    assert main([*argv, "--out", str(out), "--overwrite"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds an input of this command" in err[0], err
    assert sorted(p.name for p in out.iterdir()) == before


@pytest.mark.parametrize("command", ["fly --faults", "generate --config", "process sidecar",
                                     "crosscheck --sidecar"])
def test_json_nested_too_deeply_is_one_line(tmp_path, capsys, command):
    """A JSON file nested past Python's recursion limit is a user mistake, not a traceback."""
    import shutil

    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    log = tmp_path / "x.bin"
    shutil.copy(reference_path("rc_s15.bin"), log)
    argv = {"fly --faults": ["fly", "--faults", str(deep), "--out", str(tmp_path / "o")],
            "generate --config": ["generate", "--flights", "1", "--config", str(deep),
                                  "--out", str(tmp_path / "o")],
            "process sidecar": ["process", str(log), "--out", str(tmp_path / "o")],
            "crosscheck --sidecar": ["crosscheck", str(log), "--sidecar", str(deep)]}[command]
    if command == "process sidecar":
        shutil.copy(deep, tmp_path / "x.json")
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("tlm: error: ") and "deep" in err[0], err


@pytest.mark.parametrize("content, needle", [(None, "no such file"),
                                             ("{", "is not a sidecar JSON"),
                                             ('{"faults": []}', "names no mission")])
def test_crosscheck_refuses_a_sidecar_it_cannot_use(tmp_path, capsys, content, needle):
    """An explicit --sidecar is used or refused, never silently replaced by the log's own
    scenario."""
    side = tmp_path / "side.json"
    if content is not None:
        side.write_text(content)
    argv = ["crosscheck", str(reference_path("rc_s15.bin")), "--sidecar", str(side)]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err
