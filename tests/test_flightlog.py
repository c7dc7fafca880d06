"""tlm_sim.flightlog: schemas vs the reference SITL log, quantisation, files, .bin reading."""

from __future__ import annotations

import dataclasses
import json
import struct
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from pymavlink import DFReader

from tests.conftest import REFERENCE, close_dfreader, reference_path
from tlm_sim.flightlog import (
    FORMAT_CHARS,
    LOGGED_MESSAGES,
    MULTS,
    SCHEMAS,
    UNITS,
    FlightLog,
    allocate_buffers,
    quantise_column,
    quantise_frame,
    read_bin,
    read_events,
    read_params,
    read_schemas,
)

NORMAL = REFERENCE / "normal_s11.bin"
needs_ref = pytest.mark.skipif(not NORMAL.exists(), reason="reference SITL logs not found")

REF_TYPES = ("GPS", "IMU", "RATE", "VIBE", "MODE", "EV", "ERR", "MSG", "PARM")


# --- fixtures --------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def ref_tables() -> dict[str, pd.DataFrame]:
    return read_bin(reference_path(NORMAL.name), REF_TYPES)


@pytest.fixture(scope="session")
def ref_self_description() -> dict:
    """FMT / FMTU / UNIT / MULT of the reference log, read with pymavlink alone."""
    r = DFReader.DFReader_binary(str(reference_path(NORMAL.name)))
    fmts = {f.name: f for f in r.formats.values()}
    by_type = {f.type: f.name for f in r.formats.values()}
    fmtu, units, mults = {}, {}, {}
    while (m := r.recv_match(type=["FMTU", "UNIT", "MULT"])) is not None:
        t = m.get_type()
        if t == "FMTU":
            fmtu.setdefault(by_type[m.FmtType], (m.UnitIds, m.MultIds))
        elif t == "UNIT":
            units[chr(m.Id)] = m.Label
        elif t == "MULT":
            mults[chr(m.Id)] = m.Mult
    close_dfreader(r)
    return {"fmt": fmts, "fmtu": fmtu, "units": units, "mults": mults}


# --- schemas -----------------------------------------------------------------------------------
@needs_ref
def test_schemas_equal_reference_fmt_and_fmtu(ref_self_description):
    fmts, fmtu = ref_self_description["fmt"], ref_self_description["fmtu"]
    for name, s in SCHEMAS.items():
        f = fmts[name]
        assert s.fmt == f.format, name
        assert list(s.columns) == f.columns, name
        assert s.length == f.len, name
        assert (s.units, s.mults) == fmtu[name], name
        inst = f.columns[fmtu[name][0].index("#")] if "#" in fmtu[name][0] else None
        assert s.instance_field == inst, name


@needs_ref
def test_unit_and_mult_tables_equal_reference(ref_self_description):
    assert UNITS == ref_self_description["units"]
    log_mults = ref_self_description["mults"]
    assert set(MULTS) == set(log_mults)
    for k, v in log_mults.items():  # the log stores float32-rounded factors as doubles
        assert np.float32(MULTS[k]) == np.float32(v), k


@needs_ref
def test_read_schemas_matches_registry():
    log = read_schemas(NORMAL)
    assert len(log) > 60
    for name, s in SCHEMAS.items():
        ls = log[name]
        assert (ls.fmt, ls.columns, ls.units, ls.mults, ls.instance_field) == (
            s.fmt,
            s.columns,
            s.units,
            s.mults,
            s.instance_field,
        )


def test_required_messages_and_logged_subset():
    required = (
        "GPS GPA IMU RATE VIBE ATT BARO MAG RCIN RCOU MODE EV ERR XKF1 XKF4 CTUN BAT POS SIM "
        "SIM2 PSCN PSCE PSCD MOTB PARM MSG CMD FMT UNIT MULT FMTU"
    ).split()
    assert set(required) <= set(SCHEMAS)
    assert set(LOGGED_MESSAGES) <= set(SCHEMAS)
    assert len(LOGGED_MESSAGES) == 39
    for name in LOGGED_MESSAGES:
        assert SCHEMAS[name].columns[0] == "TimeUS"
        assert not SCHEMAS[name].string_columns  # the simulator fills numbers only


@pytest.mark.parametrize(
    ("name", "length"),
    [
        ("GPS", 51),
        ("IMU", 54),
        ("VIBE", 28),
        ("RATE", 63),
        ("ATT", 36),
        ("BARO", 47),
        ("RCIN", 39),
        ("XKF1", 56),
        ("MODE", 14),
        ("ERR", 13),
        ("EV", 12),
        ("PARM", 35),
        ("MSG", 75),
        ("FMT", 89),
        ("UNIT", 76),
        ("MULT", 20),
        ("FMTU", 44),
    ],
)
def test_struct_lengths_equal_ardupilot(name, length):
    s = SCHEMAS[name]
    assert s.length == length
    assert struct.calcsize(s.struct_format()) + 3 == length


def test_schema_helpers():
    gps = SCHEMAS["GPS"]
    assert gps.struct_format() == "<QBBIHBhiiiffffB"
    assert gps.index("Lat") == 7 and gps.char("Alt") == "e"
    assert gps.scale("HDop") == 0.01 and gps.scale("Lat") == 1e-7 and gps.scale("Spd") == 1.0
    # table value × si_factor = value in the FMTU unit
    assert gps.si_factor("HDop") == pytest.approx(1.0)
    assert gps.si_factor("Lat") == pytest.approx(1.0) and gps.unit("Lat") == "deglatitude"
    assert gps.si_factor("Alt") == pytest.approx(1.0) and gps.unit("Alt") == "m"
    assert gps.si_factor("TimeUS") == pytest.approx(1e-6) and gps.unit("TimeUS") == "s"
    assert gps.si_factor("GMS") == pytest.approx(1e-3)
    assert gps.si_factor("Status") is None
    assert SCHEMAS["CTUN"].si_factor("CRt") == pytest.approx(0.01)  # int16 cm/s
    assert SCHEMAS["MAG"].si_factor("MagX") == pytest.approx(1e-3)  # mGauss → Gauss
    assert SCHEMAS["RATE"].si_factor("ADes") == pytest.approx(0.01)  # cm/s² → m/s²
    assert SCHEMAS["XKF4"].si_factor("SV") is None
    assert SCHEMAS["PARM"].numeric_columns == ("TimeUS", "Value", "Default")
    assert SCHEMAS["PARM"].string_columns == ("Name",)
    assert SCHEMAS["IMU"].instance_field == "I" and SCHEMAS["VIBE"].instance_field == "IMU"
    assert SCHEMAS["XKF1"].instance_field == "C" and SCHEMAS["RATE"].instance_field is None
    assert SCHEMAS["IMU"].rate_hz == 25 and SCHEMAS["GPS"].rate_hz == 5
    assert SCHEMAS["MODE"].rate_hz == 0
    with pytest.raises(KeyError):
        gps.index("Nope")


def test_allocate_buffers_shapes():
    bufs = allocate_buffers(100.0)
    assert tuple(bufs) == LOGGED_MESSAGES
    assert bufs["IMU"].shape == (SCHEMAS["IMU"].max_rows(100.0), 15)
    assert bufs["IMU"].shape[0] >= 100 * 25 * 2
    assert bufs["MODE"].shape == (256, 4)
    assert all(b.dtype == np.float64 for b in bufs.values())


# --- quantisation --------------------------------------------------------------------------------
def test_quantise_characters():
    f = quantise_column([0.1, np.nan, 1e40], "f")
    assert f.dtype == np.float64
    assert f[0] == float(np.float32(0.1)) and np.isnan(f[1]) and np.isinf(f[2])
    c = quantise_column([1.214, 1.215, -1.2149, 400.0, np.nan], "c")
    assert c.tolist() == [1.21, 1.22, -1.21, 327.67, 0.0]
    assert quantise_column([700.0], "C").tolist() == [655.35]
    assert quantise_column([-1.0], "C").tolist() == [0.0]
    lat = quantise_column([-35.36326104999, 149.16523], "L")
    assert lat.tolist() == [-353632610 / 1e7, 1491652300 / 1e7]
    b = quantise_column([300.0, -5.0, 2.5, 3.5, np.nan], "B")
    assert b.dtype == np.uint8 and b.tolist() == [255, 0, 2, 4, 0]  # round half to even
    assert quantise_column([40000.0], "h").tolist() == [32767]
    assert quantise_column([-200.0], "b").tolist() == [-128]
    q = quantise_column([1.0e20, -1.0, 123456789012.4], "Q")
    assert q.dtype == np.int64 and q.tolist()[1:] == [0, 123456789012] and q[0] > 2**62
    assert quantise_column([3.0, 200.0], "M").dtype == np.uint8
    s = quantise_column([0.0, "MODE_TOO_LONG", b"ab\0cd"], "n")
    assert s.tolist() == ["", "MODE", "ab"]
    for ch in "fcCeELBbhHiIqQMdg":
        x = quantise_column(np.array([0.123456789, -7.5, 1e9, np.nan]), ch)
        y = quantise_column(x, ch)
        np.testing.assert_array_equal(x, y)  # idempotent
        assert x.dtype == FORMAT_CHARS[ch].dtype


def _filled_buffer(name: str, n: int, rng: np.random.Generator) -> np.ndarray:
    s = SCHEMAS[name]
    buf = rng.normal(0.0, 100.0, size=(n + 5, len(s.columns)))
    buf[:, 0] = rng.integers(0, 10**9, size=n + 5).astype(np.float64)
    return buf


def test_from_buffers_slices_sorts_and_types():
    rng = np.random.default_rng(1)
    imu = _filled_buffer("IMU", 40, rng)
    imu[:40, 0] = np.repeat(np.arange(20) * 40_000.0, 2)[::-1]  # reversed, pairs of equal times
    imu[:40, 1] = np.tile([1.0, 0.0], 20)  # instance column
    gps = _filled_buffer("GPS", 3, rng)
    gps[:3, 7] = [-35.36326104, -35.3632611, -35.36326126]
    mode = np.zeros((8, 4))
    log = FlightLog.from_buffers(
        {"IMU": imu, "GPS": gps, "MODE": mode}, {"IMU": 40, "GPS": 3, "MODE": 0}
    )
    assert set(log.tables) == {"IMU", "GPS"}  # empty tables are left out
    df = log.tables["IMU"]
    assert len(df) == 40
    assert list(df.columns) == list(SCHEMAS["IMU"].columns)
    assert (np.diff(df["TimeUS"].to_numpy()) >= 0).all()
    # stable: equal TimeUS keep buffer order (instance 1 was written before 0 in each pair)
    assert df["I"].tolist() == [1, 0] * 20
    assert df.dtypes["TimeUS"] == np.int64 and df.dtypes["I"] == np.uint8
    assert df.dtypes["EG"] == np.uint32 and df.dtypes["GHz"] == np.uint16
    assert df.dtypes["AccX"] == np.float64
    assert (df["AccX"].to_numpy() == df["AccX"].to_numpy().astype(np.float32)).all()
    g = log.tables["GPS"]
    assert set(g["Lat"]) == {-353632610 / 1e7, -353632611 / 1e7, -353632613 / 1e7}
    empty = log.table("MODE")
    assert len(empty) == 0 and empty.dtypes["Mode"] == np.uint8
    with pytest.raises(ValueError):
        FlightLog.from_buffers({"IMU": imu[:, :5]}, {"IMU": 4})
    with pytest.raises(ValueError):
        FlightLog.from_buffers({"IMU": imu}, {"IMU": 10_000})


def test_from_buffers_accepts_sequences_in_logged_order():
    bufs = allocate_buffers(2.0)
    counts = np.zeros(len(LOGGED_MESSAGES), dtype=np.int64)
    k = LOGGED_MESSAGES.index("EV")
    bufs["EV"][0] = [1_000_000.0, 10.0]
    counts[k] = 1
    log = FlightLog.from_buffers(tuple(bufs.values()), counts)
    assert list(log.tables) == ["EV"]
    assert log.tables["EV"].iloc[0].tolist() == [1_000_000, 10]


# --- files: hypothesis round trip ---------------------------------------------------------------
_ROUND_TRIP = ("GPS", "IMU", "MODE", "XKF1", "SIM", "CTUN", "BAT", "MAG", "POS")
_value = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64),
    st.floats(min_value=-1e4, max_value=1e4),
    st.integers(min_value=-70_000, max_value=70_000).map(float),
)


@st.composite
def _buffers(draw):
    bufs, counts = {}, {}
    for name in draw(st.lists(st.sampled_from(_ROUND_TRIP), min_size=1, max_size=4, unique=True)):
        ncol = len(SCHEMAS[name].columns)
        n = draw(st.integers(0, 12))
        buf = draw(hnp.arrays(np.float64, (n + 2, ncol), elements=_value, fill=st.nothing()))
        buf[:, 0] = draw(
            hnp.arrays(
                np.float64,
                n + 2,
                fill=st.nothing(),
                elements=st.floats(0, 2.0**53, allow_nan=False),
            )
        )
        bufs[name], counts[name] = buf, n
    return bufs, counts


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_buffers())
def test_buffers_to_csv_and_parquet_round_trip(data):
    bufs, counts = data
    log = FlightLog.from_buffers(
        bufs,
        counts,
        params={"SIM_ENGINE_MUL": 1.0, "WPNAV_SPEED": 600},
        mission={"waypoints": [[-35.36, 149.16, 20.0]]},
        faults=[{"type": "gps", "label": 1, "start_time_us": 5, "end_time_us": 9}],
        meta={"seed": 3, "duration_s": 1.5},
    )
    for name, df in log.tables.items():
        assert len(df) == counts[name]
        assert dict(df.dtypes) == SCHEMAS[name].dtypes
    with tempfile.TemporaryDirectory() as d:
        log.write(d, formats=("csv", "parquet"))
        back = FlightLog.read(d)  # Parquet
        assert back.equals(log)
        for name in log.tables:
            pd.testing.assert_frame_equal(back.tables[name], log.tables[name])
            (Path(d) / f"{name}.parquet").unlink()
        back_csv = FlightLog.read(d)  # CSV
        for name in log.tables:
            pd.testing.assert_frame_equal(back_csv.tables[name], log.tables[name])
        assert back_csv.equals(log)


def test_write_layout_csv_format_and_meta(tmp_path):
    gps = np.zeros((2, 15))
    gps[0] = [
        3e6,
        0,
        6,
        123456000,
        2300,
        10,
        1.21,
        -35.363261,
        149.16523,
        584.0,
        1.5,
        90.0,
        -0.2,
        0,
        1,
    ]

    @dataclasses.dataclass
    class Params:
        SIM_ENGINE_MUL: float = 1.0
        WPNAV_SPEED: float = 1000.0

    log = FlightLog.from_buffers(
        {"GPS": gps, "EV": np.zeros((4, 2))},
        {"GPS": 1, "EV": 0},
        params=Params(WPNAV_SPEED=600.0),
        meta={"seed": 7},
        faults=[{"type": "rc", "label": 4, "start_time_us": np.int64(1)}],
    )
    out = log.write(tmp_path / "flight", formats=("csv",))
    files = sorted(p.name for p in out.iterdir())
    assert files == ["GPS.csv", "meta.json"]  # empty EV skipped, no Parquet asked for
    lines = (out / "GPS.csv").read_text().splitlines()
    assert lines[0] == ",".join(SCHEMAS["GPS"].columns)
    assert lines[1] == (
        "3000000,0,6,123456000,2300,10,1.21,-35.3632610,149.1652300,584.00,1.5,90.0,-0.2,0.0,1"
    )
    doc = json.loads((out / "meta.json").read_text())
    assert doc["meta"] == {"seed": 7}
    assert doc["params_changed"] == {"WPNAV_SPEED": 600.0}
    assert doc["params"] == {"SIM_ENGINE_MUL": 1.0, "WPNAV_SPEED": 600.0}
    assert doc["faults"][0]["start_time_us"] == 1
    assert doc["tables"] == {"GPS": 1}
    s = log.summary()
    assert s["tables"]["GPS"]["rows"] == 1 and s["duration_s"] == 0.0
    with pytest.raises(ValueError):
        log.write(tmp_path / "x", formats=("xlsx",))


# --- reading the reference .bin -----------------------------------------------------------------
def _rate_per_instance(df: pd.DataFrame, inst: str | None) -> list[float]:
    groups = [df] if inst is None else [g for _, g in df.groupby(inst)]
    out = []
    for g in groups:
        t = g["TimeUS"].to_numpy()
        out.append((len(t) - 1) / ((t[-1] - t[0]) * 1e-6))
    return out


@needs_ref
def test_reference_rates(ref_tables):
    assert _rate_per_instance(ref_tables["GPS"], "I") == [pytest.approx(5.0, rel=0.01)]
    assert _rate_per_instance(ref_tables["IMU"], "I") == [pytest.approx(25.0, rel=0.01)] * 2
    assert _rate_per_instance(ref_tables["RATE"], None) == [pytest.approx(10.0, rel=0.01)]
    assert _rate_per_instance(ref_tables["VIBE"], "IMU") == [pytest.approx(10.0, rel=0.01)] * 2
    imu = ref_tables["IMU"]
    assert sorted(imu["I"].unique().tolist()) == [0, 1]
    assert (np.diff(imu["TimeUS"].to_numpy()) >= 0).all()


@needs_ref
def test_reference_gps_values(ref_tables):
    gps = ref_tables["GPS"]
    assert dict(gps.dtypes) == SCHEMAS["GPS"].dtypes
    assert gps["Status"].iloc[0] <= 6
    assert set(gps["Status"].unique()) <= {0, 1, 2, 3, 4, 5, 6}
    locked = gps[gps["Status"] == 6]
    assert len(locked) > 0.9 * len(gps)
    assert (locked["NSats"] == 10).all()
    assert (locked["HDop"] == 1.21).all()
    assert locked["Lat"].between(-35.38, -35.35).all()
    assert locked["Lng"].between(149.15, 149.18).all()
    assert locked["Alt"].between(570.0, 640.0).all()
    t = ref_tables["IMU"]
    at_rest = t[(t["TimeUS"] > 20e6) & (t["TimeUS"] < 40e6)]
    assert at_rest["AccZ"].mean() == pytest.approx(-9.8, abs=0.1)


@needs_ref
def test_read_bin_values_equal_pymavlink(ref_tables):
    r = DFReader.DFReader_binary(str(NORMAL))
    got: dict[str, list[dict]] = {"GPS": [], "IMU": [], "VIBE": []}
    while (m := r.recv_match(type=list(got))) is not None:
        lst = got.get(m.get_type())
        if lst is not None and len(lst) < 200:
            lst.append(m.to_dict())
        if all(len(v) >= 200 for v in got.values()):
            break
    close_dfreader(r)
    for name, rows in got.items():
        df = ref_tables[name].iloc[: len(rows)]
        for col in SCHEMAS[name].columns:
            assert df[col].tolist() == [row[col] for row in rows], (name, col)


@needs_ref
def test_read_bin_methods_agree():
    a = read_bin(NORMAL, ["GPS", "MODE", "MSG", "VIBE"], method="index")
    b = read_bin(NORMAL, ["GPS", "MODE", "MSG", "VIBE"], method="messages")
    assert list(a) == list(b)
    for name in a:
        pd.testing.assert_frame_equal(a[name], b[name])


@needs_ref
def test_read_params_and_events():
    params = read_params(NORMAL)
    assert len(params) > 1000
    assert params["LOG_BITMASK"] == 176126
    assert params["SIM_ENGINE_FAIL"] == 1 and params["FS_EKF_THRESH"] == 0
    assert params["WPNAV_SPEED"] == 600 and params["LOG_DISARMED"] == 1
    ev = read_events(NORMAL)
    assert set(ev) == {"MODE", "EV", "ERR", "MSG"}
    side = json.loads(NORMAL.with_suffix(".json").read_text())["log_events"]
    assert ev["MODE"]["TimeUS"].tolist() == [e["time_us"] for e in side["MODE"]]
    assert ev["MODE"]["Rsn"].tolist() == [e["reason"] for e in side["MODE"]]
    assert ev["EV"]["Id"].tolist() == [e["id"] for e in side["EV"]]
    assert ev["ERR"][["Subsys", "ECode"]].values.tolist() == [
        [e["subsys"], e["ecode"]] for e in side["ERR"]
    ]
    assert ev["MSG"]["Message"].iloc[0] == "ArduCopter V4.7.0-dev (2598e9d4)"
    assert ev["MODE"]["Mode"].tolist()[-1] == 3  # AUTO


@needs_ref
def test_reference_tables_round_trip_through_files(ref_tables, tmp_path):
    log = FlightLog({n: ref_tables[n] for n in ("GPS", "MODE", "MSG", "PARM")})
    log.write(tmp_path)
    pq_back = FlightLog.read(tmp_path)
    assert pq_back.equals(log)
    for p in tmp_path.glob("*.parquet"):
        p.unlink()
    assert FlightLog.read(tmp_path).equals(log)


def test_array_format_round_trip(tmp_path):
    from tlm_sim.flightlog.schema import schema_from_fmt

    s = schema_from_fmt("ARRY", "QaB", "TimeUS,Arr,X")
    df = quantise_frame(
        pd.DataFrame({"TimeUS": [1, 2], "Arr": [list(range(40)), [5, 6]], "X": [1, 2]}), s
    )
    assert df["Arr"].iloc[0].tolist() == list(range(32))
    assert df["Arr"].iloc[1].tolist() == [5, 6] + [0] * 30
    FlightLog({"ARRY": df}, schemas={"ARRY": s}).write(tmp_path)
    for back in (FlightLog.read(tmp_path), None):
        if back is None:
            (tmp_path / "ARRY.parquet").unlink()
            back = FlightLog.read(tmp_path)
        got = back.tables["ARRY"]
        assert [a.tolist() for a in got["Arr"]] == [a.tolist() for a in df["Arr"]]
        assert got["X"].tolist() == [1, 2]


def test_read_bin_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        read_bin(tmp_path / "nope.bin")


def test_lazy_tables_build_frames_on_first_access_only():
    """from_buffers keeps canonical columns; a table becomes a DataFrame when read, its
    columns() equal the DataFrame's, and the others stay unbuilt."""
    from tlm_sim.flightlog.flightlog import LazyTables

    schema = SCHEMAS["VIBE"]
    buf = np.zeros((4, len(schema.columns)))
    buf[:, 0] = [30.0, 10.0, 20.0, 0.0]  # unsorted TimeUS
    buf[:, 2] = [3.0, 1.0, 2.0, 0.5]
    log = FlightLog.from_buffers({"VIBE": buf, "GPS": np.zeros((2, len(SCHEMAS["GPS"].columns)))},
                                 {"VIBE": 3, "GPS": 0})
    assert isinstance(log.tables, LazyTables) and list(log.tables) == ["VIBE"]
    cols = log.columns("VIBE")
    assert log.tables.columns("VIBE") is not None  # not built yet
    assert list(cols["TimeUS"]) == [10, 20, 30] and log.n_rows("VIBE") == 3
    df = log.tables["VIBE"]
    assert log.tables.columns("VIBE") is None  # built now
    for c in schema.columns:
        np.testing.assert_array_equal(df[c].to_numpy(), cols[c])
    assert list(log.columns("VIBE")) == list(schema.columns) and log.n_rows("GPS") == 0
    log.tables["VIBE"] = df.iloc[:1]
    assert log.n_rows("VIBE") == 1 and "VIBE" in log.tables and len(log.tables) == 1
    del log.tables["VIBE"]
    assert len(log.tables) == 0 and log.n_rows("VIBE") == 0


def test_a_flights_meta_lists_only_the_changed_parameters(tmp_path):
    """meta.json's params_changed holds what differs from tlm's defaults, not all ~1400
    parameters (issue 22); params holds them all."""
    from tlm_sim import fly

    log = fly(1, params={"WPNAV_SPEED": 500.0, "FRAME_TYPE": 1})
    doc = json.loads((log.write(tmp_path / "f", formats=("csv",)) / "meta.json").read_text())
    assert doc["params_changed"] == {"FRAME_TYPE": 1.0, "WPNAV_SPEED": 500.0}
    assert len(doc["params"]) > 1000
