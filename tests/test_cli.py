"""The tlm command line: fly writes ArduPilot-named tables, user mistakes are one-line errors."""

from __future__ import annotations

import subprocess
import sys

import pandas as pd
import pytest

from tlm_process.cli import main
from tlm_sim.flightlog import SCHEMAS


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
    ],
)
def test_user_mistakes_are_one_line_errors(tmp_path, capsys, argv, needle):
    argv = [a if a != "X" else str(tmp_path / "o") for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1


def test_unwritable_output_folder(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["fly", "--out", str(blocker / "sub")]) == 2
    assert "cannot write" in capsys.readouterr().err


def test_help_runs_as_a_console_command():
    r = subprocess.run([sys.executable, "-m", "tlm_process.cli", "fly", "--help"],
                       capture_output=True, text=True, check=True)
    assert "--mission" in r.stdout and "--format" in r.stdout
