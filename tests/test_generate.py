"""``tlm generate``: the data set layout, re-flying from the manifest, resuming, failures,
Ctrl-C, and the same bytes from every executor (threads, processes, a Dask LocalCluster).

Flights are kept short: built-in missions with one RC fault 5-10 s after AUTO, so the
failsafe sends the copter home at once (~100 s simulated, well under a second each).
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import math
import os
import re
import shutil
from pathlib import Path

import pandas as pd
import pytest

from tlm_process.generate import (
    GenerateError,
    GenerateOptions,
    ScenarioConfig,
    generate,
    read_header,
    read_journal,
    runner,
    scenario_from_manifest,
)
from tlm_process.generate.executors import ExecutorHandle
from tlm_process.generate.parts import fault_table, table_part, to_parquet_bytes
from tlm_process.generate.writer import DatasetWriter

SHORT = ScenarioConfig(kinds={"single": 1.0}, fault_weights={"rc": 1.0},
                       single_start_s=(5.0, 10.0), missions={"builtin": 1.0})
SEED = 5


def _gen(out: Path, n: int = 3, **kw) -> object:
    opts = {"executor": "thread", "workers": 2, **kw}
    return generate(GenerateOptions(out=out, flights=n, seed=SEED, config=SHORT, progress=False,
                                    **opts))


def _flight_of(part: str) -> int:
    return int(re.search(r"flight-(\d+)", part).group(1))


def _parts(ds: Path) -> dict[str, bytes]:
    """Every table/fault part and .bin of a data set, by path relative to it."""
    files = list(ds.glob("*.parquet/flight-*.parquet")) + list(ds.glob("bin/*.bin"))
    return {str(p.relative_to(ds)): p.read_bytes() for p in sorted(files)}


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    ds = tmp_path_factory.mktemp("gen") / "ds"
    rep = _gen(ds, bin_log=True)
    assert (rep.ok, rep.failed, rep.state) == (3, 0, "complete")
    return ds


def test_dataset_layout_reads_whole_with_pandas(dataset):
    gps = pd.read_parquet(dataset / "GPS.parquet")
    assert list(gps.columns[:2]) == ["flight", "TimeUS"]
    assert sorted(gps["flight"].unique()) == [0, 1, 2]
    assert all(g["TimeUS"].is_monotonic_increasing for _, g in gps.groupby("flight"))
    imu = pd.read_parquet(dataset / "IMU.parquet")
    assert sorted(imu["I"].unique()) == [0, 1] and str(imu["AccX"].dtype) == "float32"

    faults = pd.read_parquet(dataset / "faults.parquet")
    assert list(faults["flight"]) == [0, 1, 2] and set(faults["type"]) == {"rc"}
    assert (faults["label"] == 4).all()
    assert (faults["start_time_us"] >= faults["start"] * 1e6).all()
    assert json.loads(faults["params_start"].iloc[0]) == {"SIM_RC_FAIL": 1.0}

    manifest = pd.read_parquet(dataset / "manifest.parquet")
    entries, bad = read_journal(dataset)
    assert bad == 0 and list(manifest["status"]) == ["ok"] * 3
    assert list(manifest["seed"]) == [entries[i]["scenario"]["seed"] for i in range(3)]
    header = read_header(dataset)
    assert header["state"] == "complete" and header["counts"] == {"ok": 3, "failed": 0,
                                                                   "missing": 0}
    assert header["seed"] == SEED and header["lambda"] == 1.0

    from tlm_sim.flightlog import read_bin

    bin_gps = read_bin(dataset / "bin" / "flight-00000001.bin", ["GPS"])["GPS"]
    assert len(bin_gps) == int((gps["flight"] == 1).sum())


def test_pipeline_reads_the_dataset(dataset):
    ingest = pytest.importorskip("tlm_process.pipeline.ingest")
    flights = ingest.read_flights([dataset])
    assert len(flights) == 3
    assert all(len(f.records) == 1 and f.records[0].label == 4 for f in flights)


def test_a_flight_flown_again_from_the_manifest_gives_identical_parts(dataset):
    from tlm_sim import fly

    spec = scenario_from_manifest(dataset, 2)
    log = fly(spec.mission, faults=spec.schedule, params=spec.params, seed=spec.seed,
              profile=spec.profile)
    for name in ("GPS", "IMU", "RATE", "VIBE", "ATT", "POS"):
        part = to_parquet_bytes(table_part(log.tables[name], log.schemas[name], 2))
        assert part == (dataset / f"{name}.parquet" / "flight-00000002.parquet").read_bytes()
    assert to_parquet_bytes(fault_table(log.faults, 2)) == (
        dataset / "faults.parquet" / "flight-00000002.parquet").read_bytes()


def test_resume_after_a_hard_kill_skips_finished_flights(dataset, tmp_path):
    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    before = _parts(dataset)
    # a hard kill after flight 2's parts were renamed but before its journal line, mid-way
    # through writing another line, with a temporary part lying around
    lines = (ds / "flights.jsonl").read_text().splitlines()
    keep = [ln for ln in lines if json.loads(ln)["flight"] != 2]
    (ds / "flights.jsonl").write_text("\n".join(keep) + '\n{"flight": 3, "sta')
    (ds / "GPS.parquet" / ".flight-00000003.parquet.tmp").write_bytes(b"half")
    rep = _gen(ds, n=4, bin_log=True)
    assert (rep.skipped, rep.ok, rep.failed) == (2, 2, 0)
    after = _parts(ds)
    assert {k: v for k, v in after.items() if "00000003" not in k} == before
    assert not list(ds.glob("*.parquet/.*"))
    entries, bad = read_journal(ds)
    assert bad == 0 and sorted(entries) == [0, 1, 2, 3]
    assert len((ds / "flights.jsonl").read_text().splitlines()) == 4
    rerun = _gen(ds, n=4, bin_log=True)  # nothing left to do
    assert (rerun.skipped, rerun.ran, rerun.state) == (4, 0, "complete")


def test_a_failed_flight_is_recorded_and_flown_again_next_run(tmp_path, monkeypatch):
    import tlm_process.generate.task as task

    original = task.sample_scenario

    def boom(run_seed, flight, cfg):
        if flight == 1:
            raise RuntimeError("boom")
        return original(run_seed, flight, cfg)

    monkeypatch.setattr(task, "sample_scenario", boom)
    ds = tmp_path / "ds"
    rep = _gen(ds)
    assert (rep.ok, rep.failed, rep.state) == (2, 1, "incomplete")
    assert rep.errors == ["flight 1: RuntimeError: boom"]
    entries, _ = read_journal(ds)
    assert entries[1]["status"] == "failed" and "boom" in entries[1]["traceback"]
    assert entries[1]["scenario"] is not None  # filled in by the parent
    assert not list(ds.glob("*.parquet/flight-00000001.parquet"))
    assert read_header(ds)["counts"] == {"ok": 2, "failed": 1, "missing": 0}
    monkeypatch.setattr(task, "sample_scenario", original)
    again = _gen(ds)
    assert (again.skipped, again.ok, again.state) == (2, 1, "complete")


def test_ctrl_c_leaves_a_consistent_dataset(dataset, tmp_path, monkeypatch):
    put = DatasetWriter.put
    calls = {"n": 0}

    def interrupted_put(self, result):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return put(self, result)

    monkeypatch.setattr(DatasetWriter, "put", interrupted_put)
    ds = tmp_path / "ds"
    rep = _gen(ds, n=6, workers=1, bin_log=True)
    assert rep.interrupted and rep.state == "incomplete" and 1 <= rep.ok < 6
    entries, bad = read_journal(ds)
    ok = sorted(f for f, e in entries.items() if e["status"] == "ok")
    assert bad == 0 and len(ok) == rep.ok
    assert sorted(pd.read_parquet(ds / "GPS.parquet")["flight"].unique()) == ok
    assert sorted(pd.read_parquet(ds / "faults.parquet")["flight"].unique()) == ok
    assert read_header(ds)["counts"]["ok"] == rep.ok
    monkeypatch.setattr(DatasetWriter, "put", put)
    rest = _gen(ds, n=6, bin_log=True)
    assert (rest.skipped, rest.ok, rest.state) == (len(ok), 6 - len(ok), "complete")
    first3 = {k: v for k, v in _parts(ds).items() if _flight_of(k) < 3}
    assert first3 == _parts(dataset)


def test_target_fault_ratio_sets_lambda_from_pilot_flights(dataset, tmp_path):
    """λ = γ / α, α the GPS fault share of the pilot flights (the first scenarios at λ = 1:
    here flights 0 and 1 of the fixture data set)."""
    entries, _ = read_journal(dataset)
    fault = sum(entries[i]["summary"]["gps_fault_rows"] for i in (0, 1))
    rows = sum(entries[i]["summary"]["gps_rows"] for i in (0, 1))
    ds = tmp_path / "g"
    rep = _gen(ds, n=2, target_fault_ratio=0.4, pilot_flights=2, pilot_rounds=1)
    assert rep.alpha_pilot == pytest.approx(fault / rows)
    assert rep.lam == pytest.approx(0.4 / (fault / rows)) and rep.lam > 1
    header = read_header(ds)
    assert header["lambda"] == rep.lam and header["settings"]["target_fault_ratio"] == 0.4
    new, _ = read_journal(ds)
    for i in (0, 1):
        old_f = entries[i]["scenario"]["faults"]["faults"][0]
        new_f = new[i]["scenario"]["faults"]["faults"][0]
        assert new[i]["scenario"]["lam"] == rep.lam and new_f["start"] == old_f["start"]
        old_hold, new_hold = old_f["end"] - old_f["start"], new_f["end"] - new_f["start"]
        assert abs(new_hold - old_hold * rep.lam) <= 0.15 + 0.05 * rep.lam  # 0.1 s rounding
    again = _gen(ds, n=3, target_fault_ratio=0.4, pilot_flights=2)  # no new pilot
    assert again.ok == 1 and again.lam == rep.lam and again.alpha_pilot == rep.alpha_pilot


def test_next_lambda_secant_hits_a_power_law():
    """share = c lambda^b: one secant step from two measured points gives the exact lambda."""
    def share(lam):
        return 0.1 * lam**0.7

    pts = [(1.0, share(1.0)), (4.0, share(4.0))]
    lam = runner._next_lambda(pts, 0.3)
    assert share(lam) == pytest.approx(0.3, rel=1e-12)
    # flat or falling share: Eq. 5 from the last point, within a factor 4 of it
    assert runner._next_lambda([(1.0, 0.2), (2.0, 0.2)], 0.4) == pytest.approx(4.0)
    assert runner._next_lambda([(1.0, 0.01), (2.0, 0.001)], 0.5) == pytest.approx(8.0)


def test_pilot_rounds_correct_eq5_for_a_saturating_share(monkeypatch):
    """The fault share saturates with lambda (faults end missions early): Eq. 5's one step
    undershoots, further pilot rounds land within the tolerance and are all recorded."""
    calls = []

    def fake_share(opts, handle, lam, progress):
        calls.append(lam)
        return 1.0 - math.exp(-0.1 * lam)

    monkeypatch.setattr(runner, "_pilot_share", fake_share)
    opts = GenerateOptions(out=Path("unused"), flights=1, config=SHORT, pilot_rounds=4)
    lam, alpha, points = runner._pilot_lambda(opts, None, 0.4, False)
    assert alpha == pytest.approx(1.0 - math.exp(-0.1))
    assert points[1][0] == pytest.approx(0.4 / alpha)  # round 2 flies Eq. 5's lambda
    assert points[1][1] < 0.4 * (1 - runner.PILOT_TOLERANCE)  # ... which undershoots
    assert 1.0 - math.exp(-0.1 * lam) == pytest.approx(0.4, rel=runner.PILOT_TOLERANCE)
    assert [p[0] for p in points] == calls and len(points) <= 4
    one = GenerateOptions(out=Path("unused"), flights=1, config=SHORT, pilot_rounds=1)
    assert runner._pilot_lambda(one, None, 0.4, False)[0] == pytest.approx(0.4 / alpha)


def crashing_job(job):
    """``fly_job``, except that flight 1 kills its worker process (as a crash in native code
    would)."""
    if job["flight"] == 1:
        os._exit(3)
    from tlm_process.generate.task import fly_job

    return fly_job(job)


def test_a_dying_worker_process_fails_only_its_flight(dataset, tmp_path, monkeypatch):
    """Worker processes: the pool is restarted, the lost flights are flown again one at a
    time, the one that kills its worker is recorded; the others are the same bytes as the
    threads wrote (and the fresh workers loaded the compiled flight from the numba cache)."""
    import tlm_process.generate.runner as runner

    monkeypatch.setattr(runner, "fly_job", crashing_job)
    ds = tmp_path / "p"
    rep = _gen(ds, executor="process", workers=2, bin_log=True)
    assert (rep.ok, rep.failed) == (2, 1) and "processes" in rep.executor
    assert rep.errors == ["flight 1: the worker process died while flying it"]
    assert rep.restarts == 2  # flights 0-2 lost together, then flight 1 alone
    expected = {k: v for k, v in _parts(dataset).items() if _flight_of(k) != 1}
    assert _parts(ds) == expected
    assert rep.first_flight_s < 20  # a compile takes 30 s or more


def test_dask_local_cluster_writes_the_same_bytes(dataset, tmp_path):
    pytest.importorskip("distributed")
    dask = _gen(tmp_path / "d", dask_local=2, bin_log=True)
    assert dask.ok == 3 and "Dask LocalCluster" in dask.executor
    assert _parts(tmp_path / "d") == _parts(dataset)
    assert dask.first_flight_s < 20  # workers loaded the compiled flight from the cache


def _cli(argv: list[str]) -> int:
    import argparse

    from tlm_process.commands import generate as command

    ap = argparse.ArgumentParser(prog="tlm")
    command.add_parser(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(argv)
    return args.func(args)


@pytest.mark.parametrize("argv, needle", [
    (["--flights", "0"], "--flights must be a whole number >= 1"),
    (["--flights", "2", "--lambda", "-1"], "lambda must be a finite number > 0"),
    (["--flights", "2", "--target-fault-ratio", "1.5"], "--target-fault-ratio must be"),
    (["--flights", "2", "--kinds", "none=x"], "--kinds expects NAME=SHARE"),
    (["--flights", "2", "--tables", "GPZ"], "did you mean GPS"),
    (["--flights", "2", "--workers", "0"], "--workers must be a whole number >= 1"),
    (["--flights", "2", "--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "1"],
     "cannot reach the Dask scheduler at tcp://127.0.0.1:9"),
])
def test_bad_input_is_a_one_line_error(tmp_path, capsys, argv, needle):
    code = _cli(["generate", "--out", str(tmp_path / "ds"), "--no-progress", *argv])
    err = capsys.readouterr().err
    assert code == 2 and needle in err
    assert err.startswith("tlm: error:") and err.count("\n") == 1


def test_unusable_output_folders_are_one_line_errors(dataset, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    copy = tmp_path / "copy"
    shutil.copytree(dataset, copy)
    config = tmp_path / "short.yaml"  # the fixture's settings, as a --config file
    config.write_text(json.dumps({k: SHORT.to_dict()[k] for k in (
        "kinds", "fault_weights", "single_start_s", "missions")}))
    same = ["--config", str(config), "--bin"]
    cases = [([str(blocker / "ds")], "cannot write to output folder"),
             ([str(foreign)], "holds no tlm data set"),
             ([str(copy), "--seed", "6", *same], "was made with --seed 5 (this run: 6)"),
             ([str(copy), "--seed", "5", "--lambda", "2", *same],
              "other settings (lambda: 1.0 there, 2.0 now)"),
             ([str(copy), "--seed", "5", *same[:2]], "other settings (bin: true there")]
    other = tmp_path / "other"  # made by another simulator source
    shutil.copytree(dataset, other)
    header = json.loads((other / "manifest.json").read_text())
    (other / "manifest.json").write_text(json.dumps({**header, "sim_source": "0123456789abcdef"}))
    cases.append(([str(other), "--seed", "5", *same],
                  "made with simulator source 0123456789abcdef (this tlm: "))
    for out, needle in cases:
        code = _cli(["generate", "--flights", "3", "--no-progress", "--out", *out])
        err = capsys.readouterr().err
        assert code == 2 and needle in err and err.count("\n") == 1, err
    assert (foreign / "notes.txt").read_text() == "mine"
    with pytest.raises(GenerateError, match="another simulator source"):
        scenario_from_manifest(other, 0)
    assert scenario_from_manifest(other, 0, strict=False).seed == read_journal(other)[0][0][
        "scenario"]["seed"]
    with pytest.raises(GenerateError, match="has no flight 7"):
        scenario_from_manifest(dataset, 7)


def test_tlm_fly_from_manifest_reflies_one_flight(dataset, tmp_path, capsys):
    from tlm_process.cli import main

    out = tmp_path / "again"
    assert main(["fly", "--from-manifest", str(dataset), "--flight", "1", "--out", str(out),
                 "--format", "parquet", "--no-plot"]) == 0
    mine = pd.read_parquet(out / "GPS.parquet")
    theirs = pd.read_parquet(dataset / "GPS.parquet")
    theirs = theirs[theirs["flight"] == 1].drop(columns="flight").reset_index(drop=True)
    pd.testing.assert_frame_equal(mine[theirs.columns], theirs, check_dtype=False,
                                  check_exact=True)
    assert json.loads((out / "faults.json").read_text())["faults"][0]["type"] == "rc"
    assert main(["fly", "--from-manifest", str(dataset), "--out", str(out)]) == 2
    assert "--flight" in capsys.readouterr().err
    assert main(["fly", "--from-manifest", str(dataset), "--flight", "1", "--out", str(out),
                 "--fault", "gps:60-80"]) == 2
    assert "drop --fault" in capsys.readouterr().err


def test_pilot_share_is_stratified_by_flight_kind(monkeypatch):
    """Pilots drawn 3 no-fault : 1 paper-style under a configured 1 : 1 mix: the share
    weights each kind's mean rows by its configured share (0.4), not the pilots' mix (0.2)."""
    def fake_fly_job(job):
        kind = "paper" if job["flight"] == 3 else "none"
        return {"flight": job["flight"], "status": "ok", "scenario": {"kind": kind},
                "summary": {"gps_fault_rows": 80 if kind == "paper" else 0, "gps_rows": 100}}

    monkeypatch.setattr(runner, "fly_job", fake_fly_job)
    config = ScenarioConfig(kinds={"none": 1.0, "paper": 1.0})
    opts = GenerateOptions(out=Path("unused"), flights=1, config=config, pilot_flights=4)
    with cf.ThreadPoolExecutor(1) as pool:
        handle = ExecutorHandle(kind="thread", pool=pool, slots=1, description="test")
        assert runner._pilot_share(opts, handle, 1.0, False) == pytest.approx(0.4)
        only_none = GenerateOptions(out=Path("unused"), flights=1, config=config,
                                    pilot_flights=3)  # no paper-style pilot: plain ratio
        assert runner._pilot_share(only_none, handle, 1.0, False) == 0.0


def _read_sorted(ds: Path, table: str) -> pd.DataFrame:
    df = pd.read_parquet(ds / f"{table}.parquet")
    return df.sort_values(["flight", "TimeUS"] if "TimeUS" in df else ["flight", "fault"],
                          kind="stable").reset_index(drop=True)


def test_compact_merges_parts_into_blocks_and_survives_a_killed_compaction(dataset, tmp_path,
                                                                           monkeypatch):
    """Blocks of 2 flights: flights 0-1 and 2 in two files per table; pandas reads the same
    rows; a part left beside its block (killed between rename and deletion) is dropped when
    the data set is opened again; a continued run adds flights that a second compaction
    merges into the existing block, in flight order."""
    from tlm_process.generate import compact
    from tlm_process.generate.compact import block_flights, compact_dataset

    monkeypatch.setattr(compact, "BLOCK_FLIGHTS", 2)
    ds = tmp_path / "c"
    shutil.copytree(dataset, ds)
    before = {t: _read_sorted(ds, t) for t in ("GPS", "IMU", "MODE", "faults")}
    saved = (ds / "GPS.parquet" / "flight-00000002.parquet").read_bytes()
    n_parts = len(list(ds.glob("*.parquet/flight-*.parquet")))
    assert compact_dataset(ds, {0, 1, 2}) == n_parts
    gps_files = sorted(p.name for p in (ds / "GPS.parquet").iterdir())
    assert gps_files == ["flights-00000000-00000001.parquet", "flights-00000002-00000003.parquet"]
    assert [f for f, _ in block_flights(ds / "GPS.parquet" / gps_files[0])] == [0, 1]
    for t, df in before.items():
        pd.testing.assert_frame_equal(_read_sorted(ds, t), df)
    assert compact_dataset(ds, {0, 1, 2}) == 0  # nothing left to merge
    (ds / "GPS.parquet" / "flight-00000002.parquet").write_bytes(saved)  # killed compaction
    writer = DatasetWriter(ds)
    writer.open({**read_header(ds), "flights": 3})
    writer.close()
    assert not (ds / "GPS.parquet" / "flight-00000002.parquet").exists()
    pd.testing.assert_frame_equal(_read_sorted(ds, "GPS"), before["GPS"])
    # continue to 4 flights (flight 3 lands in block 2-3) and compact through the command
    more = _gen(ds, n=4, compact=True, bin_log=True)
    assert more.ok == 1 and more.compacted_parts > 0
    blk = ds / "GPS.parquet" / "flights-00000002-00000003.parquet"
    assert [f for f, _ in block_flights(blk)] == [2, 3]
    assert not list((ds / "GPS.parquet").glob("flight-*.parquet"))
    gps = pd.read_parquet(blk)
    assert gps["flight"].is_monotonic_increasing and set(gps["flight"]) == {2, 3}
    pd.testing.assert_frame_equal(
        _read_sorted(ds, "GPS")[lambda d: d.flight < 3].reset_index(drop=True), before["GPS"])
