"""Text files the ``tlm`` command reads that are not UTF-8: one line on stderr naming the
file, exit code 2, no traceback (issue 17, item 11)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tlm_process.cli import main
from tlm_process.generate import read_journal

BAD = b"\xe9t\xe9 \xff\n"  # Latin-1 "ete" and a byte no UTF-8 text holds


def _faults(d: Path) -> list[str]:
    (d / "bad.yaml").write_bytes(b"faults:\n  - {fault: gps, start: 60, end: 90}\n# " + BAD)
    return ["fly", "--faults", str(d / "bad.yaml")]


def _params(d: Path) -> list[str]:
    (d / "bad.parm").write_bytes(b"WPNAV_SPEED 500\n# " + BAD)
    return ["fly", "--params", str(d / "bad.parm")]


def _mission(d: Path) -> list[str]:
    (d / "bad.waypoints").write_bytes(b"QGC WPL 110\n# " + BAD)
    return ["fly", "--mission-file", str(d / "bad.waypoints")]


def _manifest(d: Path) -> list[str]:
    (d / "ds").mkdir()
    (d / "ds" / "manifest.json").write_bytes(b'{"format": "' + BAD + b'"}')
    return ["fly", "--from-manifest", str(d / "ds"), "--flight", "0"]


def _config(d: Path) -> list[str]:
    (d / "bad.yaml").write_bytes(b"kinds: {none: 1}\n# " + BAD)
    return ["generate", "--flights", "1", "--config", str(d / "bad.yaml")]


def _dataset(d: Path) -> list[str]:
    _manifest(d)
    return ["generate", "--flights", "1", "--out", str(d / "ds"), "--no-progress"]


def _process(d: Path) -> list[str]:
    (d / "flight").mkdir()
    (d / "flight" / "GPS.csv").write_text("TimeUS,Lat,Lng\n")
    (d / "flight" / "faults.json").write_bytes(b'{"faults": []} ' + BAD)
    return ["process", str(d / "flight")]


CASES = {"fly --faults": (_faults, "bad.yaml"), "fly --params": (_params, "bad.parm"),
         "fly --mission-file": (_mission, "bad.waypoints"),
         "fly --from-manifest": (_manifest, "manifest.json"),
         "generate --config": (_config, "bad.yaml"), "generate --out": (_dataset, "manifest.json"),
         "process": (_process, "faults.json")}


@pytest.mark.parametrize("make, name", CASES.values(), ids=CASES)
def test_a_file_that_is_not_utf8_is_a_one_line_error(tmp_path, capsys, make, name):
    argv = make(tmp_path)
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "out")]
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.startswith("tlm: error:") and err.count("\n") == 1, err
    assert name in err and "utf-8" in err.lower(), err


def test_a_journal_line_that_is_not_utf8_counts_as_one_bad_line(tmp_path):
    (tmp_path / "flights.jsonl").write_bytes(b'{"flight": 0, "status": "ok", "scenario": {}}\n'
                                             b'{"flight": 1, "' + BAD
                                             + b'{"flight": 2, "status": "failed"}\n')
    entries, bad = read_journal(tmp_path)
    assert sorted(entries) == [0, 2] and bad == 1


def test_a_sidecar_that_is_not_utf8_is_reported_by_tlm_info(normal_flight, tmp_path):
    from tlm_process.binlog import log_info
    from tlm_sim.flightlog.binwriter import encode_bin

    (tmp_path / "f.json").write_bytes(b'{"faults": []} ' + BAD)
    (tmp_path / "f.bin").write_bytes(encode_bin(normal_flight))
    info = log_info(tmp_path / "f.bin")
    assert "f.json is not a fault sidecar JSON ('utf-8' codec can't decode" in info[
        "sidecar_error"]
