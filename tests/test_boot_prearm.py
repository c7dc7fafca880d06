"""The boot phase, ArduCopter's pre-arm checks and the arming driver (issue 21).

A vehicle that cannot pass the pre-arm checks never arms and the flight ends "not_armed"
(before: with SIM_GPS1_ENABLE 0 from boot tlm armed anyway and flew 18 km away). With
TLM_BOOT_PHASE 1 the start-up follows SITL's: the GPS is found at 9.8 s, the EKF aligns, sets
its origin after 10 s of good GPS and uses GPS once its gyro biases are learnt, and the driver
arms when the checks pass; its MSG texts are ArduCopter's, at normal_s11's times.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest

from tests.conftest import reference_path
from tlm_sim import ardupilot as AP
from tlm_sim import fly
from tlm_sim.control import arming as A
from tlm_sim.flight import END_NOT_ARMED, END_REASONS, end_reason
from tlm_sim.flightlog import read_bin
from tlm_sim.flightlog.texts import ARM_CHECK_TEXTS, event_texts, logged_texts
from tlm_sim.params import Params

BOOT = {"TLM_BOOT_PHASE": 1}
ARM_TIME = Params()["TLM_ARM_TIME"]


@lru_cache(maxsize=8)
def _flight(**params: float):
    return fly(1, params=params)


def _texts(log) -> list[tuple[float, str]]:
    """(time [s], text) of the flight's MSG lines from its events and its text log."""
    lines = logged_texts(log.meta["texts"]) + event_texts(log.tables)
    return sorted(((t * 1e-6, s) for t, s in lines), key=lambda x: x[0])


def _first(lines, text: str) -> float:
    return next(t for t, s in lines if s == text)


def _reference_texts(name: str) -> list[tuple[float, str]]:
    m = read_bin(reference_path(f"{name}.bin"), types=["MSG"])["MSG"]
    return [(t * 1e-6, s) for t, s in zip(m["TimeUS"], m["Message"], strict=True)]


def _never_flew(log) -> None:
    m = log.meta
    assert m["end_reason"] == END_NOT_ARMED
    assert m["armed_s"] is None and m["disarmed_s"] is None
    assert 10 not in set(log.tables["EV"]["Id"])
    sim = log.tables["SIM"]
    assert float(sim["Alt"].max() - sim["Alt"].iloc[0]) < 0.05
    assert float(log.tables["RCOU"]["C1"].max()) <= 1000.0  # the motors never ran


def test_gps_disabled_from_boot_never_arms():
    """ArduCopter refuses to arm without a GPS fix ("GPS 1: Bad fix", the first failing GPS
    check for a mode that needs GPS); the driver tries every 2 s for ARM_TIMEOUT_S and gives up:
    the flight ends 2 s later, on the ground."""
    log = _flight(SIM_GPS1_ENABLE=0)
    _never_flew(log)
    assert log.meta["duration_s"] == pytest.approx(ARM_TIME + A.ARM_TIMEOUT_S + 2.0, abs=0.01)
    lines = _texts(log)
    arm = [t for t, s in lines if s.startswith("Arm: ")]
    assert {s for t, s in lines if s.startswith("Arm: ")} == {"Arm: GPS 1: Bad fix"}
    assert len(arm) == round(A.ARM_TIMEOUT_S / A.ARM_RETRY_S)
    assert np.allclose(np.diff(arm), A.ARM_RETRY_S, atol=0.003)
    assert arm[0] == pytest.approx(ARM_TIME, abs=0.003)
    # AP_Arming::update shows the failures every 30 s (strictly more than 30 s apart)
    prearm = [t for t, s in lines if s == "PreArm: GPS 1: Bad fix"]
    assert len(prearm) == 4 and np.all(np.diff(prearm) > 30.0)


def test_gps_disabled_in_the_boot_phase_never_arms():
    log = _flight(SIM_GPS1_ENABLE=0, **BOOT)
    _never_flew(log)
    lines = _texts(log)
    assert _first(lines, "GPS 1: detected u-blox") == pytest.approx(9.83, abs=0.01)
    assert not [s for _, s in lines if "origin set" in s or "is using GPS" in s]
    assert lines[-1][0] < log.meta["duration_s"]
    assert [s for t, s in lines if s.startswith("Arm: ")][-1] == "Arm: GPS 1: Bad fix"


def test_only_the_mandatory_checks_still_need_a_position():
    """ARMING_CHECK 0 skips the GPS group, not Copter's mandatory position check."""
    log = _flight(SIM_GPS1_ENABLE=0, ARMING_CHECK=0)
    _never_flew(log)
    assert {s for _, s in _texts(log) if "Arm" in s} == {
        "Arm: Need Position Estimate", "PreArm: Need Position Estimate"}


@pytest.mark.parametrize(("params", "text"), [
    ({"BATT_ARM_VOLT": 13.0}, "Arm: Battery 1 below minimum arming voltage"),
    ({"SIM_ACC2_BIAS_X": 2.0}, "Arm: Accels inconsistent"),
    ({"SIM_MAG1_FAIL": 1.0}, "Arm: Compass not healthy"),
    ({"SIM_GPS1_NUMSATS": 5.0}, "Arm: AHRS: waiting for home"),
])
def test_a_failing_check_keeps_the_vehicle_on_the_ground(params, text):
    """Battery below BATT_ARM_VOLT; accelerometers 2 m/s/s apart (ARMING_ACCTHRESH 0.75); the
    first compass silent; 5 satellites (EKF3's GPS checks never pass, so no origin, no home,
    with the boot phase; without it the EKF uses GPS at once and the vehicle arms)."""
    log = _flight(**params, **(BOOT if "SIM_GPS1_NUMSATS" in params else {}))
    _never_flew(log)
    assert text in {s for _, s in _texts(log)}


def test_the_gps_lock_time_delays_arming():
    """SIM_GPS1_LCKTIME 30: no fix (Status 1, 3 satellites) before 30 s, then the driver's next
    attempt arms."""
    log = _flight(SIM_GPS1_LCKTIME=30.0)
    gps = log.tables["GPS"]
    before = gps[gps["TimeUS"] < 30e6]
    assert set(before["Status"]) == {1} and set(before["NSats"]) == {3}
    assert set(gps[gps["TimeUS"] > 30.3e6]["Status"]) == {6}
    assert 30.0 <= log.meta["armed_s"] <= 32.01
    assert log.meta["end_reason"] == "landed"
    assert "Arm: GPS 1: Bad fix" in {s for _, s in _texts(log)}


def test_without_the_boot_phase_the_flight_arms_at_tlm_arm_time(normal_flight):
    """The fast mode: GPS and EKF ready at once; EKF3's lifecycle texts all in the first second,
    the arming at TLM_ARM_TIME, home and field elevation from the first GPS sample."""
    m = normal_flight.meta
    assert m["armed_s"] == pytest.approx(ARM_TIME, abs=0.003) and not m["boot_phase"]
    lines = _texts(normal_flight)
    for lane in (0, 1):
        for text in ("initialised", "tilt alignment complete",
                     "MAG0 initial yaw alignment complete", "origin set", "is using GPS"):
            assert _first(lines, f"EKF3 IMU{lane} {text}") < 1.0
        assert ARM_TIME < _first(lines, f"EKF3 IMU{lane} MAG0 in-flight yaw alignment complete")
    assert _first(lines, "Field Elevation Set: 584m") < 1.0
    assert not [s for _, s in lines if s.startswith(("Arm:", "PreArm:"))]
    ev = normal_flight.tables["EV"]
    assert list(ev["Id"][:3]) == [62, 25, 10]


def test_end_reason_of_a_flight_that_never_armed():
    assert END_NOT_ARMED in END_REASONS
    assert end_reason(-1.0, np.zeros((0, 3)), armed=False) == END_NOT_ARMED
    assert end_reason(-1.0, np.zeros((0, 3))) == "time_cap"


def test_tlm_fly_says_why_it_did_not_fly(tmp_path, capsys):
    import json

    from tlm_process.cli import main

    out = tmp_path / "f"
    code = main(["fly", "--mission", "1", "--param", "SIM_GPS1_ENABLE=0", "--out", str(out),
                 "--format", "parquet", "--no-plot"])
    assert code == 0
    text = capsys.readouterr().out
    assert ("end reason         not_armed (never armed: the pre-arm checks failed until the "
            "driver gave up; last attempt: Arm: GPS 1: Bad fix)") in text
    assert json.loads((out / "meta.json").read_text())["meta"]["end_reason"] == "not_armed"


# ---------------------------------------------------------------- the boot phase vs SITL

#: (text, tolerance [s]) of normal_s11's boot timeline that tlm's boot phase reproduces
BOOT_TIMELINE = (
    ("EKF3 IMU0 initialised", 0.01), ("AHRS: EKF3 active", 0.01),
    ("EKF3 IMU0 tilt alignment complete", 0.3), ("EKF3 IMU1 tilt alignment complete", 0.3),
    ("EKF3 IMU0 MAG0 initial yaw alignment complete", 0.3),
    ("GPS 1: probing for u-blox at 230400 baud", 0.01), ("GPS 1: detected u-blox", 0.01),
    ("EKF3 IMU0 origin set", 0.05), ("EKF3 IMU1 origin set", 0.25),
    ("Field Elevation Set: 584m", 0.1), ("PreArm: Need Position Estimate", 0.01),
    ("EKF3 IMU0 is using GPS", 4.0), ("EKF3 IMU1 is using GPS", 4.0),
    ("Arming motors", 4.0),
)


def test_the_boot_phase_follows_sitls_timeline():
    """normal_s11's start-up, text by text: tlm's within the tolerance of SITL's time. The
    firmware's start-up and the driver's cadence are times (tlm_sim.boot); tilt alignment,
    origin and "is using GPS" come from the lanes' own state (covariance, GPS checks)."""
    log = _flight(**BOOT)
    tlm, sitl = _texts(log), _reference_texts("normal_s11")
    for text, tol in BOOT_TIMELINE:
        assert _first(tlm, text) == pytest.approx(_first(sitl, text), abs=tol), text
    assert _first(tlm, "EKF3 IMU0 is using GPS") < log.meta["armed_s"]
    assert log.meta["end_reason"] == "landed"
    # the first GPS message after the driver finds the receiver has no fix
    gps = log.tables["GPS"]
    assert (int(gps["Status"].iloc[0]), int(gps["NSats"].iloc[0])) == (1, 3)
    assert gps["TimeUS"].iloc[0] * 1e-6 == pytest.approx(9.83, abs=0.005)
    ev = log.tables["EV"]
    assert list(ev["Id"][:3]) == [62, 25, 10]  # yaw reset, home set, armed
    assert ev["TimeUS"].iloc[1] * 1e-6 == pytest.approx(20.02, abs=0.05)


def test_the_boot_phase_arm_attempts_read_as_sitls():
    """Every "Arm:" / "PreArm:" line SITL wrote before tlm's vehicle armed, in the same
    order at the same time (the driver's cadence: 3.75 s, 3.95 s, then every 2 s; SITL's
    driver drifts by up to 50 ms)."""
    log = _flight(**BOOT)
    armed = log.meta["armed_s"]
    tlm = [(t, s) for t, s in _texts(log) if s.startswith(("Arm:", "PreArm:"))]
    sitl = [(t, s) for t, s in _reference_texts("normal_s11")
            if s.startswith(("Arm:", "PreArm:")) and t < armed - 0.1]
    assert [s for _, s in tlm][:len(sitl)] == [s for _, s in sitl]
    assert np.allclose([t for t, _ in tlm][:len(sitl)], [t for t, _ in sitl], atol=0.06)


def test_baro_temperature_warms_up_as_sitls():
    """BARO.Temp: SIM_TEMP_START 25 degC warming to the air temperature + SIM_TEMP_BRD_OFF
    (31.2 degC at 584 m) with SIM_TEMP_TCONST 30 s, as AP_Baro_SITL; GndTemp from the boot
    calibration (25.37 degC), then the temperature when the field elevation is set;
    AltAMSL 0 + Alt until then."""
    log = _flight(**BOOT)
    ref = read_bin(reference_path("normal_s11.bin"), types=["BARO"])["BARO"]
    tlm = log.tables["BARO"]
    for i in (0, 1):
        r, b = ref[ref["I"] == i], tlm[tlm["I"] == i]
        r = r[r["TimeUS"] < 40e6]
        want = np.interp(r["TimeUS"], b["TimeUS"], b["Temp"])
        assert np.max(np.abs(want - r["Temp"])) < 0.02
    b0 = tlm[tlm["I"] == 0]
    assert b0["Temp"].iloc[-1] == pytest.approx(31.2, abs=0.05)
    early = b0[b0["TimeUS"] < 20e6]
    assert np.allclose(early["GndTemp"], 25.365, atol=0.005)
    assert np.allclose(early["AltAMSL"], early["Alt"])
    late = b0[b0["TimeUS"] > 21e6]
    assert np.allclose(late["GndTemp"], 28.02, atol=0.02)
    assert np.allclose(late["AltAMSL"] - late["Alt"], 584.0, atol=0.01)


# ---------------------------------------------------------------- the wording


def _row(kind: int, mask: int, **aux: float) -> list[float]:
    row = [1e6, float(kind), float(mask)] + [0.0] * (AP.N_TXT_COLS - 3)
    for k, v in aux.items():
        row[getattr(AP, k)] = v
    return row


@pytest.mark.parametrize(("mask", "aux", "text"), [
    (AP.F_NEED_POS, {}, "Need Position Estimate"),
    (AP.F_MAG_FIELD, {"A_MAG_FIELD": 900.4}, "Check mag field:  900, max 875, min 185"),
    (AP.F_GPS_AHRS, {"A_GPS_AHRS": 12.34}, "GPS and AHRS differ by 12.3m"),
    (AP.F_AHRS, {"A_LANE": AP.AHRS_NOT_STARTED}, "AHRS: EKF3 not started"),
    (AP.F_AHRS, {"A_LANE": 1.0}, "AHRS: EKF3 core 1 unhealthy"),
    (AP.F_EKF_VARIANCE, {"A_VARIANCE": AP.VAR_VELOCITY}, "EKF velocity variance"),
    (AP.F_BATTERY, {"A_BATTERY": AP.BATT_CRT_VOLT}, "Battery 1 critical voltage failsafe"),
    (AP.F_ARM_LEANING, {}, "Leaning"),
])
def test_check_texts_are_arducopters(mask, aux, text):
    assert logged_texts([_row(AP.KIND_ARM, mask, **aux)]) == [(1000000, "Arm: " + text)]
    assert logged_texts([_row(AP.KIND_PREARM, mask, **aux)]) == [(1000000, "PreArm: " + text)]


def test_several_failures_are_reported_in_arducopters_order():
    mask = AP.F_WAIT_HOME | AP.F_NEED_ALT | AP.F_EKF_ATTITUDE | AP.F_ACC_INCONS
    assert [s for _, s in logged_texts([_row(AP.KIND_ARM, mask)])] == [
        "Arm: Need Alt Estimate", "Arm: Accels inconsistent", "Arm: EKF attitude is bad",
        "Arm: AHRS: waiting for home"]
    # every check has its text, one bit each
    assert sorted(ARM_CHECK_TEXTS) == [1 << k for k in range(AP.N_FAIL_BITS)]
    assert math.log2(AP.F_ARM_LEANING) == AP.N_FAIL_BITS - 1


def test_tlm_generate_reports_flights_that_never_armed(tmp_path):
    """A dataset flight that cannot arm is counted and named, not silently empty."""
    from tlm_process.generate import GenerateOptions, ScenarioConfig, generate

    cfg = ScenarioConfig(kinds={"none": 1.0}, missions={"builtin": 1.0},
                         ranges={"BATT_ARM_VOLT": (13.0, 13.5)})
    rep = generate(GenerateOptions(out=tmp_path / "ds", flights=1, seed=0, config=cfg,
                                   progress=False, executor="thread", workers=1))
    assert (rep.ok, rep.failed, rep.not_armed) == (1, 0, [0])
    line = next(ln for ln in rep.lines() if ln.startswith("not armed"))
    assert "1 flight never armed" in line
