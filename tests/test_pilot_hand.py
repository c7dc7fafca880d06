"""The pilot's hand on the throttle (stick script ``throttle: hold`` / ``land``, ``height: H``;
tlm_sim.sensors.rc.pilot_hand): the script's codes, and a STABILIZE flight that climbs to a
height, holds it through lean steps and lands, as a pilot flies the manual-throttle modes."""

from __future__ import annotations

import numpy as np
import pytest

from tlm_sim import ardupilot as AP
from tlm_sim import fly
from tlm_sim.mission.sticks import (
    HOLD_PWM,
    LAND_PWM,
    StickScript,
    StickScriptError,
    height_code,
)
from tlm_sim.params import Params


def test_script_codes_and_steps():
    s = StickScript.from_dict({"sticks": [
        {"t": 0, "mode": "STABILIZE"}, {"t": 10, "throttle": 0.6}, {"t": 20, "height": 12},
        {"t": 30, "throttle": "HOLD"}, {"t": 40, "throttle": 0.3, "ramp": 2.0},
        {"t": 50, "throttle": "land"}]})
    tb = s.table(Params(), 60.0)
    thr = {t: tb[int(t * 50), 3] for t in (15, 25, 35, 40.02, 45, 55)}
    assert thr[15] == 1600.0 and thr[25] == height_code(12.0) == -22.0
    assert thr[35] == HOLD_PWM and thr[55] == LAND_PWM
    assert thr[40.02] == thr[45] == 1300.0  # out of the hand: a step, whatever the ramp
    assert s.sticks(35)["throttle"] == HOLD_PWM
    assert StickScript.from_dict(s.to_dict()) == s
    assert s.channels(25, Params())[2] == -22.0
    # only the throttle's codes make steps: a stick back from a negative position still ramps
    s = StickScript(({"t": 0, "pitch": -0.4, "ramp": 0}, {"t": 10, "pitch": 0.0, "ramp": 1.0},
                     {"t": 20, "throttle": 0.5}))
    assert s.sticks(10.5)["pitch"] == pytest.approx(-0.2)


@pytest.mark.parametrize("row, match", [
    ({"t": 1, "throttle": "up"}, "'hold' or 'land'"),
    ({"t": 1, "throttle": 0.5, "height": 3}, "not both"),
    ({"t": 1, "height": 150}, "outside 0..100"),
    ({"t": 1, "height": "ten"}, "finite number"),
])
def test_bad_hand_rows(row, match):
    with pytest.raises(StickScriptError, match=match):
        StickScript((row,))


def test_csv_takes_the_hand_words(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("t,throttle,height,mode\n0,,,STABILIZE\n10,,8,\n20,hold,,\n30,land,,\n")
    s = StickScript.from_file(p)
    assert [r.get("throttle", r.get("height")) for r in s.rows[1:]] == [8.0, "hold", "land"]


#: STABILIZE: the rudder gesture, the hand climbs to 10 m, pitch and roll steps, lands
SCRIPT = {"sticks": [
    {"t": 0, "mode": "STABILIZE"}, {"t": 20, "yaw": 1, "ramp": 0}, {"t": 23.5, "yaw": 0, "ramp": 0},
    {"t": 24, "height": 10}, {"t": 45, "pitch": 0.4}, {"t": 53, "pitch": 0.0},
    {"t": 61, "roll": 0.4}, {"t": 69, "roll": 0.0}, {"t": 85, "throttle": "land"}]}


@pytest.fixture(scope="module")
def log():
    return fly(None, params=Params({"FLTMODE1": AP.MODE_STABILIZE}),
               sticks=StickScript.from_dict(SCRIPT))


def _window(table, a, b):
    return table[(table.TimeUS >= a * 1e6) & (table.TimeUS < b * 1e6)]


def test_the_hand_climbs_holds_and_lands_in_stabilize(log):
    assert log.meta["end_reason"] == "landed"
    ctun, rcin = log.tables["CTUN"], log.tables["RCIN"]
    assert (rcin.C3 >= 1000).all()  # RCIN logs the hand's stick, never the code
    # the climb at 1.5 m/s to 10 m (the centre of mass: CTUN.Alt from the armed height)
    climb = _window(ctun, 27, 30).CRt.mean() / 100.0
    assert climb == pytest.approx(1.5, rel=0.1)
    held = _window(ctun, 36, 84).Alt
    assert held.mean() == pytest.approx(10.0, abs=0.35)
    assert held.max() - held.min() < 0.15  # through 8 s at 12 deg of pitch, then of roll
    assert _window(log.tables["ATT"], 47, 53).Pitch.mean() == pytest.approx(-12.0, rel=0.1)
    # landing: 0.7 m/s down, the stick down at touchdown, landed, auto-disarmed
    assert _window(ctun, 88, 94).CRt.mean() / 100.0 == pytest.approx(-0.7, rel=0.05)
    ev = log.tables["EV"]
    landed = float(ev.TimeUS[ev.Id == AP.EV_LAND_COMPLETE].iloc[0]) * 1e-6
    assert 95.0 < landed < 105.0
    assert (_window(rcin, landed, landed + 5).C3 == 1000).all()
    arm = log.tables["ARM"]
    assert list(arm.ArmState) == [1, 0] and arm.Method.iloc[-1] == AP.ARM_METHOD_DISARMDELAY
    assert np.all(np.diff(rcin.TimeUS) > 0)


def test_the_documented_manual_throttle_script_flies_and_lands():
    """docs/sticks/stabilize_acro.yaml (docs/pilot.md): STABILIZE and ACRO on the hand's
    throttle, landed and disarmed at the end."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "docs" / "sticks" / "stabilize_acro.yaml"
    log = fly(None, params=Params({"FLTMODE1": AP.MODE_STABILIZE, "FLTMODE2": AP.MODE_ACRO}),
              sticks=StickScript.from_file(path))
    assert log.meta["end_reason"] == "landed"
    modes = [int(m) for m in log.tables["MODE"].ModeNum]
    changes = [m for k, m in enumerate(modes) if k == 0 or m != modes[k - 1]]
    assert changes[-3:] == [AP.MODE_STABILIZE, AP.MODE_ACRO, AP.MODE_STABILIZE]
    held = _window(log.tables["CTUN"], 36, 100).Alt
    assert held.max() - held.min() < 1.0


def test_rcin_segments_start_after_the_liftoff(tmp_path):
    """A STABILIZE flight on the hand's throttle, X frame, motor 2 weakened, in wind (its
    liftoff tilts the copter): without a sidecar, RCIN's segments start 2 s after the copter
    first climbs 1 m (the liftoff depends on the throttle within RCIN's 10 Hz rows, which the
    replay cannot give back), and the replay passes every measure (34/36 when the segments
    started at the arming: the first one's peak roll and pitch, 3.4 deg against 3.9)."""
    from tlm_process.logread import read_log_tables
    from tlm_process.pilot.replay import replay
    from tlm_process.pilot.signature import LIFTOFF_SETTLE_S, airborne_us, segments_from_rcin

    rows = ({"t": 0, "mode": "STABILIZE"}, {"t": 20, "yaw": 1, "ramp": 0},
            {"t": 23.5, "yaw": 0, "ramp": 0}, {"t": 24, "height": 10}, {"t": 45, "pitch": 0.4},
            {"t": 53, "pitch": 0.0}, {"t": 62, "throttle": "land"})
    p = {"FLTMODE1": AP.MODE_STABILIZE, "FRAME_TYPE": 1, "SIM_ENGINE_FAIL": 2,
         "SIM_ENGINE_MUL": 0.85, "SIM_WIND_SPD": 5, "SIM_WIND_DIR": 60, "SIM_WIND_TURB": 1}
    log = fly(None, params=Params(p), sticks=StickScript(rows), seed=7)
    path = tmp_path / "stab.bin"
    log.write_bin(path)
    lt = read_log_tables(path)
    armed = log.meta["armed_s"] * 1e6
    up = airborne_us(lt.tables, armed)
    ctun = lt.tables["CTUN"]
    first_climb = ctun.TimeUS[(ctun.TimeUS >= armed) & (ctun.Alt > ctun.Alt[ctun.TimeUS >= armed]
                                                          .iloc[0] + 1.0)].iloc[0]
    assert up == pytest.approx(first_climb + LIFTOFF_SETTLE_S * 1e6)
    assert segments_from_rcin(lt.tables, lt.params)[0].start_us >= up
    j = replay(path)["judged"]
    assert j["pass"].all(), j[~j["pass"]]
