"""``tlm process``: end to end on a reference SITL log and a tlm flight folder; bad inputs."""

from __future__ import annotations

import json
from functools import lru_cache

import pandas as pd
import pytest
from conftest import reference_path

from tlm_process.cli import main

FEATURES = {"GPS": 6, "IMU": 8, "RATE": 13, "VIBE": 3}


@lru_cache(maxsize=1)
def _fault_flight():
    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule

    return fly(2, faults=FaultSchedule.from_shorthand(["accel:50-70", "engine:100-115"]),
               seed=5)


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(["process", *map(str, argv)])
    out, err = capsys.readouterr()
    return rc, out, err


def test_process_reference_log_and_tlm_folder(tmp_path, capsys):
    bin_path = reference_path("combined_s21.bin")
    flight_dir = _fault_flight().write(tmp_path / "tlm_m2", formats=("parquet",))
    ds = tmp_path / "ds"
    rc, out, err = _run(capsys, bin_path, flight_dir, "--out", ds, "--test-flight",
                        "combined_*", "--target-fault-ratio", "0.5", "--plots", "1")
    assert rc == 0, err
    assert "[1/2] combined_s21 (bin)" in out and "[2/2] tlm_m2 (tlm)" in out
    assert "position method vs recorded time, gps" in out
    assert "Accelerometer Fail" in out and "lambda for fault share 0.5" in out
    report = json.loads((ds / "report.json").read_text())
    assert report["format"] == "tlm.process"
    assert {t: len(c) for t, c in report["features"].items()} == FEATURES
    assert report["split"]["train"] == ["tlm_m2"] and report["split"]["test"] == ["combined_s21"]
    flights = {f["id"]: f for f in report["flights"]}
    assert [w["type"] for w in flights["combined_s21"]["faults"]] == [
        "gps", "accel", "engine", "rc"]
    assert [w["type"] for w in flights["tlm_m2"]["faults"]] == ["accel", "engine"]
    gps_dis = flights["combined_s21"]["anchoring_disagreement"][0]
    assert gps_dis["type"] == "gps" and gps_dis["dt_end_s"] < -10
    for table in FEATURES:
        df = pd.read_parquet(ds / f"{table}.parquet")
        feats = report["features"][table]
        assert list(df.columns) == ["flight", "split", "TimeUS", "label", *feats]
        assert set(df["flight"]) == {"combined_s21", "tlm_m2"}
        counts = report["counts"][table]
        assert counts["total"] == len(df)
        for k in range(5):
            assert counts[str(k)] == int((df["label"] == k).sum())
        train = df[df["split"] == "train"]
        assert train[feats].min().min() >= 0 and train[feats].max().max() <= 1
        # the tlm flight has accel and engine faults only; the SITL log all four
        tl = df[df["flight"] == "tlm_m2"]["label"]
        assert set(tl.unique()) == {0, 2, 3}
        assert set(df[df["flight"] == "combined_s21"]["label"].unique()) == {0, 1, 2, 3, 4}
    assert report["stretching"]["lambda"]["GPS"] == pytest.approx(
        0.5 / report["fault_share"]["GPS"], rel=1e-3)
    scaler = json.loads((ds / "scaler.json").read_text())
    assert scaler["train_flights"] == ["tlm_m2"]
    for png in ("label_shares.png", "plots/combined_s21_trajectory.png",
                "plots/combined_s21_fault1_gps.png", "plots/combined_s21_fault4_rc.png"):
        assert (ds / png).stat().st_size > 10_000, png
    assert not (ds / "plots" / "tlm_m2_trajectory.png").exists()  # --plots 1


def test_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["process", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    for text in ("INPUT", "--out DS", "--anchor", "--test-flight", "sidecar", "report.json"):
        assert text in out


def test_bad_inputs_exit_2_with_one_line(tmp_path, capsys):
    cases = []
    cases.append(([tmp_path / "nope"], "no such file or folder"))
    (tmp_path / "lonely.bin").write_bytes(b"")
    cases.append(([tmp_path / "lonely.bin"], "cannot read the DataFlash log"))
    csv = tmp_path / "csvflight"
    csv.mkdir()
    (csv / "GPS.csv").write_text("TimeUS,Status,Lat,Lng,Alt\n0,6,-35,149,500\n"
                                 "100000000,6,-35,149,500\n")
    cases.append(([csv], "no faults.json"))
    for inputs, msg in cases:
        rc, out, err = _run(capsys, *inputs, "--out", tmp_path / "ds")
        assert rc == 2 and msg in err, err
        assert err.startswith("tlm: error: ") and err.count("\n") == 1
    (csv / "faults.json").write_text(json.dumps({"faults": [
        {"type": "gps", "start_time_us": 10_000_000, "end_time_us": 50_000_000},
        {"type": "rc", "start_time_us": 40_000_000, "end_time_us": 60_000_000}]}))
    for t in ("IMU", "RATE", "VIBE"):
        (csv / f"{t}.csv").write_text("TimeUS\n0\n")
    rc, _, err = _run(capsys, csv, "--out", tmp_path / "ds")
    assert rc == 2 and "overlapping fault windows" in err and err.count("\n") == 1
    rc, _, err = _run(capsys, csv, "--out", csv)
    assert rc == 2 and "output folder is one of the inputs" in err
    with pytest.raises(SystemExit) as exc:
        main(["process", str(csv), "--out", "x", "--test-frac", "1.5"])
    assert exc.value.code == 2
