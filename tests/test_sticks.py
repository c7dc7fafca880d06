"""Stick scripts (issue 42, part 2): rows, ramps, the RC channels a receiver delivers (RCMAP,
pitch forward = low PWM, the mode switch at its position's centre), files (YAML, JSON, CSV)
and one-line errors. The reference pilot flights' script rendered here gives the PWM their
sidecars record for every segment."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import reference_path
from tlm_sim.mission.sticks import StickScript, StickScriptError, mode_pwm
from tlm_sim.params import Params

P = Params()  # copter.parm's switch: FLTMODE1..6 = 7, 9, 6, 3, 5, 0


def test_a_step_ramps_over_its_ramp_and_holds():
    s = StickScript(({"t": 10, "pitch": 0.4}, {"t": 18, "pitch": 0.0, "ramp": 1.0}))
    assert s.sticks(9.9)["pitch"] == 0.0
    assert s.sticks(10.25)["pitch"] == pytest.approx(0.2)
    assert s.sticks(12.0)["pitch"] == pytest.approx(0.4)
    assert s.sticks(18.5)["pitch"] == pytest.approx(0.2)
    assert s.sticks(30.0) == {"roll": 0.0, "pitch": 0.0, "throttle": 0.0, "yaw": 0.0}


def test_a_move_during_a_ramp_starts_where_the_stick_is():
    s = StickScript(({"t": 0, "roll": 1.0, "ramp": 1.0}, {"t": 0.5, "roll": 0.0, "ramp": 1.0}))
    assert s.sticks(0.5)["roll"] == pytest.approx(0.5)
    assert s.sticks(1.0)["roll"] == pytest.approx(0.25)
    assert s.sticks(1.5)["roll"] == pytest.approx(0.0)


def test_channels_as_a_receiver_gives_them():
    s = StickScript(({"t": 0, "mode": "loiter", "throttle": 0.5, "ramp": 0},
                     {"t": 1, "roll": 0.4, "pitch": 0.4, "yaw": -0.3, "ramp": 0}))
    ch = s.channels(2.0, P)
    assert list(ch[:5]) == [1700, 1300, 1500, 1350, 1685]  # pitch forward: low PWM
    assert list(ch[5:]) == [1000, 1000, 1800]  # the other channels: SITL's idle values
    assert mode_pwm("STABILIZE", P) == 1815 and mode_pwm("AUTO", P) == 1555
    with pytest.raises(StickScriptError, match="no mode switch position is POSHOLD"):
        mode_pwm("POSHOLD", P)
    ch6 = s.channels(2.0, {**P, "FLTMODE_CH": 6.0})
    assert ch6[4] == 1800 and ch6[5] == 1685
    assert list(StickScript(({"t": 0, "roll": 0.2},)).channels(1.0, P)[4:]) == [
        1800, 1000, 1000, 1800]  # no mode set: the switch stays where SITL's idle input has it


def test_sticks_follow_each_channels_range():
    """A vehicle whose throttle channel spans 1000-1900 and whose roll trim is 1520: mid
    throttle is 1450 (its mid-stick), a centred roll its trim, full roll its RC1_MAX."""
    from tlm_sim.mission.sticks import stick_pwm

    params = {**P, "RC3_MAX": 1900.0, "RC1_TRIM": 1520.0, "RC1_MAX": 1940.0}
    assert stick_pwm("throttle", 0.5, params) == 1450.0
    assert stick_pwm("roll", 0.0, params) == 1520.0 and stick_pwm("roll", 1.0, params) == 1940
    assert stick_pwm("roll", -1.0, params) == 1000.0
    assert stick_pwm("pitch", 1.0, params) == 1000.0  # forward is low PWM
    s = StickScript(({"t": 0, "throttle": 0.5, "roll": 0.0, "ramp": 0},))
    assert list(s.table(params, 0.1)[0, 1:4]) == [1520.0, 1500.0, 1450.0]


def test_ground_station_mode_rows():
    s = StickScript(({"t": 0, "mode": "LOITER"}, {"t": 30, "gcs_mode": "rtl"},
                     {"t": 40.5, "gcs_mode": "LAND", "roll": 0.1}))
    assert s.gcs_modes().tolist() == [[30.0, 6.0], [40.5, 9.0]]
    assert s.mode(35.0) == "LOITER"  # the switch stays where it is
    with pytest.raises(StickScriptError, match="unknown flight mode"):
        StickScript(({"t": 0, "gcs_mode": "HOVER"},))


def test_table_at_the_receivers_rate():
    s = StickScript(({"t": 1, "yaw": 1.0, "ramp": 0},))
    tab = s.table(P, 2.0)
    assert tab.shape == (101, 9)
    assert tab[49, 4] == 1500 and tab[50, 4] == 2000


@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.fixed_dictionaries(
    {"t": st.floats(0, 500)},
    optional={"roll": st.floats(-1, 1), "pitch": st.floats(-1, 1), "throttle": st.floats(0, 1),
              "yaw": st.floats(-1, 1), "ramp": st.floats(0, 5),
              "mode": st.sampled_from(["LOITER", "AUTO", "RTL", "STABILIZE"])}),
    min_size=1, max_size=12), t=st.floats(0, 600))
def test_any_script_round_trips_and_stays_in_range(rows, t):
    rows = sorted((r for r in rows if set(r) - {"t", "ramp"}), key=lambda r: r["t"])
    if not rows:
        return
    s = StickScript(tuple(rows))
    assert StickScript.from_dict(json.loads(json.dumps(s.to_dict()))) == s
    ch = s.channels(t, P)
    assert ((ch >= 1000) & (ch <= 2000)).all()
    # the 50 Hz table (all rows at once) is channels() row by row, exactly
    tab = s.table(P, min(t, 60.0))
    assert np.array_equal(tab[:, 1:], np.array([s.channels(x, P) for x in tab[:, 0]]))


def test_files(tmp_path):
    y = tmp_path / "s.yaml"
    y.write_text("sticks:\n  - {t: 0, mode: LOITER}\n  - {t: 60, pitch: 0.4}\n")
    c = tmp_path / "s.csv"
    c.write_text("t,pitch,mode\n0,,LOITER\n60,0.4,\n")
    j = tmp_path / "s.json"
    j.write_text(json.dumps({"sticks": [{"t": 0, "mode": "loiter"}, {"t": 60, "pitch": 0.4}]}))
    a, b, d = (StickScript.from_file(p) for p in (y, c, j))
    assert a == b == d


@pytest.mark.parametrize("rows,msg", [
    ([], "at least one row"),
    ([{"t": 5, "pitch": 2}], "row 0: pitch 2 is outside -1..1"),
    ([{"t": 5, "pitch": 0.1}, {"t": 4, "roll": 0.1}], "row 1: t 4 s is before"),
    ([{"t": 5, "throttle": -0.1}], "throttle -0.1 is outside 0..1"),
    ([{"t": 5, "mode": "HOVER"}], "unknown flight mode 'HOVER'"),
    ([{"t": 5, "pich": 0.1}], "unknown key 'pich'"),
    ([{"pitch": 0.1}], "missing 't'"),
    ([{"t": 5}], "sets nothing"),
    ([{"t": 5, "roll": True}], "roll must be a finite number"),
    ([{"t": 5, "roll": 0.1, "ramp": -1}], "ramp must be >= 0"),
])
def test_bad_scripts_say_which_row(rows, msg):
    with pytest.raises(StickScriptError, match=msg):
        StickScript(tuple(rows))


def test_bad_files_say_why(tmp_path):
    p = tmp_path / "s.txt"
    p.write_text("x")
    with pytest.raises(StickScriptError, match=r"\.yaml, \.yml, \.json or \.csv"):
        StickScript.from_file(p)
    c = tmp_path / "s.csv"
    c.write_text("time,pitch\n0,0.1\n")
    with pytest.raises(StickScriptError, match="header with a 't' column"):
        StickScript.from_file(c)
    y = tmp_path / "s.yaml"
    y.write_text("sticks: [ {t: 0, pitch: 0.1\n")
    with pytest.raises(StickScriptError, match="not valid YAML"):
        StickScript.from_file(y)


@pytest.mark.parametrize("name", ["manual_loiter_s90", "manual_stabilize_s93"])
def test_the_reference_pilots_script_gives_its_pwm(name):
    """The reference flights' stick script as a tlm script: at every segment's middle the
    rendered C1, C2, C4 are the PWM the sidecar says the driver sent and RCIN logged."""
    side = json.loads(reference_path(f"pilot/{name}.json").read_text())
    rows = []
    for seg in side["stick_script"]:
        st_ = seg["sticks"]
        rows.append({"t": seg["start_time_us"] * 1e-6, "roll": st_["roll"],
                     "pitch": st_["pitch"], "yaw": st_["yaw"], "ramp": seg["ramp_s"]})
    s = StickScript(tuple(rows))
    for seg in side["stick_script"]:
        mid = 0.5 * (seg["start_time_us"] + seg["end_time_us"]) * 1e-6
        ch = s.channels(mid, P)
        for c in ("C1", "C2", "C4"):
            assert ch[int(c[1]) - 1] == seg["pwm"][c] == seg["rcin"][c]["median"], (seg["name"], c)
