"""tools/detector_check.py, issue 40's detector check on one vehicle (fit, train on tlm
flights of it, detect on its good and damaged logs): the columns an older log lacks are found
and left out, the verdict follows the 2 % rule and the prop_damage reports, and a small run
goes through every step."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.conftest import real_path, reference_path

_PATH = Path(__file__).resolve().parents[1] / "tools" / "detector_check.py"
_spec = importlib.util.spec_from_file_location("detector_check", _PATH)
dc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(dc)


def test_an_older_logs_missing_columns_are_left_out():
    """log171 (Copter 3.3): no VIBE, GPA, BAT or EKF3 tables, no IMU health, RATE.AOutSlew,
    BARO.H or CTUN.ThH (what docs/noise.md's procedure drops by hand); a 4.7 SITL log lacks
    none. Each log's outputs go to the folder tlm detect names after it."""
    dropped, folders = dc.read_checked([str(real_path("log171.bin"))])
    for col in ("IMU.GH", "IMU.AH", "RATE.AOutSlew", "BARO.H", "CTUN.ThH", "VIBE.VibeX",
                "XKF4.SV", "BAT.Volt", "GPA.HAcc"):
        assert col in dropped, col
    assert folders == ["log171"]
    sitl = str(reference_path("pilot/manual_loiter_s90.bin"))
    dropped, folders = dc.read_checked([sitl, sitl])
    assert dropped == [] and folders == ["manual_loiter_s90", "manual_loiter_s90-2"]


def _det(tmp_path: Path, called: dict[str, int], reports: list[tuple[str, str]]) -> Path:
    det = tmp_path / "det"
    for name, n in called.items():
        (det / name).mkdir(parents=True)
        fault = np.zeros(1000, dtype=np.int16)
        fault[:n] = 14
        pd.DataFrame({"TimeUS": np.arange(1000) * 100_000, "fault": fault}).to_parquet(
            det / name / "predictions.parquet")
    pd.DataFrame([{"log": f"{log}.bin", "class": c, "label": 14, "start_s": 1.0,
                   "end_s": 3.0, "peak_p": 0.9, "also": ""} for log, c in reports],
                 columns=["log", "class", "label", "start_s", "end_s", "peak_p", "also"]
                 ).to_csv(det / "summary.csv", index=False)
    return det


@pytest.mark.parametrize("called_good, damaged_class, ok", [
    (20, "prop_damage", True),     # 2.0 % of the good log's rows: at the limit
    (21, "prop_damage", False),    # 2.1 %
    (0, "motor_partial", False),   # the damaged log reported, but not as a damaged propeller
])
def test_the_verdict(tmp_path, called_good, damaged_class, ok):
    det = _det(tmp_path, {"g": called_good, "d": 300},
               [("g", "vibration")] * bool(called_good) + [("d", damaged_class)])
    table, verdict = dc.judge(det, [("g.bin", "good", "g"), ("d.bin", "damaged", "d")])
    assert verdict is ok
    assert list(table.called) == [called_good, 300] and list(table.rows) == [1000, 1000]
    text = dc.report(table, verdict, ["VIBE.VibeX"])
    assert f"verdict: {'pass' if ok else 'FAIL'}" in text
    assert "left out (a checked log lacks them): VIBE.VibeX" in text


@pytest.mark.slow
def test_a_small_check_runs_every_step(tmp_path, capsys):
    """Fit on SITL's POSHOLD flight, 6 training flights, detect on two SITL pilot logs: the
    four steps, the report file and an exit status that is the verdict's."""
    pilot = reference_path("pilot")
    rc = dc.main(["--fit", str(pilot / "manual_poshold_s91.bin"),
                  "--good", str(pilot / "manual_loiter_s90.bin"),
                  "--damaged", str(pilot / "hover_partial_s95.bin"),
                  "--out", str(tmp_path / "c"), "--flights", "6", "--iterations", "1"])
    out = capsys.readouterr().out
    for step in ("1/4 tlm fit", "2/4 tlm generate 6 flights of the vehicle (+ frame)",
                 "3/4 tlm train", "4/4 tlm detect on 2 logs"):
        assert step in out, step
    text = (tmp_path / "c" / "report.md").read_text()
    assert "| manual_loiter_s90.bin | good |" in text
    assert "| hover_partial_s95.bin | damaged |" in text
    assert rc == (0 if "verdict: pass" in text else 1)
    assert "scale: [0.7, 1.4]" in (tmp_path / "c" / "train.yaml").read_text()
