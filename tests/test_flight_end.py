"""Why a flight ended (``FlightLog.meta["end_reason"]``): landed, crash check, or cut off by
the time cap (issue 17, item 10)."""

from __future__ import annotations

import json

import numpy as np

from tlm_sim import fly
from tlm_sim.flight import END_CRASH, END_LANDED, END_TIME_CAP, end_reason


def test_a_normal_flight_ends_landed(normal_flight):
    meta = normal_flight.meta
    assert meta["end_reason"] == END_LANDED and meta["disarmed_s"] is not None
    assert meta["duration_s"] < meta["max_duration_s"]


def test_a_flight_too_slow_to_finish_is_marked_time_cap():
    log = fly(1, params={"WPNAV_SPEED": 10})  # 0.1 m/s: the mission cannot be flown in time
    meta = log.meta
    assert meta["end_reason"] == END_TIME_CAP and meta["disarmed_s"] is None
    assert abs(meta["duration_s"] - meta["max_duration_s"]) < 0.01


def test_the_crash_check_disarm_is_told_from_a_landing():
    err = np.array([[5e6, 25.0, 1.0], [9e6, 12.0, 1.0]])  # THRUST_LOSS, then CRASH_CHECK
    assert end_reason(100.0, err) == END_CRASH
    assert end_reason(100.0, err[:1]) == END_LANDED
    assert end_reason(-1.0, err) == END_TIME_CAP
    assert end_reason(100.0, np.zeros((0, 3))) == END_LANDED


def test_tlm_fly_shows_the_end_reason(tmp_path, capsys):
    from tlm_process.cli import main

    out = tmp_path / "f"
    code = main(["fly", "--mission", "2", "--param", "WPNAV_SPEED=10", "--out", str(out),
                 "--format", "parquet", "--no-plot"])
    assert code == 0
    assert "end reason         time_cap (still armed at the time cap" in capsys.readouterr().out
    assert json.loads((out / "meta.json").read_text())["meta"]["end_reason"] == "time_cap"
    assert json.loads((out / "summary.json").read_text())["end_reason"] == "time_cap"
