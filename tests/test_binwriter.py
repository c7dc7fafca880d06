"""DataFlash .bin writer and Mission Planner text log: exact round trips through pymavlink,
ArduPilot's start sequence, fault MSG lines, the reference logs rewritten, and the CLI
(``tlm fly --format bin``, ``tlm convert``, ``tlm info``)."""

from __future__ import annotations

import datetime as dt
import json
from functools import lru_cache

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pymavlink import mavutil

from tests.conftest import reference_path
from tlm_process.cli import main
from tlm_sim import fly
from tlm_sim.faults import FaultSchedule
from tlm_sim.faults.detect import faults_from_param_changes
from tlm_sim.flightlog import FORMAT_CHARS, FlightLog, read_bin
from tlm_sim.flightlog.binreader import param_changes_from_parm
from tlm_sim.flightlog.binwriter import FIRMWARE_STRING, encode_bin
from tlm_sim.flightlog.mplog import format_column, read_mp_log, write_mp_log
from tlm_sim.flightlog.quantise import column_to_raw, quantise_column, raw_to_column


@lru_cache(maxsize=1)
def gps_fault_flight() -> FlightLog:
    """Built-in mission 1 with a 20 s GPS loss."""
    return fly(1, faults=FaultSchedule.from_shorthand(["gps:60-80"]), seed=3)


def _assert_tables_equal(a: dict[str, pd.DataFrame], b: dict[str, pd.DataFrame]) -> None:
    for name, df in a.items():
        other = b[name]
        assert list(other.columns) == list(df.columns), name
        assert other.dtypes.equals(df.dtypes), name
        pd.testing.assert_frame_equal(other.reset_index(drop=True), df.reset_index(drop=True),
                                      check_exact=True, obj=name)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    log = gps_fault_flight()
    path = tmp_path_factory.mktemp("bin") / "flight.bin"
    log.write_bin(path)
    return log, path


def test_bin_round_trip_is_exact(written):
    log, path = written
    back = read_bin(path)
    _assert_tables_equal(log.tables, back)
    # both decoders of the reader agree on our file too
    _assert_tables_equal({n: back[n] for n in ("GPS", "MODE", "PARM", "MSG")},
                         read_bin(path, ["GPS", "MODE", "PARM", "MSG"], method="messages"))


def test_start_sequence_and_self_description(written):
    _, path = written
    data = path.read_bytes()
    # first message: FMT describing FMT (type 128, length 89)
    assert data[:3] == bytes([0xA3, 0x95, 128])
    assert data[3] == 128 and data[4] == 89 and data[5:8] == b"FMT"
    t = read_bin(path, ["FMT", "FMTU", "UNIT", "MULT", "VER", "MSG", "CMD", "PARM"])
    fmt = t["FMT"]
    assert len(set(fmt.Type)) == len(fmt) and 255 not in set(fmt.Type)
    assert set(t["FMTU"].FmtType) == set(fmt.Type)  # one FMTU per type
    assert len(t["UNIT"]) == 38 and len(t["MULT"]) == 15
    assert t["VER"].BU.iloc[0] == 2 and t["VER"].FWS.iloc[0] == FIRMWARE_STRING
    assert t["MSG"].Message.iloc[0] == FIRMWARE_STRING
    assert "Frame: QUAD/PLUS" in set(t["MSG"].Message)
    cmd = t["CMD"]
    n_wp = gps_fault_flight().meta["n_waypoints"]
    assert len(cmd) == n_wp + 3 and (cmd.CTot == n_wp + 3).all()
    assert list(cmd.CId.iloc[[0, 1, 2, -1]]) == [16, 22, 16, 20]


def test_pymavlink_decodes_every_message_with_copter_modes_and_gps_time(written):
    log, path = written
    conn = mavutil.mavlink_connection(str(path))
    counts: dict[str, int] = {}
    modes = []
    first_gps_ts = None
    while True:
        m = conn.recv_match()
        if m is None:
            break
        name = m.get_type()
        counts[name] = counts.get(name, 0) + 1
        if name == "MODE":
            modes.append(conn.flightmode)
        if name == "GPS" and first_gps_ts is None and m.GWk > 0:
            first_gps_ts = m._timestamp
    for name, df in log.tables.items():
        assert counts.get(name) == len(df), name
    assert "AUTO" in modes and "GUIDED" in modes  # Copter mode names, not Plane's
    # wall-clock time from GPS week/ms: the simulated boot day
    assert dt.datetime.fromtimestamp(first_gps_ts, dt.UTC).date() == dt.date(2025, 10, 24)


def test_faults_and_parameter_changes_are_in_the_log(written):
    log, path = written
    t = read_bin(path, ["MSG", "PARM"])
    rec = log.faults[0]
    msg = t["MSG"].set_index("Message").TimeUS
    assert msg["tlm: fault gps (label 1) start"] == rec["start_time_us"]
    assert msg["tlm: fault gps (label 1) end"] == rec["end_time_us"]
    changes = param_changes_from_parm(t["PARM"])
    found = faults_from_param_changes(changes)
    assert [(f["type"], f["start_time_us"], f["end_time_us"]) for f in found] == [
        ("gps", rec["start_time_us"], rec["end_time_us"])]
    start = t["PARM"][t["PARM"].TimeUS == t["PARM"].TimeUS.min()].set_index("Name")
    assert start.loc["SIM_GPS1_ENABLE", "Value"] == 1.0  # value before the fault
    assert start.loc["WPNAV_SPEED", "Value"] == log.params["WPNAV_SPEED"]


def test_bin_is_deterministic():
    log = gps_fault_flight()
    assert encode_bin(log) == encode_bin(log)


def test_reference_log_survives_read_write_read(tmp_path):
    src = reference_path("rc_s15.bin")
    log = FlightLog.from_bin(src)
    out = log.write_bin(tmp_path / "rc.bin")
    back = read_bin(out)
    skip = {"FMT", "FMTU", "UNIT", "MULT"}  # regenerated
    _assert_tables_equal({n: df for n, df in log.tables.items() if n not in skip}, back)


def test_mission_planner_log_round_trip_and_line_format(tmp_path):
    log = gps_fault_flight()
    path = write_mp_log(log, tmp_path / "f.log")
    raw = path.read_bytes()
    assert raw.startswith(b"FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns\r\n")
    lines = raw.decode().split("\r\n")
    gps = next(ln for ln in lines if ln.startswith("GPS, ") and ", 6, " in ln)
    fields = gps.split(", ")
    assert len(fields) == 16 and fields[7] == "1.21"  # HDop: two decimals
    assert fields[10].count(".") == 1 and len(fields[10].split(".")[1]) == 2  # Alt in metres
    assert any(ln.startswith("MODE, ") and ", AUTO, 3, " in ln for ln in lines)
    back = read_mp_log(path)
    _assert_tables_equal(log.tables, back)


@pytest.mark.parametrize("char, values, text", [
    ("f", [90.0, 1.5, -0.2, 1e-5, float("nan")], ["90", "1.5", "-0.2", "1E-05", "NaN"]),
    ("c", [1.21, -3.0], ["1.21", "-3.00"]),
    ("L", [-35.363261, 149.16523], ["-35.363261", "149.16523"]),
    ("M", [3, 6, 9], ["AUTO", "RTL", "LAND"]),
    ("B", [0, 255], ["0", "255"]),
])
def test_mission_planner_number_text(char, values, text):
    assert format_column(quantise_column(values, char), char) == text


_NUMERIC = [c for c, fc in FORMAT_CHARS.items() if fc.kind not in ("str", "array")]


@settings(max_examples=60, deadline=None)
@given(st.sampled_from(_NUMERIC),
       st.lists(st.floats(allow_nan=True, allow_infinity=False, width=64), min_size=1,
                max_size=8))
def test_column_to_raw_inverts_raw_to_column(char, values):
    canonical = quantise_column(np.asarray(values), char)
    raw = column_to_raw(canonical, char)
    assert raw.dtype.itemsize == FORMAT_CHARS[char].size
    np.testing.assert_array_equal(raw_to_column(raw, char), canonical)


def test_strings_are_truncated_and_padded():
    raw = column_to_raw(np.array(["AUTO", "a" * 80, ""], dtype=object), "Z")
    assert raw.dtype == np.dtype("S64") and raw[1] == b"a" * 64
    assert list(raw_to_column(raw, "Z")) == ["AUTO", "a" * 64, ""]


# ------------------------------------------------------------------------------ CLI ------
def test_fly_format_bin_writes_flight_bin(tmp_path, capsys):
    out = tmp_path / "f"
    assert main(["fly", "--mission", "3", "--out", str(out), "--format", "bin", "--no-plot",
                 "--fault", "rc:100-130"]) == 0
    assert (out / "flight.bin").exists() and not (out / "GPS.csv").exists()
    log = FlightLog.read(out)  # tables from flight.bin, context from meta.json
    assert {"GPS", "IMU", "RATE", "VIBE"} <= set(log.tables)
    assert log.faults and log.faults[0]["type"] == "rc"
    assert main(["info", str(out / "flight.bin")]) == 0
    text = capsys.readouterr().out
    assert text.count("rc (label 4)") == 1 and "[PARM, MSG, sidecar]" in text  # faults.json
    assert "SIM_RC_FAIL = 1" in text


def test_convert_reference_log_to_csv_parquet_and_text(tmp_path, capsys):
    src = reference_path("rc_s15.bin")
    assert main(["convert", str(src), "--out", str(tmp_path / "c"), "--types", "GPS,IMU,MODE"]) == 0
    gps = pd.read_csv(tmp_path / "c" / "GPS.csv")
    ref = read_bin(src, ["GPS", "IMU"])
    assert len(gps) == len(ref["GPS"]) and list(gps.columns) == list(ref["GPS"].columns)
    back = FlightLog.read(tmp_path / "c")
    _assert_tables_equal({"GPS": ref["GPS"], "IMU": ref["IMU"]}, back.tables)
    assert main(["convert", str(src), "--out", str(tmp_path / "p"), "--format", "parquet",
                 "--types", "VIBE"]) == 0
    assert len(pd.read_parquet(tmp_path / "p" / "VIBE.parquet")) == len(read_bin(src, ["VIBE"])
                                                                       ["VIBE"])
    assert main(["convert", str(src), "--out", str(tmp_path / "t"), "--format", "log",
                 "--types", "GPS,MODE"]) == 0
    assert len(read_mp_log(tmp_path / "t" / "rc_s15.log")["GPS"]) == len(ref["GPS"])


def test_info_reports_reference_faults_as_the_sidecar(tmp_path, capsys):
    src = reference_path("combined_s21.bin")
    assert main(["info", str(src), "--json", str(tmp_path / "i.json")]) == 0
    info = json.loads((tmp_path / "i.json").read_text())
    side = json.loads(src.with_suffix(".json").read_text())["faults"]
    parm = [f for f in info["faults"] if f["source"].startswith("PARM")]  # + ", sidecar"
    assert [f["type"] for f in parm] == ["gps", "accel", "engine", "rc"]
    for f, s in zip(parm, side, strict=True):
        assert abs(f["start_time_us"] - s["start_time_us"]) < 1000
        assert abs(f["end_time_us"] - s["end_time_us"]) < 1000
    assert info["messages"]["IMU"]["instances"] == 2
    assert abs(info["messages"]["IMU"]["rate_hz"] - 25.0) < 0.5
    assert [m["name"] for m in info["modes"]][-1] == "RTL"
    assert info["modes"][-1]["reason"] == "RADIO_FAILSAFE"


@pytest.mark.parametrize("argv, needle", [
    (["convert", "/nonexistent.bin", "--out", "X"], "not found"),
    (["convert", "REF", "--out", "X", "--format", "xlsx"], "--format"),
    (["convert", "REF", "--out", "X", "--types", "NOPE"], "not in this log"),
    (["info", "/nonexistent.bin"], "not found"),
])
def test_convert_and_info_mistakes_are_one_line_errors(tmp_path, capsys, argv, needle):
    src = str(reference_path("rc_s15.bin"))
    argv = [src if a == "REF" else str(tmp_path / a) if a == "X" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1
