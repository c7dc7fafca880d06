"""Whole-flight behaviour: missions completed, RTL landing, determinism, log rates, EKF accuracy."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from tests.conftest import flown
from tlm_sim import Params, fly
from tlm_sim.flightlog import SCHEMAS
from tlm_sim.geo import latlon_to_ne
from tlm_sim.mission import builtin_mission


def _truth_ne(log):
    sim = log.tables["SIM"]
    home = log.mission.home
    n, e = latlon_to_ne(sim["Lat"].to_numpy(float), sim["Lng"].to_numpy(float), home[0], home[1])
    return n, e, sim["Alt"].to_numpy(float) - home[2]


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_mission_completed_within_wpnav_radius(k):
    log = flown(k)
    m = builtin_mission(k)
    assert log.meta["waypoints_reached"] == m.n_waypoints
    n, e, alt = _truth_ne(log)
    wp = m.ned()
    radius = Params()["WPNAV_RADIUS"] / 100.0
    # SIM is logged at 10 Hz (~0.35 m apart at cruise): distance from each waypoint to the path
    d = np.sqrt((n[None, :] - wp[:, 0:1]) ** 2 + (e[None, :] - wp[:, 1:2]) ** 2
                + (alt[None, :] + wp[:, 2:3]) ** 2)
    closest = d.min(axis=1)
    assert closest.max() <= radius, f"waypoint {closest.argmax()} missed by {closest.max():.2f} m"


@pytest.mark.parametrize("k", [1, 2, 3, 4])
def test_rtl_lands_at_home_and_disarms(k):
    log = flown(k)
    assert log.meta["landed"] and log.meta["disarmed_s"] is not None
    n, e, alt = _truth_ne(log)
    assert math.hypot(n[-1], e[-1]) < 2.0
    assert abs(alt[-1]) < 0.2
    ev = log.tables["EV"]["Id"].tolist()
    assert ev[-2:] == [18, 11]  # LAND_COMPLETE then DISARMED
    assert ev[:2] == [25, 10]  # SET_HOME (with the EKF origin), ARMED
    modes = log.tables["MODE"]["Mode"].tolist()
    assert modes == [0, 4, 3]  # STABILIZE at boot, GUIDED takeoff, AUTO (RTL is AUTO's last item)


def test_same_seed_identical_tables_different_seed_differs():
    a = flown(1, 0)
    b = fly(1, seed=0)
    for name, ta in a.tables.items():
        pd.testing.assert_frame_equal(ta, b.tables[name], check_exact=True)
    c = flown(1, 5)
    assert not a.tables["IMU"].equals(c.tables["IMU"])


def test_log_rates_match_ardupilot_defaults(normal_flight):
    log = normal_flight
    dur = log.meta["duration_s"]
    expect = {
        "GPS": 5,
        "IMU": 25 * 2,
        "RATE": 10,
        "VIBE": 10 * 2,
        "ATT": 10,
        "BARO": 20,
        "RCIN": 10,
        "XKF1": 20,
    }
    for name, hz in expect.items():
        assert len(log.tables[name]) / dur == pytest.approx(hz, rel=0.02), name
    imu = log.tables["IMU"]
    assert sorted(imu["I"].unique()) == [0, 1]
    assert set(imu.loc[imu.I == 1, "GHz"]) == {760} and set(imu.loc[imu.I == 1, "AHz"]) == {800}


def test_tables_have_ardupilot_columns(normal_flight):
    for name, t in normal_flight.tables.items():
        assert tuple(t.columns) == SCHEMAS[name].columns, name


def test_ekf_accuracy_on_a_clean_flight(normal_flight):
    """Primary-lane EKF against truth while armed: position < 1 m RMS, attitude < 1 deg RMS."""
    log = normal_flight
    pos = log.tables["POS"]
    sim = log.tables["SIM"]
    att = log.tables["ATT"]
    armed = (sim.TimeUS > log.meta["armed_s"] * 1e6 + 5e6) & (
        sim.TimeUS < log.meta["disarmed_s"] * 1e6
    )
    home = log.mission.home
    n1, e1 = latlon_to_ne(pos.Lat.to_numpy(float), pos.Lng.to_numpy(float), home[0], home[1])
    n2, e2 = latlon_to_ne(sim.Lat.to_numpy(float), sim.Lng.to_numpy(float), home[0], home[1])
    m = armed.to_numpy()
    err = np.sqrt((n1 - n2) ** 2 + (e1 - e2) ** 2 + (pos.Alt.to_numpy() - sim.Alt.to_numpy()) ** 2)
    assert np.sqrt(np.mean(err[m] ** 2)) < 1.0
    droll = att.Roll.to_numpy() - sim.Roll.to_numpy()
    dpitch = att.Pitch.to_numpy() - sim.Pitch.to_numpy()
    dyaw = (att.Yaw.to_numpy() - sim.Yaw.to_numpy() + 180.0) % 360.0 - 180.0
    rms = np.sqrt(np.mean((droll**2 + dpitch**2 + dyaw**2)[m]))
    assert rms < 1.0


def test_hover_throttle_and_speeds(normal_flight):
    """Cruise, climb and RTL speeds and hover throttle in the ranges the SITL logs show."""
    log = normal_flight
    gps = log.tables["GPS"]
    ctun = log.tables["CTUN"]
    auto_t = log.tables["MODE"].query("Mode == 3").TimeUS.iloc[0]
    cruise = gps[(gps.TimeUS > auto_t + 20e6) & (gps.TimeUS < auto_t + 300e6)]
    assert cruise.Spd.median() == pytest.approx(3.4, abs=0.3)
    assert gps.Spd.max() == pytest.approx(6.0, abs=0.3)  # RTL return at WPNAV_SPEED
    assert (-gps.VZ).max() == pytest.approx(2.5, abs=0.3)  # WPNAV_SPEED_UP on takeoff
    inflight = ctun[(ctun.TimeUS > auto_t) & (ctun.TimeUS < auto_t + 300e6)]
    assert 0.33 < inflight.ThO.median() < 0.42
    assert 0.36 < inflight.ThH.iloc[-1] < 0.41


def test_gps_fields(normal_flight):
    gps = normal_flight.tables["GPS"]
    assert set(gps.Status) == {6} and set(gps.NSats) == {10}
    assert np.allclose(gps.HDop, 1.21)
    assert gps.GWk.iloc[0] > 2000
    assert np.all(np.diff(gps.GMS) % 200 == 0)


def test_radio_failsafe_returns_home_and_lands():
    """SIM_RC_FAIL 1 at 120 s: ERR 2/2 and 5/1 after RC_FS_TIMEOUT (1 s), RTL (mode 6, reason 3),
    ERR 5/0 when RC returns at 150 s, stays in RTL, lands at home and disarms."""
    log = fly(3, faults=[(120.0, "SIM_RC_FAIL", 1), (150.0, "SIM_RC_FAIL", 0)], seed=2)
    err = log.tables["ERR"]
    fs = err[(err.Subsys == 5) & (err.ECode == 1)].TimeUS.iloc[0] * 1e-6
    assert 120.9 <= fs <= 121.2
    assert ((err.Subsys == 2) & (err.ECode == 2)).any()
    assert err[(err.Subsys == 5) & (err.ECode == 0)].TimeUS.iloc[0] * 1e-6 == pytest.approx(
        150.0, abs=0.1)
    mode = log.tables["MODE"]
    rtl = mode[mode.Mode == 6]
    assert len(rtl) == 1 and rtl.Rsn.iloc[0] == 3
    assert rtl.TimeUS.iloc[0] * 1e-6 == pytest.approx(fs, abs=0.01)
    assert mode.Mode.iloc[-1] == 6
    assert log.meta["landed"]
    n, e, _ = _truth_ne(log)
    assert math.hypot(n[-1], e[-1]) < 2.0
