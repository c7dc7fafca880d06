"""Fault signatures: what a GPS, accelerometer, engine or RC fault does to a flight, as numbers.

:func:`fault_signature` measures one fault window the same way in a tlm ``FlightLog.tables`` and
in the tables ``read_bin`` gives for a genuine SITL ``.bin``. It uses only messages and fields
that both logs have: GPS, IMU, CTUN, XKF1, SIM (the simulator's true attitude and position),
MODE, EV and ERR; for the compass also MAG, XKF4 and XKFS. SITL's SIM2, MSG and CMD are not
used (tlm does not log them).

Conventions (all times are log TimeUS, microseconds since boot; results in SI units):

* the window is ``[start_time_us, end_time_us]``; durations are seconds after ``start_time_us``
  (``*_s``) or after ``end_time_us`` (``*_after_end_s``);
* "truth" is the SIM message; the height above home is ``SIM.Alt`` minus its median before
  arming (SITL's ground is flat at the home altitude); horizontal positions are the flat-earth
  north/east offsets of ``SIM.Lat/Lng`` from the truth home, and the EKF estimate is the primary
  core's ``XKF1.PN/PE`` (the primary is core 0 until an ERR 24 names another; ``POS`` is not
  used because ArduPilot stops logging it while the EKF has no absolute position);
* the true ground speed is the SIM position differenced over :data:`SPEED_BASE_S`;
* flags are 1.0/0.0 and a time that never comes is NaN.

The window edges get a margin of :data:`EDGE_MARGIN_S` for "fraction of rows inside/outside"
metrics: a parameter change reaches the next sensor sample, not the same microsecond.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.reference import time_window
from tlm_sim.geo import latlon_to_ne

ARMED, DISARMED = 10, 11  # EV ids
AUTO, RTL = 3, 6  # MODE ModeNum
RSN_RADIO_FAILSAFE = 3  # ModeReason::RADIO_FAILSAFE
ERR_RADIO, ERR_FS_RADIO = 2, 5  # ERR Subsys
ERR_COMPASS, ERR_EKF_PRIMARY, ERR_THRUST_LOSS, ERR_VIBE_FS = 3, 24, 25, 29  # ERR Subsys

#: margin at the window edges for in/out row fractions [s] (two 5 Hz GPS samples)
EDGE_MARGIN_S = 0.5
#: baseline of the true ground speed difference [s]
SPEED_BASE_S = 0.5
#: height above home below which the vehicle counts as on the ground [m]
GROUND_H_M = 0.5
#: EKF-truth distance below which the EKF counts as recovered after a GPS fault [m]
EKF_RECOVERED_M = 5.0
#: early phase of a fault in which the climb (accel) and roll (engine) are measured [s]
EARLY_S = 3.0
#: path length after the recovery over which a resumed mission is measured [s]
RESUME_S = 30.0

FAULT_TYPES = ("gps", "accel", "engine", "rc", "compass")


def _max(s: pd.Series) -> float:
    return float(s.max()) if len(s) else float("nan")


class _Flight:
    """Shared time lines of one log: arming, truth height and position, EKF position, modes."""

    def __init__(self, tables: Mapping[str, pd.DataFrame]):
        self.t = tables
        ev = tables["EV"]
        armed = ev[ev.Id == ARMED].TimeUS
        self.arm_us = float(armed.iloc[0]) if len(armed) else float("nan")
        disarm = ev[(ev.Id == DISARMED) & (ev.TimeUS > self.arm_us)].TimeUS
        self.disarm_us = float(disarm.iloc[0]) if len(disarm) else float("nan")
        sim = tables["SIM"].sort_values("TimeUS")
        pre = sim[sim.TimeUS < self.arm_us]
        ground = pre if len(pre) else sim.iloc[:1]
        self.home_alt = float(ground.Alt.median())
        self.home = (float(ground.Lat.iloc[-1]), float(ground.Lng.iloc[-1]))
        self.sim_t = sim.TimeUS.to_numpy(float)
        self.h = sim.Alt.to_numpy(float) - self.home_alt
        self.roll = sim.Roll.to_numpy(float)
        self.pitch = sim.Pitch.to_numpy(float)
        n, e = latlon_to_ne(sim.Lat.to_numpy(float), sim.Lng.to_numpy(float), *self.home)
        self.n, self.e = np.asarray(n), np.asarray(e)
        mode = tables["MODE"].sort_values("TimeUS")
        self.mode_t = mode.TimeUS.to_numpy(float)
        self.mode = mode.ModeNum.to_numpy(int)
        self.mode_rsn = mode.Rsn.to_numpy(int)
        self.err = tables.get("ERR", pd.DataFrame(columns=["TimeUS", "Subsys", "ECode"]))

    # --- truth -------------------------------------------------------------------------------
    def sel(self, t0: float, t1: float) -> np.ndarray:
        """Boolean mask of SIM rows in [t0, t1]."""
        return (self.sim_t >= t0) & (self.sim_t <= t1)

    def first_time(self, cond: np.ndarray, t0: float, t1: float = np.inf) -> float:
        """First SIM time in [t0, t1] where cond holds, NaN if none."""
        idx = np.flatnonzero(cond & self.sel(t0, t1))
        return float(self.sim_t[idx[0]]) if len(idx) else float("nan")

    def ground_speed(self) -> np.ndarray:
        """True horizontal speed [m/s] at each SIM row (backward difference over SPEED_BASE_S)."""
        dt = np.median(np.diff(self.sim_t)) if len(self.sim_t) > 1 else 1e5
        k = max(1, int(round(SPEED_BASE_S * 1e6 / dt)))
        v = np.full(len(self.sim_t), np.nan)
        dist = np.hypot(self.n[k:] - self.n[:-k], self.e[k:] - self.e[:-k])
        v[k:] = dist / ((self.sim_t[k:] - self.sim_t[:-k]) * 1e-6)
        return v

    def path_m(self, t0: float, t1: float) -> float:
        """Truth horizontal path length over [t0, t1] [m]."""
        m = self.sel(t0, t1)
        return float(np.hypot(np.diff(self.n[m]), np.diff(self.e[m])).sum()) if m.sum() > 1 \
            else float("nan")

    def primary_lane(self, t: np.ndarray) -> np.ndarray:
        """EKF primary core at times t: 0 until an ERR 24 (EKF_PRIMARY) names another lane."""
        e = self.err[self.err.Subsys == ERR_EKF_PRIMARY].sort_values("TimeUS")
        i = np.searchsorted(e.TimeUS.to_numpy(float), t, side="right") - 1
        lanes = np.concatenate([[0], e.ECode.to_numpy(int)])
        return lanes[i + 1]

    def ekf_error(self) -> tuple[np.ndarray, np.ndarray]:
        """(TimeUS, horizontal distance [m] between the primary core's XKF1 PN/PE and the truth).

        XKF1 positions are relative to the EKF origin, which both SITL and tlm set at the
        home position on the ground (SITL's ORGN equals home).
        """
        x = self.t["XKF1"].sort_values("TimeUS")
        x = x[x.C.to_numpy(int) == self.primary_lane(x.TimeUS.to_numpy(float))]
        tp = x.TimeUS.to_numpy(float)
        tn = np.interp(tp, self.sim_t, self.n)
        te = np.interp(tp, self.sim_t, self.e)
        return tp, np.hypot(x.PN.to_numpy(float) - tn, x.PE.to_numpy(float) - te)

    # --- events ------------------------------------------------------------------------------
    def mode_at(self, t: float) -> int:
        i = np.searchsorted(self.mode_t, t, side="right") - 1
        return int(self.mode[i]) if i >= 0 else -1

    def mode_kept(self, mode: int, t0: float, t1: float) -> float:
        """1.0 if the mode is ``mode`` at t0 and does not change before t1."""
        changes = (self.mode_t > t0) & (self.mode_t <= t1) & (self.mode != mode)
        return float(self.mode_at(t0) == mode and not changes.any())

    def disarmed_in(self, t0: float, t1: float) -> float:
        return float(t0 <= self.disarm_us <= t1)

    def err_count(self, subsys: int, t0: float, t1: float, code: int | None = None) -> float:
        e = time_window(self.err, t0, t1)
        e = e[e.Subsys == subsys]
        if code is not None:
            e = e[e.ECode == code]
        return float(len(e))


def _gps(f: _Flight, t0: float, t1: float) -> dict[str, float]:
    gps = f.t["GPS"]
    gps = gps[gps.I == 0] if "I" in gps else gps
    m = EDGE_MARGIN_S * 1e6
    inside = time_window(gps, t0 + m, t1)
    armed = time_window(gps, f.arm_us, f.disarm_us if np.isfinite(f.disarm_us) else np.inf)
    outside = armed[(armed.TimeUS < t0) | (armed.TimeUS > t1 + m)]
    tp, err = f.ekf_error()
    w = (tp >= t0) & (tp <= t1)
    after = np.flatnonzero((tp > t1) & (err < EKF_RECOVERED_M))
    sel = f.sel(t0, t1)
    ctun = time_window(f.t["CTUN"], t0, t1)
    return {
        "nofix_frac_in": float((inside.Status < 3).mean()) if len(inside) else float("nan"),
        "nofix_frac_out": float((outside.Status < 3).mean()) if len(outside) else float("nan"),
        "nsats_max_in": _max(inside.NSats),
        "nsats_min_out": float(outside.NSats.min()) if len(outside) else float("nan"),
        "ekf_err_max_m": float(err[w].max()) if w.any() else float("nan"),
        "ekf_err_at_end_m": float(np.interp(t1, tp, err)),
        "ekf_recovered_after_end_s": float((tp[after[0]] - t1) * 1e-6) if len(after)
        else float("nan"),
        "speed_max_ms": float(np.nanmax(f.ground_speed()[sel])) if sel.any() else float("nan"),
        "roll_max_deg": float(np.abs(f.roll[sel]).max()),
        "pitch_max_deg": float(np.abs(f.pitch[sel]).max()),
        "baro_alt_range_m": float(ctun.BAlt.max() - ctun.BAlt.min()),
        "auto_kept": f.mode_kept(AUTO, t0, t1),
        "path_after_end_m": f.path_m(t1, t1 + RESUME_S * 1e6),
    }


def _accel_fail_values(fault: Mapping[str, Any]) -> dict[int, float]:
    """IMU instance -> the constant its accelerometer reports (SIM_ACCELn_FAIL = v, §2.7)."""
    ps = fault.get("params_start") or {}
    out = {}
    for i in (0, 1, 2):
        v = ps.get(f"SIM_ACCEL{i + 1}_FAIL")
        if v:
            out[i] = float(v)
    return out or {0: 1.0, 1: 1.0}


def _accel(f: _Flight, t0: float, t1: float, fault: Mapping[str, Any]) -> dict[str, float]:
    imu = f.t["IMU"]
    m = EDGE_MARGIN_S * 1e6
    out: dict[str, float] = {}
    for i, v in _accel_fail_values(fault).items():
        d = imu[imu.I == i]
        stuck = np.isclose(d.AccX, v, atol=1e-3) & np.isclose(d.AccY, v, atol=1e-3) \
            & np.isclose(d.AccZ, v, atol=1e-3)
        tin = (d.TimeUS >= t0 + m) & (d.TimeUS <= t1)
        tout = (d.TimeUS < t0) | (d.TimeUS > t1 + m)
        out[f"imu{i}_stuck_frac_in"] = float(stuck[tin].mean()) if tin.any() else float("nan")
        out[f"imu{i}_stuck_frac_out"] = float(stuck[tout].mean()) if tout.any() else float("nan")
    early = f.sel(t0, t0 + EARLY_S * 1e6)
    sel = f.sel(t0, t1)
    h0 = float(f.h[sel][0])  # the first truth sample in the window
    settle = f.sel(t1 + 10e6, t1 + 20e6)
    ctun = time_window(f.t["CTUN"], t0, t0 + EARLY_S * 1e6)
    out.update({
        "climb_3s_m": float(f.h[early].max() - h0),
        "climb_max_m": float(f.h[sel].max() - h0),
        "drop_max_m": float(h0 - f.h[sel].min()),
        "thr_max_3s": _max(ctun.ThO),
        "roll_max_deg": float(np.abs(f.roll[sel]).max()),
        "pitch_max_deg": float(np.abs(f.pitch[sel]).max()),
        "err24_ekf_primary": f.err_count(ERR_EKF_PRIMARY, t0, t1),
        "err29_vibe_fs": f.err_count(ERR_VIBE_FS, t0, t1),
        "err25_thrust_loss": f.err_count(ERR_THRUST_LOSS, t0, t1),
        "auto_kept": f.mode_kept(AUTO, t0, t1),
        "settle_roll_max_deg": float(np.abs(f.roll[settle]).max()) if settle.any()
        else float("nan"),
    })
    return out


def _engine(f: _Flight, t0: float, t1: float) -> dict[str, float]:
    ground = f.first_time(f.h <= GROUND_H_M, t0, t1)
    early = f.sel(t0, t0 + EARLY_S * 1e6)
    gps = time_window(f.t["GPS"], t0, t0 + 2 * EARLY_S * 1e6)
    up1 = f.first_time(f.h > 1.0, t1)
    up10 = f.first_time(f.h > 10.0, t1)
    return {
        "ground_s": (ground - t0) * 1e-6,
        "impact_speed_ms": _max(gps.VZ),
        "roll_max_3s_deg": float(np.abs(f.roll[early]).max()),
        "armed_kept": 1.0 - f.disarmed_in(t0, t1),
        "auto_kept": f.mode_kept(AUTO, t0, t1),
        "err25_thrust_loss": f.err_count(ERR_THRUST_LOSS, t0, t1),
        "liftoff_1m_after_end_s": (up1 - t1) * 1e-6,
        "above_10m_after_end_s": (up10 - t1) * 1e-6,
        "auto_after_end": float(f.mode_at(up10) == AUTO) if np.isfinite(up10) else 0.0,
        "path_after_10m_m": f.path_m(up10, up10 + RESUME_S * 1e6) if np.isfinite(up10)
        else 0.0,
    }


def _rc(f: _Flight, t0: float, t1: float) -> dict[str, float]:
    rtl = np.flatnonzero((f.mode_t >= t0) & (f.mode == RTL))
    t_rtl = float(f.mode_t[rtl[0]]) if len(rtl) else float("nan")
    end = f.disarm_us if np.isfinite(f.disarm_us) else float(f.sim_t[-1])
    last = np.searchsorted(f.sim_t, end, side="right") - 1
    return {
        "rtl_delay_s": (t_rtl - t0) * 1e-6,
        "rtl_reason": float(f.mode_rsn[rtl[0]]) if len(rtl) else float("nan"),
        "err2_2_late_frame": f.err_count(ERR_RADIO, t0, t1, 2),
        "err5_1_failsafe": f.err_count(ERR_FS_RADIO, t0, t1, 1),
        "err5_0_cleared": f.err_count(ERR_FS_RADIO, t1, t1 + 2e6, 0),
        "rtl_kept_after_end": f.mode_kept(RTL, t1, end) if np.isfinite(t_rtl) else 0.0,
        "disarm_s": (f.disarm_us - t0) * 1e-6 if f.disarm_us >= t0 else float("nan"),
        "final_home_dist_m": float(np.hypot(f.n[last], f.e[last])),
    }


def _first_rel(t: np.ndarray, cond: np.ndarray, after: float, origin: float) -> float:
    """Seconds from origin to the first time t > after where cond holds (NaN if none)."""
    idx = np.flatnonzero(cond & (t > after))
    return float((t[idx[0]] - origin) * 1e-6) if len(idx) else float("nan")


def _compass(f: _Flight, t0: float, t1: float) -> dict[str, float]:
    """Compass 1 without data (SIM_MAG1_FAIL 1): its health, ERR 3, the EKF's compass change."""
    mag = f.t["MAG"].sort_values("TimeUS", kind="stable")
    m0 = mag[mag.I == 0]
    tm, h0 = m0.TimeUS.to_numpy(float), m0.Health.to_numpy(float)
    inside = time_window(mag, t0 + 1e6, t1)
    err = f.err[f.err.Subsys == ERR_COMPASS].sort_values("TimeUS")
    te, code = err.TimeUS.to_numpy(float), err.ECode.to_numpy(int)
    xs = f.t["XKFS"].sort_values("TimeUS", kind="stable")
    switched = xs[(xs.TimeUS > t0) & (xs.MI != 0)]
    tp, ekf_err = f.ekf_error()
    in_win = (tp >= t0) & (tp <= t1)
    return {
        "health0_lost_s": _first_rel(tm, h0 == 0, t0, t0),
        "health0_back_s": _first_rel(tm, h0 == 1, t1, t0),
        "mag0_frozen_std": float(inside[inside.I == 0][["MagX", "MagY", "MagZ"]].std().max()),
        "mag_others_healthy_frac": float(inside[inside.I != 0].Health.mean()),
        "err3_4_s": _first_rel(te, code == 4, t0, t0),
        "err3_0_s": _first_rel(te, code == 0, t0, t0),
        "switch_compass_s": float((switched.TimeUS.iloc[0] - t0) * 1e-6) if len(switched)
        else float("nan"),
        "switch_compass_to": float(switched.MI.iloc[0]) if len(switched) else float("nan"),
        "err24_ekf_primary": f.err_count(ERR_EKF_PRIMARY, t0, t1),
        "sm_max": _max(time_window(f.t["XKF4"], t0, t1).SM),
        "ekf_err_max_m": float(ekf_err[in_win].max()) if in_win.any() else float("nan"),
        "auto_kept": f.mode_kept(AUTO, t0, t1),
    }


def truth_timeline(tables: Mapping[str, pd.DataFrame]) -> pd.DataFrame:
    """The truth (SIM) as plotted next to a signature.

    Returns:
        DataFrame with TimeUS, ``h_m`` (height above home), ``roll_deg``, ``pitch_deg`` and
        ``speed_ms`` (true ground speed), one row per SIM row.
    """
    f = _Flight(tables)
    return pd.DataFrame({"TimeUS": f.sim_t, "h_m": f.h, "roll_deg": f.roll,
                         "pitch_deg": f.pitch, "speed_ms": f.ground_speed()})


def fault_signature(tables: Mapping[str, pd.DataFrame], fault: Mapping[str, Any]
                    ) -> dict[str, float]:
    """Measure one fault's signature in a flight log.

    Args:
        tables: log tables by message name (tlm ``FlightLog.tables`` or ``read_bin`` output).
        fault: at least ``type`` ("gps", "accel", "engine" or "rc"), ``start_time_us`` and
            ``end_time_us`` (log TimeUS); for "accel", ``params_start`` (e.g.
            ``{"SIM_ACCEL1_FAIL": 1}``) selects the failed IMUs and their stuck value (default:
            IMU 0 and 1 reading 1 m/s^2).

    Returns:
        Metric name -> value (see the module docstring for units and conventions):

        * gps: ``nofix_frac_in/out`` (GPS rows with Status < 3), ``nsats_max_in``,
          ``nsats_min_out``, ``ekf_err_max_m`` and ``ekf_err_at_end_m`` (primary XKF1 vs truth),
          ``ekf_recovered_after_end_s`` (back within 5 m), ``speed_max_ms``, ``roll_max_deg``,
          ``pitch_max_deg``, ``baro_alt_range_m`` (CTUN.BAlt), ``auto_kept``,
          ``path_after_end_m`` (truth path in the 30 s after the end).
        * accel: ``imu<i>_stuck_frac_in/out`` (rows with AccX = AccY = AccZ = the fail value),
          ``climb_3s_m``, ``climb_max_m``, ``drop_max_m`` (relative to the height at the start),
          ``thr_max_3s`` (CTUN.ThO), ``roll_max_deg``, ``pitch_max_deg``, ERR counts
          ``err24_ekf_primary``, ``err29_vibe_fs``, ``err25_thrust_loss``, ``auto_kept``,
          ``settle_roll_max_deg`` (10-20 s after the end).
        * engine: ``ground_s`` (truth height <= 0.5 m), ``impact_speed_ms`` (max GPS.VZ),
          ``roll_max_3s_deg``, ``armed_kept``, ``auto_kept``, ``err25_thrust_loss``,
          ``liftoff_1m_after_end_s``, ``above_10m_after_end_s``, ``auto_after_end`` (mode at
          10 m), ``path_after_10m_m`` (truth path in the 30 s after reaching 10 m: a resumed
          mission flies ~6 m/s).
        * compass: ``health0_lost_s`` / ``health0_back_s`` (MAG I=0 Health 0 after the start,
          1 after the end; seconds after the start), ``mag0_frozen_std`` (largest std of its
          MagX/Y/Z from 1 s after the start), ``mag_others_healthy_frac``, ``err3_4_s`` /
          ``err3_0_s``, ``switch_compass_s`` / ``switch_compass_to`` (first XKFS row with
          MI != 0), ``err24_ekf_primary``, ``sm_max`` (XKF4.SM), ``ekf_err_max_m``,
          ``auto_kept``.
        * rc: ``rtl_delay_s`` (first MODE RTL), ``rtl_reason`` (its Rsn), ERR counts
          ``err2_2_late_frame``, ``err5_1_failsafe`` (in the window), ``err5_0_cleared`` (2 s
          after the end), ``rtl_kept_after_end``, ``disarm_s``, ``final_home_dist_m`` (truth at
          disarming).
    """
    kind = fault["type"]
    if kind not in FAULT_TYPES:
        raise ValueError(f"unknown fault type {kind!r}; expected one of {FAULT_TYPES}")
    t0, t1 = float(fault["start_time_us"]), float(fault["end_time_us"])
    if not t1 > t0:
        raise ValueError(f"fault window must have end_time_us > start_time_us, got {t0}..{t1}")
    f = _Flight(tables)
    if kind == "gps":
        return _gps(f, t0, t1)
    if kind == "accel":
        return _accel(f, t0, t1, fault)
    if kind == "engine":
        return _engine(f, t0, t1)
    if kind == "compass":
        return _compass(f, t0, t1)
    return _rc(f, t0, t1)
