"""A generated data set under kills, full disks, hostile folders and hand-edited manifests
(issue 17 items 3, 4, 8, 11): what readers see, what is deleted, and one-line errors.

A hard kill is a real one: a child process runs ``generate`` / ``compact_dataset`` and calls
``os._exit`` at the kill point (no ``finally``, no handler runs), exactly inside the two
windows where the folder holds more than the journal says: between a flight's files and its
journal line (and between the line and the renames), and between a block's rename and the
deletion of its parts.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from tests.test_generate import SEED, SHORT
from tlm_process.generate import (
    GenerateError,
    GenerateOptions,
    generate,
    read_dataset_table,
    read_header,
    read_journal,
    scenario_from_manifest,
)
from tlm_process.generate import writer as writer_mod
from tlm_process.pipeline.errors import IngestError
from tlm_process.pipeline.ingest import read_dataset

REPO = Path(__file__).resolve().parents[1]


def _gen(out: Path, n: int = 3, **kw) -> object:
    opts = {"executor": "thread", "workers": 1, **kw}
    return generate(GenerateOptions(out=out, flights=n, seed=SEED, config=SHORT, progress=False,
                                    **opts))


def _parts(ds: Path) -> dict[str, bytes]:
    files = list(ds.glob("*.parquet/flight-*.parquet")) + list(ds.glob("bin/*.bin"))
    return {str(p.relative_to(ds)): p.read_bytes() for p in sorted(files)}


def _raw(ds: Path, table: str) -> pd.DataFrame:
    """What plain pandas reads from a table folder."""
    return pd.read_parquet(ds / f"{table}.parquet")


@pytest.fixture(scope="module")
def dataset(tmp_path_factory) -> Path:
    ds = tmp_path_factory.mktemp("robust") / "ds"
    rep = _gen(ds)
    assert (rep.ok, rep.state) == (3, "complete")
    return ds


# --------------------------------------------------------------------------------------------
# item 3: kills inside the unsafe windows
# --------------------------------------------------------------------------------------------

_CHILD = textwrap.dedent('''
    import os, sys
    from pathlib import Path
    point, ds = sys.argv[1], Path(sys.argv[2])
    if point in ("journal", "rename"):
        from tlm_process.generate import GenerateOptions, ScenarioConfig, generate
        from tlm_process.generate.writer import DatasetWriter
        if point == "journal":   # flight 1's files written, its journal line not
            append = DatasetWriter._append
            def _append(self, entry):
                if entry["flight"] == 1:
                    os._exit(9)
                append(self, entry)
            DatasetWriter._append = _append
        else:                    # flight 1's journal line written, its GPS part not renamed
            replace = os.replace
            def _replace(src, dst):
                if str(dst).endswith(os.path.join("GPS.parquet", "flight-00000001.parquet")):
                    os._exit(9)
                replace(src, dst)
            os.replace = _replace
        config = ScenarioConfig(kinds={"single": 1.0}, fault_weights={"rc": 1.0},
                                single_start_s=(5.0, 10.0), missions={"builtin": 1.0})
        generate(GenerateOptions(out=ds, flights=3, seed=5, config=config, progress=False,
                                 executor="thread", workers=1))
    else:                        # a block renamed into place, its parts not yet deleted
        from tlm_process.generate import compact
        unlink = Path.unlink
        def _unlink(self, missing_ok=False):
            if self.parent.name == "GPS.parquet" and self.name.startswith("flight-"):
                os._exit(9)
            unlink(self, missing_ok=missing_ok)
        Path.unlink = _unlink
        compact.compact_dataset(ds, {0, 1, 2}, block=2)
    sys.exit(3)  # the kill point was not reached
''')


def _killed(point: str, ds: Path) -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO), os.environ.get(
        "PYTHONPATH", "")])}
    res = subprocess.run([sys.executable, "-c", _CHILD, point, str(ds)], env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 9, res.stderr[-2000:]


def test_killed_before_a_flights_journal_line_nothing_of_it_is_read(dataset, tmp_path):
    """The issue's case: killed after a flight's table parts, before its fault records and
    journal line. Before: tlm process read that flight's GPS rows with no fault records (all
    labelled normal). Now no reader sees any of it, tlm process refuses the data set unless
    --partial, and the resumed data set is byte-identical to an uninterrupted one."""
    ds = tmp_path / "ds"
    _killed("journal", ds)
    assert read_header(ds)["state"] == "running"
    assert sorted(read_journal(ds)[0]) == [0]
    assert list(ds.glob("*.parquet/.flight-00000001.parquet.tmp"))  # written, not committed
    for table in ("GPS", "IMU", "faults"):  # plain pandas: flight 0 only, nothing of flight 1
        assert set(_raw(ds, table)["flight"]) == {0}
    with pytest.raises(IngestError, match=r"state running.*run the same tlm generate command "
                                          r"again.*--partial"):
        read_dataset(ds)
    flights, info = read_dataset(ds, partial=True)
    assert [f.id for f in flights] == ["ds:0"] and [r.label for r in flights[0].records] == [4]
    assert info["state"] == "running" and info["committed"] == 1 and info["partial"]
    assert set(read_dataset_table(ds, "GPS", partial=True)["flight"]) == {0}
    rep = _gen(ds)
    assert (rep.skipped, rep.ok, rep.state) == (1, 2, "complete")
    assert _parts(ds) == _parts(dataset)
    assert not list(ds.glob("*.parquet/.*"))


def test_killed_between_the_journal_line_and_the_renames_the_flight_rolls_forward(dataset,
                                                                                  tmp_path):
    """Flight 1 is committed (journal line written, fault part renamed first) but its GPS
    part is still under its temporary name: the loader reads it from there, and opening the
    data set again renames it into place."""
    ds = tmp_path / "ds"
    _killed("rename", ds)
    assert sorted(read_journal(ds)[0]) == [0, 1]
    assert set(_raw(ds, "faults")["flight"]) == {0, 1}
    assert set(_raw(ds, "GPS")["flight"]) == {0}  # plain pandas misses flight 1's GPS rows
    gps = read_dataset_table(ds, "GPS", partial=True)
    want = _raw(dataset, "GPS")
    pd.testing.assert_frame_equal(gps, want[want.flight < 2].reset_index(drop=True))
    flights, _ = read_dataset(ds, partial=True)
    assert [len(f.tables["GPS"]) for f in flights] == [
        int((want.flight == f).sum()) for f in (0, 1)]
    rep = _gen(ds)
    assert (rep.skipped, rep.ok, rep.state) == (2, 1, "complete")
    assert _parts(ds) == _parts(dataset)


def test_killed_compaction_is_never_read_twice_and_is_repaired(dataset, tmp_path):
    """Killed after GPS block 0-1 was renamed into place, before its parts were deleted.
    Before: state complete, every such GPS row twice for tlm process. Now the state says
    compacting, the loader reads each flight once (block wins), and the next run repairs."""
    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    _killed("compact", ds)
    assert read_header(ds)["state"] == "compacting"
    gps_dir = ds / "GPS.parquet"
    assert (gps_dir / "flights-00000000-00000001.parquet").exists()
    assert (gps_dir / "flight-00000000.parquet").exists()
    want = _raw(dataset, "GPS")
    assert len(_raw(ds, "GPS")) > len(want)  # plain pandas reads flights 0 and 1 twice
    with pytest.raises(IngestError, match="state compacting"):
        read_dataset(ds)
    got = read_dataset_table(ds, "GPS", partial=True)
    pd.testing.assert_frame_equal(got, want)
    flights, _ = read_dataset(ds, partial=True)
    assert [len(f.tables["GPS"]) for f in flights] == [
        int((want.flight == f).sum()) for f in (0, 1, 2)]
    rep = _gen(ds)
    assert rep.state == "complete" and rep.ran == 0
    assert not (gps_dir / "flight-00000000.parquet").exists()
    pd.testing.assert_frame_equal(_raw(ds, "GPS").sort_values(["flight", "TimeUS"], kind="stable")
                                  .reset_index(drop=True), want)
    pd.testing.assert_frame_equal(read_dataset_table(ds, "GPS"), want)


def test_loader_matches_pandas_on_a_whole_data_set_and_refuses_inconsistent_ones(dataset,
                                                                                 tmp_path):
    for table in ("GPS", "IMU", "MODE", "faults"):
        pd.testing.assert_frame_equal(read_dataset_table(dataset, table), _raw(dataset, table))
    with pytest.raises(GenerateError, match="has no table NOPE"):
        read_dataset_table(dataset, "NOPE")
    # a complete manifest whose journal lacks a flight
    ds = tmp_path / "a"
    shutil.copytree(dataset, ds)
    lines = (ds / "flights.jsonl").read_text().splitlines()
    (ds / "flights.jsonl").write_text("\n".join(lines[:2]) + "\n")
    with pytest.raises(GenerateError, match="inconsistent: its manifest says complete but the "
                                            "journal lists 2 of 3"):
        read_dataset_table(ds, "GPS")
    # a committed flight's part deleted outside tlm
    ds = tmp_path / "b"
    shutil.copytree(dataset, ds)
    (ds / "IMU.parquet" / "flight-00000002.parquet").unlink()
    with pytest.raises(IngestError, match=r"damaged: flight 2's IMU part .* is gone.*run the "
                                          r"same tlm generate command again"):
        read_dataset(ds, partial=True)
    rep = _gen(ds)  # the repair: the flight is forgotten and flown again
    assert (rep.skipped, rep.ok, rep.state) == (2, 1, "complete")
    assert _parts(ds) == _parts(dataset)
    # a part cut short (a power cut): one line naming it; deleted, the next run flies it again
    cut = ds / "GPS.parquet" / "flight-00000001.parquet"
    cut.write_bytes(b"")
    with pytest.raises(GenerateError, match=r"cannot read .*flight-00000001.parquet"):
        read_dataset_table(ds, "GPS")
    cut.unlink()
    assert _gen(ds).ok == 1 and _parts(ds) == _parts(dataset)


def test_a_block_whose_flights_span_several_row_groups_is_read_and_rewritten_right(tmp_path):
    """pyarrow splits a table of more than its row group limit (1M rows) into several row
    groups; a block's flights were mapped one row group each, which misread such blocks."""
    from tlm_process.generate.compact import (
        FLIGHTS_KEY,
        _merge_block,
        block_flights,
        flight_row_groups,
        open_parquet,
    )

    d = tmp_path / "GPS.parquet"
    d.mkdir()
    meta = {FLIGHTS_KEY: json.dumps([[0, 5], [1, 5]]).encode()}
    schema = pa.schema([("flight", pa.int32()), ("TimeUS", pa.int64())], metadata=meta)
    block = d / "flights-00000000-00000009.parquet"
    with pq.ParquetWriter(block, schema) as w:
        for f in (0, 1):
            w.write_table(pa.table({"flight": pa.array([f] * 5, pa.int32()),
                                    "TimeUS": pa.array(range(f * 10, f * 10 + 5), pa.int64())},
                                   schema=schema), row_group_size=4)
    with open_parquet(block) as pf:
        assert flight_row_groups(pf) == {0: [0, 1], 1: [2, 3]}
    part = d / "flight-00000002.parquet"
    pq.write_table(pa.table({"flight": pa.array([2] * 3, pa.int32()),
                             "TimeUS": pa.array([20, 21, 22], pa.int64())}), part)
    assert _merge_block(block, {2: part}) == 1
    out = pq.read_table(block)
    assert out["flight"].to_pylist() == [0] * 5 + [1] * 5 + [2] * 3
    assert out["TimeUS"].to_pylist() == [*range(5), *range(10, 15), 20, 21, 22]
    assert block_flights(block) == [(0, 5), (1, 5), (2, 3)]


def test_a_process_output_killed_while_written_has_no_report(tmp_path, monkeypatch):
    """report.json is written last: a tlm process run killed while writing tables into a
    folder that held an older output leaves no report.json, so tlm evaluate refuses it
    (before: the old report described the new, half-written tables)."""
    from tlm_process.evaluate.data import EvaluateError, load_dataset
    from tlm_process.pipeline.process import Dataset, write_dataset

    df = pd.DataFrame({"flight": ["a", "a"], "split": ["train", "train"], "TimeUS": [1, 2],
                       "label": [0, 1], "x": [0.0, 1.0]})
    ds = Dataset({"GPS": df, "IMU": df}, {"GPS": ["x"], "IMU": ["x"]}, ["a"], [], None)
    out = tmp_path / "p"
    write_dataset(ds, out)
    assert load_dataset(out).tables["GPS"]["x"].tolist() == [0.0, 1.0]
    calls = {"n": 0}
    original = pd.DataFrame.to_parquet

    def killed(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt  # stands for the kill: nothing after it runs
        return original(self, *a, **k)

    monkeypatch.setattr(pd.DataFrame, "to_parquet", killed)
    with pytest.raises(KeyboardInterrupt):
        write_dataset(Dataset({n: df.assign(x=[5.0, 6.0]) for n in ("GPS", "IMU")},
                              ds.features, ["a"], [], None), out)
    with pytest.raises(EvaluateError, match="no report.json"):
        load_dataset(out)
    assert not list(out.glob(".*"))


def test_tlm_process_refuses_a_killed_data_set_and_records_partial(dataset, tmp_path, capsys):
    from tlm_process.cli import main

    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    header = json.loads((ds / "manifest.json").read_text())
    (ds / "manifest.json").write_text(json.dumps({**header, "state": "running"}))
    code = main(["process", str(ds), "--out", str(tmp_path / "p"), "--plots", "0", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "state running" in err and "--partial" in err
    code = main(["process", str(ds), "--out", str(tmp_path / "p"), "--plots", "0", "--quiet",
                 "--partial"])
    err = capsys.readouterr().err
    assert code == 0 and "tlm: warning:" in err and "3 finished of 3 flights" in err
    report = json.loads((tmp_path / "p" / "report.json").read_text())
    assert report["inputs"]["partial"] is True
    assert report["inputs"]["generated"][0]["state"] == "running"


# --------------------------------------------------------------------------------------------
# item 4: nothing outside tlm's own files is deleted
# --------------------------------------------------------------------------------------------

def test_dotfiles_and_foreign_names_survive_open_and_resume(dataset, tmp_path):
    """Before: every dotfile at the top and every hidden file in a table folder was deleted
    when the data set was opened."""
    out = tmp_path / "only-dotfiles"
    out.mkdir()
    (out / ".env").write_text("SECRET=1")
    (out / ".gitignore").write_text("*\n")
    rep = _gen(out, n=1)
    assert rep.state == "complete"
    assert (out / ".env").read_text() == "SECRET=1" and (out / ".gitignore").exists()
    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    keep = [ds / ".env", ds / "GPS.parquet" / ".keep", ds / "GPS.parquet" / "README",
            ds / "GPS.parquet" / ".flight-x.parquet.tmp"]
    for p in keep:
        p.write_text("mine")
    (ds / "GPS.parquet" / ".flight-00000009.parquet.tmp").write_bytes(b"tlm's, half written")
    (ds / ".manifest.json.tmp").write_text("tlm's")
    rep = _gen(ds)
    assert rep.state == "complete"
    assert all(p.read_text() == "mine" for p in keep)
    assert not (ds / "GPS.parquet" / ".flight-00000009.parquet.tmp").exists()
    assert not (ds / ".manifest.json.tmp").exists()


@pytest.mark.parametrize("folder", ["bin", "GPS.parquet"])
def test_a_symlinked_table_or_bin_folder_is_refused_and_its_target_kept(dataset, tmp_path,
                                                                        folder):
    """Before: resuming deleted the files in a symlinked folder's target (parts of flights
    without a journal line, hidden files)."""
    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    target = tmp_path / "elsewhere"
    if (ds / folder).exists():
        shutil.copytree(ds / folder, target)
        shutil.rmtree(ds / folder)
    else:
        target.mkdir()
    victims = [target / "flight-00000007.parquet", target / "flight-00000007.bin",
               target / ".secret"]
    for p in victims:
        p.write_text("not tlm's")
    (ds / folder).symlink_to(target, target_is_directory=True)
    with pytest.raises(GenerateError, match="is a symbolic link") as exc:
        _gen(ds)
    assert "\n" not in str(exc.value)
    assert all(p.read_text() == "not tlm's" for p in victims)
    with pytest.raises(GenerateError, match="is a symbolic link"):
        read_dataset_table(ds, "faults")


# --------------------------------------------------------------------------------------------
# item 8: full disk, non-UTF-8 --out
# --------------------------------------------------------------------------------------------

def _full_disk_on(flight: int, monkeypatch) -> None:
    write = writer_mod._write_file

    def full(path: Path, data: bytes) -> None:
        if f"flight-{flight:08d}" in path.name and "IMU" in str(path.parent.name):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        write(path, data)

    monkeypatch.setattr(writer_mod, "_write_file", full)


def test_a_full_disk_is_one_line_with_a_closed_manifest_and_resumes(dataset, tmp_path,
                                                                    monkeypatch, capsys):
    from tlm_process.cli import main

    _full_disk_on(1, monkeypatch)
    ds = tmp_path / "ds"
    with pytest.raises(GenerateError, match="cannot write flight 1 .*No space left on device"
                                            ".*run the same command again") as exc:
        _gen(ds)
    assert "\n" not in str(exc.value)
    header = read_header(ds)
    assert header["state"] == "incomplete" and header["counts"]["ok"] == 1
    assert not list(ds.glob("*.parquet/.*")) and not list(ds.glob("*.parquet/*00000001*"))
    # the same through the command line: one line, exit 2
    code = main(["generate", "--flights", "2", "--out", str(tmp_path / "cli"), "--kinds",
                 "single=1", "--missions", "builtin=1", "--no-progress", "--executor",
                 "thread", "--workers", "1"])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("tlm: error: cannot write flight 1")
    assert err.count("\n") == 1 and "Traceback" not in err
    assert read_header(tmp_path / "cli")["state"] == "incomplete"
    monkeypatch.undo()
    rep = _gen(ds)
    assert (rep.skipped, rep.ok, rep.state) == (1, 2, "complete")
    assert _parts(ds) == _parts(dataset)


def test_a_disk_too_full_for_the_manifest_says_so_in_one_line(tmp_path, monkeypatch):
    _full_disk_on(0, monkeypatch)

    def no_header(path, doc):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    ds = tmp_path / "ds"
    ds.mkdir()
    header_writes = {"n": 0}
    real = writer_mod.write_json_atomic

    def first_only(path, doc):  # the header of open() is written, the closing one is not
        header_writes["n"] += 1
        (real if header_writes["n"] == 1 else no_header)(path, doc)

    monkeypatch.setattr(writer_mod, "write_json_atomic", first_only)
    with pytest.raises(GenerateError, match="cannot write flight 0 .*then: cannot close data "
                                            "set .*still says running") as exc:
        _gen(ds, n=1)
    assert "\n" not in str(exc.value)


def test_a_non_utf8_out_folder_works(tmp_path, capsys):
    from tlm_process.cli import main

    out = os.fsdecode(os.fsencode(str(tmp_path)) + b"/ds\xff")
    code = main(["generate", "--flights", "1", "--out", out, "--kinds", "single=1",
                 "--missions", "builtin=1", "--no-progress", "--executor", "thread",
                 "--workers", "1", "--compact"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "ds\\udcff (complete)" in captured.out
    assert read_header(Path(out))["state"] == "complete"
    assert len(read_dataset_table(out, "GPS")) > 0
    assert len(read_dataset(out)[0]) == 1


# --------------------------------------------------------------------------------------------
# item 11: hand-edited journal and manifest values
# --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("edit, needle", [
    (("header", "flights", "abc"), "'flights' must be a whole number >= 0, got \"abc\""),
    (("header", "state", 5), "'state' must be a text, got 5"),
    (("header", "runs", 5), "'runs' must be a list"),
    (("header", "lambda", "x"), "'lambda' must be a number"),
    (("journal", "status", 5), "line 2: 'status' must be \"ok\" or \"failed\", got 5"),
    (("journal", "scenario", []), "line 2: 'scenario' must be an object or null, got []"),
    (("journal", "flight", -1), "line 2: 'flight' must be a whole number >= 0"),
    (("journal", "parts", "GPS"), "line 2: 'parts' must be a list of table names"),
])
def test_hand_edited_values_are_one_line_errors_everywhere(dataset, tmp_path, capsys, edit,
                                                           needle):
    from tlm_process.cli import main

    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    where, key, value = edit
    if where == "header":
        doc = json.loads((ds / "manifest.json").read_text())
        (ds / "manifest.json").write_text(json.dumps({**doc, key: value}))
    else:
        lines = (ds / "flights.jsonl").read_text().splitlines()
        lines[1] = json.dumps({**json.loads(lines[1]), key: value})
        (ds / "flights.jsonl").write_text("\n".join(lines) + "\n")
    for call in (lambda: _gen(ds), lambda: scenario_from_manifest(ds, 0),
                 lambda: read_dataset_table(ds, "GPS")):
        with pytest.raises(GenerateError) as exc:
            call()
        assert needle in str(exc.value) and "\n" not in str(exc.value)
    code = main(["process", str(ds), "--out", str(tmp_path / "p"), "--plots", "0", "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and needle in err and err.count("\n") == 1


def test_odd_but_typed_scenario_values_do_not_break_a_resume_or_a_replay(dataset, tmp_path):
    """A failed flight's scenario with odd inner values: the run closes the manifest (its
    manifest.parquet row shows what it can) and flies the flight; a replay of a finished
    flight whose scenario was edited is a one-line error."""
    ds = tmp_path / "ds"
    shutil.copytree(dataset, ds)
    lines = (ds / "flights.jsonl").read_text().splitlines()
    odd = {**json.loads(lines[2]), "status": "failed", "scenario": {"mission": [], "faults": "x"},
           "summary": {"faults": 3, "gps_rows": "many"}}
    lines[2] = json.dumps(odd)
    lines[1] = json.dumps({**json.loads(lines[1]), "scenario": {"seed": "x", "mission": 5}})
    (ds / "flights.jsonl").write_text("\n".join(lines) + "\n")
    with pytest.raises(GenerateError, match="flight 1: its scenario in the journal cannot be "
                                            "flown") as exc:
        scenario_from_manifest(ds, 1)
    assert "\n" not in str(exc.value)
    rep = _gen(ds)
    assert (rep.ok, rep.state) == (1, "complete")
    frame = pd.read_parquet(ds / "manifest.parquet")
    assert list(frame["status"]) == ["ok"] * 3
