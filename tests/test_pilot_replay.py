"""Pilot-flown flights (issue 42): the shared SITL pilot flights re-flown from their RCIN match
SITL per stick segment (issue 42's tolerances), the real log171 replays to its end, and a
stick script flies, arms and disarms as a pilot's would."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_process.pilot.replay import (
    gcs_requests,
    is_pilot_flown,
    judge,
    rc_table,
    replay,
    with_arm_gesture,
)
from tlm_sim import ardupilot as AP
from tlm_sim.flight import fly, rc_table_us
from tlm_sim.mission.sticks import StickScript
from tlm_sim.params import Params

FLIGHTS = ("manual_loiter_s90", "manual_poshold_s91", "manual_althold_s92",
           "manual_stabilize_s93", "hover_partial_s95", "hover_partial_s97")
SCRIPT = Path(__file__).resolve().parents[1] / "docs" / "sticks" / "reference_loiter.yaml"


@pytest.mark.parametrize("name", FLIGHTS)
def test_reference_pilot_flight_replays_within_tolerance(name):
    r = replay(reference_path(f"pilot/{name}.bin"))
    bad = r["judged"][~r["judged"]["pass"]]
    assert bad.empty, bad.to_string()
    assert len(r["judged"]) >= 45  # 9 segments, 5 or more measures each
    assert r["checks"]["flight_time"]["pass"], r["flight_time_s"]
    assert r["scenario"]["end_reason"] == "landed"
    assert not r["scenario"]["notes"]  # SITL's pilot armed by the rudder gesture itself


def test_weakened_motor_shows_in_the_hover():
    """hover_partial_s97 (SIM_ENGINE_MUL 0.85 on motor 1, X frame): motor 1 runs ~105 us above
    the others in SITL's hover, and in tlm's."""
    r = replay(reference_path("pilot/hover_partial_s97.bin"))
    hover = r["segments"]["tlm"].iloc[0]
    assert hover["segment"] == "hover"
    assert hover["motor1_excess_us"] == pytest.approx(105.0, rel=0.05)
    assert r["scenario"]["faults"][0][1:] == ["SIM_ENGINE_MUL", 0.85]


def test_real_log171_replays_to_the_end():
    """Another vehicle and firmware (Copter 3.3): no threshold, but the LOITER segments are
    re-flown and compared, with a note on the inserted arming gesture; its switch to ACRO
    (not on its mode switch: every FLTMODEn is LOITER) is asked for at the log's time, and
    the pilot's full pitch stick back then forward flips tlm's copter (ACRO_TRAINER 0) within
    a quarter of a second of the real one (0.02 s, measured)."""
    r = replay(reference_path("../real/log171.bin"))
    assert len(r["judged"]) > 20
    notes = " ".join(r["scenario"]["notes"])
    assert "rudder gesture" in notes and "does not fly" not in notes
    assert "asked for at their times: ACRO at 217.2 s" in notes
    log = r["_log"]
    modes = log.tables["MODE"]
    assert (modes["ModeNum"] == AP.MODE_LOITER).any()
    acro = modes[modes["ModeNum"] == AP.MODE_ACRO]
    assert list(acro["TimeUS"] * 1e-6) == pytest.approx([217.209], abs=0.01)
    assert log.meta["armed_s"] == pytest.approx(72.6, abs=0.05)  # the log's arming
    att = log.tables["ATT"]
    flip = att["TimeUS"][att["Roll"].abs() > 90.0].iloc[0] * 1e-6
    assert flip == pytest.approx(238.98, abs=0.25)  # log171: |Roll| beyond 90 at 238.98 s


def test_mode_changes_off_the_switch_are_asked_for_in_a_log_without_reasons():
    """Copter 3.x logs no MODE reason: a change into a pilot mode that RCIN's mode switch does
    not select becomes a request at its time; the switch's own changes and RTL / LAND (the
    failsafes') do not."""
    mode = pd.DataFrame({"TimeUS": [10e6, 20e6, 30e6, 40e6], "ModeNum": [5, 1, 5, 6]})
    rcin = pd.DataFrame({"TimeUS": np.arange(0, 50e6, 1e5), "C5": 1000.0})
    values = {f"FLTMODE{k}": 5.0 for k in range(1, 7)}
    assert gcs_requests({"MODE": mode, "RCIN": rcin}, values) == [(20.0, 1)]
    values["FLTMODE1"] = 1.0  # the switch selects ACRO itself: nothing to ask for
    assert gcs_requests({"MODE": mode, "RCIN": rcin}, values) == [(30.0, 5)]
    with_rsn = mode.assign(Rsn=[1, 2, 1, 3])  # a 4.x log: its GCS rows only
    assert gcs_requests({"MODE": with_rsn, "RCIN": rcin}, values) == [(20.0, 1)]


def test_acro_p_of_older_firmware_is_acro_rate():
    from tlm_process.fit.fit import log_vehicle_params

    assert Params({"ACRO_RP_P": 8.0})["ACRO_RP_RATE"] == 360.0
    keep, _ = log_vehicle_params({"ACRO_YAW_P": 1.8, "ACRO_TRAINER": 0.0})
    assert keep == {"ACRO_Y_RATE": pytest.approx(81.0), "ACRO_TRAINER": 0.0}


def test_pilot_flown_detection():
    from tlm_process.logread import read_log_tables

    pilot = read_log_tables(reference_path("pilot/manual_loiter_s90.bin"), ["MODE", "RCIN"])
    auto = read_log_tables(reference_path("normal_s11.bin"), ["MODE", "RCIN"])
    assert is_pilot_flown(pilot.tables)
    assert not is_pilot_flown(auto.tables)


def test_arm_gesture_inserted_only_when_missing():
    t = np.column_stack([np.arange(0, 20, 0.1), np.full((200, 8), 1500.0)])
    t[:, 3] = 1000.0  # throttle down
    params = {"RCMAP_YAW": 4, "RCMAP_THROTTLE": 3}
    out, note = with_arm_gesture(t, 10.0, params)
    assert note and "7.0 s" in note
    inside = out[(out[:, 0] >= 6.98) & (out[:, 0] <= 10.0)]
    assert (inside[:, 4] == 2000.0).all() and (inside[:, 3] == 1000.0).all()
    again, note2 = with_arm_gesture(out, 10.0, params)
    assert note2 is None and np.array_equal(again, out)


def test_rc_table_drops_rows_without_radio_and_fills_channels():
    import pandas as pd

    rcin = pd.DataFrame({"TimeUS": [1e6, 2e6, 3e6], "C1": [0, 1500, 1600], "C2": [0, 1500, 1500],
                         "C3": [0, 1100, 1100], "C4": [0, 1500, 1500], "C5": [0, 0, 1685]})
    t = rc_table({"RCIN": rcin})
    assert t.shape == (2, 9)
    assert t[0, 0] == 2.0 and t[1, 1] == 1600.0
    assert t[0, 5] == 1800.0 and t[1, 5] == 1685.0  # SITL's idle channel 5 where the log has 0
    assert t[0, 8] == 1800.0  # channel 8 missing: idle


def test_rc_table_interpolates_the_sticks_onto_the_receiver_frames():
    """RCIN at 10 Hz: the sticks (RCMAP's channels) are linear between rows at 50 Hz, the mode
    switch is held row to row, and rows 0.5 s apart (the radio lost) are not filled."""
    import pandas as pd

    from tlm_process.pilot.replay import RC_FRAME_HZ
    from tlm_sim.sensors.rc import RC_FRAME_US

    assert RC_FRAME_HZ == 1e6 / RC_FRAME_US
    rcin = pd.DataFrame({"TimeUS": [1.0e6, 1.1e6, 1.6e6], "C1": [1500, 1600, 1600],
                         "C2": [1500, 1400, 1400], "C3": [1100, 1200, 1200],
                         "C4": [1500, 1500, 1700], "C5": [1165, 1685, 1685],
                         "C6": [1000, 2000, 2000]})
    t = rc_table({"RCIN": rcin})
    assert np.allclose(t[:, 0], [1.0, 1.02, 1.04, 1.06, 1.08, 1.1, 1.6])
    assert np.allclose(t[:6, 1], np.linspace(1500, 1600, 6))
    assert np.allclose(t[:6, 2], np.linspace(1500, 1400, 6))
    assert np.allclose(t[:6, 3], np.linspace(1100, 1200, 6))
    assert (t[:5, 5] == 1165).all() and (t[:5, 6] == 1000).all() and t[5, 5] == 1685
    # channel 6 mapped to roll: it moves, channel 1 is held
    t = rc_table({"RCIN": rcin}, {"RCMAP_ROLL": 6})
    assert np.allclose(t[:6, 6], np.linspace(1000, 2000, 6)) and (t[:5, 1] == 1500).all()


def test_gcs_mode_changes_of_a_log_are_asked_for_again():
    import pandas as pd

    from tlm_process.pilot.replay import gcs_requests

    mode = pd.DataFrame({"TimeUS": [1e6, 5e6, 9e6], "Mode": [0, 5, 2], "ModeNum": [0, 5, 2],
                         "Rsn": [26, 2, 1]})
    assert gcs_requests({"MODE": mode}) == [(5.0, 5)]
    assert gcs_requests({"MODE": mode.drop(columns="Rsn")}) == []  # Copter 3.x: no reasons
    with pytest.raises(ValueError, match="give sticks"):
        fly(1, gcs_modes=[(10.0, "LOITER")])
    with pytest.raises(ValueError, match="unknown flight mode"):
        fly(None, sticks=np.column_stack([[0.0], np.full((1, 8), 1500.0)]),
            gcs_modes=[(10.0, "HOVER")])


def test_judge_tolerances():
    import pandas as pd

    ref = pd.DataFrame([{"segment": "pitch_forward", "start_s": 0.0, "end_s": 8.0,
                         "pitch_mean_deg": -10.0, "pitch_peak_deg": 11.0, "roll_mean_deg": 0.1,
                         "roll_peak_deg": 0.2, "speed_max_ms": 4.7, "alt_std_m": 0.0,
                         "alt_range_m": 0.02, "motor1_excess_us": 0.1, "thr_out": 0.37}])
    ours = ref.copy()
    ours["pitch_mean_deg"] = -8.4  # 16 % off
    ours["roll_mean_deg"] = 0.5  # within the 0.5 deg floor
    j = judge(ref, ours, {})
    by = dict(zip(j["measure"], j["pass"], strict=True))
    assert not by["pitch_mean_deg"] and by["roll_mean_deg"] and by["speed_max_ms"]
    # other draws of the gusts: the log's value within their range (widened by the tolerance)
    other = ours.copy()
    other["pitch_mean_deg"] = -11.0
    j = judge(ref, ours, {}, draws=[other])
    row = j[j["measure"] == "pitch_mean_deg"].iloc[0]
    assert row["pass"] and row["tlm"] == -8.4 and (row["tlm_min"], row["tlm_max"]) == (-11.0, -8.4)
    far = ours.copy()
    far["pitch_mean_deg"] = -6.0
    j = judge(ref, ours, {}, draws=[far])
    assert not j[j["measure"] == "pitch_mean_deg"].iloc[0]["pass"]


def _flight(script, params=None):
    return fly(None, params=Params(params or {}), sticks=StickScript.from_dict(script))


def test_stick_script_flies_arms_and_disarms_like_a_pilot():
    log = fly(None, sticks=StickScript.from_file(SCRIPT))
    assert log.meta["end_reason"] == "landed" and log.meta["mission"] == "pilot"
    arm = log.tables["ARM"]
    assert list(arm["ArmState"]) == [1, 0]
    assert list(arm["Method"]) == [AP.ARM_METHOD_RUDDER, AP.ARM_METHOD_RUDDER]
    assert log.meta["armed_s"] == pytest.approx(45.4, abs=0.1)  # 3 s after the gesture began
    assert set(log.tables["MODE"]["ModeNum"]) == {AP.MODE_STABILIZE, AP.MODE_LOITER}
    ev = list(log.tables["EV"]["Id"])
    for e in (AP.EV_ARMED, AP.EV_AUTO_ARMED, AP.EV_NOT_LANDED, AP.EV_LAND_COMPLETE,
              AP.EV_DISARMED):
        assert e in ev
    ctun = log.tables["CTUN"]
    hold = ctun[(ctun.TimeUS > 60e6) & (ctun.TimeUS < 135e6)]
    assert hold["Alt"].max() - hold["Alt"].min() < 0.3  # LOITER holds the height
    assert log.n_rows("CMD") == 0 if "CMD" in log.tables else True  # no mission is logged
    rcin = log.tables["RCIN"]
    assert rcin[(rcin.TimeUS > 80e6) & (rcin.TimeUS < 84e6)]["C2"].eq(1300).all()


def test_auto_disarm_after_landing_with_the_throttle_down():
    script = {"sticks": [{"t": 0, "mode": "LOITER"}, {"t": 20, "yaw": 1, "ramp": 0},
                         {"t": 23.5, "yaw": 0, "ramp": 0}, {"t": 24, "throttle": 0.8, "ramp": 0},
                         {"t": 28, "throttle": 0.5}, {"t": 35, "throttle": 0.1},
                         {"t": 45, "throttle": 0.0, "ramp": 0}]}
    log = _flight(script)
    arm = log.tables["ARM"]
    assert list(arm["Method"])[-1] == AP.ARM_METHOD_DISARMDELAY
    landed = log.tables["EV"].query(f"Id == {AP.EV_LAND_COMPLETE}")["TimeUS"].iloc[0]
    # throttle at zero from 45 s (+0.4 s), landed before: disarmed DISARM_DELAY (10 s) later
    assert arm["TimeUS"].iloc[-1] * 1e-6 == pytest.approx(max(45.4, landed * 1e-6) + 10.0,
                                                          abs=0.2)


def test_stabilize_and_mode_switch_to_alt_hold():
    params = {"FLTMODE1": 0, "FLTMODE2": 2}
    script = {"sticks": [{"t": 0, "mode": "STABILIZE"}, {"t": 20, "yaw": 1, "ramp": 0},
                         {"t": 23.5, "yaw": 0, "ramp": 0}, {"t": 24, "throttle": 0.6},
                         {"t": 30, "mode": "ALT_HOLD", "throttle": 0.5},
                         {"t": 50, "roll": 0.4}, {"t": 55, "roll": 0.0},
                         {"t": 62, "gcs_mode": "LOITER"}, {"t": 66, "gcs_mode": "AUTO"}]}
    log = _flight(script, params)
    modes = log.tables["MODE"]
    alt_hold = modes[modes["ModeNum"] == AP.MODE_ALT_HOLD]
    assert alt_hold["TimeUS"].iloc[0] * 1e-6 == pytest.approx(30.2, abs=0.05)  # 200 ms debounce
    assert list(alt_hold["Rsn"]) == [AP.RSN_RC_COMMAND]
    # the ground station: LOITER over MAVLink at 62 s (the switch stays on ALT_HOLD), AUTO
    # refused (tlm flies no mission from a pilot's flight)
    last = modes.iloc[-1]
    assert (last["ModeNum"], last["Rsn"]) == (AP.MODE_LOITER, AP.RSN_GCS)
    assert last["TimeUS"] * 1e-6 == pytest.approx(62.0, abs=0.01)
    att = log.tables["ATT"]
    lean = att[(att.TimeUS > 52e6) & (att.TimeUS < 55e6)]["Roll"].mean()
    assert lean == pytest.approx(0.4 * 30.0 * 480 / 480, rel=0.1)
    ctun = log.tables["CTUN"]
    hold = ctun[(ctun.TimeUS > 36e6) & (ctun.TimeUS < 60e6)]
    assert hold["Alt"].max() - hold["Alt"].min() < 0.5


def test_rc_table_input_checks():
    p = Params()
    with pytest.raises(ValueError, match="9 columns"):
        rc_table_us(np.zeros((3, 5)), p)
    bad = np.column_stack([[1.0, 0.5], np.full((2, 8), 1500.0)])
    with pytest.raises(ValueError, match="in order"):
        rc_table_us(bad, p)
    ok = rc_table_us(np.column_stack([[0.0, 1.25], np.full((2, 8), 1500.0)]), p)
    assert ok[1, 0] == 1.25e6


def test_crosscheck_replays_a_pilot_flown_log(tmp_path):
    """``tlm crosscheck`` on a pilot-flown log re-flies it from RCIN: the console summary,
    report.md with every judged measure, overlay.png, the re-flown tlm_flight.bin, the JSON;
    exit code 0 when every measure is within tolerance (1 otherwise: log171, another
    vehicle)."""
    import json

    from tlm_process.cli import main

    out = tmp_path / "r"
    code = main(["crosscheck", str(reference_path("pilot/manual_althold_s92.bin")), "--out",
                 str(out), "--json", str(tmp_path / "r.json")])
    assert code == 0
    report = (out / "report.md").read_text()
    assert "replay from RCIN" in report and "| pitch_forward | pitch_mean_deg |" in report
    assert (out / "overlay.png").stat().st_size > 10_000 and (out / "tlm_flight.bin").is_file()
    doc = json.loads((tmp_path / "r.json").read_text())
    assert doc["checks"]["segments"]["pass"] and len(doc["judged"]) == 63
    code = main(["crosscheck", str(reference_path("../real/log171.bin")), "--out",
                 str(tmp_path / "real")])
    assert code == 1 and (tmp_path / "real" / "overlay.png").is_file()


def test_pilot_takeoff_to_pilot_tkoff_alt():
    """PILOT_TKOFF_ALT 5 m: a short push above the dead band (2 s at 60 % throttle, ~0.26
    m/s) takes the copter on to 5 m before it holds."""
    script = {"sticks": [{"t": 0, "mode": "LOITER"}, {"t": 20, "yaw": 1, "ramp": 0},
                         {"t": 23.5, "yaw": 0, "ramp": 0}, {"t": 26.5, "throttle": 0.6},
                         {"t": 28.5, "throttle": 0.5}]}
    log = _flight(script, {"PILOT_TKOFF_ALT": 500})
    ctun = log.tables["CTUN"]
    held = ctun[(ctun.TimeUS > 45e6) & (ctun.TimeUS < 55e6)]["Alt"]
    assert held.mean() == pytest.approx(5.0, abs=0.3) and held.max() - held.min() < 0.2


def test_radio_failsafe_in_a_pilot_mode_flies_home():
    """SIM_RC_FAIL 1 while the pilot flies LOITER: ERR radio, RTL (reason radio failsafe),
    landed and disarmed at home."""
    script = StickScript.from_file(SCRIPT)
    log = fly(None, [(90.0, "SIM_RC_FAIL", 1.0)], sticks=script)
    modes = log.tables["MODE"]
    assert (modes["ModeNum"].iloc[-1], modes["Rsn"].iloc[-1]) == (AP.MODE_RTL,
                                                                    AP.RSN_RADIO_FAILSAFE)
    assert log.meta["end_reason"] == "landed"
    assert log.tables["ARM"]["Method"].iloc[-1] == AP.ARM_METHOD_LANDED


def test_tlm_fly_sticks_command(tmp_path, capsys):
    from tlm_process.cli import main

    out = tmp_path / "f"
    assert main(["fly", "--sticks", str(SCRIPT), "--out", str(out), "--format", "csv",
                 "--no-plot", "--fault", "gps_glitch:90-110"]) == 0
    text = capsys.readouterr().out
    assert "none: flown by a pilot's sticks" in text and "gps_glitch" in text
    assert (out / "RCIN.csv").is_file()
    assert main(["fly", "--sticks", str(SCRIPT), "--out", str(tmp_path / "g"),
                 "--fault", "gps:wp3-wp5"]) == 2
    assert "no waypoints" in capsys.readouterr().err
    assert main(["fly", "--sticks", str(SCRIPT), "--mission", "2", "--out",
                 str(tmp_path / "h")]) == 2
    assert "drop --mission" in capsys.readouterr().err


def test_a_log_flown_in_random_gusts_is_judged_over_draws_of_them(tmp_path):
    """A pilot flight in SITL's random gusts (SIM_WIND_TURB 1; tlm's, hexa, motor 3 weakened,
    ALT_HOLD) re-flown from its RCIN with another seed: the replay flies GUST_DRAWS draws of the
    gusts and judges each measure on their range; every measure passes (one seed alone can
    miss a peak lean after a release: docs/pilot.md)."""
    from tlm_process.pilot.replay import GUST_DRAWS, replay

    script = StickScript.from_file(SCRIPT).to_dict()
    for row in script["sticks"]:
        if "mode" in row:
            row["mode"] = "ALT_HOLD"
    p = {"FRAME_CLASS": 2, "FLTMODE1": 2, "SIM_WIND_SPD": 5, "SIM_WIND_DIR": 90,
         "SIM_WIND_TURB": 1, "SIM_ENGINE_MUL": 0.8, "SIM_ENGINE_FAIL": 4}
    log = fly(None, params=Params(p), sticks=StickScript.from_dict(script), seed=5)
    path = tmp_path / "gusty.bin"
    log.write_bin(path)
    r = replay(path)
    assert r["scenario"]["gust_draws"] == GUST_DRAWS
    j = r["judged"]
    assert (j["tlm_min"] <= j["tlm"]).all() and (j["tlm"] <= j["tlm_max"]).all()
    assert (j["tlm_max"] > j["tlm_min"]).any()  # the draws differ
    assert r["checks"]["segments"]["pass"] and r["checks"]["flight_time"]["pass"]
