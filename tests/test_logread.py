"""tlm_process.logread: real ArduPilot logs (Copter 3.x TimeMS, numbered instances, text
logs, logs that start at arming) read into normalised tables, and the arming rule."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.conftest import real_path, reference_path
from tlm_process.logread import (
    LogReadError,
    arming_time_us,
    disarm_time_us,
    is_text_log,
    motor_idle_pwm,
    read_log_tables,
)

REAL_LOGS = ("log171.bin", "backend_log_80k.bin", "nan.log", "mechanical_fail.log")


# --------------------------------------------------------------------------- a text log -----
TEXT_LOG = """\
ArduCopter V3.1 (test)
FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format
FMT, 129, 23, PARM, Nf, Name,Value
FMT, 131, 31, IMU, Iffffff, TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ
FMT, 135, 31, IMU2, Iffffff, TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ
FMT, 136, 31, IMU3, Iffffff, TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ
FMT, 13, 4, EV, B, Id
FMT, 3, 6, MODE, Mh, Mode,ThrCrs
PARM, RC3_MIN, 1000
PARM, RC3_MAX, 2000
MODE, Stabilize, 0
IMU, 1000, 0.1, 0, 0, 0, 0, -9.8
IMU2, 1000, 0.2, 0, 0, 0, 0, -9.8
IMU3, 1000, 0.3, 0, 0, 0, 0, -9.8
EV, 10
IMU, 1020, NaN, 0, 0, 0, 0, -9.8
IMU3, 1020, 0.3, 0, 0, 0, 0, -9.8
IMU2, 1020, 0.2, 0, 0, 0, 0, -9.8
EV, 11
IMU, 1040, 0.1, 0, 0, 0, 0, -9.8
"""


@pytest.fixture
def text_log(tmp_path: Path) -> Path:
    p = tmp_path / "old.log"
    p.write_text(TEXT_LOG.replace("\n", "\r\n"), newline="")
    return p


def test_text_log_timems_to_timeus(text_log: Path) -> None:
    assert is_text_log(text_log)
    lt = read_log_tables(text_log)
    assert lt.kind == "text"
    imu = lt.tables["IMU"]
    assert imu["TimeUS"].dtype == np.int64
    assert (imu["TimeUS"] == imu["TimeMS"] * 1000).all()  # TimeMS kept beside it
    assert list(imu.columns[:3]) == ["TimeUS", "I", "TimeMS"]
    assert any("TimeMS x 1000" in n for n in lt.notes)
    assert lt.params == {"RC3_MIN": 1000.0, "RC3_MAX": 2000.0}
    # a mode written as a name becomes its number
    assert lt.tables["MODE"]["Mode"].tolist() == [0]
    # a message without a time column: the time of the stamped message before it
    ev = lt.tables["EV"]
    assert ev["TimeUS"].tolist() == [1_000_000, 1_020_000]
    assert any("log order" in n and "EV" in n for n in lt.notes)
    assert any("not messages" in n for n in lt.notes)  # the firmware line


def test_imu2_imu3_folded_into_imu_instances(text_log: Path) -> None:
    lt = read_log_tables(text_log)
    assert "IMU2" not in lt.tables and "IMU3" not in lt.tables
    imu = lt.tables["IMU"]
    assert imu.groupby("I").size().to_dict() == {0: 3, 1: 2, 2: 2}
    # GyrX tells the instance; sorted by time, instance order at equal times
    assert imu["TimeUS"].is_monotonic_increasing
    first = imu[imu.TimeUS == 1_000_000]
    assert first["I"].tolist() == [0, 1, 2]
    np.testing.assert_allclose(first["GyrX"], [0.1, 0.2, 0.3], rtol=1e-6)
    np.testing.assert_allclose(imu.loc[imu.I == 2, "GyrX"], 0.3, rtol=1e-6)
    assert imu["GyrX"].isna().sum() == 1  # NaN kept
    assert any("IMU2, IMU3 folded into IMU" in n for n in lt.notes)
    # names: IMU brings its instances; other tables left out
    only = read_log_tables(text_log, ["IMU", "EV"])
    assert sorted(only.tables) == ["EV", "IMU"]
    assert len(only.tables["IMU"]) == 7
    assert only.tables["EV"]["TimeUS"].tolist() == [1_000_000, 1_020_000]
    assert only.params == lt.params  # the parameters come along anyway
    assert arming_time_us(lt.tables) == (1_000_000, "EV 10")
    assert disarm_time_us(lt.tables) == (1_020_000, "EV 11")


def test_not_a_log(tmp_path: Path) -> None:
    p = tmp_path / "x.log"
    p.write_text("hello\n")
    with pytest.raises(LogReadError):
        read_log_tables(p)
    with pytest.raises(FileNotFoundError):
        read_log_tables(tmp_path / "missing.bin")


# --------------------------------------------------------------------------- arming rules ---
def _rcou(times_s: list[float], c1: list[int], prefix: str = "C") -> pd.DataFrame:
    n = len(times_s)
    df = pd.DataFrame({"TimeUS": (np.asarray(times_s) * 1e6).astype(np.int64)})
    df[f"{prefix}1"] = c1
    for k in (2, 3, 4):
        df[f"{prefix}{k}"] = [1000] * n
    df[f"{prefix}5"] = [1900] * n  # not a motor on a quad
    return df


def test_arming_from_ev() -> None:
    tables = {
        "EV": pd.DataFrame({"TimeUS": [5, 10, 20, 30, 40], "Id": [62, 10, 11, 10, 11]}),
        "ARM": pd.DataFrame({"TimeUS": [3], "ArmState": [1]}),
    }
    assert arming_time_us(tables) == (10, "EV 10")
    assert disarm_time_us(tables) == (20, "EV 11")


def test_arming_from_arm_message() -> None:
    tables = {
        "EV": pd.DataFrame({"TimeUS": [5], "Id": [62]}),
        "ARM": pd.DataFrame({"TimeUS": [12, 50], "ArmState": [1, 0]}),
        "GPS": pd.DataFrame({"TimeUS": [0, 100]}),
    }
    assert arming_time_us(tables) == (12, "ARM ArmState 1")
    assert disarm_time_us(tables) == (50, "ARM ArmState 0")
    # no disarm: the log's end
    tables["ARM"] = tables["ARM"].iloc[:1]
    assert disarm_time_us(tables) == (100, "log end")


def test_arming_from_rcou_rise() -> None:
    params = {"MOT_PWM_MIN": 1000.0, "MOT_PWM_MAX": 2000.0, "MOT_SPIN_ARM": 0.1}
    idle, thr = motor_idle_pwm(params)
    assert (idle, thr) == (1100.0, 1050.0)
    # a logged-from-boot log without EV/ARM: disarmed at 1000, armed idle 1100 at 20 s
    tables = {"RCOU": _rcou([0, 10, 20, 30], [1000, 1000, 1100, 1300]),
              "GPS": pd.DataFrame({"TimeUS": [0, 50_000_000]})}
    t, src = arming_time_us(tables, params)
    assert t == 20_000_000 and src.startswith("RCOU")
    assert disarm_time_us(tables, params) == (50_000_000, "log end")
    # a rise within the arming delay (3 s) of the log's start: the log started at arming
    tables["RCOU"] = _rcou([0, 1, 2.5, 3], [1000, 1000, 1100, 1300])
    t, src = arming_time_us(tables, params)
    assert t == 0 and src.startswith("log start")
    # the fifth channel (not a motor of a quad) does not arm it
    tables["RCOU"] = _rcou([0, 1], [1000, 1000])
    assert arming_time_us(tables, params) == (None, "never armed")
    assert disarm_time_us(tables, params) == (None, "never armed")
    # a hexa's fifth channel is a motor
    assert arming_time_us(tables, {**params, "FRAME_CLASS": 2})[0] == 0


def test_arming_at_log_start_when_rcou_starts_armed() -> None:
    # LOG_DISARMED 0: the log starts at arming, the motors already at idle in the first row;
    # 3.x names: RC3_MIN/MAX range, MOT_SPIN_ARMED on the 0-1000 scale, Chan columns
    params = {"RC3_MIN": 1022.0, "RC3_MAX": 1997.0, "MOT_SPIN_ARMED": 100.0}
    idle, thr = motor_idle_pwm(params)
    assert idle == pytest.approx(1022 + 97.5) and thr == pytest.approx(1022 + 48.75)
    tables = {"RCOU": _rcou([1.0, 1.1], [1122, 1300], prefix="Chan"),
              "IMU": pd.DataFrame({"TimeUS": [900_000, 2_000_000]})}
    t, src = arming_time_us(tables, params)
    assert t == 900_000 and src.startswith("log start")
    # no parameters at all: 1000-2000 us and MOT_SPIN_ARM 0.1
    assert motor_idle_pwm({}) == (1100.0, 1050.0)
    assert arming_time_us({}, {}) == (None, "never armed")


# --------------------------------------------------------------------------- real logs ------
@pytest.mark.parametrize("name", REAL_LOGS)
def test_every_real_log_reads(name: str) -> None:
    lt = read_log_tables(real_path(name))
    assert lt.tables and lt.notes
    for n, df in lt.tables.items():
        assert len(df), n
        assert df["TimeUS"].dtype == np.int64, n
        assert df["TimeUS"].is_monotonic_increasing, n
        assert n not in ("IMU2", "IMU3", "BAR2", "BAR3", "MAG2", "MAG3", "GPS2", "GPA2")
    if "IMU" in lt.tables:
        assert "I" in lt.tables["IMU"].columns
    arming_time_us(lt.tables, lt.params)
    disarm_time_us(lt.tables, lt.params)


def test_log171_copter33() -> None:
    lt = read_log_tables(real_path("log171.bin"))
    imu = lt.tables["IMU"]
    assert imu.groupby("I").size().to_dict() == {0: 11916, 1: 11916, 2: 11916}
    assert set(lt.tables["BARO"]["I"]) == {0, 1} and set(lt.tables["MAG"]["I"]) == {0, 1, 2}
    assert (imu["TimeUS"] == imu["TimeMS"] * 1000).all()
    # GPS's TimeMS is the GPS time of week in 3.3: the boot time is T
    gps = lt.tables["GPS"]
    assert (gps["TimeUS"] == gps["T"] * 1000).all()
    t, src = arming_time_us(lt.tables, lt.params)
    assert src == "EV 10"
    # the motors rise to the armed idle (MOT_SPIN_ARMED 50: 1049 us) 2 s after EV 10
    rcou = lt.tables["RCOU"]
    rise = int(rcou.loc[(rcou[["Ch1", "Ch2", "Ch3", "Ch4"]] > 1000).any(axis=1),
                        "TimeUS"].iloc[0])
    assert 0 <= rise - t <= 3_000_000
    # without its EV table, the RCOU rule finds that rise
    tables = {n: df for n, df in lt.tables.items() if n != "EV"}
    t2, src2 = arming_time_us(tables, lt.params)
    assert t2 == rise and src2.startswith("RCOU")
    assert disarm_time_us(lt.tables, lt.params) == (int(gps["TimeUS"].iloc[-1]), "log end")


def test_text_logs_copter31() -> None:
    nan = read_log_tables(real_path("nan.log"))
    assert set(nan.tables["IMU"]["I"]) == {0, 1}
    assert arming_time_us(nan.tables, nan.params) == (95_890_000, "EV 10")
    assert disarm_time_us(nan.tables, nan.params) == (100_080_000, "EV 11")
    mech = read_log_tables(real_path("mechanical_fail.log"))
    assert "IMU" not in mech.tables
    assert arming_time_us(mech.tables, mech.params)[1] == "EV 10"


def test_sitl_log_arming_equals_ev10() -> None:
    from tlm_sim.flightlog import read_bin

    path = reference_path("normal_s11.bin")
    ev = read_bin(path, ["EV"])["EV"]
    t_ev = int(ev.loc[ev.Id == 10, "TimeUS"].iloc[0])
    lt = read_log_tables(path)
    assert arming_time_us(lt.tables, lt.params) == (t_ev, "EV 10")
    # the ARM message says the same
    no_ev = {n: df for n, df in lt.tables.items() if n != "EV"}
    assert arming_time_us(no_ev, lt.params) == (t_ev, "ARM ArmState 1")
    # a 4.x log keeps its TimeUS and instance column untouched
    imu = lt.tables["IMU"]
    raw = read_bin(path, ["IMU"])["IMU"]
    assert len(imu) == len(raw) and set(imu["I"]) == {0, 1}
    assert imu["TimeUS"].is_monotonic_increasing


def test_sitl_log_cut_at_arming() -> None:
    """A log that starts at arming (LOG_DISARMED 0), made by cutting a SITL log's tables
    just after its EV 10: its motors spin up 2.2 s later, within the arming delay."""
    lt = read_log_tables(reference_path("normal_s11.bin"))
    t_ev, _ = arming_time_us(lt.tables, lt.params)
    cut = {n: df[df.TimeUS > t_ev].reset_index(drop=True) for n, df in lt.tables.items()}
    cut = {n: df for n, df in cut.items() if len(df)}
    t, src = arming_time_us(cut, lt.params)
    assert src.startswith("log start")
    assert t == min(int(df.TimeUS.iloc[0]) for df in cut.values())
    assert 0 < t - t_ev < 200_000
    # cut later, at the motors' spin-up: the first RCOU row is already armed
    late = {n: df[df.TimeUS > t_ev + 2_300_000] for n, df in lt.tables.items()}
    t, src = arming_time_us(late, lt.params)
    assert src.startswith("log start (the first RCOU row")
    d, dsrc = disarm_time_us(cut, lt.params)
    assert dsrc == "EV 11" and d == disarm_time_us(lt.tables, lt.params)[0]


# --------------------------------------------------------------------------- tlm info/convert
def _cli(argv: list[str], capsys) -> tuple[int, str, str]:  # noqa: ANN001 - pytest fixture
    from tlm_process.cli import main

    rc = main(argv)
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out, err


@pytest.mark.parametrize("name, armed", [
    ("log171.bin", "72.61 - 254.07 s (181.5 s)  [armed: EV 10; disarmed: log end]"),
    ("nan.log", "95.89 - 100.08 s (4.2 s)  [armed: EV 10; disarmed: EV 11] (the first of 2"),
    ("mechanical_fail.log", "66.94 - 177.08 s (110.1 s)  [armed: EV 10; disarmed: EV 11]"),
    ("backend_log_80k.bin", "- (never armed)"),
])
def test_info_on_real_logs(name: str, armed: str, tmp_path: Path, capsys) -> None:
    import json

    path = real_path(name)
    rc, out, err = _cli(["info", str(path), "--json", str(tmp_path / "i.json")], capsys)
    assert rc == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("armed"))
    assert armed in line
    info = json.loads((tmp_path / "i.json").read_text())
    assert info["time_span_s"] is not None
    if name != "backend_log_80k.bin":
        assert info["normalised"]  # what was normalised is said
        assert "IMU2" not in info["messages"]
    # messages logged once or in a start-up burst have no rate (no "FMTU 19373.5 Hz")
    for m in info["messages"].values():
        assert m["rate_hz"] is None or m["rate_hz"] < 1000
    if name == "log171.bin":
        assert info["messages"]["IMU"]["instances"] == 3
        assert info["messages"]["IMU"]["rate_hz"] == pytest.approx(49.1, abs=0.5)
        assert info["messages"]["PARM"]["rate_hz"] is None
        assert [m["name"] for m in info["modes"]] == ["LOITER", "LOITER", "ACRO"]
    if name == "backend_log_80k.bin":
        for n in ("FMTU", "MULT", "UNIT", "PARM"):
            assert info["messages"][n]["rate_hz"] is None
            assert info["messages"][n]["logged"] == "at start"
        assert " 80000.0" not in out and "at start" in out


def test_info_rates_of_a_sitl_log(tmp_path: Path, capsys) -> None:
    import json

    path = reference_path("normal_s11.bin")
    rc, out, _ = _cli(["info", str(path), "--json", str(tmp_path / "i.json")], capsys)
    assert rc == 0
    info = json.loads((tmp_path / "i.json").read_text())
    assert info["messages"]["IMU"]["rate_hz"] == pytest.approx(25.0, abs=0.5)
    assert info["messages"]["GPS"]["rate_hz"] == pytest.approx(5.0, abs=0.2)
    assert info["messages"]["VER"]["logged"] == "once"
    assert info["messages"]["FMTU"]["rate_hz"] is None  # written as each type first appears
    assert info["armed_source"] == "EV 10" and info["disarm_source"] == "EV 11"
    assert "[armed: EV 10; disarmed: EV 11]" in out


@pytest.mark.parametrize("name", REAL_LOGS)
@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_convert_real_logs(name: str, fmt: str, tmp_path: Path, capsys) -> None:
    from tlm_sim.flightlog import FlightLog

    path = real_path(name)
    rc, out, err = _cli(["convert", str(path), "--out", str(tmp_path / "o"), "--format", fmt],
                        capsys)
    assert rc == 0, err
    assert "converted" in out
    back = FlightLog.read(tmp_path / "o")
    lt = read_log_tables(path)
    assert sorted(back.tables) == sorted(lt.tables)
    for n, df in back.tables.items():
        assert len(df) == len(lt.tables[n]), n
        if "TimeUS" not in df.columns:  # a 4.x log's FMT, written as logged
            continue
        # a 4.x log is written in log order, read_log_tables sorts by time
        assert (np.sort(df["TimeUS"].to_numpy())
                == lt.tables[n]["TimeUS"].to_numpy()).all(), n


def test_convert_old_log_to_text_is_refused(tmp_path: Path, capsys) -> None:
    rc, _, err = _cli(["convert", str(real_path("nan.log")), "--out", str(tmp_path / "o"),
                       "--format", "log"], capsys)
    assert rc == 2 and "--format log" in err and "csv or parquet" in err
    assert not (tmp_path / "o").exists()


# --------------------------------------------------------------------------- tlm process ----
def _cut_at_arming(src: Path, out: Path) -> tuple[Path, int]:
    """A copy of SITL log ``src`` that starts just after its EV 10, as a vehicle logging
    with LOG_DISARMED 0 writes it (no arming event, no ARM 1), written by tlm's writer, with
    the sidecar beside it; returns (path, the EV 10 time)."""
    import shutil

    from tlm_sim.flightlog import FlightLog, read_bin
    from tlm_sim.flightlog.binreader import read_params, read_schemas
    from tlm_sim.flightlog.binwriter import write_bin

    tables = read_bin(src)
    ev = tables["EV"]
    t_ev = int(ev.loc[ev.Id == 10, "TimeUS"].iloc[0])
    schemas = read_schemas(src)
    cut = {n: df[df.TimeUS > t_ev].reset_index(drop=True) for n, df in tables.items()
           if n not in ("FMT", "FMTU", "UNIT", "MULT", "FILE") and "TimeUS" in df.columns}
    cut = {n: df for n, df in cut.items() if len(df)}
    out.mkdir(parents=True, exist_ok=True)
    path = write_bin(FlightLog(cut, params=read_params(src),
                               schemas={n: schemas[n] for n in cut}), out / f"{src.stem}.bin")
    shutil.copy(src.with_suffix(".json"), out / f"{src.stem}.json")
    return path, t_ev


def test_process_log_that_starts_at_arming(tmp_path: Path) -> None:
    from tlm_process.pipeline.ingest import read_flights
    from tlm_process.pipeline.process import process_flight

    src = reference_path("gps_s12.bin")
    path, t_ev = _cut_at_arming(src, tmp_path / "cut")
    flight = read_flights([path])[0]
    assert flight.meta["armed_source"].startswith("log start")
    assert flight.meta["disarm_source"] == "EV 11"
    done = process_flight(flight)
    first = min(int(df.TimeUS.iloc[0]) for df in flight.tables.values())
    assert done.phase == "armed" and done.span_us[0] == first
    assert 0 < first - t_ev < 100_000
    # the same armed rows and fault labels as the whole log (armed from its EV 10)
    whole = process_flight(read_flights([src])[0])
    assert whole.span_us[1] == done.span_us[1]  # EV 11: rows after disarm not kept
    for name, df in whole.features.items():
        assert len(done.features[name]) == len(df), name
        assert (done.features[name]["label"].to_numpy() == df["label"].to_numpy()).all()
    assert "armed_span_us" not in read_flights([src])[0].meta  # EV 10 logs: as before


def test_process_log_with_arm_messages_only(tmp_path: Path) -> None:
    """Rows after the disarm are not kept when the arming comes from ARM messages."""
    from tlm_process.pipeline.ingest import Flight
    from tlm_process.pipeline.process import process_flight

    lt = read_log_tables(reference_path("normal_s11.bin"),
                         ["GPS", "IMU", "RATE", "VIBE", "ARM", "EV"])
    tables = {n: df for n, df in lt.tables.items() if n not in ("EV", "ARM")}
    no_ev = {n: df for n, df in lt.tables.items() if n != "EV"}
    t0, src = arming_time_us(no_ev, lt.params)
    t1, end = disarm_time_us(no_ev, lt.params, t0)
    assert (src, end) == ("ARM ArmState 1", "ARM ArmState 0")
    flight = Flight("n", "n", "bin", tables, [], meta={"armed_span_us": [t0, t1]})
    done = process_flight(flight)
    assert done.span_us == (t0, t1)
    assert done.features["IMU"]["TimeUS"].max() <= t1
    assert lt.tables["IMU"]["TimeUS"].max() > t1 + 1_000_000  # there were rows after it


@pytest.mark.parametrize("name, span", [("log171.bin", (72_606_000, 254_071_000)),
                                        ("nan.log", (95_890_000, 100_080_000))])
def test_tlm_process_real_logs(name: str, span: tuple[int, int], tmp_path: Path,
                               capsys) -> None:
    import json

    rc, out, err = _cli(["process", str(real_path(name)), "--out", str(tmp_path / "ds"),
                         "--tables", "IMU,GPS", "--plots", "0", "--quiet"], capsys)
    assert rc == 0, err
    report = json.loads((tmp_path / "ds" / "report.json").read_text())
    (flight,) = report["flights"]
    assert flight["phase"] == "armed" and tuple(flight["span_us"]) == span
    imu = pd.read_parquet(tmp_path / "ds" / "IMU.parquet")
    assert imu["TimeUS"].between(*span).all()
    assert "TimeMS" not in imu.columns  # a time column, dropped by Algorithm 2


def test_process_refuses_a_real_log_without_imu(tmp_path: Path, capsys) -> None:
    rc, _, err = _cli(["process", str(real_path("mechanical_fail.log")), "--out",
                       str(tmp_path / "ds"), "--tables", "IMU,GPS"], capsys)
    assert rc == 2 and "no IMU table" in err


# --------------------------------------------------------------------------- tlm crosscheck -
@pytest.mark.filterwarnings("ignore::tlm_sim.params.UnmodelledParamWarning")
def test_crosscheck_scenario_of_a_log_that_starts_at_arming(tmp_path: Path) -> None:
    from tlm_process.crosscheck.metrics import armed_span_us
    from tlm_process.crosscheck.scenario import reconstruct

    src = reference_path("gps_s12.bin")
    path, t_ev = _cut_at_arming(src, tmp_path / "cut")
    sc = reconstruct(path)
    first = min(int(df.TimeUS.iloc[0]) for df in sc.tables.values() if len(df))
    assert sc.sitl_arm_us == first and 0 < first - t_ev < 100_000
    whole = reconstruct(src)
    assert whole.sitl_arm_us == t_ev  # EV 10 as before
    assert armed_span_us(sc.tables)[1] == armed_span_us(whole.tables)[1]  # EV 11
    # ARM messages alone give the span too
    no_ev = {n: df for n, df in whole.tables.items() if n != "EV"}
    a, d = armed_span_us(no_ev)
    arm = whole.tables["ARM"]
    assert (a, d) == tuple(float(arm.TimeUS[arm.ArmState == s].iloc[0]) for s in (1, 0))


@pytest.mark.parametrize("name, error", [
    ("mechanical_fail.log", "the log has no mission (no CMD messages with Prm2, Prm3, Prm4, "
                            "Frame: an older firmware's layout); nor RCIN with the pilot's sticks"),
    ("backend_log_80k.bin", "never armed"),
])
def test_crosscheck_refuses_real_logs_in_one_line(name: str, error: str, tmp_path: Path,
                                                  capsys) -> None:
    rc, _, err = _cli(["crosscheck", str(real_path(name)), "--out", str(tmp_path / "c")],
                      capsys)
    assert rc == 2
    last = err.strip().splitlines()[-1]
    assert last.startswith("tlm: error:") and error in last


def test_copter31_log_is_re_flown_from_its_rcin(tmp_path: Path, capsys) -> None:
    """nan.log (Copter 3.1, STABILIZE, no mission): its RCIN and RCOU name the channels
    ``Chan1``... (read as ``C1``...), its LOG_BITMASK is a 16-bit mask logged negative (-22530)
    and its COMPASS_MOT_* are NaN (not modelled, left out): ``tlm crosscheck`` re-flies it from
    its RCIN to a report instead of refusing it."""
    lt = read_log_tables(real_path("nan.log"))
    for name in ("RCIN", "RCOU"):
        assert {f"C{k}" for k in range(1, 9)} <= set(lt.tables[name])
        assert f"{name} Chan1... as C1... (Copter 3.1's channel names)" in lt.notes
    assert lt.tables["RCIN"]["C3"].between(1000, 1100).all()
    rc, out, err = _cli(["crosscheck", str(real_path("nan.log")), "--out", str(tmp_path / "c")],
                        capsys)
    assert rc in (0, 1) and "Traceback" not in err
    assert "replayed from RCIN: nan" in out and "stick segments:" in out
    assert (tmp_path / "c" / "report.md").is_file()


def test_copter3_rate_and_ctun_come_in_4x_units():
    """log171 (Copter 3.3) logs RATE's outputs in +-4500 and its throttle in 0..1000, its rates
    in centidegrees per second, CTUN's throttle as ThrOut 0..1000: the reader gives them as a
    4.x log does (the whole-log detector read a 3.3 hover's yaw output 4500 times too large),
    and says so in its notes."""
    lt = read_log_tables(real_path("log171.bin"))
    rate = lt.tables["RATE"]
    assert rate["AOut"].max() <= 1.0 and rate[["ROut", "POut", "YOut"]].abs().max().max() <= 1.2
    hover = rate[(rate.TimeUS > 197.5e6) & (rate.TimeUS < 216.5e6)]
    assert 0.3 < hover["AOut"].mean() < 0.5
    imu = lt.tables["IMU"].query("I == 0")
    gyro = np.degrees(np.interp(rate.TimeUS, imu.TimeUS, imu.GyrX))
    assert np.polyfit(gyro, rate["R"], 1)[0] == pytest.approx(1.0, abs=0.3)  # deg/s
    assert lt.tables["CTUN"]["ThO"].max() <= 1.0
    assert any("Copter 3.x output units" in n for n in lt.notes)
    sitl = read_log_tables(reference_path("normal_s11.bin"), ["RATE", "CTUN", "IMU"])
    assert not any("Copter 3.x" in n for n in sitl.notes)  # a 4.x log is left alone
