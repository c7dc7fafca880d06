"""``tlm generate`` limits and end states: absurd ``--flights`` counts are refused before
anything is written, the to-do list is planned lazily, and flights cut off by the simulator's
time cap are reported (issue 17, items 9 and 10)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import pandas as pd
import pytest

from tlm_process.generate import GenerateOptions, ScenarioConfig, generate, read_header, runner

SHORT = ScenarioConfig(kinds={"single": 1.0}, fault_weights={"rc": 1.0},
                       single_start_s=(5.0, 10.0), missions={"builtin": 1.0})


def _cli(argv: list[str]) -> int:
    import argparse

    from tlm_process.commands import generate as command

    ap = argparse.ArgumentParser(prog="tlm")
    command.add_parser(ap.add_subparsers(dest="command", required=True))
    args = ap.parse_args(argv)
    return args.func(args)


def _gen(out: Path, n: int, config: ScenarioConfig = SHORT, seed: int = 5, **kw):
    return generate(GenerateOptions(out=out, flights=n, seed=seed, config=config,
                                    progress=False, executor="thread", workers=2, **kw))


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    ds = tmp_path_factory.mktemp("lim") / "ds"
    rep = _gen(ds, 3)
    assert (rep.ok, rep.state) == (3, "complete")
    return ds


def _snapshot(ds: Path) -> dict[str, bytes]:
    return {str(p.relative_to(ds)): p.read_bytes() for p in sorted(ds.rglob("*")) if p.is_file()}


def test_absurd_flight_count_is_refused_at_once_and_writes_nothing(small, tmp_path, capsys):
    new = tmp_path / "new"
    t0 = time.perf_counter()
    code = _cli(["generate", "--out", str(new), "--no-progress", "--flights", str(10**12)])
    assert time.perf_counter() - t0 < 1.0
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("tlm: error: --flights must be at most 100_000_000")
    assert "8-digit" in err and err.count("\n") == 1
    assert not new.exists()
    before = _snapshot(small)  # an existing data set is left exactly as it was
    code = _cli(["generate", "--out", str(small), "--no-progress", "--seed", "5",
                 "--flights", str(runner.MAX_FLIGHTS + 1)])
    assert code == 2 and "at most" in capsys.readouterr().err
    assert _snapshot(small) == before


def test_a_huge_run_is_planned_lazily(small, tmp_path, monkeypatch):
    """Continuing a data set with --flights at the limit hands out flight 3 (0-2 are done) at
    once, without building a list of 10^8 flights first."""
    import shutil

    ds = tmp_path / "ds"
    shutil.copytree(small, ds)
    asked: list[int] = []

    def make_job(flight, *a, **kw):
        asked.append(flight)
        raise KeyboardInterrupt  # as Ctrl-C: hand out nothing more

    monkeypatch.setattr(runner, "make_job", make_job)
    t0 = time.perf_counter()
    rep = _gen(ds, runner.MAX_FLIGHTS)
    assert time.perf_counter() - t0 < 5.0
    assert asked == [3] and rep.interrupted and rep.skipped == 3 and rep.ran == 0
    header = read_header(ds)
    assert header["flights"] == runner.MAX_FLIGHTS and header["state"] == "incomplete"
    assert header["counts"] == {"ok": 3, "failed": 0, "missing": runner.MAX_FLIGHTS - 3}


def test_fewer_flights_than_the_data_set_holds_says_what_completes_it(small, tmp_path):
    import shutil

    ds = tmp_path / "ds"
    shutil.copytree(small, ds)
    header = json.loads((ds / "manifest.json").read_text())
    (ds / "manifest.json").write_text(json.dumps({**header, "flights": 5}))  # an earlier 5
    rep = _gen(ds, 2)
    assert (rep.skipped, rep.ran, rep.state, rep.dataset_flights) == (2, 0, "incomplete", 5)
    assert any("an earlier run asked for 5 flights" in ln and "--flights 5" in ln
               for ln in rep.lines())
    rest = _gen(ds, 5)
    assert (rest.skipped, rest.ok, rest.state) == (3, 2, "complete")
    assert not any("earlier run" in ln for ln in rest.lines())


def test_flights_cut_off_by_the_time_cap_are_reported(tmp_path):
    """Flight 0 of seed 0 draws WPNAV_SPEED ~0.12 m/s and cannot fly its mission before the
    time cap; flights 1 and 2 (2-2.6 m/s) fly theirs and land."""
    slow = ScenarioConfig(kinds={"none": 1.0}, missions={"builtin": 1.0},
                          ranges={"WPNAV_SPEED": (10.0, 300.0)})
    rep = _gen(tmp_path / "ds", 3, config=slow, seed=0)
    assert (rep.ok, rep.failed, rep.capped) == (3, 0, [0])
    line = next(ln for ln in rep.lines() if ln.startswith("capped"))
    assert "1 flight still armed at the time cap, cut off (flight 0)" in line
    frame = pd.read_parquet(tmp_path / "ds" / "manifest.parquet")
    assert list(frame["end_reason"]) == ["time_cap", "landed", "landed"]
    assert list(frame["status"]) == ["ok"] * 3  # valid tables, just cut off
    assert read_header(tmp_path / "ds")["runs"][-1]["capped"] == 1


def test_the_scheduler_docs_and_help_say_dask_is_unauthenticated(capsys):
    doc = (Path(__file__).resolve().parents[1] / "docs" / "generate.md").read_text()
    section = doc.split("### Dask security", 1)[1].split("\n#", 1)[0]
    for needle in ("**unauthenticated**", "can run code on every worker",
                   "--host 127.0.0.1", "ssh -N -L 8786:127.0.0.1:8786", "tls://"):
        assert needle in section, needle
    assert "--scheduler tcp://10." not in doc  # no example pointing at a LAN address
    with pytest.raises(SystemExit):
        _cli(["generate", "--help"])
    assert "unauthenticated" in " ".join(capsys.readouterr().out.split())
