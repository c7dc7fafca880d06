"""Partial motor (label 9), battery (label 11), SIM_RC_FAIL 2 and SIM_SHOVE / SIM_TWIST.

Signatures: motor_partial_s47 and battery_s45 re-flown in tlm (each once) and measured the same
way as the SITL logs, within 35 % of SITL's numbers (times relative to the fault's start).
Behaviour: the battery failsafe's actions and latch, the throttle failsafe against
FS_THR_VALUE, and the one-shot shove and twist.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path
from tlm_process.fault_metrics import Flight
from tlm_process.reference import time_window
from tlm_sim.flightlog.texts import event_texts

TOL = 0.35


def _close(tlm: float, sitl: float, tol: float = TOL) -> bool:
    return abs(tlm - sitl) <= tol * abs(sitl)


@lru_cache(maxsize=4)
def _pair(name: str):
    """(SITL tables, SITL t0, t1, tlm tables with MSG, tlm t0, t1) of a reference flight."""
    import tlm_sim
    from tlm_process.crosscheck.scenario import reconstruct
    from tlm_sim.flightlog import read_bin

    path = reference_path(f"{name}.bin")
    sc = reconstruct(path)
    sitl = read_bin(str(path), types=["MSG", "ERR", "EV", "MODE", "SIM", "CTUN", "RCOU", "IMU",
                                      "BAT"])
    f = sc.faults[0]
    log = tlm_sim.fly(sc.mission, sc.schedule, sc.params, seed=sc.seed)
    tl = dict(log.tables)
    tl["MSG"] = pd.DataFrame([{"TimeUS": t, "Message": m} for t, m in event_texts(tl)])
    return (sitl, float(f["start_time_us"]), float(f["end_time_us"]), tl,
            sc.to_tlm_us(f["start_time_us"]), sc.to_tlm_us(f["end_time_us"]))


def _msg_times(t, t0, text):
    m = t["MSG"]
    return [(r.TimeUS - t0) * 1e-6 for r in m.itertuples() if text in r.Message and r.TimeUS >= t0]


def _err_times(t, t0, t1, subsys, code):
    e = t["ERR"]
    e = e[(e.Subsys == subsys) & (e.ECode == code) & (e.TimeUS >= t0) & (e.TimeUS <= t1)]
    return [(x - t0) * 1e-6 for x in e.TimeUS]


# --- motor_partial_s47: motor 1 x 0.5 --------------------------------------------------------


def _motor(t, t0, t1):
    f = Flight(t)
    sel = f.sel(t0, t1)
    tt, h = f.sim_t[sel], f.h[sel]
    ground = np.flatnonzero(h <= 0.5)
    after = f.sel(t1, t1 + 30e6)
    ta, ha = f.sim_t[after], f.h[after]
    rc = time_window(t["RCOU"], t0, t1)
    roll = time_window(t["SIM"], t0, t0 + 3e6)
    rs = (roll.TimeUS.to_numpy() - t0) * 1e-6
    # on the ground after the last touchdown (SITL: the bounce at +8 s), until the clear
    t_down = tt[np.flatnonzero(h > 0.3)[-1] + 1]
    imu = time_window(t["IMU"], t_down + 1e6, t1)
    imu = imu[imu.I == 0]
    return {
        "roll_peak": float(roll.Roll.abs()[rs <= 1.0].max()),
        "roll_after": float(roll.Roll.abs()[rs >= 1.0].mean()),
        "down_s": (t_down - t0) * 1e-6,
        "ground_accz_std": float(imu.AccZ.std()),
        "ground_gyr_p95": float(np.percentile(imu[["GyrX", "GyrY", "GyrZ"]].abs().to_numpy(), 95)),
        "ground_hop_m": float(h[tt >= t_down + 1e6].max()),
        "err25": _err_times(t, t0, t1, 25, 1),
        "ground_s": (tt[ground[0]] - t0) * 1e-6,
        "sink_max": float((-np.diff(h) / np.diff(tt) * 1e6).max()),
        "liftoff_s": (ta[np.flatnonzero(ha > 1.0)[0]] - t1) * 1e-6,
        "above10_s": (ta[np.flatnonzero(ha > 10.0)[0]] - t1) * 1e-6,
        "tho": float(time_window(t["CTUN"], t0, t1).ThO.mean()),
        "rcou": [float(rc[f"C{i}"].mean()) for i in range(1, 5)],
        "armed_kept": 1.0 - f.disarmed_in(t0, t1),
        "auto_kept": f.mode_kept(3, t0, t1 + 30e6),
        "hit": _msg_times(t, t0, "SIM Hit ground"),
    }


@lru_cache(maxsize=1)
def _motor_pair():
    s, s0, s1, tl, t0, t1 = _pair("motor_partial_s47")
    return _motor(s, s0, s1), _motor(tl, t0, t1)


def test_partial_motor_comes_down_and_hits_the_ground_like_sitl():
    sitl, tlm = _motor_pair()
    assert _close(tlm["ground_s"], sitl["ground_s"])  # 5.45 vs 5.38 s
    assert _close(tlm["sink_max"], sitl["sink_max"])  # 5.43 vs 5.50 m/s
    assert tlm["hit"] and _close(tlm["hit"][0], sitl["hit"][0])  # SIM Hit ground
    assert tlm["armed_kept"] == sitl["armed_kept"] == 1.0  # the crash check does not disarm


def test_partial_motor_saturates_the_weak_motor_like_sitl():
    sitl, tlm = _motor_pair()
    assert _close(tlm["tho"], sitl["tho"])  # mean ThO 0.977 vs 0.976
    for r in (sitl["rcou"], tlm["rcou"]):
        assert r[0] >= 1850.0 and r[0] == max(r)  # motor 1 commanded near full output
    assert _close(np.mean(tlm["rcou"][1:]) - 1000.0, np.mean(sitl["rcou"][1:]) - 1000.0)


def test_partial_motor_relifts_after_the_clear_and_resumes_the_mission():
    sitl, tlm = _motor_pair()
    assert _close(tlm["liftoff_s"], sitl["liftoff_s"])  # 1.02 vs 0.96 s
    assert _close(tlm["above10_s"], sitl["above10_s"])  # 4.62 vs 4.56 s
    assert tlm["auto_kept"] == sitl["auto_kept"] == 1.0


def test_partial_motor_reports_thrust_loss_of_motor_one_twice():
    sitl, tlm = _motor_pair()
    assert len(tlm["err25"]) == len(sitl["err25"]) == 2
    _, _, _, tl, t0, _ = _pair("motor_partial_s47")
    assert _msg_times(tl, t0, "Potential Thrust Loss (1)") == pytest.approx(tlm["err25"],
                                                                           abs=1e-6)
    assert _close(tlm["err25"][1], sitl["err25"][1])  # 8.00 vs 7.92 s


def test_partial_motor_first_thrust_loss_time():
    sitl, tlm = _motor_pair()
    assert _close(tlm["err25"][0], sitl["err25"][0])  # 2.71 vs 2.86 s (was 4.05 s)


def test_partial_motor_rolls_and_recovers_like_sitl():
    """Right after the motor weakens the copter rolls towards it and the saturated mixer brings
    it back: the first peak and the lean of the next two seconds as SITL's (before the angle
    controller's acceleration limit, the body-frame feed-forward and the thrust direction
    about the target heading were ArduCopter's: 51 deg, held above 40 deg for 1.5 s)."""
    sitl, tlm = _motor_pair()
    assert _close(tlm["roll_peak"], sitl["roll_peak"])  # 36.7 vs 36.3 deg (was 51.5)
    assert _close(tlm["roll_after"], sitl["roll_after"])  # +1..+3 s: 17.9 vs 16.6 (39.4)


def test_partial_motor_copter_stays_still_on_the_ground_like_sitl():
    """After its last touchdown the copter sits still at full throttle until the motor is
    restored, as SITL's (it used to hop 0.3 m and roll to 95 deg)."""
    sitl, tlm = _motor_pair()
    assert _close(tlm["down_s"], sitl["down_s"])  # 7.95 vs 7.88 s
    for r in (sitl, tlm):
        assert r["ground_hop_m"] < 0.05
        assert r["ground_accz_std"] < 0.05  # 0.009 vs 0.014 m/s^2 (was 1.9)
        assert r["ground_gyr_p95"] < 0.01  # rad/s


# --- battery_s45: SIM_BATT_VOLTAGE 12.6 -> 10.2 -> 12.6 -------------------------------------


def _battery(t, t0, t1):
    dur = (t1 - t0) * 1e-6
    bat = t["BAT"]

    def mean(table, col, a, z):
        return float(time_window(t[table], t0 + a * 1e6, t0 + z * 1e6)[col].mean())

    used = bat[bat.TimeUS <= t1].CurrTot.iloc[-1] - bat[bat.TimeUS <= t0].CurrTot.iloc[-1]
    return {
        "err6": _err_times(t, t0, np.inf, 6, 1),
        "err6_0": _err_times(t, t0, np.inf, 6, 0),
        "modes": int((t["MODE"].TimeUS > t0).sum()),
        "low_msg": _msg_times(t, t0, "Battery 1 is low 10.20V"),
        "tho": [mean("CTUN", "ThO", -20, 0), mean("CTUN", "ThO", 3, dur),
                mean("CTUN", "ThO", dur + 5, dur + 25)],
        "rcou": mean("RCOU", "C1", 3, dur),
        "volt": mean("BAT", "Volt", 3, dur),
        "voltr": mean("BAT", "VoltR", 3, dur),
        "used_window": float(used),
        "used_end": float(bat.CurrTot.iloc[-1]),
        "wh_end": float(bat.EnrgTot.iloc[-1]),
        "rem_end": float(bat.RemPct.iloc[-1]),
        "rem_t0": float(bat[bat.TimeUS <= t0].RemPct.iloc[-1]),
    }


@lru_cache(maxsize=1)
def _battery_pair():
    s, s0, s1, tl, t0, t1 = _pair("battery_s45")
    return _battery(s, s0, s1), _battery(tl, t0, t1)


def test_battery_low_failsafe_after_the_timer_warns_only_and_latches():
    sitl, tlm = _battery_pair()
    assert len(tlm["err6"]) == len(sitl["err6"]) == 1
    assert _close(tlm["err6"][0], sitl["err6"][0])  # 10.08 vs 10.15 s (BATT_LOW_TIMER 10 s)
    assert tlm["low_msg"] == pytest.approx(tlm["err6"], abs=1e-6)
    assert tlm["err6_0"] == sitl["err6_0"] == []  # latched: no ERR 6/0 at the clear
    assert tlm["modes"] == sitl["modes"] == 0  # BATT_FS_LOW_ACT 0: no mode change


def test_battery_voltage_scales_thrust_and_throttle_like_sitl():
    sitl, tlm = _battery_pair()
    for a, b in zip(tlm["tho"], sitl["tho"], strict=True):  # 0.36 -> 0.46 -> 0.37
        assert _close(a, b, 0.05)
    assert abs(tlm["rcou"] - sitl["rcou"]) < 10.0  # ~1735 us
    assert tlm["volt"] == pytest.approx(sitl["volt"], abs=0.01)  # 10.2 V
    assert _close(tlm["voltr"] - tlm["volt"], sitl["voltr"] - sitl["volt"])  # sag 1.1 vs 0.94 V


def test_battery_monitor_counts_charge_and_energy_like_sitl():
    sitl, tlm = _battery_pair()
    assert _close(tlm["used_window"], sitl["used_window"], 0.05)  # 432 vs 432 mAh
    assert _close(tlm["used_end"], sitl["used_end"], 0.05)  # 3469 vs 3451 mAh
    assert _close(tlm["wh_end"], sitl["wh_end"], 0.05)  # 42.7 vs 42.4 Wh
    assert tlm["rem_t0"] == pytest.approx(sitl["rem_t0"], abs=1)  # BATT_CAPACITY 3300
    assert tlm["rem_end"] == sitl["rem_end"] == 0


# --- behaviour: battery failsafe actions, throttle failsafe, shove and twist -----------------


@lru_cache(maxsize=16)
def _fly(params: tuple, changes: tuple):
    from tlm_sim import fly

    return fly(1, list(changes), dict(params), seed=3).tables


def _errs(t, subsys):
    if "ERR" not in t:  # no ERR row in the flight
        return []
    e = t["ERR"]
    return [(r.TimeUS * 1e-6, r.ECode) for r in e.itertuples() if r.Subsys == subsys]


def _modes(t, after_s):
    m = t["MODE"]
    return [(r.TimeUS * 1e-6, r.ModeNum, r.Rsn) for r in m.itertuples() if r.TimeUS > after_s * 1e6]


@pytest.mark.parametrize(("act", "mode"), [(1, 9), (2, 6)])
def test_battery_failsafe_action_lands_or_returns_and_latches(act, mode):
    t = _fly((("BATT_FS_LOW_ACT", act),),
             ((60.0, "SIM_BATT_VOLTAGE", 10.2), (80.0, "SIM_BATT_VOLTAGE", 12.6)))
    err = _errs(t, 6)
    assert [c for _, c in err] == [1]
    assert 70.05 < err[0][0] < 70.25  # BATT_LOW_TIMER 10 s at the 10 Hz monitor
    modes = _modes(t, 60.0)
    assert modes[0] == (err[0][0], mode, 4)  # ModeReason BATTERY_FAILSAFE
    assert all(m == (9 if act == 1 else m) for _, m, _ in modes)  # LAND stays LAND
    ev = t["EV"]
    assert (ev.Id == 11).any()  # it comes down and disarms


def test_battery_capacity_failsafe_needs_no_timer():
    t = _fly((("BATT_LOW_MAH", 3000.0),), ())
    err = _errs(t, 6)
    bat = t["BAT"]
    at = bat[bat.TimeUS <= err[0][0] * 1e6 + 1].iloc[-1]
    assert len(err) == 1 and 295.0 <= at.CurrTot < 305.0  # 3300 - 3000 mAh used
    assert all(m != 9 for _, m, _ in _modes(t, err[0][0] - 1e-6))  # action none: no LAND


def test_battery_critical_after_low_escalates_with_its_own_action():
    t = _fly((("BATT_LOW_VOLT", 11.0), ("BATT_CRT_VOLT", 10.0), ("BATT_FS_CRT_ACT", 1)),
             ((60.0, "SIM_BATT_VOLTAGE", 10.5), (75.0, "SIM_BATT_VOLTAGE", 9.8)))
    err = _errs(t, 6)
    assert [c for _, c in err] == [1, 1]
    assert 70.05 < err[0][0] < 70.25 and 85.05 < err[1][0] < 85.25
    modes = _modes(t, 60.0)
    assert modes[0] == (err[1][0], 9, 4)
    texts = [m for _, m in event_texts(t) if m.startswith("Battery 1")]
    assert texts[0].startswith("Battery 1 is low 10.50V")
    assert texts[1].startswith("Battery 1 is critical 9.80V")


@pytest.mark.parametrize(("value", "fails"), [(975.0, True), (940.0, False)])
def test_rc_fail_2_throttle_below_fs_thr_value(value, fails):
    t = _fly((("FS_THR_VALUE", value),), ((60.0, "SIM_RC_FAIL", 2), (70.0, "SIM_RC_FAIL", 0)))
    assert _errs(t, 2) == []  # frames keep coming: no late-frame ERR
    err5 = _errs(t, 5)
    if not fails:
        assert err5 == [] and all(m != 6 for _, m, _ in _modes(t, 60.0)[:1])
        return
    assert [c for _, c in err5] == [1, 0]
    assert 60.04 <= err5[0][0] <= 60.1  # the third frame below FS_THR_VALUE (50 Hz)
    assert 70.04 <= err5[1][0] <= 70.1  # three good frames clear it
    assert _modes(t, 60.0)[0] == (err5[0][0], 6, 3)  # RTL, ModeReason RADIO_FAILSAFE


def _hover(p: dict):
    from tlm_sim.dynamics import build_frame, hover_command, init_state, set_airborne
    from tlm_sim.dynamics import layout as X
    from tlm_sim.params import Params

    frame = build_frame(Params(p))
    x = np.zeros(X.N_STATE)
    init_state(x, frame, 0.0)
    set_airborne(x, frame, 50.0, hover_command(frame))
    return x, frame


@pytest.mark.parametrize(("kind", "unit"), [("SHOVE", "accel"), ("TWIST", "rate")])
def test_shove_and_twist_act_for_exactly_their_time(kind, unit):
    from tlm_sim.dynamics import PHYSICS_DT_S, command_to_pwm, hover_command, run_ticks
    from tlm_sim.dynamics import layout as X
    from tlm_sim.dynamics.frame import F_SHOVE_TIME, F_TWIST_TIME
    from tlm_sim.rng import new_rng

    base, frame0 = _hover({})
    x, frame = _hover({f"SIM_{kind}_Y": 2.0, f"SIM_{kind}_TIME": 100.0})
    pwm = np.full(4, command_to_pwm(hover_command(frame), frame))
    slot = X.VE if unit == "accel" else X.WX + 1
    n_on = int(np.ceil(0.1 / PHYSICS_DT_S))  # 121 ticks of 833 us cover 100 ms
    for n in (n_on, 12):
        run_ticks(x, pwm, frame, PHYSICS_DT_S, 0.0, n, new_rng(0, 2))
        run_ticks(base, pwm, frame0, PHYSICS_DT_S, 0.0, n, new_rng(0, 2))
        if n == n_on:
            gained = x[slot] - base[slot]
            assert gained == pytest.approx(2.0 * n_on * PHYSICS_DT_S, rel=0.15)
    # the push stopped after its time: the simulator set the duration back to 0, and the
    # difference to the undisturbed copter no longer grows
    assert frame[F_SHOVE_TIME if kind == "SHOVE" else F_TWIST_TIME] == 0.0
    assert x[X.SHOVE_MS if kind == "SHOVE" else X.TWIST_MS] == 0.0
    assert 0.9 * gained <= x[slot] - base[slot] <= 1.001 * gained


def test_generate_draws_the_weakened_motor():
    """motor_partial's ``motor`` knob: motor 1 (the default, SITL's) flies the type's own
    parameters; another sets its SIM_ENGINE_FAIL bit, cleared to SITL's default motor 1."""
    from tlm_process.generate.scenario import fault_params, magnitude_knobs

    assert list(magnitude_knobs()["motor_partial"]["motor"].default) == [1]
    assert fault_params("motor_partial", {"mul": 0.6, "motor": 1}, 35.0) == (
        {"SIM_ENGINE_MUL": 0.6}, {"SIM_ENGINE_MUL": 1.0})
    assert fault_params("motor_partial", {"mul": 0.6, "motor": 3}, 35.0) == (
        {"SIM_ENGINE_FAIL": 4.0, "SIM_ENGINE_MUL": 0.6},
        {"SIM_ENGINE_FAIL": 1.0, "SIM_ENGINE_MUL": 1.0})
