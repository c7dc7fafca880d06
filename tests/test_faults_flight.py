"""Fault schedules in flight: triggers, Eq. 4 records, failsafes, profiles, satellite jitter.

The per-fault signatures against the reference SITL logs are in test_fault_signatures.py; this
file checks the machinery: that a schedule's boundaries take effect when they should, that the
records carry the SITL sidecar keys with sensible positions, and the failsafe behaviours that
the reference flights (FS_EKF_THRESH 0) do not exercise.
"""

from __future__ import annotations

import json
import math
from functools import cache

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_sim import fly
from tlm_sim.control import layout as C
from tlm_sim.control.config import build_control_config
from tlm_sim.control.failsafe import crash_check, vertical_cf_reset, vertical_cf_update
from tlm_sim.dynamics.frame import F_ENGINE_MASK, build_frame
from tlm_sim.faults import FaultSchedule
from tlm_sim.params import Params

SIDECAR_KEYS = {"type", "label", "start_time_us", "end_time_us", "start_lat", "start_lon",
                "start_alt", "end_lat", "end_lon", "end_alt", "params_start", "params_end"}


@cache
def _flight(specs: tuple[str, ...], seed: int = 4, profile: str = "current",
            params: tuple[tuple[str, float], ...] = ()):
    return fly(1, FaultSchedule.from_shorthand(list(specs)), dict(params), seed=seed,
               profile=profile)


def _window(df: pd.DataFrame, t0: float, t1: float) -> pd.DataFrame:
    return df[(df.TimeUS >= t0) & (df.TimeUS <= t1)]


# ------------------------------------------------------------------------------- records


def test_records_have_the_sidecar_keys_and_times_of_the_parameter_changes():
    log = _flight(("gps:wp8-wp12", "engine:150+20", "rc:220-250"))
    assert [r["type"] for r in log.faults] == ["gps", "engine", "rc"]
    assert [r["label"] for r in log.faults] == [1, 3, 4]
    changes = log.meta["param_changes"]
    for i, rec in enumerate(log.faults):
        assert SIDECAR_KEYS <= set(rec)
        assert rec["start_time_us"] < rec["end_time_us"]
        mine = [c for c in changes if c["fault"] == i]
        assert rec["start_time_us"] == min(c["time_us"] for c in mine if c["edge"] == "start")
        assert rec["end_time_us"] == max(c["time_us"] for c in mine if c["edge"] == "end")
    eng = log.faults[1]
    # timed boundaries land on the first physics tick at or after the requested time
    assert 0 <= eng["start_time_us"] - 150_000_000 < 1000
    assert eng["params_start"] == {"SIM_ENGINE_MUL": 0.0}
    # Eq. 4 position: the EKF estimate, metres above home; the truth alongside
    assert abs(eng["start_alt"] - eng["start_true_alt"]) < 1.0
    dn = (eng["start_lat"] - eng["start_true_lat"]) * 111_320.0
    assert abs(dn) < 5.0
    assert abs(eng["end_true_alt"]) < 0.5  # the engine fault ends with the copter on the ground
    assert json.loads(json.dumps(log.faults)) == log.faults  # JSON-ready


def test_waypoint_triggers_follow_the_mission_progress():
    log = _flight(("gps:wp8-wp12", "engine:150+20", "rc:220-250"))
    gps = log.tables["GPS"]
    rec = log.faults[0]
    assert rec["start"] == "wp8" and rec["end"] == "wp12"
    inside = _window(gps, rec["start_time_us"] + 1, rec["end_time_us"])
    before = gps[gps.TimeUS < rec["start_time_us"]]
    after = _window(gps, rec["end_time_us"] + 250_000, rec["end_time_us"] + 30e6)
    assert len(inside) > 10 and (inside.Status < 3).all() and (inside.NSats == 3).all()
    assert (before.Status >= 3).all() and (after.Status >= 3).all()
    # the vehicle reached waypoint 8 between arming and the fault: at 3.4 m/s on ~13 m legs
    # that takes 30-60 s of AUTO
    mode = log.tables["MODE"]
    auto_t = float(mode[mode.Mode == 3].TimeUS.iloc[0])
    assert 20e6 < rec["start_time_us"] - auto_t < 60e6


def test_flight_with_a_schedule_is_deterministic():
    a = fly(1, FaultSchedule.from_shorthand(["accel:60+10"]), seed=9)
    b = fly(1, FaultSchedule.from_shorthand(["accel:60+10"]), seed=9)
    assert a.faults == b.faults
    pd.testing.assert_frame_equal(a.tables["SIM"], b.tables["SIM"])


def test_a_fault_still_running_at_the_end_is_closed_by_the_log():
    log = _flight(("rc:100",))
    (rec,) = log.faults
    assert rec["end"] is None and rec["end_by"] == "flight end"
    assert rec["end_time_us"] == int(log.tables["SIM"].TimeUS.iloc[-1]) or (
        rec["end_time_us"] >= int(log.tables["SIM"].TimeUS.iloc[-1]))
    assert log.meta["landed"]


def test_the_same_reader_reads_tlm_and_sitl_records():
    side = json.loads(reference_path("gps_s12.json").read_text())
    log = _flight(("gps:wp8-wp12", "engine:150+20", "rc:220-250"))
    for rec in (side["faults"][0], log.faults[0]):
        assert SIDECAR_KEYS <= set(rec)
        assert isinstance(rec["start_time_us"], int) and rec["label"] == 1
        assert rec["params_start"].keys() == {"SIM_GPS1_ENABLE"}


# ------------------------------------------------------------------------------- failsafes


def test_gps_loss_with_the_default_ekf_threshold_lands():
    """FS_EKF_THRESH 0.8 (ArduCopter's default): position invalid 7 s after the loss, EKF
    failsafe ~1 s later (ERR 16/2, 17/1), LAND with reason 6, pause, descend, disarm."""
    log = _flight(("gps:100",), params=(("FS_EKF_THRESH", 0.8),))
    t0 = log.faults[0]["start_time_us"]
    mode = log.tables["MODE"]
    land = mode[(mode.Mode == 9)]
    assert len(land) == 1 and int(land.Rsn.iloc[0]) == 6
    assert 7.5e6 <= float(land.TimeUS.iloc[0]) - t0 <= 9.5e6
    err = {(int(r.Subsys), int(r.ECode)) for r in log.tables["ERR"].itertuples()}
    assert {(16, 2), (17, 1)} <= err
    assert log.meta["landed"] and log.meta["final_mode"] == 9
    sim = log.tables["SIM"]
    t_land = float(land.TimeUS.iloc[0])
    hold = _window(sim, t_land + 0.5e6, t_land + 3.5e6)
    assert hold.Alt.max() - hold.Alt.min() < 1.5  # the 4 s pause holds the height


def test_gps_loss_with_the_check_off_stays_in_auto():
    log = _flight(("gps:100-140",))
    mode = log.tables["MODE"]
    assert not (mode.Mode == 9).any()
    assert not ((mode.TimeUS > 100e6) & (mode.TimeUS < 140e6)).any()


def test_double_accel_fault_turns_vibration_compensation_on_and_off():
    log = _flight(("accel:100+30",))
    err = log.tables["ERR"]
    vibe = err[err.Subsys == 29]
    assert list(vibe.ECode) == [1, 0]
    t_on = float(vibe.TimeUS.iloc[0]) - 100e6
    # EKF3's bad-IMU response starts with the GPS sample after its first detection (~1.2 s in),
    # the vibration check needs 1 s of it (SITL: 2.25 and 2.28 s)
    assert 1.8e6 <= t_on <= 2.8e6
    assert float(vibe.TimeUS.iloc[1]) > 130e6 + 15e6  # off 15 s after the EKF recovers
    # full throttle until the response reaches the EKF output: a 14-20 m climb in 3 s (SITL
    # 17.8 and 18.3 m), then bounded while the fault lasts (no runaway climb)
    sim = log.tables["SIM"]
    z0 = float(_window(sim, 99e6, 100e6).Alt.mean())
    assert 14.0 <= _window(sim, 100e6, 103e6).Alt.max() - z0 <= 20.0
    assert _window(sim, 100e6, 130e6).Alt.max() - z0 < 22.0


def test_engine_fault_ekf_is_level_again_soon_after_the_impact():
    log = _flight(("engine:100-120",))
    sim = log.tables["SIM"]
    home = float(sim.Alt.iloc[0])
    ground = _window(sim, 100e6, 120e6)
    t_hit = float(ground[ground.Alt <= home + 0.3].TimeUS.iloc[0])
    att = log.tables["ATT"]
    settled = _window(att, t_hit + 1.5e6, t_hit + 2.0e6)
    assert len(settled) and (np.hypot(settled.Roll, settled.Pitch) < 20.0).any()
    err = {(int(r.Subsys), int(r.ECode)) for r in log.tables["ERR"].itertuples()}
    assert (12, 1) not in err  # no crash-check disarm: the ground contact levels the frame
    up = _window(sim, 120e6, 125e6)
    assert (up.Alt > home + 1.0).any()


# ------------------------------------------------------------------------------- profiles


def test_paper_profile_reads_sim_engine_fail_as_a_motor_index():
    cur = build_frame(Params({"SIM_ENGINE_FAIL": 1}))
    assert cur[F_ENGINE_MASK] == 1.0  # current: bit mask, bit 0 = motor 1
    for index, mask in ((0, 1.0), (1, 2.0), (3, 8.0)):
        cfg = build_frame(Params({"TLM_PROFILE": 1, "SIM_ENGINE_FAIL": index}))
        assert cfg[F_ENGINE_MASK] == mask


def test_paper_profile_rc_timeout_and_satellite_jitter():
    log = _flight(("gps:60-90", "rc:150-170"), profile="paper")
    assert log.meta["profile"] == "paper"
    rc = log.faults[1]
    mode = log.tables["MODE"]
    rtl = mode[mode.Mode == 6]
    assert 0.45e6 <= float(rtl.TimeUS.iloc[0]) - rc["start_time_us"] <= 0.6e6  # 0.5 s then
    gps = log.tables["GPS"]
    fault = gps[gps.Status < 3]
    normal = gps[gps.Status >= 3]
    assert fault.NSats.between(3, 10).all() and fault.NSats.nunique() > 3
    assert normal.NSats.between(8, 20).all() and normal.NSats.nunique() > 5


def test_current_profile_keeps_sitl_satellite_counts():
    log = _flight(("gps:60-90", "rc:150-170"))
    gps = log.tables["GPS"]
    assert set(gps.NSats.unique()) == {3, 10}


# ------------------------------------------------------------------------------- units


def test_height_rate_filter_absorbs_a_constant_accelerometer_error():
    """At rest with a 3 m/s^2 accelerometer error, the third-order filter's rate settles at 0
    and its acceleration state learns -3 m/s^2 (the filter follows the EKF height)."""
    g = build_control_config(Params())
    c = np.zeros(C.N_CONTROL_STATE)
    vertical_cf_reset(c, -20.0, 0.0)
    for _ in range(4000):  # 10 s at 400 Hz
        vertical_cf_update(c, g, -20.0, 3.0, 0.0025)
    assert abs(c[C.VCF_VEL]) < 1e-3
    assert c[C.VCF_ACC] == pytest.approx(-3.0, abs=1e-3)
    assert c[C.VCF_POS] == pytest.approx(-20.0, abs=1e-3)


def test_height_rate_filter_tracks_a_steady_climb():
    g = build_control_config(Params())
    c = np.zeros(C.N_CONTROL_STATE)
    dt = 0.0025
    for k in range(4000):
        vertical_cf_update(c, g, -2.0 * k * dt, 0.0, dt)  # climbing 2 m/s, no accel info
    assert c[C.VCF_VEL] == pytest.approx(-2.0, abs=1e-2)


def test_crash_check_needs_two_seconds_of_all_conditions():
    g = build_control_config(Params())
    c = np.zeros(C.N_CONTROL_STATE)
    lean = math.radians(40.0)
    cos_tilt = math.cos(lean)
    c[C.ATT_ROLL_CMD] = 0.0
    fired = [crash_check(c, g, 0.0025, cos_tilt, lean, 0.0, 0.0) for _ in range(820)]
    assert 798 <= fired.index(True) <= 802  # 2 s at 400 Hz
    c[C.CRASH_TIMER] = 0.0
    c[C.ALP + 2] = 5.0  # still accelerating (falling): |a_lp| >= 3 m/s^2
    assert not any(crash_check(c, g, 0.0025, cos_tilt, lean, 0.0, 0.0) for _ in range(900))
    c[C.ALP + 2] = 0.0
    c[C.LANDED] = 1.0
    assert not any(crash_check(c, g, 0.0025, cos_tilt, lean, 0.0, 0.0) for _ in range(900))
    c[C.LANDED] = 0.0
    assert not any(crash_check(c, g, 0.0025, cos_tilt, lean, 0.0, 12.0) for _ in range(900))


def test_gps_loss_constant_position_mode_flies_away_and_back():
    """ArduCopter with FS_EKF_THRESH 0 after 15 s without GPS (gps_s12.bin, combined_s21.bin):
    EKF3 stops aiding, the AHRS has no position and AC_PosControl's estimate is the origin
    (PSCN.PN = PSCE.PE = 0), the target is held at error_max (8.45 m) from it towards the
    frozen path point, the velocity target never reached by the EKF's velocity keeps the lean
    at ANGLE_MAX (30 deg); when GPS returns the estimate jumps to the GPS position and the
    vehicle flies back to its path at WPNAV_SPEED plus the held feed-forward."""
    log = _flight(("gps:100-140",))
    rec = log.faults[0]
    t0, t1 = rec["start_time_us"], rec["end_time_us"]
    pn, pe, att = log.tables["PSCN"], log.tables["PSCE"], log.tables["ATT"]
    lost = _window(pn, t0 + 15.5e6, t1 - 0.5e6)
    assert len(lost) > 200 and (lost.PN == 0.0).all()
    assert (_window(pe, t0 + 15.5e6, t1 - 0.5e6).PE == 0.0).all()
    assert (_window(pn, t0, t0 + 14.5e6).PN != 0.0).all()  # dead reckoning before that
    tgt = np.hypot(lost.TPN.to_numpy(), _window(pe, t0 + 15.5e6, t1 - 0.5e6).TPE.to_numpy())
    np.testing.assert_allclose(tgt, 8.45, atol=0.01)
    a = _window(att, t0 + 18e6, t1)
    lean = np.degrees(np.arccos(np.cos(np.radians(a.DesPitch)) * np.cos(np.radians(a.DesRoll))))
    assert np.mean(np.abs(lean - 30.0) < 1.0) > 0.75
    # GPS back: the estimate is the vehicle's position again, the target 8.45 m from it
    back = _window(pn, t1 + 1e6, t1 + 3e6)
    assert (np.abs(back.PN) > 10.0).all()
    # ... and the vehicle returns to its path: a minute later it flies the mission at cruise speed
    gps = log.tables["GPS"]
    cruise = _window(gps, t0 - 20e6, t0 - 10e6).Spd.mean()
    assert _window(gps, t1 + 60e6, t1 + 70e6).Spd.mean() == pytest.approx(cruise, abs=0.5)
