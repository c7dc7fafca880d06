"""Every fault type of ``FAULT_TYPES`` (labels 1-13) through the fault front doors: the
shorthand (``--fault baro:120+30``), schedule files, Eq. 4 records and
``tlm_sim.faults.detect`` (which tells engine's SIM_ENGINE_MUL 0 from motor_partial's 0.5 and
needs all of vibration's three and baro's two parameters back before a fault ends)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from tests.conftest import flown
from tlm_sim.faults import FAULT_TYPES, FaultSchedule
from tlm_sim.faults.detect import faults_from_param_changes
from tlm_sim.faults.records import fault_records

TYPES = list(FAULT_TYPES)


def _changes(rows: list[tuple[int, str, float]]) -> pd.DataFrame:
    t, n, v = zip(*rows, strict=True)
    return pd.DataFrame({"TimeUS": list(t), "Name": list(n), "Value": list(v)})


def _type_changes(kind: str, t0: int, t1: int) -> list[tuple[int, str, float]]:
    """A type's start parameters set 1 ms apart from t0 and its end ones from t1 (as SITL's
    PARAM_SET sequence logs them)."""
    ft = FAULT_TYPES[kind]
    return ([(t0 + 1000 * k, n, v) for k, (n, v) in enumerate(ft.params_start.items())]
            + [(t1 + 1000 * k, n, v) for k, (n, v) in enumerate(ft.params_end.items())])


@pytest.mark.parametrize("kind", TYPES)
def test_shorthand_knows_every_type(kind):
    (f,) = FaultSchedule.from_shorthand([f"{kind}:120+30"]).faults
    ft = FAULT_TYPES[kind]
    assert (f.type, f.label) == (kind, ft.label)
    assert (f.start.value, f.end.value) == (120.0, 150.0)
    assert dict(f.params_start) == dict(ft.params_start)
    assert dict(f.params_end) == dict(ft.params_end)
    (g,) = FaultSchedule.from_shorthand([f"{kind.upper()}:wp3-wp9"]).faults
    assert g.type == kind and str(g.end) == "wp9"


def _all_types_schedule() -> FaultSchedule:
    return FaultSchedule.from_dict({"faults": [
        {"fault": k, "start": 30 + 25 * i, "end": 45 + 25 * i} for i, k in enumerate(TYPES)]})


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_schedule_files_know_every_type(tmp_path, suffix):
    sched = _all_types_schedule()
    path = tmp_path / f"faults{suffix}"
    sched.to_file(path) if hasattr(sched, "to_file") else path.write_text(
        json.dumps(sched.to_dict()))
    back = FaultSchedule.from_file(path)
    assert [f.type for f in back.faults] == TYPES
    assert [f.label for f in back.faults] == [FAULT_TYPES[k].label for k in TYPES]
    assert back.to_dict() == sched.to_dict()
    assert {c.name for c in back.param_changes()} == {
        n for ft in FAULT_TYPES.values() for n in ft.params_start}


def test_schedule_file_with_own_values_of_a_new_type(tmp_path):
    path = tmp_path / "f.yaml"
    path.write_text("faults:\n  - {fault: motor_partial, start: 100, end: 130,\n"
                    "     params_start: {SIM_ENGINE_MUL: 0.7}}\n")
    (f,) = FaultSchedule.from_file(path).faults
    assert dict(f.params_start) == {"SIM_ENGINE_MUL": 0.7}
    assert dict(f.params_end) == {"SIM_ENGINE_MUL": 1.0}  # the type's clearing value
    assert f.to_dict() == {"fault": "motor_partial", "start": 100, "end": 130,
                           "params_start": {"SIM_ENGINE_MUL": 0.7}}


def test_eq4_records_for_every_type():
    """fault_records writes the sidecar's keys for every type (positions from a normal flight's
    POS and SIM, boundaries at the applied change times)."""
    sched = _all_types_schedule()
    changes = sched.param_changes()
    applied = [c.at * 1e6 for c in changes]
    import numpy as np

    tables = flown(1).tables
    recs = fault_records(sched, changes, np.asarray(applied), tables, 584.0, 4.0e8)
    assert [r["type"] for r in recs] == TYPES
    for i, (r, k) in enumerate(zip(recs, TYPES, strict=True)):
        ft = FAULT_TYPES[k]
        assert r["label"] == ft.label and r["fault"] == i if "fault" in r else True
        assert r["params_start"] == dict(ft.params_start)
        assert r["params_end"] == dict(ft.params_end)
        assert r["start_time_us"] == (30 + 25 * i) * 1e6
        assert r["end_time_us"] == (45 + 25 * i) * 1e6
        for key in ("start_lat", "start_lon", "start_alt", "end_lat", "end_lon", "end_alt"):
            assert np.isfinite(r[key]), (k, key)
    assert json.loads(json.dumps(recs)) == recs


@pytest.mark.parametrize("kind", TYPES)
def test_detect_finds_every_type_from_its_parameter_changes(kind):
    (f,) = faults_from_param_changes(_changes(_type_changes(kind, 10_000_000, 40_000_000)))
    n_end = len(FAULT_TYPES[kind].params_end)
    assert (f["type"], f["label"]) == (kind, FAULT_TYPES[kind].label)
    assert f["start_time_us"] == 10_000_000
    assert f["end_time_us"] == 40_000_000 + 1000 * (n_end - 1)  # the last parameter back


def test_detect_tells_engine_from_motor_partial():
    rows = (_type_changes("engine", 10_000_000, 20_000_000)
            + _type_changes("motor_partial", 30_000_000, 40_000_000))
    found = faults_from_param_changes(_changes(rows))
    assert [(f["type"], f["start_time_us"], f["end_time_us"]) for f in found] == [
        ("engine", 10_000_000, 20_000_000), ("motor_partial", 30_000_000, 40_000_000)]
    # a multiplier that is neither engine's 0 nor motor_partial's 0.5 is no known fault
    assert faults_from_param_changes(_changes([(1, "SIM_ENGINE_MUL", 0.7),
                                               (2, "SIM_ENGINE_MUL", 1.0)])) == []


def test_detect_vibration_needs_all_three_and_baro_both_parameters_back():
    vib = _type_changes("vibration", 10_000_000, 20_000_000)
    (f,) = faults_from_param_changes(_changes(vib[:-1]))  # SIM_ACC2_RND never set back
    assert f["type"] == "vibration" and f["end_time_us"] is None
    (f,) = faults_from_param_changes(_changes(vib))
    assert f["end_time_us"] == 20_002_000
    baro = _type_changes("baro", 10_000_000, 20_000_000)
    assert [n for _, n, _ in baro[:2]] == ["SIM_BARO_DISABLE", "SIM_BAR2_DISABLE"]
    (f,) = faults_from_param_changes(_changes(baro[:3]))
    assert f["type"] == "baro" and f["end_time_us"] is None
    (f,) = faults_from_param_changes(_changes(baro))
    assert f["end_time_us"] == 20_001_000


@pytest.mark.slow
def test_tlm_bin_of_new_faults_is_detected_again(tmp_path):
    """A tlm flight with the new faults it models, written as a .bin: its PARM messages give
    back the same faults (what ``tlm crosscheck`` reads from a log without sidecar)."""
    from tlm_sim import fly
    from tlm_sim.flightlog import read_bin
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    kinds = [k for k in TYPES if FAULT_TYPES[k].label > 4]
    sched = FaultSchedule.from_shorthand([f"{k}:{40 + 35 * i}+20" for i, k in enumerate(kinds)])
    log = fly(1, faults=sched, seed=4)
    path = log.write_bin(tmp_path / "f.bin")
    parm = read_bin(str(path), types=["PARM"])["PARM"]
    found = faults_from_param_changes(param_changes_from_parm(parm, exclude=()))
    assert [f["type"] for f in found] == [r["type"] for r in log.faults] == kinds
    for f, r in zip(found, log.faults, strict=True):
        assert abs(f["start_time_us"] - r["start_time_us"]) < 1000
        assert abs(f["end_time_us"] - r["end_time_us"]) < 1000


REFERENCES = ("gps_s12", "accel_s13", "engine_s14", "rc_s15", "combined_s21", "gyro_s42",
              "compass_s43", "baro_s44", "battery_s45", "gps_glitch_s46", "motor_partial_s47",
              "vibration_s48")


@pytest.mark.parametrize("name", REFERENCES)
def test_detect_reads_every_reference_log_as_its_sidecar(name):
    """The log's PARM messages alone give the sidecar's faults, to the microsecond: float32
    values (SIM_GPS1_GLTCH_X 0.0003, SIM_BATT_VOLTAGE 10.2, SIM_ACCn_RND 4.8) match."""
    from tests.conftest import reference_path
    from tlm_sim.flightlog import read_bin
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    path = reference_path(f"{name}.bin")
    parm = read_bin(str(path), types=["PARM"])["PARM"]
    found = faults_from_param_changes(param_changes_from_parm(parm, exclude=()))
    side = json.loads(path.with_suffix(".json").read_text())["faults"]
    key = ("type", "label", "start_time_us", "end_time_us")
    assert [tuple(f[k] for k in key) for f in found] == [tuple(f[k] for k in key) for f in side]
