"""Mission items beyond plain waypoints, flown as ArduCopter 4.7's AUTO flies them: a
NAV_WAYPOINT's hold time (param1), NAV_LOITER_TIME, DO_CHANGE_SPEED and NAV_LAND; everything
else a WPL file asks that tlm does not fly is a one-line error (exit 2 from ``tlm fly``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tlm_process.cli import main
from tlm_sim import fly
from tlm_sim.flightlog.texts import mission_texts
from tlm_sim.geo import HOME_CMAC, ne_to_latlon
from tlm_sim.mission import Mission, MissionError, builtin_mission, read_wpl, write_wpl

WP, LOITER, RTL, LAND, TAKEOFF, SPEED = 16, 19, 20, 21, 22, 178
RADIUS_M = 1.5  # how close the copter holds its point (truth and EKF)


def _line(seq: int, cmd: int, n: float = 0.0, e: float = 0.0, alt: float = 20.0,
          p: tuple[float, ...] = (0, 0, 0, 0), frame: int = 3, here: bool = False) -> str:
    """One WPL line: a command at north/east n, e [m] from CMAC (lat = lon = 0 if ``here``)."""
    lat, lon = (0.0, 0.0) if here else ne_to_latlon(n, e, *HOME_CMAC[:2])
    pp = (tuple(p) + (0, 0, 0, 0))[:4]
    return "\t".join(str(v) for v in (seq, 0, frame, cmd, *pp, float(lat), float(lon), alt, 1))


def _wpl(tmp_path, *items: tuple, name: str = "m") -> str:
    """A WPL file: home, TAKEOFF to 20 m, then ``items`` (``_line`` arguments after seq)."""
    lat, lon, alt = HOME_CMAC
    lines = ["QGC WPL 110", f"0\t1\t0\t16\t0\t0\t0\t0\t{lat}\t{lon}\t{alt}\t1",
             _line(1, TAKEOFF, alt=20.0)]
    lines += [_line(k + 2, *it) for k, it in enumerate(items)]
    path = tmp_path / f"{name}.waypoints"
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def _mise(log) -> dict[int, float]:
    """Item number -> time [s] its MISE row says it started."""
    m = log.tables["MISE"]
    return dict(zip(m.CNum.astype(int), m.TimeUS * 1e-6, strict=True))


def _texts(log) -> dict[str, float]:
    return {text: t * 1e-6 for t, text in mission_texts(log.tables)}


def _truth(log):
    """(time [s], north, east [m], ground speed [m/s]) of the simulated copter (SIM2)."""
    s = log.tables["SIM2"]
    return (s.TimeUS.to_numpy() * 1e-6, s.PN.to_numpy(), s.PE.to_numpy(),
            np.hypot(s.VN.to_numpy(), s.VE.to_numpy()))


def _ekf(log):
    """(time [s], north, east [m]) of the primary EKF lane (XKF1 C 0)."""
    x = log.tables["XKF1"]
    x = x[x.C == 0]
    return x.TimeUS.to_numpy() * 1e-6, x.PN.to_numpy(), x.PE.to_numpy()


def _held(log, n, e, t0, t1) -> tuple[float, float]:
    """Largest horizontal distance [m] of the truth and of the EKF from (n, e) in [t0, t1]."""
    out = []
    for t, pn, pe, *_ in (_truth(log), _ekf(log)):
        k = (t >= t0) & (t <= t1)
        assert k.sum() > 5
        out.append(float(np.hypot(pn[k] - n, pe[k] - e).max()))
    return out[0], out[1]


# ------------------------------------------------------------------ holds: WAYPOINT, LOITER
def _hold_mission(tmp_path, hold_wp: float, hold_loiter: float, name: str) -> Mission:
    return read_wpl(_wpl(
        tmp_path,
        (WP, 60.0, 0.0),
        (WP, 60.0, 60.0, 20.0, (hold_wp,)),
        (LOITER, 0.0, 60.0, 25.0, (hold_loiter,)),
        (WP, 0.0, 0.0),
        (RTL, 0, 0, 0.0, (), 0),
        name=name))


@pytest.fixture(scope="module")
def holds(tmp_path_factory):
    """Two flights of one mission: holding 10 s at item 3 (a waypoint) and 6 s at item 4 (a
    loiter), and holding 1 s at both."""
    d = tmp_path_factory.mktemp("holds")
    long_ = _hold_mission(d, 10.0, 6.0, "long")
    short = _hold_mission(d, 1.0, 1.0, "short")
    return long_, fly(long_, seed=3), fly(short, seed=3)


def test_wpl_hold_times_reach_the_mission(holds):
    m = holds[0]
    assert m.nav_commands.tolist() == [WP, WP, LOITER, WP]
    assert m.holds.tolist() == [0.0, 10.0, 6.0, 0.0]
    assert m.stops().tolist() == [False, True, True, True]
    items = m.items()
    assert items[:, 0].tolist() == [WP, TAKEOFF, WP, WP, LOITER, WP, RTL]
    assert items[3, 1] == 10.0 and items[4, 1] == 6.0 and items[4, 3] == 1.0  # ccw flag: +1


def test_waypoint_hold_holds_there_then_goes_on(holds):
    m, log, short = holds
    n, e = m.ned()[1, :2]
    start, start_short = _mise(log), _mise(short)
    texts = _texts(log)
    # the next item starts, and "Reached command #3" is said, after the 10 s hold
    assert texts["Reached command #3"] == pytest.approx(start[4], abs=1e-6)
    assert texts["Mission: 4 LoitTime"] == pytest.approx(start[4], abs=1e-6)
    # both flights are the same until the copter has stopped there: the holds differ by 9 s
    assert start[3] == start_short[3]
    assert start[4] - start_short[4] == pytest.approx(9.0, abs=0.01)
    # the timer started when the waypoint was reached: held there for the 10 s before
    truth, ekf = _held(log, n, e, start[4] - 10.0, start[4])
    assert truth < RADIUS_M and ekf < RADIUS_M
    t, pn, pe, v = _truth(log)
    k = (t >= start[4] - 10.0) & (t <= start[4])
    assert v[k].max() < 0.5
    # ... and was on its way (more than WPNAV_RADIUS away) 4 s before that
    i = np.searchsorted(t, start[4] - 14.0)
    assert math.hypot(pn[i] - n, pe[i] - e) > 2.0
    # then it goes on: 5 s later it has left
    i = np.searchsorted(t, start[4] + 5.0)
    assert math.hypot(pn[i] - n, pe[i] - e) > 3.0


def test_loiter_time_holds_there_then_goes_on(holds):
    m, log, short = holds
    n, e = m.ned()[2, :2]
    start, start_short = _mise(log), _mise(short)
    texts = _texts(log)
    assert texts["Reached command #4"] == pytest.approx(start[5], abs=1e-6)
    truth, ekf = _held(log, n, e, start[5] - 6.0, start[5])
    assert truth < RADIUS_M and ekf < RADIUS_M
    # flown later by the first hold's 9 s, held 5 s longer
    assert start[5] - start_short[5] == pytest.approx(9.0 + 5.0, abs=0.5)
    # the loiter's altitude (25 m) is held too
    ctun = log.tables["CTUN"]
    k = (ctun.TimeUS * 1e-6 >= start[5] - 6.0) & (ctun.TimeUS * 1e-6 <= start[5])
    assert np.abs(ctun.Alt[k] - 25.0).max() < 0.5
    assert log.meta["end_reason"] == "landed" and log.meta["waypoints_reached"] == 4


# ---------------------------------------------------------------------------- change speed
@pytest.fixture(scope="module")
def speeds(tmp_path_factory):
    """Three 200 m legs: WPNAV_SPEED (6 m/s), then DO_CHANGE_SPEED 2.5 m/s (ground speed),
    then 9 m/s (airspeed)."""
    d = tmp_path_factory.mktemp("speeds")
    m = read_wpl(_wpl(
        d,
        (WP, 0.0, 0.0),
        (WP, 200.0, 0.0),
        (SPEED, 0, 0, 0.0, (1, 2.5, -1), 2),
        (WP, 200.0, 200.0),
        (SPEED, 0, 0, 0.0, (0, 9.0), 2),
        (WP, 0.0, 200.0),
        (RTL, 0, 0, 0.0, (), 0)))
    return m, fly(m, seed=5)


def _cruise(log, a, b) -> float:
    """Median ground speed [m/s] over the middle half of the leg from a to b (NE, m)."""
    t, pn, pe, v = _truth(log)
    a, b = np.asarray(a, float), np.asarray(b, float)
    u = (b - a) / np.linalg.norm(b - a)
    along = (pn - a[0]) * u[0] + (pe - a[1]) * u[1]
    across = np.abs(-(pn - a[0]) * u[1] + (pe - a[1]) * u[0])
    length = float(np.linalg.norm(b - a))
    k = (along > 0.25 * length) & (along < 0.75 * length) & (across < 5.0)
    assert k.sum() > 50
    return float(np.median(v[k]))


def test_change_speed_sets_the_following_legs_cruise(speeds):
    m, log = speeds
    assert np.isnan(m.speed_changes[[0, 1]]).all()
    assert m.speed_changes[2] == 2.5 and m.speed_changes[3] == 9.0
    assert m.leg_speeds()[2:].tolist() == [2.5, 9.0]
    assert m.item_numbers().tolist() == [2, 3, 5, 7]
    assert _cruise(log, (0, 0), (200, 0)) == pytest.approx(6.0, rel=0.03)  # WPNAV_SPEED
    assert _cruise(log, (200, 0), (200, 200)) == pytest.approx(2.5, rel=0.03)
    assert _cruise(log, (200, 200), (0, 200)) == pytest.approx(9.0, rel=0.03)
    # the return flies at RTL_SPEED (0: WPNAV_SPEED), as ArduCopter's RTL re-inits its speed
    assert _cruise(log, (0, 200), (0, 0)) == pytest.approx(6.0, rel=0.03)
    # the DO items are logged and announced as they start, with the next waypoint
    mise, texts = log.tables["MISE"], _texts(log)
    assert mise.CId.tolist() == [TAKEOFF, WP, WP, SPEED, WP, SPEED, WP, RTL]
    row = mise[mise.CNum == 4].iloc[0]
    assert (row.Prm1, row.Prm2, row.Frame) == (1.0, 2.5, 0)
    assert texts["Reached command #3"] == texts["Mission: 4 ChangeSpeed"] == (
        texts["Mission: 5 WP"])
    cmd = log.mission.items()
    assert cmd[6, 0] == SPEED and cmd[6, 2] == 9.0 and cmd[6, 1] == 1  # (written as ground)


# -------------------------------------------------------------------------------------- LAND
@pytest.fixture(scope="module", params=["there", "here"])
def landing(request, tmp_path_factory):
    """A LAND at its own location (40 m east of the last waypoint), or at lat = lon = 0 (where
    the copter is: the last waypoint)."""
    d = tmp_path_factory.mktemp("land")
    here = request.param == "here"
    m = read_wpl(_wpl(d, (WP, 0.0, 0.0), (WP, 50.0, 0.0, 15.0),
                      (LAND, 50.0, 40.0, 0.0, (), 3, here)))
    return request.param, m, fly(m, seed=2)


def test_land_lands_there_and_disarms(landing):
    kind, m, log = landing
    assert m.lands and m.nav_commands[-1] == LAND and m.waypoints[-1, 2] == 0.0
    n, e = m.ned()[-1, :2]
    assert (n, e) == pytest.approx((50.0, 0.0 if kind == "here" else 40.0), abs=1e-6)
    assert log.meta["end_reason"] == "landed" and log.meta["landed"]
    assert log.meta["final_mode"] == 3  # still AUTO: the mission's own landing
    arm = log.tables["ARM"]
    assert arm.ArmState.iloc[-1] == 0 and arm.Method.iloc[-1] == 13  # LANDED, not MISSIONEXIT
    t, pn, pe, v = _truth(log)
    assert math.hypot(pn[-1] - n, pe[-1] - e) < RADIUS_M
    sim2 = log.tables["SIM2"]
    assert abs(sim2.PD.iloc[-1]) < 0.3  # on the ground
    mise = log.tables["MISE"]
    assert mise.CId.tolist() == [TAKEOFF, WP, WP, LAND]  # no RTL
    texts = _texts(log)
    assert "Mission: 4 Land" in texts and not any(x.startswith("Reached command #4")
                                                  for x in texts)
    if kind == "there":  # it flew to the landing point at the altitude it came from (15 m)
        ctun = log.tables["CTUN"]
        t = ctun.TimeUS * 1e-6
        k = (t > texts["Mission: 4 Land"]) & (t < texts["Mission: 4 Land"] + 3.0)
        assert np.abs(ctun.Alt[k] - 15.0).max() < 0.6


# ---------------------------------------------------------------------- the Mission API
def test_mission_item_arrays_validated_and_kept():
    base = builtin_mission(1)
    wp = base.waypoints[:6]
    m = Mission(wp, hold_s=[0, 5, 0, 0, 0, 0], speed_changes=[np.nan, 3.0] + [np.nan] * 4,
                commands=[16, 16, 19, 16, 16, 16])
    assert m.has_items and not m.lands
    # only defaults: the same as no arrays at all
    plain = Mission(wp, hold_s=np.zeros(6), speed_changes=np.full(6, np.nan),
                    commands=np.full(6, 16))
    assert plain == Mission(wp) and not plain.has_items and plain.hold_s is None
    assert Mission.from_dict(m.to_json()) == m
    with pytest.raises(MissionError, match="waypoint 1 has hold time 2.5 s: ArduCopter holds "
                                           "whole seconds"):
        Mission(wp, hold_s=[0, 2.5, 0, 0, 0, 0])
    with pytest.raises(MissionError, match="waypoint 2 has command 17"):
        Mission(wp, commands=[16, 16, 17, 16, 16, 16])
    with pytest.raises(MissionError, match="waypoint 2 is a NAV_LAND but not the last row"):
        Mission(wp, commands=[16, 16, 21, 16, 16, 16])
    with pytest.raises(MissionError,
                       match="waypoint 5 is a NAV_LAND at [0-9.]+ m: a landing point's altitude"):
        Mission(wp, commands=[16] * 5 + [21])
    with pytest.raises(MissionError, match="speed change before waypoint 3 is 0.05 m/s"):
        Mission(wp, speed_changes=[np.nan] * 3 + [0.05, np.nan, np.nan])
    with pytest.raises(MissionError, match=r"hold_s must have shape \(6,\)"):
        Mission(wp, hold_s=[1, 2])


def test_write_wpl_round_trips_the_items(tmp_path, holds, speeds):
    for m in (holds[0], speeds[0]):
        back = read_wpl(write_wpl(m, tmp_path / "x.waypoints"), name=m.name)
        assert back == m
    wp = builtin_mission(1).waypoints[:4].copy()
    wp[-1, 2] = 0.0
    m = Mission(wp, commands=[16, 16, 16, 21], hold_s=[0, 3, 0, 0])
    p = write_wpl(m, tmp_path / "land.waypoints")
    rows = [r.split("\t") for r in p.read_text().splitlines()[1:]]
    assert [r[3] for r in rows] == ["16", "22", "16", "16", "16", "21"]  # no RTL after LAND
    assert rows[3][4] == "3"
    assert read_wpl(p, name=m.name) == m
    wp2 = builtin_mission(1).waypoints[:3].copy()
    wp2[1, 2] = 0.0
    with pytest.raises(MissionError, match="waypoint 1 is at altitude 0"):
        write_wpl(Mission(wp2), tmp_path / "zero.waypoints")


def test_zero_position_and_altitude_mean_where_the_copter_is(tmp_path):
    m = read_wpl(_wpl(tmp_path, (WP, 30.0, 0.0, 18.0), (WP, 0, 0, 0.0, (4,), 3, True),
                      (LOITER, 30.0, 30.0, 0.0, (2,)), (RTL, 0, 0, 0.0, (), 0)))
    ned = m.ned()
    assert ned[1] == pytest.approx(ned[0])  # lat = lon = 0 and alt 0: where it was
    assert ned[2, :2] == pytest.approx([30.0, 30.0], abs=1e-6) and ned[2, 2] == ned[0, 2]


# ------------------------------------------------------------------------ refused items
@pytest.mark.parametrize(
    ("item", "needle"),
    [
        ((WP, 10, 0, 20, (0, 2)), "NAV_WAYPOINT param2 (acceptance radius) is 2: tlm does not "
                                  "fly it"),
        ((WP, 10, 0, 20, (0, 0, 1)), "NAV_WAYPOINT param3 (pass radius) is 1"),
        ((WP, 10, 0, 20, (0, 0, 0, 90)), "NAV_WAYPOINT param4 (yaw) is 90"),
        ((WP, 10, 0, 20, (2.5,)), "NAV_WAYPOINT param1 (hold time) is 2.5 s: ArduCopter holds "
                                  "whole seconds"),
        ((WP, 10, 0, 20, (-1,)), "param1 (hold time) is -1 s"),
        ((LOITER, 10, 0, 20, (5, 0, 10)), "NAV_LOITER_TIME param3 (radius) is 10"),
        ((LAND, 10, 0, 0, (0, 1)), "NAV_LAND param2 (precision land mode) is 1"),
        ((LAND, 10, 0, 5), "NAV_LAND altitude is 5 m: set it to 0"),
        ((SPEED, 0, 0, 0, (2, 3)), "DO_CHANGE_SPEED param1 (speed type) is 2 (climb speed)"),
        ((SPEED, 0, 0, 0, (1, 0.05)), "DO_CHANGE_SPEED param2 (speed) is 0.05 m/s"),
        ((SPEED, 0, 0, 0, (1, 5, 50)), "DO_CHANGE_SPEED param3 (throttle) is 50"),
        ((17, 10, 0, 20), "unsupported command 17 (tlm flies 16 NAV_WAYPOINT, 19 "
                          "NAV_LOITER_TIME, 20 NAV_RETURN_TO_LAUNCH, 21 NAV_LAND, 22 "
                          "NAV_TAKEOFF, 178 DO_CHANGE_SPEED)"),
    ],
)
def test_refused_items_are_one_line_errors(tmp_path, capsys, item, needle):
    path = _wpl(tmp_path, (WP, 0.0, 0.0), item, (WP, 20.0, 0.0))
    with pytest.raises(MissionError) as exc:
        read_wpl(path)
    assert str(exc.value).startswith(f"{path}:5: ") and needle in str(exc.value)
    assert main(["fly", "--mission-file", path, "--out", str(tmp_path / "o"), "--no-plot"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{path}:5: " in err and needle in err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize(
    ("items", "line", "needle"),
    [
        (((SPEED, 0, 0, 0, (1, 3)), (SPEED, 0, 0, 0, (1, 4)), (WP, 10, 0)), 5,
         "a second DO_CHANGE_SPEED (after line 4) before the same waypoint"),
        (((WP, 10, 0), (SPEED, 0, 0, 0, (1, 3)), (RTL, 0, 0, 0, (), 0)), 6,
         "ArduCopter's RTL flies at RTL_SPEED"),
        (((WP, 10, 0), (SPEED, 0, 0, 0, (1, 3))), 5, "DO_CHANGE_SPEED has no waypoint after it"),
        (((WP, 10, 0), (LAND, 10, 0, 0.0), (WP, 20, 0)), 6,
         "NAV_WAYPOINT item after LAND (line 5) is not supported"),
    ],
)
def test_refused_item_orders(tmp_path, items, line, needle):
    path = _wpl(tmp_path, *items)
    with pytest.raises(MissionError, match=None) as exc:
        read_wpl(path)
    assert f"{path}:{line}: " in str(exc.value) and needle in str(exc.value)


def test_speed_change_that_keeps_the_speed_changes_nothing(tmp_path):
    m = read_wpl(_wpl(tmp_path, (WP, 0.0, 0.0), (SPEED, 0, 0, 0, (1, -1)), (WP, 30.0, 0.0)))
    assert m.speed_changes is None and not m.has_items
