"""ACRO as ArduCopter 4.7 flies it (mode_acro.cpp, AC_AttitudeControl's body-rate input):
stick -> body rates with expo, the trainer's levelling and angle limit, the attitude target
turning at the shaped body rates; and a flight in it (manual throttle, the trainer levelling
after a roll, the yaw rate of the yaw stick, ACRO refused in the radio failsafe)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_sim import ardupilot as AP
from tlm_sim import fly
from tlm_sim.control import layout as C
from tlm_sim.control.attitude import attitude_reset, attitude_update
from tlm_sim.control.config import build_control_config
from tlm_sim.control.pilot import stick_norm
from tlm_sim.control.pilot_modes import acro_rates, input_expo
from tlm_sim.mission.sticks import StickScript
from tlm_sim.params import Params

LEVEL_Q = np.array([1.0, 0.0, 0.0, 0.0])


def _cfg(**params):
    return build_control_config(Params(params))


def _sticks(roll=0.0, pitch=0.0, yaw=0.0, roll_t=0.0, pitch_t=0.0):
    c = np.zeros(C.N_CONTROL_STATE)
    c[C.PIL_ROLL], c[C.PIL_PITCH], c[C.PIL_YAW] = roll, pitch, yaw
    attitude_reset(c, roll_t, pitch_t, 0.0)
    return c


def test_stick_rates_with_expo_and_the_circle_limit():
    g = _cfg(ACRO_TRAINER=0)
    c = _sticks(roll=0.3, pitch=-0.2, yaw=0.5)
    acro_rates(c, g, LEVEL_Q)
    rp = math.radians(360.0)  # ACRO_RP_RATE, ACRO_RP_EXPO 0.3
    assert c[C.ACRO_RATE_CMD] == pytest.approx(rp * 0.7 * 0.3 / (1 - 0.3 * 0.3))
    assert c[C.ACRO_RATE_CMD + 1] == pytest.approx(-rp * 0.7 * 0.2 / (1 - 0.3 * 0.2))
    assert c[C.ACRO_RATE_CMD + 2] == pytest.approx(math.radians(202.5) * 0.5)  # no yaw expo
    # both sticks full: the pair is scaled back onto the unit circle first
    c = _sticks(roll=1.0, pitch=1.0)
    acro_rates(c, g, LEVEL_Q)
    s = math.sqrt(0.5)
    assert c[C.ACRO_RATE_CMD] == pytest.approx(rp * input_expo(s, 0.3))
    assert c[C.ACRO_RATE_CMD + 1] == c[C.ACRO_RATE_CMD]
    assert input_expo(1.0, 0.3) == 1.0 and input_expo(0.5, 0.95) == 0.5


def test_trainer_levels_and_limits_the_target():
    # ACRO_TRAINER 2 (the default): sticks centred, target rolled 20 deg -> 20 deg/s back
    g = _cfg()
    c = _sticks(roll_t=math.radians(20.0))
    acro_rates(c, g, LEVEL_Q)
    assert c[C.ACRO_RATE_CMD] == pytest.approx(-math.radians(20.0))
    assert c[C.ACRO_RATE_CMD + 1] == pytest.approx(0.0, abs=1e-12)
    g_half = _cfg(ACRO_BAL_ROLL=0.5)
    acro_rates(c, g_half, LEVEL_Q)
    assert c[C.ACRO_RATE_CMD] == pytest.approx(-math.radians(10.0))
    # beyond ANGLE_MAX (30 deg) the limit pulls harder than the levelling (capped at 30 deg)
    c = _sticks(roll=1.0, roll_t=math.radians(35.0))
    acro_rates(c, g, LEVEL_Q)
    full = math.radians(360.0)
    assert c[C.ACRO_RATE_CMD] < full - math.radians(30.0)
    # ACRO_TRAINER 1: the levelling fades out with the stick (full stick: none)
    g1 = _cfg(ACRO_TRAINER=1)
    c = _sticks(roll=1.0, roll_t=math.radians(35.0))
    acro_rates(c, g1, LEVEL_Q)
    assert c[C.ACRO_RATE_CMD] == pytest.approx(full)
    # ACRO_TRAINER 0: none at all
    c = _sticks(roll_t=math.radians(20.0))
    acro_rates(c, _cfg(ACRO_TRAINER=0), LEVEL_Q)
    assert c[C.ACRO_RATE_CMD] == 0.0


@settings(max_examples=40, deadline=None)
@given(st.floats(-1, 1), st.floats(-60, 60))
def test_trainer_1_sum_is_bounded_as_arducopter_bounds_it(stick, roll_deg):
    """ACRO_TRAINER 1: stick rate plus levelling (faded by 1 - |stick|), limited to
    ||stick rate| - |levelling||; with the stick centred, the levelling alone."""
    g = _cfg(ACRO_TRAINER=1)
    c = _sticks(roll=stick, roll_t=math.radians(roll_deg))
    acro_rates(c, g, LEVEL_Q)
    want = math.radians(360.0) * input_expo(stick, 0.3)
    level = -math.radians(min(max(roll_deg, -30.0), 30.0)) * (1.0 - abs(stick))
    lim = abs(abs(want) - abs(level))
    assert c[C.ACRO_RATE_CMD] == pytest.approx(min(max(want + level, -lim), lim), abs=1e-9)


def _quat(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy])


def test_body_rate_input_turns_the_target_at_the_shaped_rate():
    """The body-rate target ramps at ATC_ACCEL_R_MAX to the command and the target attitude
    turns by it; a copter on its target gets exactly that rate as its rate target."""
    g = _cfg()
    dt, accel = g[C.G_DT], g[C.G_ACCEL_MAX]
    c = np.zeros(C.N_CONTROL_STATE)
    attitude_reset(c, 0.0, 0.0, 0.0)
    c[C.ATT_RATE_BF_IN] = 1.0
    c[C.ACRO_RATE_CMD] = 1.0  # rad/s roll
    out = np.zeros(3)
    w = roll = 0.0
    for _ in range(400):
        q = _quat(c[C.ATT_ROLL_T], c[C.ATT_PITCH_T], c[C.ATT_YAW_T])
        attitude_update(c, g, q, np.zeros(3), out)
        roll += w * dt  # the target turns by the previous rate, then the rate moves on
        w = min(w + accel * dt, 1.0)
        assert c[C.ATT_ANG_VEL_T] == pytest.approx(w, abs=1e-12)
    assert c[C.ATT_ROLL_T] == pytest.approx(roll, abs=1e-9)
    assert c[C.ATT_ROLL_RATE_T] == pytest.approx(1.0)
    # a yaw body rate on a rolled target: euler pitch and yaw rates, and on target the
    # attitude controller asks for the body rate itself
    c[C.ACRO_RATE_CMD] = 0.0
    c[C.ACRO_RATE_CMD + 2] = 0.5
    c[C.ATT_ANG_VEL_T : C.ATT_ANG_VEL_T + 3] = (0.0, 0.0, 0.5)
    q = _quat(c[C.ATT_ROLL_T], c[C.ATT_PITCH_T], c[C.ATT_YAW_T])
    attitude_update(c, g, q, np.zeros(3), out)
    r = c[C.ATT_ROLL_T]
    assert c[C.ATT_PITCH_RATE_T] == pytest.approx(-math.sin(r) * 0.5)
    assert c[C.ATT_YAW_RATE_T] == pytest.approx(math.cos(r) * 0.5)
    q = _quat(c[C.ATT_ROLL_T], c[C.ATT_PITCH_T], c[C.ATT_YAW_T])
    attitude_update(c, g, q, np.zeros(3), out)
    # the target first turned by 0.5 rad/s x dt, the angle P acts on that step
    assert out == pytest.approx([0.0, 0.0, 0.5 * (1.0 + g[C.G_ANG_P + 2] * dt)], abs=1e-6)


#: ALT_HOLD take-off to about 7 m, ACRO (mid-stick throttle), a roll step, a pitch step and a
#: yaw step, back to ALT_HOLD and down
ACRO_SCRIPT = {"sticks": [
    {"t": 0, "mode": "ALT_HOLD"}, {"t": 20, "yaw": 1, "ramp": 0}, {"t": 23.5, "yaw": 0, "ramp": 0},
    {"t": 24, "throttle": 0.8}, {"t": 32, "throttle": 0.5}, {"t": 40, "mode": "ACRO"},
    {"t": 45, "roll": 0.3, "ramp": 0}, {"t": 46, "roll": 0.0, "ramp": 0},
    {"t": 50, "pitch": -0.2, "ramp": 0}, {"t": 53, "pitch": 0.0, "ramp": 0},
    {"t": 60, "yaw": 0.5, "ramp": 0}, {"t": 62, "yaw": 0.0, "ramp": 0},
    {"t": 66, "mode": "ALT_HOLD"}, {"t": 70, "throttle": 0.2}, {"t": 90, "throttle": 0.0}]}
ACRO_PARAMS = {"FLTMODE1": AP.MODE_ALT_HOLD, "FLTMODE2": AP.MODE_ACRO}


@pytest.fixture(scope="module")
def acro_log():
    return fly(None, params=Params(ACRO_PARAMS), sticks=StickScript.from_dict(ACRO_SCRIPT))


def _window(table, a, b):
    return table[(table.TimeUS >= a * 1e6) & (table.TimeUS < b * 1e6)]


def test_acro_flight_rates_trainer_and_throttle(acro_log):
    log = acro_log
    assert log.meta["end_reason"] == "landed"
    modes = log.tables["MODE"]
    acro = modes[modes.ModeNum == AP.MODE_ACRO]
    assert len(acro) == 1 and acro.TimeUS.iloc[0] * 1e-6 == pytest.approx(40.2, abs=0.05)
    att = log.tables["ATT"]
    # roll stick 0.3 for 1 s (1650 us, 0.271 beyond RC1_DZ): 74.3 deg/s asked, less the
    # trainer's levelling of 1/s x the target roll; it stops the roll near ANGLE_MAX (30 deg,
    # 10 deg of overshoot at most) and levels it once released (30 -> 2 deg in under 4 s)
    g = build_control_config(Params(ACRO_PARAMS))
    asked = math.degrees(g[C.G_ACRO_RP_RATE] * input_expo(stick_norm(g, 0, 1650.0), 0.3))
    assert asked == pytest.approx(74.3, abs=0.1)
    des = _window(att, 45.05, 45.55)
    t, d = des.TimeUS.to_numpy() * 1e-6, des.DesRoll.to_numpy()
    stick_rate = np.diff(d) / np.diff(t) + 0.5 * (d[1:] + d[:-1])
    assert stick_rate == pytest.approx(np.full(len(stick_rate), asked), rel=0.03)
    assert 28.0 < _window(att, 45, 46.5).Roll.max() < 40.0
    assert abs(_window(att, 49.5, 50).Roll).max() < 2.0
    # pitch stick 0.2 back: nose up, levelled after
    assert 20.0 < _window(att, 50, 53.5).Pitch.max() < 40.0
    assert abs(_window(att, 58, 60).Pitch).max() < 2.0
    # yaw stick 0.5 (1750 us): ACRO_Y_RATE 202.5 deg/s x 0.479 once the rate has built up
    # (the target's heading; the copter's own, catching up on its lag, within 7 %)
    asked = 202.5 * stick_norm(g, 3, 1750.0)
    for col, rel in (("DesYaw", 0.005), ("Yaw", 0.07)):
        yaw = np.unwrap(np.radians(_window(att, 60.8, 61.8)[col].to_numpy()))
        assert math.degrees((yaw[-1] - yaw[0]) / 0.9) == pytest.approx(asked, rel=rel)
    # manual throttle: mid-stick is the hover throttle, without angle boost
    ctun = _window(log.tables["CTUN"], 41, 65)
    assert np.allclose(ctun.ThO, ctun.ThI) and (ctun.ABst == 0).all()
    assert ctun.ThI.to_numpy() == pytest.approx(ctun.ThH.to_numpy(), abs=0.01)


def test_acro_is_refused_in_the_radio_failsafe():
    rows = ({"t": 0, "mode": "LOITER"}, {"t": 42.4, "yaw": 1.0, "ramp": 0},
            {"t": 46.0, "yaw": 0.0, "ramp": 0}, {"t": 46.2, "throttle": 0.8, "ramp": 0},
            {"t": 56.9, "throttle": 0.5}, {"t": 60.0, "gcs_mode": "ACRO"},
            {"t": 61.0, "gcs_mode": "LOITER"}, {"t": 75.0, "gcs_mode": "ACRO"})
    log = fly(None, sticks=StickScript(rows), faults=[(70.0, "SIM_RC_FAIL", 1)], seed=1)
    mode = log.tables["MODE"]
    acro = mode[mode.ModeNum == AP.MODE_ACRO]
    assert list(acro.TimeUS * 1e-6) == pytest.approx([60.0], abs=0.01)  # before: accepted
    rtl = mode[mode.ModeNum == AP.MODE_RTL]
    assert len(rtl) == 1 and float(rtl.TimeUS.iloc[0]) * 1e-6 < 75.0
    assert int(mode.ModeNum.iloc[-1]) in (AP.MODE_RTL, AP.MODE_LAND)


def test_an_acro_log_replays_from_its_rcin(tmp_path):
    """A log flown in ACRO (X frame; the pilot's hand on the throttle in STABILIZE and ACRO)
    re-flown from its RCIN: the switch's ACRO is flown again and every judged measure of every
    stick segment passes (the height is not judged: the throttle is the pilot's)."""
    from tlm_process.pilot.replay import replay

    rows = [{"t": 0, "mode": "STABILIZE"}, {"t": 20, "yaw": 1, "ramp": 0},
            {"t": 23.5, "yaw": 0, "ramp": 0}, {"t": 24, "height": 10}, {"t": 40, "mode": "ACRO"},
            {"t": 50, "pitch": 0.2}, {"t": 58, "pitch": 0}, {"t": 66, "roll": 0.2},
            {"t": 74, "roll": 0}, {"t": 82, "yaw": 0.3}, {"t": 86, "yaw": 0},
            {"t": 96, "mode": "STABILIZE"}, {"t": 99, "throttle": "land"}]
    params = {"FLTMODE1": AP.MODE_STABILIZE, "FLTMODE2": AP.MODE_ACRO, "FRAME_TYPE": 1}
    log = fly(None, params=Params(params), sticks=StickScript(tuple(rows)), seed=5)
    path = tmp_path / "acro.bin"
    log.write_bin(path)
    r = replay(path)
    modes = r["_log"].tables["MODE"]
    assert (modes["ModeNum"] == AP.MODE_ACRO).any()
    j = r["judged"]
    assert len(j) > 40 and j["pass"].all(), j[~j["pass"]]
    assert r["checks"]["flight_time"]["pass"]


def test_the_radio_failsafe_takes_acro_home():
    """The transmitter lost in ACRO, airborne: RTL (reason RADIO_FAILSAFE) takes the attitude
    target back from the body rates; the copter comes home level and lands."""
    rows = ({"t": 0, "mode": "STABILIZE"}, {"t": 20, "yaw": 1, "ramp": 0},
            {"t": 23.5, "yaw": 0, "ramp": 0}, {"t": 24, "height": 10}, {"t": 40, "mode": "ACRO"},
            {"t": 45, "pitch": 0.1, "ramp": 0}, {"t": 47, "pitch": 0.0, "ramp": 0})
    log = fly(None, params=Params({"FLTMODE1": AP.MODE_STABILIZE, "FLTMODE2": AP.MODE_ACRO}),
              sticks=StickScript(rows), faults=[(55.0, "SIM_RC_FAIL", 1)], seed=1)
    mode = log.tables["MODE"]
    rtl = mode[mode.ModeNum == AP.MODE_RTL]
    assert len(rtl) == 1 and int(rtl.Rsn.iloc[0]) == AP.RSN_RADIO_FAILSAFE
    assert log.meta["end_reason"] == "landed"
    att = log.tables["ATT"]
    home = att[att.TimeUS > rtl.TimeUS.iloc[0] + 10e6]
    assert abs(home.Roll).max() < 15.0 and abs(home.Pitch).max() < 25.0
    pos = log.tables["POS"] if "POS" in log.tables else None
    assert pos is None or abs(pos.RelHomeAlt.iloc[-1]) < 1.0


def test_the_replay_rehearsal_tool_flies_and_judges_one_flight(tmp_path):
    """tools/replay_rehearsal.py (docs/pilot.md): one of its 15 flights, ACRO on the X frame in
    wind with motor 2 weakened, re-flown from RCIN: every measure within tolerance."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "tools" / "replay_rehearsal.py"
    spec = importlib.util.spec_from_file_location("replay_rehearsal", path)
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    text = tool.one(("ACRO", "x", str(tmp_path)))
    assert text.split()[:3] == ["ACRO", "x", "landed"] and "54/54 measures" in text
    assert "outside" not in text and (tmp_path / "ACRO_x.bin").is_file()


def test_one_list_of_pilot_modes():
    """PILOT_MODES (Python: the replay) and is_pilot_mode (the loop) name the same modes, and
    the manual-throttle ones are STABILIZE and ACRO."""
    from tlm_sim.control.pilot_modes import PILOT_MODES, has_manual_throttle, is_pilot_mode

    for m in AP.MODE_NAMES:
        assert is_pilot_mode(float(m)) == (m in PILOT_MODES), AP.MODE_NAMES[m]
        assert has_manual_throttle(float(m)) == (m in (AP.MODE_STABILIZE, AP.MODE_ACRO))
