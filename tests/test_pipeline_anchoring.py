"""Fault Time Point Anchoring (Eq. 4) on the reference SITL logs, tlm flights and made-up logs."""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest
from conftest import reference_path

from tlm_process.pipeline import (
    AnchorError,
    IngestError,
    anchor_by_position,
    anchor_flight,
    compare_methods,
    label_tables,
    parse_records,
    process_flight,
    read_flights,
)
from tlm_process.pipeline.anchoring import FaultWindow, check_windows
from tlm_process.pipeline.ingest import Flight

GPS_PERIOD_S = 0.2  # 5 Hz
FAULTED = ("gps_s12", "accel_s13", "engine_s14", "rc_s15", "combined_s21")


@lru_cache(maxsize=8)
def _processed(name: str):
    flight = read_flights([reference_path(f"{name}.bin")])[0]
    return process_flight(flight)


def _sidecar(name: str) -> list[dict]:
    return json.loads(reference_path(f"{name}.json").read_text())["faults"]


@pytest.mark.parametrize("name", FAULTED)
def test_reference_labels_fall_inside_sidecar_windows(name):
    p = _processed(name)
    faults = _sidecar(name)
    assert [w.method for w in p.windows] == ["time"] * len(faults)
    for table in ("GPS", "IMU", "RATE", "VIBE"):
        df = p.features[table]
        t = df["TimeUS"].to_numpy()
        for f in faults:
            t0, t1 = f["start_time_us"], f["end_time_us"]
            lab = df["label"].to_numpy() == f["label"]
            assert lab.any()
            inside = t[lab]
            # every labelled row lies in the sidecar window ...
            assert inside.min() >= t0 and inside.max() <= t1
            # ... and the window is covered to within one GPS period at each end
            assert (inside.min() - t0) * 1e-6 <= GPS_PERIOD_S
            assert (t1 - inside.max()) * 1e-6 <= GPS_PERIOD_S
            # every row of the window carries the label
            in_window = (t >= t0) & (t < t1)
            assert (lab == in_window).all()
        others = ~np.isin(df["label"].to_numpy(), [f["label"] for f in faults])
        assert (df["label"].to_numpy()[others] == 0).all()


@pytest.mark.parametrize("name", ["gps_s12", "combined_s21"])
def test_gps_label_count_matches_the_logged_no_fix_rows(name):
    gps = _processed(name).labelled["GPS"]
    no_fix = gps["Status"].to_numpy() == 1  # what the GPS fault does (armed phase only here)
    faulty = gps["label"].to_numpy() == 1
    assert abs(int(no_fix.sum()) - int(faulty.sum())) <= 1
    assert int((no_fix & faulty).sum()) >= int(faulty.sum()) - 1  # one row of receiver lag


@pytest.mark.parametrize("name", ["accel_s13", "combined_s21"])
def test_accel_label_count_matches_the_logged_constant_accel(name):
    imu = _processed(name).labelled["IMU"]
    imu = imu[imu["I"] == 0]
    stuck = (imu[["AccX", "AccY", "AccZ"]].sub(1.0).abs() < 0.05).all(axis=1).to_numpy()
    faulty = imu["label"].to_numpy() == 2
    assert not (stuck & ~faulty).any()  # (1, 1, 1) readings only inside the window
    assert 0 <= int(faulty.sum()) - int(stuck.sum()) <= 3  # the 20 Hz filter's settling rows


@pytest.mark.parametrize("name", FAULTED)
def test_reference_counts_per_class_follow_window_length_and_rate(name):
    p = _processed(name)
    rates = {"GPS": 5.0, "IMU": 25.0, "RATE": 10.0, "VIBE": 10.0}  # instance 0 only
    for f in _sidecar(name):
        dur = (f["end_time_us"] - f["start_time_us"]) * 1e-6
        for table, hz in rates.items():
            n = int((p.features[table]["label"] == f["label"]).sum())
            assert abs(n - dur * hz) <= 1.0, (table, f["type"], n, dur * hz)


def test_normal_reference_flight_is_all_label_zero():
    p = _processed("normal_s11")
    assert p.windows == []
    for df in p.features.values():
        assert (df["label"] == 0).all() and len(df) > 1000


def test_paper_position_method_on_the_reference_logs():
    """The paper's method matches starts to the row, but misses the end of a GPS fault (the
    recorded EKF estimate is far from the GPS) and of an engine fault (vehicle on the ground)."""
    for name in FAULTED:
        for c in _processed(name).comparison:
            assert abs(c.dt_start_s) <= GPS_PERIOD_S and abs(c.rows_start) <= 1
            assert c.match_start_m < 1.5
            if c.type in ("accel", "rc"):
                assert abs(c.dt_end_s) <= 0.3 and abs(c.rows_end) <= 2
            elif c.type == "gps":
                assert c.offset_end_m > 100  # recorded end position vs GPS at that time
                assert c.dt_end_s < -10 and c.rows_end < -50
            else:  # engine: every ground row is as near
                assert c.dt_end_s < -15


def test_position_anchoring_can_be_forced_and_errs_where_the_paper_errs():
    flight = read_flights([reference_path("combined_s21.bin")])[0]
    by_pos = anchor_flight(flight, "position")
    by_time = anchor_flight(flight, "time")
    assert [w.method for w in by_pos] == ["position"] * 4
    dt_end = {w.type: (p.end_us - w.end_us) * 1e-6 for w, p in zip(by_time, by_pos, strict=True)}
    assert dt_end["gps"] < -10 and dt_end["engine"] < -15
    assert abs(dt_end["accel"]) < 0.5 and abs(dt_end["rc"]) < 0.5


def _loop_flight(records: list[dict]) -> Flight:
    """A made-up 5 Hz log flying a 100 m square twice (so every spot is passed twice)."""
    t = np.arange(0, 400, 0.2)
    s = (t % 200) / 200 * 400  # metres along the square, 2 m/s
    side = np.minimum(s // 100, 3)
    u = s - side * 100
    north = np.select([side == 0, side == 1, side == 2, side == 3], [u, 100, 100 - u, 0])
    east = np.select([side == 0, side == 1, side == 2, side == 3], [0, u, 100, 100 - u])
    lat = -35.0 + north / 111_319.49
    lon = 149.0 + east / (111_319.49 * np.cos(np.radians(-35.0)))
    gps = pd.DataFrame({"TimeUS": (t * 1e6).astype(np.int64), "Status": 6, "Lat": lat,
                        "Lng": lon, "Alt": 520.0})
    return Flight("loop", "loop", "csv", {"GPS": gps}, parse_records(records),
                  home=(-35.0, 149.0, 500.0))


def _at(t_s: float) -> dict:
    """Position of the made-up loop at t_s, as a record would hold it (20 m above home)."""
    f = _loop_flight([])
    g = f.tables["GPS"]
    i = int(round(t_s / 0.2))
    return {"lat": float(g.Lat[i]), "lon": float(g.Lng[i]), "alt": 20.0}


def _rec(ftype: str, t0: float, t1: float, times: bool = False) -> dict:
    a, b = _at(t0), _at(t1)
    d = {"type": ftype, "start_lat": a["lat"], "start_lon": a["lon"], "start_alt": a["alt"],
         "end_lat": b["lat"], "end_lon": b["lon"], "end_alt": b["alt"]}
    if times:
        d.update(start_time_us=int(t0 * 1e6), end_time_us=int(t1 * 1e6))
    return d


def test_position_anchoring_keeps_boundaries_in_order_on_a_loop():
    # both faults on the second lap: the first lap passes the same spots 200 s earlier
    flight = _loop_flight([_rec("gps", 230.0, 260.0), _rec("rc", 300.0, 330.0)])
    windows = anchor_flight(flight)  # auto: no times recorded -> position
    assert [w.method for w in windows] == ["position", "position"]
    got = [(w.start_us * 1e-6, w.end_us * 1e-6) for w in windows]
    # the least-total-distance ordered assignment is ambiguous between laps only as a whole;
    # each window must be 30 s long and in order
    for (s, e) in got:
        assert e - s == pytest.approx(30.0, abs=0.21)
    assert got[0][1] < got[1][0]
    # a first-lap start followed by a second-lap end is never chosen
    flight = _loop_flight([_rec("gps", 30.0, 60.0), _rec("accel", 240.0, 250.0)])
    w = anchor_flight(flight)
    assert w[0].start_us * 1e-6 == pytest.approx(30.0, abs=0.21)
    assert w[0].end_us * 1e-6 == pytest.approx(60.0, abs=0.21)
    assert w[1].start_us * 1e-6 == pytest.approx(240.0, abs=0.21)


def test_time_and_position_agree_on_a_clean_log():
    flight = _loop_flight([_rec("gps", 30.0, 60.0, times=True),
                           _rec("engine", 250.0, 270.0, times=True)])
    comp = compare_methods(flight)
    assert [c.type for c in comp] == ["gps", "engine"]
    for c in comp:
        assert abs(c.dt_start_s) <= 0.2 and abs(c.dt_end_s) <= 0.2
        assert c.offset_start_m < 1 and c.offset_end_m < 1


def test_overlapping_windows_are_an_error():
    recs = [{"type": "gps", "start_time_us": 10_000_000, "end_time_us": 50_000_000},
            {"type": "rc", "start_time_us": 40_000_000, "end_time_us": 60_000_000}]
    flight = _loop_flight(recs)
    with pytest.raises(AnchorError, match="overlapping fault windows") as exc:
        anchor_flight(flight)
    assert "\n" not in str(exc.value)
    with pytest.raises(AnchorError, match="overlapping"):
        check_windows([FaultWindow(0, "gps", 1, 0, 10, "time"),
                       FaultWindow(1, "rc", 4, 5, 20, "time")])


def test_a_record_that_matches_nowhere_is_an_error():
    late = _loop_flight([{"type": "gps", "start_time_us": 900_000_000,
                          "end_time_us": 950_000_000}])
    with pytest.raises(AnchorError, match="matches nowhere"):
        anchor_flight(late)
    far = _rec("accel", 30.0, 60.0)
    far["end_lat"] += 0.01  # 1.1 km north of the track
    with pytest.raises(AnchorError, match=r"end position matches nowhere.*1\d{3}\.\d m"):
        anchor_by_position(_loop_flight([far]))


def test_a_log_without_gps_is_an_error(tmp_path):
    flight = _loop_flight([])
    flight.tables["GPS"] = flight.tables["GPS"].iloc[:0]
    with pytest.raises(AnchorError, match="no GPS"):
        anchor_flight(flight)
    (tmp_path / "IMU.csv").write_text("TimeUS,I,AccX\n1,0,0.5\n")
    (tmp_path / "faults.json").write_text('{"faults": []}')
    (tmp_path / "GPS.csv").write_text("TimeUS,I,Status,Lat,Lng,Alt\n")
    with pytest.raises(IngestError, match="no GPS rows"):
        read_flights([tmp_path])


def test_held_fault_labels_to_the_end_of_the_log():
    flight = _loop_flight([{"type": "rc", "start_time_us": 300_000_000, "end_by": "flight end",
                            "end_time_us": 399_800_000}])
    windows = anchor_flight(flight)
    assert not np.isfinite(windows[0].end_us)
    lab = label_tables(flight.tables, windows)["GPS"]
    assert (lab["label"][lab["TimeUS"] >= 300_000_000] == 4).all()
    assert (lab["label"][lab["TimeUS"] < 300_000_000] == 0).all()
