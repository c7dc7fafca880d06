"""DataFlash .bin reader: reference SITL logs, log context, instances, damaged files (fuzz)."""

from __future__ import annotations

import faulthandler
import json
import struct
import sys
import warnings
import zlib
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import close_dfreader, reference_path
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pymavlink import DFReader

from tlm_sim.flightlog import (
    FORMAT_CHARS,
    SCHEMAS,
    BinLogError,
    BinLogWarning,
    read_bin,
    read_log,
    read_messages,
    read_mission,
    read_modes,
    read_param_changes,
    read_params,
    split_instances,
)
from tlm_sim.flightlog.binreader import BOOKKEEPING_PARAMS, mission_from_cmd
from tlm_sim.flightlog.binscan import FMT_LENGTH, FMT_TYPE, scan_bin

LOGS = ("normal_s11", "gps_s12", "accel_s13", "engine_s14", "rc_s15", "combined_s21")
SLICE_BYTES = 200_000  # start of normal_s11.bin used by the damaged-file tests
HANG_S = 60  # a read taking this long is a hang: faulthandler dumps the stacks and exits


def _ref(name: str) -> Path:
    return reference_path(f"{name}.bin")


def _sidecar(name: str) -> dict:
    return json.loads(_ref(name).with_suffix(".json").read_text())


@lru_cache(maxsize=8)
def _log(name: str):
    return read_log(_ref(name))


# --- reference logs: index, counts, rates, first rows ---------------------------------------------
@pytest.mark.parametrize("name", LOGS)
def test_scan_equals_pymavlink_and_sidecar_counts(name):
    """Offsets and FMT definitions equal pymavlink's; counts equal the sidecar's."""
    path = _ref(name)
    ix = scan_bin(path)
    r = DFReader.DFReader_binary(str(path))
    close_dfreader(r)  # the offsets and formats below are already parsed
    for t in range(256):
        theirs = np.asarray(r.offsets[t], dtype=np.int64)
        if t in r.formats:  # pymavlink also lists the incomplete final message
            theirs = theirs[theirs + r.formats[t].len <= r.data_len]
        ours = ix.offsets.get(t, np.zeros(0, dtype=np.int64))
        assert np.array_equal(ours, theirs), (name, t)
    assert {f.name: (f.type, f.length, f.format, list(f.columns)) for f in ix.formats.values()} \
        == {f.name: (f.type, f.len, f.format, f.columns) for f in r.formats.values()}
    side = _sidecar(name)["log_message_rates"]
    assert {n: ix.count(n) for n in side} == {n: v["count"] for n, v in side.items()}
    assert ix.issues == [] and ix.skipped_bytes == 0
    assert 0 < ix.tail_bytes < 255  # every reference log ends inside a message


# message → (instance values, rate per instance in Hz) in every reference flight
RATES = {
    "GPS": ((0,), 5.0), "GPA": ((0,), 5.0), "IMU": ((0, 1), 25.0), "RATE": (None, 10.0),
    "VIBE": ((0, 1), 10.0), "ATT": (None, 10.0), "BARO": ((0, 1), 10.0),
    "MAG": ((0, 1, 2), 10.0), "XKF1": ((0, 1), 10.0), "XKF4": ((0, 1), 10.0),
    "RCIN": (None, 10.0), "CTUN": (None, 10.0), "SIM2": (None, 50.0), "POS": (None, 10.0),
}


def test_reference_rates_and_instances():
    log = _log("normal_s11")
    for name, (instances, hz) in RATES.items():
        df = log.tables[name]
        parts = split_instances(df, log.schemas[name])
        assert tuple(parts) == (instances or (0,)), name
        counts = {len(p) for p in parts.values()}
        assert max(counts) - min(counts) <= 1, (name, counts)  # instances logged together
        for part in parts.values():
            t = part["TimeUS"].to_numpy()
            assert np.all(np.diff(t) >= 0), name
            rate = (len(t) - 1) / ((t[-1] - t[0]) * 1e-6)
            assert rate == pytest.approx(hz, rel=0.01), (name, rate)
    side = _sidecar("normal_s11")["log_message_rates"]
    assert len(log.tables["IMU"]) == side["IMU"]["count"] == 2 * len(split_instances(
        log.tables["IMU"], "IMU")[0])


FIRST_ROW_TYPES = ("GPS", "IMU", "RATE", "VIBE", "ATT", "BARO", "XKF1", "MAG", "SIM2", "PARM",
                   "CMD", "MSG", "MODE", "EV", "FMTU", "UNIT", "MULT")


def test_reference_first_rows_equal_pymavlink():
    """First row of each type (and of each IMU instance) as pymavlink reads it."""
    path = _ref("gps_s12")
    r = DFReader.DFReader_binary(str(path))
    first: dict[str, dict] = {}
    imu1 = None
    while (m := r.recv_match(type=list(FIRST_ROW_TYPES))) is not None:
        name = m.get_type()
        first.setdefault(name, m.to_dict())
        if name == "IMU" and m.I == 1 and imu1 is None:
            imu1 = m.to_dict()
        if len(first) == len(FIRST_ROW_TYPES) and imu1 is not None:
            break
    close_dfreader(r)
    tables = read_bin(path, FIRST_ROW_TYPES)
    for name, expected in first.items():
        row = tables[name].iloc[0].to_dict()
        for col in tables[name].columns:
            assert row[col] == expected[col], (name, col, row[col], expected[col])
    got_imu1 = split_instances(tables["IMU"], "IMU")[1].iloc[0].to_dict()
    assert {c: got_imu1[c] for c in imu1 if c != "mavpackettype"} == {
        c: v for c, v in imu1.items() if c != "mavpackettype"}
    assert tables["MSG"]["Message"].iloc[0] == "ArduCopter V4.7.0-dev (2598e9d4)"
    assert tables["CMD"]["CTot"].iloc[0] == 93
    assert tables["GPS"]["TimeUS"].dtype == np.int64 and tables["GPS"]["HDop"].dtype == float


def test_methods_agree_on_every_type(ref_slice):
    """Bulk decoding equals pymavlink recv_match decoding: every type of the first 200 kB,
    and the multi-instance / string types of a whole log."""
    assert_tables_equal(read_bin(ref_slice.path), read_bin(ref_slice.path, method="messages"))
    types = ["IMU", "XKF1", "BARO", "MAG", "PARM", "CMD", "FMTU", "ORGN"]
    path = _ref("rc_s15")
    assert_tables_equal(read_bin(path, types), read_bin(path, types, method="messages"))


def assert_tables_equal(a: dict[str, pd.DataFrame], b: dict[str, pd.DataFrame]) -> None:
    assert list(a) == list(b)
    for name in a:
        pd.testing.assert_frame_equal(a[name], b[name], check_exact=True, obj=name)


# --- log context ----------------------------------------------------------------------------------
def test_mission_from_reference_log():
    mission = read_mission(_ref("normal_s11"))
    side = _sidecar("normal_s11")["mission"]
    assert len(mission) == side["n_waypoints"] + 3 == 93  # home, takeoff, waypoints, RTL
    assert [m["CNum"] for m in mission] == list(range(93))
    assert mission[1]["CId"] == 22 and mission[-1]["CId"] == 20  # NAV_TAKEOFF, NAV_RTL
    wps = mission[2:-1]
    assert {m["CId"] for m in wps} == {16} and {m["Frame"] for m in wps} == {3}
    lat_lon_alt = np.array([[m["Lat"], m["Lng"], m["Alt"]] for m in wps])
    np.testing.assert_allclose(lat_lon_alt[:, :2], np.array(side["waypoints"])[:, :2], atol=1e-7)
    # sidecar altitudes are rounded to cm; the uploaded float32 values differ by < 1 cm + ulp
    np.testing.assert_allclose(lat_lon_alt[:, 2], np.array(side["waypoints"])[:, 2], atol=0.0101)
    assert set(mission[0]) == {"CNum", "CId", "Prm1", "Prm2", "Prm3", "Prm4", "Lat", "Lng",
                               "Alt", "Frame"}


def test_mission_last_upload_wins():
    def cmd(rows):
        cols = ("TimeUS", "CTot", "CNum", "CId", "Prm1", "Prm2", "Prm3", "Prm4", "Lat", "Lng",
                "Alt", "Frame")
        return pd.DataFrame([dict(zip(cols, r, strict=True)) for r in rows])

    first = [(1, 3, k, 16, 0, 0, 0, 0, -35.0, 149.0, 10.0 + k, 3) for k in range(3)]
    second = [(2, 2, k, 16, 0, 0, 0, 0, -36.0, 150.0, 20.0 + k, 3) for k in range(2)]
    update = [(3, 2, 1, 16, 0, 0, 0, 0, -36.5, 150.5, 99.0, 3)]
    assert [m["Alt"] for m in mission_from_cmd(cmd(first))] == [10.0, 11.0, 12.0]
    got = mission_from_cmd(cmd(first + second))
    assert [(m["Lat"], m["Alt"]) for m in got] == [(-36.0, 20.0), (-36.0, 21.0)]
    got = mission_from_cmd(cmd(first + second + update))
    assert [m["Alt"] for m in got] == [20.0, 99.0] and got[1]["Lng"] == 150.5
    assert mission_from_cmd(cmd([])) == []


def test_param_changes_gps_fault():
    path = _ref("gps_s12")
    fault = _sidecar("gps_s12")["faults"][0]
    ch = read_param_changes(path)
    gps = ch[ch["Name"] == "SIM_GPS1_ENABLE"]
    assert gps["TimeUS"].tolist() == [fault["start_time_us"], fault["end_time_us"]]
    assert gps[["Value", "Old"]].values.tolist() == [[0.0, 1.0], [1.0, 0.0]]
    assert not ch["Name"].isin(BOOKKEEPING_PARAMS).any()
    assert list(ch.columns) == ["TimeUS", "Name", "Value", "Old"]
    everything = read_param_changes(path, exclude=(), value_changes_only=False)
    parm = read_bin(path, ["PARM"])["PARM"]
    initial = read_params(path)
    assert len(initial) == 1349 and len(everything) == len(parm) - 1349
    assert everything["TimeUS"].tolist() == parm["TimeUS"].iloc[1349:].tolist()
    assert (everything["Name"] == "SIM_GPS1_ENABLE").sum() == 4  # each PARAM_SET logged twice
    assert (everything["Name"] == "MIS_TOTAL").sum() == 92  # one per uploaded item


def test_modes_and_messages():
    path = _ref("rc_s15")
    modes = read_modes(path)
    side = _sidecar("rc_s15")["log_events"]
    assert modes["TimeUS"].tolist() == [e["time_us"] for e in side["MODE"]]
    assert modes["ModeName"].tolist()[:5] == ["STABILIZE", "STABILIZE", "GUIDED", "GUIDED", "AUTO"]
    rtl = modes[modes["ModeName"] == "RTL"]
    assert rtl["RsnName"].tolist() == ["RADIO_FAILSAFE"]
    assert modes["RsnName"].iloc[0] == "INITIALISED"
    msgs = read_messages(path)
    assert list(msgs.columns) == ["TimeUS", "Message"]
    assert msgs["Message"].tolist() == [e["text"] for e in side["MSG"]]
    assert "Radio Failsafe" in msgs["Message"].tolist()


def test_read_log_equals_separate_readers():
    path = _ref("gps_s12")
    log = _log("gps_s12")
    assert_tables_equal(log.tables, read_bin(path))
    assert log.params == read_params(path)
    pd.testing.assert_frame_equal(log.param_changes, read_param_changes(path))
    assert log.mission == read_mission(path)
    pd.testing.assert_frame_equal(log.modes, read_modes(path))
    pd.testing.assert_frame_equal(log.messages, read_messages(path))
    side = _sidecar("gps_s12")
    assert log.info["messages"]["GPS"] == side["log_message_rates"]["GPS"]["count"]
    assert log.info["size_bytes"] == side["log_size_bytes"]
    assert log.info["issues"] == [] and log.info["tail_bytes"] > 0
    for name, s in SCHEMAS.items():  # registry schemas where the log's layout equals them
        assert log.schemas[name] is s, name
    assert log.schemas["XKT"].instance_field == "C"  # not in the registry: from FMT + FMTU
    only = read_log(path, types=())
    assert only.tables == {} and only.mission == log.mission


def test_split_instances():
    tables = _log("normal_s11").tables
    imu = split_instances(tables["IMU"], "IMU")
    assert list(imu) == [0, 1] and len(imu[0]) == len(imu[1])
    assert (imu[1]["I"] == 1).all() and imu[1].index.equals(pd.RangeIndex(len(imu[1])))
    pd.testing.assert_frame_equal(
        pd.concat(imu.values()).sort_values(["TimeUS", "I"]).reset_index(drop=True),
        tables["IMU"].sort_values(["TimeUS", "I"]).reset_index(drop=True),
    )
    assert list(split_instances(tables["XKF1"], SCHEMAS["XKF1"])) == [0, 1]
    assert list(split_instances(tables["VIBE"], "VIBE")) == [0, 1]
    rate = split_instances(tables["RATE"], "RATE")
    assert list(rate) == [0] and len(rate[0]) == len(tables["RATE"])
    with pytest.raises(KeyError):
        split_instances(tables["RATE"], "NOPE")


# --- damaged and foreign files -----------------------------------------------------------------
@dataclass
class Slice:
    """The first SLICE_BYTES of normal_s11.bin (a copy in a temporary folder) and its index."""

    dir: Path
    data: bytes
    tables: dict[str, pd.DataFrame]
    offsets: dict[int, np.ndarray]
    by_name: dict
    fmt_offsets: np.ndarray

    @property
    def path(self) -> Path:
        return self.write(self.data, "slice.bin")

    def write(self, data: bytes, name: str = "damaged.bin") -> Path:
        p = self.dir / name
        p.write_bytes(data)
        return p


@pytest.fixture(scope="module")
def ref_slice(tmp_path_factory) -> Slice:
    with open(_ref("normal_s11"), "rb") as f:
        data = f.read(SLICE_BYTES)
    s = Slice(tmp_path_factory.mktemp("binreader"), data, {}, {}, {}, np.zeros(0))
    ix = scan_bin(s.path)
    s.tables, s.offsets, s.by_name = read_bin(s.path), ix.offsets, ix.by_name
    s.fmt_offsets = ix.offsets[FMT_TYPE]
    return s


def _read_checked(path: Path):
    """read_log, failing on anything but BinLogError / BinLogWarning or on a hang."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        faulthandler.dump_traceback_later(HANG_S, exit=True, file=sys.__stderr__)
        try:
            log = read_log(path)
        except BinLogError as e:
            msg = str(e)
            assert path.name in msg and "not an ArduPilot DataFlash log" in msg, msg
            assert "\n" not in msg
            return None, []
        finally:
            faulthandler.cancel_dump_traceback_later()
    # a ResourceWarning about another file is the garbage collector closing what some other
    # test left open, not this read's doing; one about this file would be
    other = [f"{w.category.__name__}: {w.message}" for w in caught
             if not issubclass(w.category, BinLogWarning)
             and not (issubclass(w.category, ResourceWarning) and str(path) not in str(w.message))]
    assert other == []
    for name, df in log.tables.items():
        schema = log.schemas[name]
        assert list(df.columns) == list(schema.columns), name
        for col, ch in zip(schema.columns, schema.fmt, strict=True):
            if FORMAT_CHARS[ch].kind in ("int", "scaled", "float"):
                assert df[col].dtype == FORMAT_CHARS[ch].dtype, (name, col)
    assert sum(len(df) for df in log.tables.values()) <= path.stat().st_size // 4
    assert isinstance(log.mission, list) and isinstance(log.params, dict)
    assert list(log.modes.columns)[-2:] == ["ModeName", "RsnName"]
    return log, [str(w.message) for w in caught]


def _png() -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(kind + data)
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    ihdr = struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0)  # 1x1 RGB
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
            + chunk(b"IDAT", zlib.compress(b"\x00\xff\x00\x00")) + chunk(b"IEND", b""))


@pytest.mark.parametrize(
    ("content", "what"),
    [
        (b"", "empty file"),
        (b"TimeUS,Lat,Lng\n1,2,3\n" * 50, "no FMT message"),
        (np.random.default_rng(3).integers(0, 256, 50_000, dtype=np.uint8).tobytes(),
         "no FMT message"),
        (_png(), "no FMT message"),
        (b"\xa3\x95\x80" + b"\x00" * 200, "no valid FMT message"),
    ],
    ids=["empty", "text", "random", "png", "zero-fmt"],
)
def test_not_a_dataflash_log(tmp_path, content, what):
    path = tmp_path / "foreign.bin"
    path.write_bytes(content)
    with pytest.raises(BinLogError, match=what) as err:
        read_bin(path)
    assert str(path) in str(err.value) and isinstance(err.value, ValueError)
    with pytest.raises(BinLogError):
        read_bin(path, method="messages")
    with pytest.raises(FileNotFoundError):
        read_bin(tmp_path / "missing.bin")


def test_genuine_log_reads_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_bin(_ref("rc_s15"), ["GPS", "MODE"])


def test_flipped_type_byte_loses_one_message(ref_slice):
    imu = ref_slice.by_name["IMU"]
    victim = int(ref_slice.offsets[imu.type][5])
    data = bytearray(ref_slice.data)
    data[victim + 2] = 7  # a type no FMT defines
    log, warned = _read_checked(ref_slice.write(bytes(data)))
    assert len(warned) == 1 and "skipped" in warned[0] and f"byte {victim}" in warned[0]
    for name, df in ref_slice.tables.items():
        expected = df.drop(index=5).reset_index(drop=True) if name == "IMU" else df
        pd.testing.assert_frame_equal(log.tables[name], expected, obj=name)


def test_signalling_nan_payload_reads_quietly(ref_slice):
    imu = ref_slice.by_name["IMU"]
    at = int(ref_slice.offsets[imu.type][0]) + 3 + 8 + 1 + 3 * 4  # AccX of the first IMU row
    data = bytearray(ref_slice.data)
    data[at : at + 4] = struct.pack("<I", 0x7FA00000)  # float32 signalling NaN
    log, warned = _read_checked(ref_slice.write(bytes(data)))
    assert warned == [] and np.isnan(log.tables["IMU"]["AccX"].iloc[0])
    assert log.tables["IMU"]["AccY"].iloc[0] == ref_slice.tables["IMU"]["AccY"].iloc[0]


def _fmt_offset(ref_slice: Slice, name: str) -> int:
    t = ref_slice.by_name[name].type
    return next(int(o) for o in ref_slice.fmt_offsets if ref_slice.data[o + 3] == t)


def test_damaged_fmt_drops_its_type_only(ref_slice):
    data = bytearray(ref_slice.data)
    data[_fmt_offset(ref_slice, "VIBE") + 4] += 1  # FMT length no longer matches the format
    log, warned = _read_checked(ref_slice.write(bytes(data)))
    assert len(ref_slice.tables["VIBE"]) > 100
    assert any("damaged FMT" in w for w in warned) and any("skipped" in w for w in warned)
    assert "VIBE" not in log.tables
    for name, df in ref_slice.tables.items():
        if name not in ("VIBE", "FMT"):  # the FMT table holds the damaged FMT as it is
            pd.testing.assert_frame_equal(log.tables[name], df, obj=name)


def test_messages_method_reports_unusable_fmt_as_binlogerror(ref_slice):
    """A FMT whose column list no longer matches its format (two names run together) is a
    BinLogError naming the file on pymavlink's path, not a ValueError from the schema."""
    data = bytearray(ref_slice.data)
    at = _fmt_offset(ref_slice, "GPS")
    cols = bytes(data[at + 25 : at + 89]).rstrip(b"\0")
    data[at + 25 + cols.rindex(b",")] = ord("_")
    path = ref_slice.write(bytes(data))
    with pytest.raises(BinLogError, match=path.name):
        read_bin(path, ["GPS"], method="messages")


def test_conflicting_fmt_keeps_first(ref_slice):
    at = _fmt_offset(ref_slice, "RATE")
    fake = bytearray(ref_slice.data[at : at + FMT_LENGTH])
    fake[5:9] = b"RATX"
    cut = int(ref_slice.offsets[ref_slice.by_name["IMU"].type][10])
    data = ref_slice.data
    log, warned = _read_checked(ref_slice.write(data[:cut] + bytes(fake) + data[cut:]))
    assert len(warned) == 1 and "redefining" in warned[0]
    assert "RATX" not in log.tables
    assert_tables_equal({n: df for n, df in log.tables.items() if n != "FMT"},
                        {n: df for n, df in ref_slice.tables.items() if n != "FMT"})


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(cut=st.integers(0, SLICE_BYTES))
def test_truncated_file_gives_prefix_without_warning(ref_slice, cut):
    log, warned = _read_checked(ref_slice.write(ref_slice.data[:cut]))
    if log is None:
        assert cut < FMT_LENGTH
        return
    assert warned == []
    for name, df in ref_slice.tables.items():
        f = ref_slice.by_name[name]
        keep = int(np.count_nonzero(ref_slice.offsets[f.type] + f.length <= cut))
        got = log.tables.get(name, df.iloc[:0])
        pd.testing.assert_frame_equal(got, df.iloc[:keep], obj=name)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(at=st.integers(0, 10_000), junk=st.binary(min_size=1, max_size=400))
def test_inserted_garbage_is_skipped(ref_slice, at, junk):
    junk = junk.replace(b"\xa3\x95", b"\xa3\x00")
    starts = np.sort(np.concatenate(list(ref_slice.offsets.values())))
    pos = int(starts[at % starts.size])  # a message boundary
    data = ref_slice.data
    log, warned = _read_checked(ref_slice.write(data[:pos] + junk + data[pos:]))
    assert len(warned) == 1 and warned[0].startswith("damaged.bin: read 0.2 MB to ")
    assert warned[0].endswith(f" s (log time); skipped {len(junk)} bytes that are not messages "
                              f"(1 place, first at byte {pos})")
    assert_tables_equal(log.tables, ref_slice.tables)


_MUTATION = st.one_of(
    st.tuples(st.just("truncate"), st.floats(0, 1)),
    st.tuples(st.just("flip"), st.floats(0, 1, exclude_max=True), st.integers(0, 7)),
    st.tuples(st.just("byte"), st.floats(0, 1, exclude_max=True), st.integers(0, 255)),
    st.tuples(st.just("insert"), st.floats(0, 1), st.binary(min_size=1, max_size=300)),
    st.tuples(st.just("delete"), st.floats(0, 1), st.integers(1, 3000)),
    st.tuples(st.just("header"), st.floats(0, 1, exclude_max=True), st.integers(0, 255)),
    st.tuples(st.just("fmt"), st.integers(0, 10_000), st.sampled_from([3, 4, 5, 9, 10, 25, 30]),
              st.integers(0, 255)),
)


def _mutate(ref_slice: Slice, ops: list[tuple]) -> bytes:
    """Apply mutations in order: truncate, flip a bit, set a byte, insert or delete bytes,
    write a message header, or change the type/length/name/format/column byte of an FMT."""
    d = bytearray(ref_slice.data)
    for op in ops:
        kind = op[0]
        if kind == "fmt":
            o = int(ref_slice.fmt_offsets[op[1] % ref_slice.fmt_offsets.size]) + op[2]
            if o < len(d):
                d[o] = op[3]
            continue
        if not d:
            break
        i = min(int(op[1] * len(d)), len(d) - 1)
        if kind == "truncate":
            del d[i:]
        elif kind == "flip":
            d[i] ^= 1 << op[2]
        elif kind == "byte":
            d[i] = op[2]
        elif kind == "insert":
            d[i:i] = op[2]
        elif kind == "delete":
            del d[i : i + op[2]]
        elif kind == "header":
            d[i : i + 3] = bytes([0xA3, 0x95, op[2]])
    return bytes(d)


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(_MUTATION, min_size=1, max_size=6))
def test_fuzz_mutated_log_never_crashes_or_hangs(ref_slice, ops):
    """Any mutation: BinLogError or a consistent partial log with BinLogWarnings only."""
    _read_checked(ref_slice.write(_mutate(ref_slice, ops)))


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ops=st.lists(_MUTATION, min_size=1, max_size=4))
def test_fuzz_messages_method_raises_only_binlogerror(ref_slice, ops):
    """The pymavlink cross-check path on damaged input: tables or BinLogError, nothing else."""
    path = ref_slice.write(_mutate(ref_slice, ops))
    faulthandler.dump_traceback_later(HANG_S, exit=True, file=sys.__stderr__)
    try:
        out = read_bin(path, ["GPS", "IMU", "PARM", "MSG"], method="messages")
        assert set(out) == {"GPS", "IMU", "PARM", "MSG"}
    except BinLogError as e:
        assert path.name in str(e)
    finally:
        faulthandler.cancel_dump_traceback_later()


# --- hostile logs through the readers, tlm info and tlm convert ----------------------------------
def _patched_fmt(ref_slice: Slice, changes: dict[str, tuple[int, bytes]]) -> bytes:
    """The slice with bytes of some FMT messages replaced: name → (offset in the FMT, bytes)."""
    data = bytearray(ref_slice.data)
    for name, (at, new) in changes.items():
        o = _fmt_offset(ref_slice, name) + at
        data[o : o + len(new)] = new
    return bytes(data)


def _tree(root: Path) -> set[Path]:
    return {p for p in root.rglob("*")}


def _cli(argv: list[str], capsys) -> tuple[int, str, str]:
    """``tlm ARGV`` in this process: (exit code, stdout, stderr); any exception fails the test."""
    from tlm_process.cli import main

    faulthandler.dump_traceback_later(HANG_S, exit=True, file=sys.__stderr__)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BinLogWarning)
            rc = main(argv)
    finally:
        faulthandler.cancel_dump_traceback_later()
    out, err = capsys.readouterr()
    assert rc in (0, 2), (rc, err)
    if rc == 2:
        assert len(err.strip().splitlines()) == 1 and err.startswith("tlm: error: "), err
    return rc, out, err


def test_unsafe_fmt_names_are_skipped_and_nothing_is_written_outside_out(ref_slice, tmp_path,
                                                                         capsys):
    """Item 5: FMT names '../x' and '/abs' (RATE's and VIBE's FMT) must not become paths."""
    work = tmp_path / "work"
    work.mkdir()
    src = work / "hostile.bin"
    src.write_bytes(_patched_fmt(ref_slice, {"RATE": (5, b"../x"), "VIBE": (5, b"/abs")}))
    abs_before = Path("/abs.csv").exists()
    before = _tree(tmp_path)
    rc, out, _ = _cli(["convert", str(src), "--out", str(work / "out")], capsys)
    assert rc == 0
    assert {p for p in _tree(tmp_path) - before if work / "out" not in p.parents} == {work / "out"}
    assert Path("/abs.csv").exists() == abs_before
    assert "'../x'" in out and "'/abs'" in out and "not a message name" in out
    n_rate, n_vibe = len(ref_slice.tables["RATE"]), len(ref_slice.tables["VIBE"])
    with pytest.warns(BinLogWarning, match="not a message name"):
        log = read_log(src)
    lost = log.info["lost_messages"]
    assert sorted(lost.values()) == sorted([n_rate, n_vibe])
    assert any("'../x'" in k for k in lost) and any("'/abs'" in k for k in lost)
    assert not any("/" in n or "." in n for n in log.tables)
    rc, out, _ = _cli(["info", str(src)], capsys)
    assert rc == 0 and "'../x'" in out and "messages lost: " in out


def test_flightlog_write_refuses_unsafe_table_names(tmp_path):
    from tlm_sim.flightlog import FlightLog
    from tlm_sim.flightlog.flightlog import write_table

    gps = SCHEMAS["GPS"]
    df = pd.DataFrame({c: [] for c in gps.columns})
    for bad in ("../x", "/abs", "a.b", "a\\b", "", "x\0"):
        log = FlightLog({bad: df}, schemas={bad: gps})
        with pytest.raises(ValueError, match="safe file name"):
            log.write(tmp_path / "out", formats=["csv"])
        with pytest.raises(ValueError, match="safe file name"):
            write_table(tmp_path, bad, df, gps, ["csv"])
    assert _tree(tmp_path) == set()


# the columns tlm info needs from each context table: every one renamed by a one-bit flip
_CONTEXT_COLUMNS = {"MODE": ("TimeUS", "ModeNum", "Rsn"), "EV": ("TimeUS", "Id"),
                    "PARM": ("TimeUS", "Name", "Value"), "MSG": ("TimeUS", "Message")}


def _column_flip(ref_slice: Slice, name: str, column: str, bit: int = 0) -> bytes:
    """The slice with one bit flipped in the first letter of ``column`` in ``name``'s FMT."""
    o = _fmt_offset(ref_slice, name)
    cols = bytes(ref_slice.data[o + 25 : o + 89])
    at = o + 25 + ([0] + [k + 1 for k, c in enumerate(cols) if c == ord(",")])[
        ref_slice.by_name[name].columns.index(column)]
    data = bytearray(ref_slice.data)
    data[at] ^= 1 << bit
    return bytes(data)


@pytest.mark.parametrize(("name", "column"),
                         [(n, c) for n, cols in _CONTEXT_COLUMNS.items() for c in cols])
def test_info_names_a_context_table_whose_column_a_bit_flip_renamed(ref_slice, tmp_path, capsys,
                                                                    name, column):
    """Item 6: a renamed MODE/EV/PARM/MSG column (a crash before) is named; the rest reported."""
    src = tmp_path / "flip.bin"
    src.write_bytes(_column_flip(ref_slice, name, column))
    rc, out, _ = _cli(["info", str(src), "--json", str(tmp_path / "i.json")], capsys)
    assert rc == 0
    assert f"{name} has no {column} column; ignored" in out
    assert "faults found" in out and "messages " in out
    info = json.loads((tmp_path / "i.json").read_text())
    assert any(f"{name} has no {column}" in d for d in info["damage"])
    assert info["messages"]["IMU"]["count"] == len(ref_slice.tables["IMU"])


def test_info_survives_a_sample_of_column_name_bit_flips(ref_slice, tmp_path, capsys):
    """Item 6: 48 of the 4 × 60 × 8 one-bit flips in the column names of MODE, EV, PARM and
    MSG (fixed seed): each exits 0 or 2 (one line), never an uncaught exception."""
    rng = np.random.default_rng(17)
    src = tmp_path / "flip.bin"
    for _ in range(48):
        name = str(rng.choice(list(_CONTEXT_COLUMNS)))
        o = _fmt_offset(ref_slice, name) + 25 + int(rng.integers(60))
        data = bytearray(ref_slice.data)
        data[o] ^= 1 << int(rng.integers(8))
        src.write_bytes(bytes(data))
        _cli(["info", str(src)], capsys)


def test_renamed_fmt_is_reported(ref_slice, tmp_path):
    """Item 7: a bit flip that renames RATE's FMT to RATA left read_bin(..., ["RATE"]) empty
    without a word."""
    src = tmp_path / "rata.bin"
    src.write_bytes(_patched_fmt(ref_slice, {"RATE": (5 + 3, b"A")}))
    with pytest.warns(BinLogWarning, match=r"named 'RATA' but has the layout of RATE"):
        out = read_bin(src, ["RATE"])
    assert len(out["RATE"]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_bin(ref_slice.path, ["RATE"])  # the intact log: no warning


def test_a_real_message_of_a_known_layout_is_not_taken_for_a_renamed_one(ref_slice, tmp_path):
    """NKF1 has XKF1's layout: a log cut before XKF1's FMT is not 'damaged' (found by
    test_truncated_file_gives_prefix_without_warning); only a one-bit rename is."""
    from tlm_sim.flightlog.binscan import _one_bit_apart

    assert _one_bit_apart("RATA", "RATE") and _one_bit_apart("GPS", "GPR")
    assert not _one_bit_apart("NKF1", "XKF1")  # N ^ X has three bits
    assert not _one_bit_apart("RATE", "RATE") and not _one_bit_apart("RAT", "RATE")
    xkf1 = _fmt_offset(ref_slice, "XKF1")
    src = tmp_path / "cut.bin"
    src.write_bytes(ref_slice.data[:xkf1])
    log, warned = _read_checked(src)
    assert not any("has the layout of" in w for w in warned)


def test_lost_messages_are_counted_per_type(ref_slice, tmp_path, capsys):
    """Item 7: what the reader drops is counted per type and printed by tlm info/convert."""
    n_vibe = len(ref_slice.tables["VIBE"])
    src = tmp_path / "vibe.bin"
    data = bytearray(ref_slice.data)
    data[_fmt_offset(ref_slice, "VIBE") + 4] += 1  # VIBE's FMT length no longer matches
    imu = int(ref_slice.offsets[ref_slice.by_name["IMU"].type][5])
    data[imu + 2] = 7  # one IMU message of a type no FMT defines
    src.write_bytes(bytes(data))
    log, warned = _read_checked(src)
    lost = log.info["lost_messages"]
    vibe_type = ref_slice.by_name["VIBE"].type
    assert lost == {f"type {vibe_type} ('VIBE', damaged FMT)": n_vibe, "type 7": 1}
    assert any("lost messages: type 7 1" in w or "type 7 1" in w for w in warned)
    rc, out, _ = _cli(["info", str(src)], capsys)
    assert rc == 0 and f"'VIBE', damaged FMT) {n_vibe}" in out
    rc, out, _ = _cli(["convert", str(src), "--out", str(tmp_path / "c")], capsys)
    assert rc == 0 and "damage " in out and "'VIBE', damaged FMT" in out


@pytest.mark.parametrize("what", ["device", "folder", "fifo"])
def test_info_and_convert_refuse_a_file_that_is_not_regular(tmp_path, capsys, what):
    """Item 11: /dev/zero said 'file not found' (it exists: it is not a regular file)."""
    import os

    if what == "device":
        path = Path("/dev/zero")
    elif what == "folder":
        path = tmp_path
    else:
        path = tmp_path / "pipe.bin"
        os.mkfifo(path)
    for argv in (["info", str(path)], ["convert", str(path), "--out", str(tmp_path / "o")]):
        rc, _, err = _cli(argv, capsys)
        assert rc == 2 and "not a regular file" in err and "not found" not in err
    assert not (tmp_path / "o").exists()
    with pytest.raises(BinLogError, match="not a regular file"):
        read_bin(path)


@settings(max_examples=30, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(ops=st.lists(_MUTATION, min_size=1, max_size=6))
def test_fuzz_info_and_convert_on_mutated_logs(ref_slice, capsys, ops):
    """tlm info and tlm convert on the reader's fuzz mutants: exit 0 or 2 (one line), never an
    uncaught exception or a hang, nothing written outside --out."""
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        root = Path(d)
        src = root / "m.bin"
        src.write_bytes(_mutate(ref_slice, ops))
        _cli(["info", str(src), "--json", str(root / "info.json")], capsys)
        before = _tree(root)
        rc, _, _ = _cli(["convert", str(src), "--out", str(root / "out")], capsys)
        new = _tree(root) - before
        assert all(p == root / "out" or root / "out" in p.parents for p in new)
        if rc == 0:
            assert (root / "out" / "meta.json").exists()
