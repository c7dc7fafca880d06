"""Barometer faults (label 6, sitl-faults.md §3): two independent barometers with SITL's
DISABLE / GLITCH / DRIFT / FREEZE / RND per instance, their health and ERR 18, and ArduCopter's
reaction when both are gone (baro_s44.bin: EKF3's height times out after 10 s, the position
controller's estimate becomes the origin and the copter climbs at WPNAV_SPEED_UP and flies off
its route until the baros return, then descends back).

One reconstructed reference flight (baro_s44) and a few short built-in-mission flights, each
flown once per module.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
import pandas as pd
import pytest

from tests.conftest import reference_path

T0, T1 = 100.0, 130.0  # fault window of the behaviour flights [s]
REL = 0.35  # the tolerance on each signature value
#: absolute floor for the log-rate-limited times (10 Hz BARO/ERR rows, 5 Hz GPS fusion)
ABS_S = 0.15
SIG_TYPES = ["BARO", "ERR", "CTUN", "SIM", "XKF1", "MODE", "ATT"]


# --- measuring a baro fault the same way in SITL's and tlm's tables ----------------------------
def _path_distance(n: np.ndarray, e: np.ndarray, path: np.ndarray) -> np.ndarray:
    """Distance [m] of points (n, e) from the polyline path[:, :2] (NE, m)."""
    p = np.stack([n, e], 1)
    best = np.full(len(p), np.inf)
    for a, b in zip(path[:-1, :2], path[1:, :2], strict=True):
        d = b - a
        t = np.clip(((p - a) @ d) / max(float(d @ d), 1e-9), 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(p - (a + t[:, None] * d)).T))
    return best


def baro_signature(t: dict[str, pd.DataFrame], t0: float, t1: float,
                   home: tuple[float, float, float], path: np.ndarray) -> dict[str, Any]:
    """The baro_s44 facts of the reference README, in seconds after the fault start t0 [us]
    (t1: its end [us]); heights are the truth (SIM) above home, path the mission (NE, m)."""
    out: dict[str, Any] = {}
    dur = (t1 - t0) * 1e-6
    b = t["BARO"]
    for i in (0, 1):
        bi = b[b.I == i]
        off = bi[(bi.TimeUS >= t0) & (bi.H == 0)]
        on = bi[(bi.TimeUS >= t1) & (bi.H == 1)]
        out[f"h{i}_off_s"] = (off.TimeUS.iloc[0] - t0) * 1e-6 if len(off) else np.nan
        out[f"h{i}_on_s"] = (on.TimeUS.iloc[0] - t0) * 1e-6 if len(on) else np.nan
        win = bi[(bi.TimeUS > t0 + 0.3e6) & (bi.TimeUS < t1)]
        out[f"alt{i}_std"] = float(win.Alt.std())
    err = t["ERR"][t["ERR"].Subsys == 18]
    out["err18"] = [(int(c), (tt - t0) * 1e-6) for tt, c in zip(err.TimeUS, err.ECode,
                                                                strict=True)]
    c = t["CTUN"]
    rc = (c.TimeUS - t0) * 1e-6
    lost = c[(rc > 0) & (c.TimeUS < t1) & (c.Alt.abs() < 1e-6)]
    out["alt_invalid_s"] = float(rc[lost.index[0]]) if len(lost) else np.nan
    out["dalt_m"] = float(lost.DAlt.median()) if len(lost) else np.nan
    out["tho_before"] = float(c[(rc > -20) & (rc < 0)].ThO.mean())
    out["tho_window"] = float(c[(rc > 0) & (c.TimeUS < t1)].ThO.mean())
    s = t["SIM"]
    ts = ((s.TimeUS - t0) * 1e-6).to_numpy()
    h = s.Alt.to_numpy() - home[2]
    i0, i1 = np.searchsorted(ts, 0.0), np.searchsorted(ts, dur)
    out["h_start_m"] = float(h[i0])
    out["climb_m"] = float(h[i1] - h[i0])
    k = max(round(1.0 / float(np.median(np.diff(ts)))), 1)
    rate = (h[k:] - h[:-k]) / (ts[k:] - ts[:-k])  # 1 s climb rate
    out["climb_rate_max"] = float(rate[i0:i1].max())
    after = (ts[:-k] > dur) & (ts[:-k] < dur + 60.0)
    out["descent_rate_max"] = float(-rate[after].min())
    back = np.nonzero((ts > dur) & (np.abs(h - h[i0]) < 1.5))[0]
    out["back_s"] = float(ts[back[0]] - dur) if len(back) else np.nan
    n = (s.Lat.to_numpy() - home[0]) * 111319.49079327357
    e = (s.Lng.to_numpy() - home[1]) * 111319.49079327357 * np.cos(np.radians(home[0]))
    out["track_off_max_m"] = float(_path_distance(n, e, path)[i0:i1 + 40].max())
    speed = np.hypot(np.diff(n), np.diff(e)) / np.diff(ts)
    out["speed_window"] = float(speed[i0:i1].mean())
    out["speed_before"] = float(speed[np.searchsorted(ts, -20.0):i0].mean())
    x = t["XKF1"][t["XKF1"].C == 0]
    xt = ((x.TimeUS - t0) * 1e-6).to_numpy()
    sel = (xt > 0.0) & (xt < dur)
    out["ekf_h_err_m"] = float(np.abs(-x.PD.to_numpy()[sel] - np.interp(xt[sel], ts, h)).max())
    m = t["MODE"]
    out["mode_changes"] = int(((m.TimeUS > t0) & (m.TimeUS < t1 + 60e6)).sum())
    return out


@lru_cache(maxsize=1)
def _baro_s44() -> tuple[dict[str, Any], dict[str, Any]]:
    """(SITL's, tlm's) signature of the baro_s44 fault; tlm flies the reconstructed scenario."""
    from tlm_process.crosscheck.scenario import reconstruct
    from tlm_sim import fly
    from tlm_sim.flightlog import read_bin

    bin_path = reference_path("baro_s44.bin")
    sc = reconstruct(bin_path)
    f = sc.faults[0]
    path = np.vstack([[0.0, 0.0, 0.0], sc.mission.ned()])
    home = tuple(sc.mission.home)
    ref = baro_signature(read_bin(str(bin_path), types=SIG_TYPES), f["start_time_us"],
                         f["end_time_us"], home, path)
    log = fly(sc.mission, sc.schedule, sc.params, seed=sc.seed)
    tlm = baro_signature(log.tables, sc.to_tlm_us(f["start_time_us"]),
                         sc.to_tlm_us(f["end_time_us"]), home, path)
    return ref, tlm


def _close(tlm: float, ref: float, floor: float = 0.0) -> bool:
    return abs(tlm - ref) <= max(REL * abs(ref), floor)


# --- the reference flight -----------------------------------------------------------------------
def test_baro_s44_health_and_err_timing():
    ref, tlm = _baro_s44()
    for k in ("h0_off_s", "h1_off_s", "h0_on_s", "h1_on_s"):
        assert _close(tlm[k], ref[k], ABS_S), (k, tlm[k], ref[k])
    assert tlm["alt0_std"] == tlm["alt1_std"] == ref["alt0_std"] == 0.0  # BARO.Alt frozen
    assert [c for c, _ in tlm["err18"]] == [c for c, _ in ref["err18"]] == [4, 0]
    for (_, tt), (_, tr) in zip(tlm["err18"], ref["err18"], strict=True):
        assert _close(tt, tr, ABS_S), (tt, tr)


def test_baro_s44_height_invalid_climb_and_return():
    ref, tlm = _baro_s44()
    assert _close(tlm["alt_invalid_s"], ref["alt_invalid_s"])  # SITL +10.19 s
    assert tlm["dalt_m"] == pytest.approx(ref["dalt_m"], abs=0.01)  # DAlt 3.625 m
    for k in ("climb_m", "climb_rate_max", "descent_rate_max", "back_s", "track_off_max_m",
              "speed_window"):
        assert _close(tlm[k], ref[k]), (k, tlm[k], ref[k])
    assert tlm["tho_window"] - tlm["tho_before"] == pytest.approx(
        ref["tho_window"] - ref["tho_before"], rel=REL)
    assert tlm["ekf_h_err_m"] < 0.2  # the EKF height follows the truth
    assert tlm["mode_changes"] == ref["mode_changes"] == 0  # AUTO throughout


# --- behaviour on a built-in mission -------------------------------------------------------------
@lru_cache(maxsize=8)
def _fly(*changes: tuple[str, float, float]):
    """Mission 1, seed 3, each (parameter, value during T0..T1, value after) as a fault."""
    from tlm_sim import fly

    sched = []
    for name, v_on, v_off in changes:
        sched += [(T0, name, v_on), (T1, name, v_off)]
    return fly(1, faults=sched, seed=3).tables


def _baro(t: dict[str, pd.DataFrame], i: int) -> pd.DataFrame:
    b = t["BARO"]
    return b[b.I == i].reset_index(drop=True)


def _between(df: pd.DataFrame, a: float, b: float) -> pd.DataFrame:
    return df[(df.TimeUS >= a * 1e6) & (df.TimeUS < b * 1e6)]


def _err18(t) -> pd.DataFrame:
    """The flight's ERR 18 (BARO) rows (a flight without any ERR has no ERR table)."""
    if "ERR" not in t:
        return pd.DataFrame({"TimeUS": [], "Subsys": [], "ECode": []})
    err = t["ERR"]
    return err[err.Subsys == 18]


def _truth_h(t: dict[str, pd.DataFrame], a: float, b: float) -> np.ndarray:
    from tlm_sim.mission import builtin_mission

    return _between(t["SIM"], a, b).Alt.to_numpy() - builtin_mission(1).home[2]


def test_second_baro_has_its_own_noise():
    """BARO[1] is no longer a copy of BARO[0]: SIM_BAR2_RND 0.2 m uniform noise of its own,
    while BARO[0] (SIM_BARO_RND 0) is noiseless; the EKF fuses BARO[0] only."""
    t = _fly()
    d = _baro(t, 1).Alt - _baro(t, 0).Alt
    assert d.abs().max() <= 0.2 + 1e-9
    assert d.std() == pytest.approx(0.2 / np.sqrt(3.0), rel=0.1)
    assert abs(d.mean()) < 0.01
    assert (_baro(t, 0).H == 1).all() and (_baro(t, 1).H == 1).all()
    assert not len(_err18(t))
    # more noise on baro 2 changes nothing but BARO[1]
    from tlm_sim import fly

    noisy = fly(1, params={"SIM_BAR2_RND": 1.0}, seed=3).tables
    assert set(t) == set(noisy)
    for name in t:
        df, other = t[name], noisy[name]
        if name == "BARO":
            df, other = df[df.I == 0], other[other.I == 0]
        assert df.equals(other), name


def test_one_baro_disabled_the_other_carries_on():
    t = _fly(("SIM_BARO_DISABLE", 1.0, 0.0))
    b0, b1 = _baro(t, 0), _baro(t, 1)
    w0 = _between(b0, T0 + 0.2, T1)
    assert (w0.H == 0).all() and w0.Alt.std() == 0.0  # stopped, frozen at its last value
    assert (_between(b1, T0, T1).H == 1).all()
    assert (_between(b0, T1 + 0.2, T1 + 20).H == 1).all()
    # the primary moves to baro 2 in the same update: no ERR 18 (sitl-faults.md §3.3)
    assert not len(_err18(t))
    c = _between(t["CTUN"], T0, T1)
    assert (c.Alt.abs() > 1.0).all()  # the height stays valid
    assert np.allclose(c.BAlt, np.interp(c.TimeUS, b1.TimeUS, b1.Alt), atol=0.25)
    normal = _fly()
    h, h_n = _truth_h(t, T0, T1 + 20), _truth_h(normal, T0, T1 + 20)
    assert np.abs(h - h_n).max() < 1.0  # no climb


def test_both_disabled_err_and_climb():
    t = _fly(("SIM_BARO_DISABLE", 1.0, 0.0), ("SIM_BAR2_DISABLE", 1.0, 0.0))
    err = _err18(t)
    assert list(err.ECode) == [4, 0]
    assert T0 <= err.TimeUS.iloc[0] * 1e-6 < T0 + 0.2
    assert T1 <= err.TimeUS.iloc[1] * 1e-6 < T1 + 0.2
    c = t["CTUN"]
    lost = c[c.Alt.abs() < 1e-6]
    lost = lost[lost.TimeUS > T0 * 1e6]
    assert 9.8 < lost.TimeUS.iloc[0] * 1e-6 - T0 < 10.5  # EKF3's 10 s height timeout
    assert lost.TimeUS.iloc[-1] * 1e-6 < T1 + 0.5
    h = _truth_h(t, T0, T1)
    assert h[-1] - h[0] > 0.8 * 2.5 * (T1 - T0 - 10.5)  # climbing at WPNAV_SPEED_UP
    x = _between(t["XKF4"], T0 + 11, T1)
    assert ((x.TS.astype(int) & 4) != 0).all()  # height timeout bit


def test_glitch_is_an_offset_while_set():
    t = _fly(("SIM_BARO_GLITCH", 5.0, 0.0))
    d = _baro(t, 0).Alt - _baro(t, 1).Alt
    tt = _baro(t, 0).TimeUS * 1e-6
    assert d[(tt > T0 + 0.2) & (tt < T1)].mean() == pytest.approx(5.0, abs=0.05)
    assert d[(tt > T1 + 0.2)].abs().max() < 0.25
    # a 5 m step passes EKF3's height gate: the estimate is pulled up, the copter comes down
    normal = _fly()
    drop = _truth_h(normal, T1 - 5, T1) - _truth_h(t, T1 - 5, T1)
    assert 3.0 < drop.mean() < 6.0


def test_drift_grows_and_stays():
    t = _fly(("SIM_BAR2_DRIFT", 0.5, 0.0))
    d = _baro(t, 1).Alt - _baro(t, 0).Alt
    tt = _baro(t, 1).TimeUS * 1e-6
    mid = d[(tt > T0 + 10) & (tt < T0 + 10.1)].mean()
    assert mid == pytest.approx(5.0, abs=0.3)
    end = d[(tt > T1 + 5)].mean()  # 0.5 m/s for 30 s: 15 m that stay after DRIFT 0
    assert end == pytest.approx(15.0, abs=0.3)
    assert d[tt > T1 + 5].std() < 0.2


def test_freeze_holds_the_value():
    t = _fly(("SIM_BAR2_FREEZE", 1.0, 0.0))
    b1 = _baro(t, 1)
    w = _between(b1, T0 + 0.2, T1)
    assert w.Alt.std() == 0.0 and (w.H == 1).all()  # frozen, still healthy
    assert _between(b1, T1 + 1, T1 + 20).Alt.std() > 0.0  # follows again after the clear
    assert not len(_err18(t))
