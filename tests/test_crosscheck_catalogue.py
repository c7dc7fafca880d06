"""``tlm crosscheck`` on SITL's fault catalogue: signature comparison with pass/fail at 35 %,
issue 19's checks, faults rebuilt from parameter changes when tlm does not know their type
(or does not model a parameter), and the re-flown flight written as ``DIR/tlm_flight.bin``."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_process.cli import main
from tlm_process.crosscheck.metrics import signature_rows
from tlm_process.crosscheck.scenario import reconstruct, unknown_faults
from tlm_sim.params import is_modelled


def _row(tlm: dict, sitl: dict) -> dict:
    (r,) = signature_rows(tlm, sitl)
    return r


def test_signature_rows_relative_difference_and_floors():
    r = _row({"thr_mean_in": 0.46}, {"thr_mean_in": 0.40})
    assert r["rel_diff"] == pytest.approx(0.15) and r["pass"]
    assert not _row({"climb_m": 30.0}, {"climb_m": 54.6})["pass"]  # 45 % off
    assert _row({"climb_m": 36.0}, {"climb_m": 54.6})["pass"]  # 34 %
    # near zero the unit's floor decides: 0.04 s vs 0.09 s is 56 % but 0.05 s apart
    assert _row({"baro_h_drop_s": 0.04}, {"baro_h_drop_s": 0.09})["pass"]
    assert not _row({"baro_h_drop_s": 0.5}, {"baro_h_drop_s": 0.09})["pass"]
    assert _row({"imu0_std_in": 0.0004}, {"imu0_std_in": 0.0})["pass"]
    assert not _row({"imu0_std_in": 0.0023}, {"imu0_std_in": 0.0})["pass"]  # not frozen
    # flags equal, ERR counts by presence, NaN only when both lack the event
    assert not _row({"auto_kept": 0.0}, {"auto_kept": 1.0})["pass"]
    assert _row({"err24_ekf_primary": 3.0}, {"err24_ekf_primary": 7.0})["pass"]
    assert not _row({"err24_ekf_primary": 0.0}, {"err24_ekf_primary": 7.0})["pass"]
    assert _row({"err6_1_s": math.nan}, {"err6_1_s": math.nan})["pass"]
    assert not _row({"err6_1_s": math.nan}, {"err6_1_s": 10.15})["pass"]
    assert not _row({}, {"err6_1_s": 10.15})["pass"]  # tlm lacks the metric


def test_unknown_sim_changes_become_unknown_faults():
    changes = pd.DataFrame({
        "TimeUS": [10, 20, 30, 40, 50, 60, 70],
        "Name": ["SIM_ENGINE_MUL", "SIM_FOO", "SIM_BAR", "SIM_FOO", "SIM_BAR", "WPNAV_SPEED",
                 "SIM_ENGINE_MUL"],
        "Value": [0.0, 1.0, 2.0, 0.0, 0.0, 500.0, 1.0],
        "Old": [1.0, 0.0, 0.0, 1.0, 2.0, 600.0, 0.0],
    })
    known = [{"type": "engine", "start_time_us": 10, "end_time_us": 70,
              "params_start": {"SIM_ENGINE_MUL": 0.0}, "params_end": {"SIM_ENGINE_MUL": 1.0}}]
    (u,) = unknown_faults(changes, known)  # SIM_ENGINE_MUL is the engine fault's
    assert u["type"] == "unknown" and u["label"] is None
    assert (u["start_time_us"], u["end_time_us"]) == (20, 50)
    assert u["params_start"] == {"SIM_FOO": 1.0, "SIM_BAR": 2.0}
    assert u["params_end"] == {"SIM_FOO": 0.0, "SIM_BAR": 0.0}
    assert [c[1] for c in u["changes"]] == ["SIM_FOO", "SIM_BAR", "SIM_FOO", "SIM_BAR"]
    # alone, the engine parameter opens one group that lasts until every parameter is back
    (g,) = unknown_faults(changes, [])
    assert (g["start_time_us"], g["end_time_us"]) == (10, 70)
    assert g["params_start"]["SIM_ENGINE_MUL"] == 0.0 and g["params_end"]["SIM_ENGINE_MUL"] == 1


def test_new_reference_flights_rebuild_their_fault(tmp_path):
    """Each new reference's sidecar fault is rebuilt: as a schedule when tlm models its
    parameters, else without the unmodelled ones (named in the notes)."""
    for name, kind in (("motor_partial_s47", "motor_partial"), ("gyro_s42", "gyro"),
                       ("baro_s44", "baro"), ("gps_glitch_s46", "gps_glitch")):
        sc = reconstruct(reference_path(f"{name}.bin"))
        assert [f["type"] for f in sc.faults] == [kind]
        flyable = all(is_modelled(p) for p in sc.faults[0]["params_start"])
        if flyable:
            assert sc.schedule is not None and sc.notes == []
            assert [f.type for f in sc.schedule.faults] == [kind]
        else:
            assert sc.schedule is None and any("not modelled" in n for n in sc.notes)
        tlm = sc.tlm_fault_records()
        assert tlm[0]["start_time_us"] == pytest.approx(
            sc.to_tlm_us(sc.faults[0]["start_time_us"]))


def test_a_type_tlm_does_not_know_flies_as_parameter_changes(tmp_path):
    src = reference_path("motor_partial_s47.bin")
    side = json.loads(src.with_suffix(".json").read_text())
    side["faults"][0]["type"] = "weak_motor"
    side["faults"][0]["label"] = 99
    p = tmp_path / "side.json"
    p.write_text(json.dumps(side))
    sc = reconstruct(src, p)
    assert sc.schedule is None and sc.fly_faults == sc.changes
    t0 = sc.to_tlm_us(side["faults"][0]["start_time_us"]) * 1e-6
    t1 = sc.to_tlm_us(side["faults"][0]["end_time_us"]) * 1e-6
    assert sc.changes == [(round(t0, 3), "SIM_ENGINE_MUL", 0.5),
                          (round(t1, 3), "SIM_ENGINE_MUL", 1.0)]
    assert any("weak_motor" in n for n in sc.notes)


def test_log_alone_detects_motor_partial_not_engine(tmp_path):
    alone = tmp_path / "mp.bin"
    alone.symlink_to(reference_path("motor_partial_s47.bin"))
    sc = reconstruct(alone)
    assert sc.source == "log"
    assert [(f["type"], f["label"]) for f in sc.faults] == [("motor_partial", 9)]
    ref = json.loads(reference_path("motor_partial_s47.json").read_text())["faults"][0]
    assert abs(sc.faults[0]["start_time_us"] - ref["start_time_us"]) < 1000
    assert sc.schedule.faults[0].params_start == {"SIM_ENGINE_MUL": 0.5}


@pytest.mark.slow
def test_crosscheck_writes_checks_signatures_and_the_flight(tmp_path, capsys):
    from tlm_sim.flightlog import read_bin

    src = str(reference_path("motor_partial_s47.bin"))
    out, rj = tmp_path / "cc", tmp_path / "r.json"
    main(["crosscheck", src, "--out", str(out), "--json", str(rj)])
    text = capsys.readouterr().out
    assert "fault motor_partial:" in text and "signature metrics within 35 %" in text
    r = json.loads(rj.read_text())
    c = r["checks"]
    assert c["flight_time"]["pass"] and c["trajectory_rms"]["pass"]
    (f,) = r["faults"]
    assert f["type"] == "motor_partial" and f["compared"] == len(f["sitl"]) > 5
    rows = {x["metric"]: x for x in f["rows"]}
    for k in ("thr_mean_in", "ground_s", "impact_speed_ms", "armed_kept", "auto_kept"):
        assert rows[k]["pass"], rows[k]
    report = (out / "report.md").read_text()
    assert "## Checks (issue 19)" in report and "| thr_mean_in |" in report
    flown = read_bin(str(out / "tlm_flight.bin"), types=["GPS", "PARM"])
    assert len(flown["GPS"]) > 1000
    parm = flown["PARM"]
    mul = parm[parm.Name == "SIM_ENGINE_MUL"].Value.to_numpy()
    assert np.any(np.isclose(mul, 0.5))


def test_the_frame_comes_from_the_log_and_a_frame_tlm_cannot_fly_is_a_one_line_error(
        tmp_path, capsys):
    """normal_x_s50 flies the X frame (PARM FRAME_TYPE 1, SITL model "x"). A sidecar naming a
    SITL model tlm has no frame for, or one that disagrees with the log's FRAME_CLASS /
    FRAME_TYPE (SITL would fly a mismatched mixer), is a ScenarioError, which the command
    reports in one line (exit 2)."""
    import json
    import shutil

    from tlm_process.crosscheck.scenario import ScenarioError

    src = reference_path("normal_x_s50.bin")
    sc = reconstruct(src)
    assert (sc.params["FRAME_CLASS"], sc.params["FRAME_TYPE"]) == (1, 1)
    doc = json.loads(src.with_suffix(".json").read_text())
    for model, match in (("octa-quad", "not a frame tlm simulates"), ("+", "mismatched mixer")):
        doc["sitl"]["model"] = model
        side = tmp_path / f"{model}.json"
        side.write_text(json.dumps(doc))
        with pytest.raises(ScenarioError, match=match):
            reconstruct(src, side)
    # the command: a copy of the log with the mismatched sidecar beside it
    log = tmp_path / "normal_x_s50.bin"
    shutil.copy(src, log)
    shutil.copy(tmp_path / "+.json", log.with_suffix(".json"))
    assert main(["crosscheck", str(log), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "mismatched mixer" in err and len(err.strip().splitlines()) == 1
