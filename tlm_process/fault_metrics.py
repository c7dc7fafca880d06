"""Fault signature metrics: what each built-in fault type does to a flight, as numbers.

:func:`tlm_process.fault_signatures.fault_signature` measures one fault window with the
metric function of the fault's type (the ``signature`` of its record,
:mod:`tlm_process.fault_types`); the built-in types' functions are here (``gps_metrics`` ...
``prop_damage_metrics``), with :class:`Flight`, the log's shared time lines a new type's
metrics build on. All take ``(flight, start_time_us, end_time_us, fault, route)``.

They measure the same way in a tlm ``FlightLog.tables`` and
in the tables ``read_bin`` gives for a genuine SITL ``.bin``. They use only messages and fields
that both logs have: GPS, IMU, CTUN, XKF1, SIM (the simulator's true attitude and position),
MODE, EV and ERR, and for the catalogue's faults BARO, MAG, XKF4, XKFS, VIBE, BAT, RCOU and
the mission's CMD (route deviation). SITL's SIM2 and MSG are not used.

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

Metrics by fault type
---------------------

* gps: ``nofix_frac_in/out`` (GPS rows with Status < 3), ``nsats_max_in``,
  ``nsats_min_out``, ``ekf_err_max_m`` and ``ekf_err_at_end_m`` (primary XKF1 vs truth),
  ``ekf_recovered_after_end_s`` (back within 5 m), ``speed_max_ms``, ``roll_max_deg``,
  ``pitch_max_deg``, ``baro_alt_range_m`` (CTUN.BAlt), ``auto_kept``,
  ``path_after_end_m`` (truth path in the 30 s after the end).
* accel: ``imu<i>_stuck_frac_in/out`` (rows with AccX = AccY = AccZ = the fail value),
  ``climb_3s_m``, ``climb_max_m``, ``drop_max_m`` (relative to the height at the start),
  ``thr_max_3s`` (CTUN.ThO), ``roll_max_deg``, ``pitch_max_deg``, ERR counts
  ``err24_ekf_primary``, ``err29_vibe_fs``, ``err25_thrust_loss``, ``auto_kept``,
  ``settle_roll_max_deg`` (10-20 s after the end, the true roll beyond what the mission
  path asks for: see "Settling" below).
* engine: ``ground_s`` (truth height <= 0.5 m), ``impact_speed_ms`` (max GPS.VZ),
  ``roll_max_3s_deg``, ``armed_kept``, ``auto_kept``, ``err25_thrust_loss``,
  ``liftoff_1m_after_end_s``, ``above_10m_after_end_s``, ``auto_after_end`` (mode at
  10 m), ``path_after_10m_m`` (truth path in the 30 s after reaching 10 m: a resumed
  mission flies ~6 m/s).
* rc: ``rtl_delay_s`` (first MODE RTL), ``rtl_reason`` (its Rsn), ERR counts
  ``err2_2_late_frame``, ``err5_1_failsafe`` (in the window), ``err5_0_cleared`` (2 s
  after the end), ``rtl_kept_after_end``, ``disarm_s``, ``final_home_dist_m`` (truth at
  disarming).
* gyro (accel_samples the same with ``ah``/AccX-Z): per masked IMU i
  ``imu<i>_gh_drop_s`` / ``imu<i>_gh_restore_s`` (first IMU row with GH 0 in the
  window, first with GH 1 after it), ``imu<i>_std_in`` / ``imu<i>_std_before`` (largest
  gyro-axis standard deviation in the window after the edge margin / the 20 s before:
  0 when frozen); per other IMU ``imu<i>_healthy_frac_in``; ``err24_ekf_primary`` and
  ``lane_changes`` (XKF4.PI changes of core 0) from the start to 60 s after the end,
  ``ekf_err_max_m``, ``roll_max_deg``, ``auto_kept``.
* baro: ``baro_h_drop_s`` (first BARO.H 0 of the disabled baros),
  ``baro_h_restore_s`` (the last of them back to 1), ``err18_4_s``, ``err18_0_s``,
  ``alt_invalid_s`` (first CTUN.Alt 0.00: EKF3's height relative to the origin is
  invalid), ``climb_m`` (max true height in the window minus the start height),
  ``climb_rate_max_ms`` (true, over 0.5 s), ``thr_mean_before`` (20 s) /
  ``thr_mean_in`` (CTUN.ThO), ``descent_rate_max_ms`` (60 s after the end),
  ``back_after_end_s`` (back within 1.5 m of the start height, from 1 s after the
  end), ``route_dev_max_m`` (truth from the mission line, to 5 s after the end),
  ``auto_kept`` (to 60 s after the end).
* compass: per failed compass i ``mag<i>_health_drop_s`` / ``mag<i>_health_restore_s``
  (MAG.Health), ``mag<i>_std_in`` (largest MagX/Y/Z standard deviation after the drop:
  0 when no data or frozen); per other compass ``mag<i>_healthy_frac_in``;
  ``err3_4_s``, ``err3_0_s``, ``err24_ekf_primary``, ``lane_changes``, ``sm_max``
  (XKF4.SM), ``ekf_err_max_m``, ``auto_kept``, ``switch_compass_s`` /
  ``switch_compass_to`` (first XKFS row whose compass index MI is not a failed one).
* gps_glitch: ``gps_offset_n_m`` / ``gps_offset_e_m`` / ``gps_offset_m`` (mean logged
  GPS minus truth with a fix, from 1 s after the start), ``err24_first_s`` (first lane
  switch), ``err11_2_s`` ("GPS Glitch or Compass error"), ``err11_0_s`` ("Glitch
  cleared", after it), ``ekf_err_max_m``, ``route_dev_max_m`` (truth from the mission
  line in the window), ``err11_2_after_end_s`` / ``err11_0_after_end_s`` (the same
  after the clear, within 60 s), ``ekf_err_max_after_end_m`` (30 s),
  ``lane_changes`` (start to 30 s after the end), ``auto_kept``.
* motor_partial: ``thr_mean_in`` (CTUN.ThO), ``rcou_failed_mean`` (RCOU of the
  SIM_ENGINE_FAIL motors), ``err25_s`` (first thrust loss), ``ground_s``,
  ``impact_speed_ms`` (max GPS.VZ to 1 s after the ground), ``roll_max_deg`` (before
  the ground), ``armed_kept``, ``auto_kept``, ``liftoff_1m_after_end_s``,
  ``above_10m_after_end_s``.
* vibration: per IMU i ``vibe<i>_mean`` / ``vibe<i>_max`` (VIBE X, Y, Z in the window),
  ``vibe<i>_before_max`` (20 s before), ``clip<i>_in`` (clipping count added in the
  window); ``accz_std_before`` / ``accz_std_in`` (IMU 0 AccZ at 25 Hz),
  ``thr_mean_in``, ``err29_vibe_fs``, ``ekf_err_max_m``, ``auto_kept``.
* battery: ``volt_before`` / ``volt_in`` (from 1 s in) / ``volt_after`` (5-25 s after)
  (BAT.Volt), ``thr_before`` (20 s) / ``thr_in`` (from 3 s in) / ``thr_after`` (5-25 s
  after) (CTUN.ThO), ``err6_1_s`` (battery failsafe), ``err6_0_after_end`` (count, 60 s),
  ``auto_kept``.
* gps_jam: ``nofix_frac`` (share of GPS rows in the jam window with Status < 3),
  ``gps_truth_med_m`` / ``gps_truth_max_m`` (GPS minus truth, every GPS row in the window),
  ``err11_2_s`` (first "GPS Glitch" ERR after the start), ``offroute_max_m`` (truth from the
  route lines, to ``JAM_AFTER_S`` after the end), ``fix_frac_in`` / ``fix_frac_out`` (GPS
  rows with Status >= 3; out: armed, before the start or 10 s after the end),
  ``nsats_min_in``, ``nsats_max_in``, ``hdop_max_in``, ``ekf_err_max_m``, ``auto_kept``.
* prop_damage (tlm's own type): ``rcou_excess_before_us`` / ``rcou_excess_in_us`` (the
  imbalanced motor's RCOU less the motors' mean, 20 s before / from 3 s in),
  ``accxy_std_before`` / ``accxy_std_in`` (IMU 0 AccX, AccY, the larger),
  ``vibexy_before`` / ``vibexy_in`` (VIBE X and Y of IMU 0), ``thr_mean_in``, ``armed_kept``,
  ``auto_kept``.
  Jamming is random: its metrics are judged over seeds (``tlm crosscheck --seeds``).

Settling
--------

``settle_roll_max_deg`` asks whether the copter flies its mission normally again 10-20 s after
the accelerometer fault ("stable again within a few seconds"). It is the largest distance, in
that window, of the true roll (SIM.Roll) from the roll the mission path itself asks for: the
position controller's feed-forward acceleration (PSCN.DAN / PSCE.DAE, the path's acceleration
before any correction of position or velocity errors) projected on the vehicle's right axis at
the true yaw, as atan(a_right / g), with a timing tolerance of :data:`PATH_LAG_S` (the roll may
match any path roll of the +-0.3 s around it). On a straight leg the path asks for no roll and
the metric is max |roll|, as before; in a corner the path asks for the turn's bank (up to
~16 deg on the reference routes) and only the roll beyond it counts.

Why: the two flights are at different points of their route in that window. tlm gains ~3 s
on SITL during the fault (0.45 s ahead at its start, 3.4 s after it), so in accel_s13 tlm
turns a 98 deg corner 18-20 s after the end and SITL 21-24 s after it; a plain max |roll|
compared tlm's bank with SITL's straight flight (17 vs 0.24 deg) although both had settled.
A copter still swinging is still caught: the swing is not in the path's feed-forward (it comes
from the corrections of position and velocity errors), so a +-30 deg oscillation scores
~30 deg on a straight leg and in a turn alike. The tolerance: on the route legs of SITL's
reference flights the roll follows the path's demand within 0.1 s (at most 0.9 deg beyond it);
tlm's corner exits level the roll up to 0.3 s before the feed-forward ends (tlm's normal_s11:
1.8 deg beyond at 0.3 s, 2.4 at 0.1 s), a cornering difference of tlm that is not the
settling this metric is about, and far shorter than a swing (~1.4 s period during the fault).
Limit: the path's feed-forward has no drag-compensating tilt, so where the vehicle does not
face its direction of travel (AUTO's final RTL leg: 13-15 deg) the drag lean is counted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.reference import time_window
from tlm_sim import ardupilot as AP
from tlm_sim.ardupilot import GRAVITY_MSS
from tlm_sim.geo import latlon_to_ne

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
#: the accel fault's settling window, seconds after its end
SETTLE_FROM_S, SETTLE_TO_S = 10.0, 20.0
#: timing tolerance between the true roll and the roll the path asks for [s] (see the
#: module docstring, "Settling")
PATH_LAG_S = 0.3
#: a PSCN/PSCE row older than this no longer gives the path's acceleration [s]
PSC_MAX_AGE_S = 0.25

#: The log messages :func:`fault_signature` reads (``read_bin(path, SIGNATURE_MESSAGES)``).
SIGNATURE_MESSAGES = ("GPS", "IMU", "CTUN", "XKF1", "XKF4", "XKFS", "SIM", "MODE", "EV", "ERR",
                      "BARO", "MAG", "BAT", "RCOU", "VIBE", "CMD", "PSCN", "PSCE")
#: seconds before a fault over which "before" baselines are measured
BEFORE_S = 20.0
#: seconds after a fault's end over which recoveries (lane switches, glitch, descent) are seen
AFTER_S = 60.0
#: how long after a GPS jam the truth's distance from the route still counts [s]
JAM_AFTER_S = 30.0
#: height difference from the start height within which the vehicle counts as back [m]
BACK_M = 1.5


def _max(s: pd.Series) -> float:
    return float(s.max()) if len(s) else float("nan")


class Flight:
    """Shared time lines of one log: arming, truth height and position, EKF position, modes.

    Attributes (times are log TimeUS [us]): ``t`` the tables by message name, ``arm_us`` /
    ``disarm_us`` (NaN if none), ``home_alt`` (truth altitude AMSL before arming [m]),
    ``home`` (lat, lon [deg]), ``sim_t`` the SIM rows' times with the truth ``h`` (height
    above home [m]), ``roll`` / ``pitch`` / ``yaw`` [deg] and ``n`` / ``e`` (north / east of
    home [m]); ``mode_t`` / ``mode`` / ``mode_rsn`` the MODE rows; ``err`` the ERR table.
    """

    def __init__(self, tables: Mapping[str, pd.DataFrame]):
        self.t = tables
        ev = tables["EV"]
        armed = ev[ev.Id == AP.EV_ARMED].TimeUS
        self.arm_us = float(armed.iloc[0]) if len(armed) else float("nan")
        disarm = ev[(ev.Id == AP.EV_DISARMED) & (ev.TimeUS > self.arm_us)].TimeUS
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
        self.yaw = sim.Yaw.to_numpy(float)
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

    def path_roll(self) -> np.ndarray:
        """Roll [deg] the mission path asks for at each SIM row: the position controller's
        feed-forward acceleration (PSCN.DAN, PSCE.DAE: the path's own acceleration, without the
        corrections for position and velocity errors) on the vehicle's right axis at the true
        yaw, as atan(a_right / g). 0 where no PSCN/PSCE row is less than PSC_MAX_AGE_S old (no
        position control, or a log without them)."""
        out = np.zeros(len(self.sim_t))
        pn, pe = self.t.get("PSCN"), self.t.get("PSCE")
        if pn is None or pe is None or not len(pn) or not len(pe):
            return out
        acc = []
        for tab, col in ((pn, "DAN"), (pe, "DAE")):
            tab = tab.sort_values("TimeUS")
            tt = tab.TimeUS.to_numpy(float)
            i = np.searchsorted(tt, self.sim_t, side="right") - 1
            ok = (i >= 0) & (self.sim_t - tt[np.maximum(i, 0)] <= PSC_MAX_AGE_S * 1e6)
            acc.append(np.where(ok, tab[col].to_numpy(float)[np.maximum(i, 0)], 0.0))
        yaw = np.radians(self.yaw)
        a_right = -np.sin(yaw) * acc[0] + np.cos(yaw) * acc[1]
        return np.degrees(np.arctan2(a_right, GRAVITY_MSS))

    def roll_beyond_path(self) -> np.ndarray:
        """|roll| beyond what the path asks for [deg] at each SIM row: the distance of the
        true roll from the range of :meth:`path_roll` within +-PATH_LAG_S (0 inside it)."""
        ff = self.path_roll()
        if len(ff) < 2:
            return np.abs(self.roll - ff)
        k = max(0, int(round(PATH_LAG_S * 1e6 / np.median(np.diff(self.sim_t)))))
        padded = np.pad(ff, k, mode="edge")
        win = np.lib.stride_tricks.sliding_window_view(padded, 2 * k + 1)
        lo, hi = win.min(axis=1), win.max(axis=1)
        return np.maximum(np.maximum(lo - self.roll, self.roll - hi), 0.0)

    def primary_lane(self, t: np.ndarray) -> np.ndarray:
        """EKF primary core at times t: 0 until an ERR 24 (EKF_PRIMARY) names another lane."""
        e = self.err[self.err.Subsys == AP.ERR_EKF_PRIMARY].sort_values("TimeUS")
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

    def vertical_speed(self) -> np.ndarray:
        """True climb rate [m/s, up positive] at each SIM row (backward difference over
        SPEED_BASE_S)."""
        dt = np.median(np.diff(self.sim_t)) if len(self.sim_t) > 1 else 1e5
        k = max(1, int(round(SPEED_BASE_S * 1e6 / dt)))
        v = np.full(len(self.sim_t), np.nan)
        v[k:] = (self.h[k:] - self.h[:-k]) / ((self.sim_t[k:] - self.sim_t[:-k]) * 1e-6)
        return v

    def route_distance(self, route: np.ndarray | None, t0: float, t1: float) -> float:
        """Largest horizontal distance [m] of the truth in [t0, t1] from the polyline through
        ``route`` (lat, lon rows: the mission's waypoints); NaN without a route."""
        m = self.sel(t0, t1)
        if route is None or len(route) < 2 or not m.any():
            return float("nan")
        rn, re_ = latlon_to_ne(route[:, 0], route[:, 1], *self.home)
        a = np.column_stack([rn, re_])
        p = np.column_stack([self.n[m], self.e[m]])
        seg = a[1:] - a[:-1]
        best = np.full(len(p), np.inf)
        for k in range(len(seg)):
            ll = float(seg[k] @ seg[k])
            u = np.clip(((p - a[k]) @ seg[k]) / ll, 0.0, 1.0) if ll > 0 else np.zeros(len(p))
            d = np.hypot(*(p - a[k] - u[:, None] * seg[k]).T)
            best = np.minimum(best, d)
        return float(best.max())

    # --- events ------------------------------------------------------------------------------
    def first_err(self, subsys: int, code: int | None, t0: float, t1: float = np.inf) -> float:
        """TimeUS of the first ERR row of ``subsys`` (and ``code``) in [t0, t1], NaN if none."""
        e = self.err[(self.err.Subsys == subsys) & (self.err.TimeUS >= t0)
                     & (self.err.TimeUS <= t1)]
        if code is not None:
            e = e[e.ECode == code]
        return float(e.TimeUS.min()) if len(e) else float("nan")

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


def _gps1(f: Flight) -> pd.DataFrame:
    """The GPS rows of the first receiver."""
    gps = f.t["GPS"]
    return gps[gps.I == 0] if "I" in gps else gps


def _gps_rows(f: Flight, t0: float, t1: float, after_us: float
              ) -> tuple[pd.DataFrame, pd.DataFrame]:
    """GPS 1 rows inside the window (from the edge margin on) and the armed rows outside it
    (before ``t0`` or more than ``after_us`` after ``t1``)."""
    gps = _gps1(f)
    inside = time_window(gps, t0 + EDGE_MARGIN_S * 1e6, t1)
    armed = time_window(gps, f.arm_us, f.disarm_us if np.isfinite(f.disarm_us) else np.inf)
    return inside, armed[(armed.TimeUS < t0) | (armed.TimeUS > t1 + after_us)]


def gps_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                route: np.ndarray | None) -> dict[str, float]:
    inside, outside = _gps_rows(f, t0, t1, EDGE_MARGIN_S * 1e6)
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
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
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


def accel_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                  route: np.ndarray | None) -> dict[str, float]:
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
    settle = f.sel(t1 + SETTLE_FROM_S * 1e6, t1 + SETTLE_TO_S * 1e6)
    ctun = time_window(f.t["CTUN"], t0, t0 + EARLY_S * 1e6)
    out.update({
        "climb_3s_m": float(f.h[early].max() - h0),
        "climb_max_m": float(f.h[sel].max() - h0),
        "drop_max_m": float(h0 - f.h[sel].min()),
        "thr_max_3s": _max(ctun.ThO),
        "roll_max_deg": float(np.abs(f.roll[sel]).max()),
        "pitch_max_deg": float(np.abs(f.pitch[sel]).max()),
        "err24_ekf_primary": f.err_count(AP.ERR_EKF_PRIMARY, t0, t1),
        "err29_vibe_fs": f.err_count(AP.ERR_FAILSAFE_VIBE, t0, t1),
        "err25_thrust_loss": f.err_count(AP.ERR_THRUST_LOSS_CHECK, t0, t1),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
        "settle_roll_max_deg": float(f.roll_beyond_path()[settle].max()) if settle.any()
        else float("nan"),
    })
    return out


def engine_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                   route: np.ndarray | None) -> dict[str, float]:
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
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
        "err25_thrust_loss": f.err_count(AP.ERR_THRUST_LOSS_CHECK, t0, t1),
        "liftoff_1m_after_end_s": (up1 - t1) * 1e-6,
        "above_10m_after_end_s": (up10 - t1) * 1e-6,
        "auto_after_end": float(f.mode_at(up10) == AP.MODE_AUTO) if np.isfinite(up10) else 0.0,
        "path_after_10m_m": f.path_m(up10, up10 + RESUME_S * 1e6) if np.isfinite(up10)
        else 0.0,
    }


def rc_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
               route: np.ndarray | None) -> dict[str, float]:
    rtl = np.flatnonzero((f.mode_t >= t0) & (f.mode == AP.MODE_RTL))
    t_rtl = float(f.mode_t[rtl[0]]) if len(rtl) else float("nan")
    end = f.disarm_us if np.isfinite(f.disarm_us) else float(f.sim_t[-1])
    last = np.searchsorted(f.sim_t, end, side="right") - 1
    return {
        "rtl_delay_s": (t_rtl - t0) * 1e-6,
        "rtl_reason": float(f.mode_rsn[rtl[0]]) if len(rtl) else float("nan"),
        "err2_2_late_frame": f.err_count(AP.ERR_RADIO, t0, t1, AP.ERR_CODE_LATE_FRAME),
        "err5_1_failsafe": f.err_count(AP.ERR_FAILSAFE_RADIO, t0, t1, AP.ERR_CODE_FAILSAFE),
        "err5_0_cleared": f.err_count(AP.ERR_FAILSAFE_RADIO, t1, t1 + 2e6, AP.ERR_CODE_RESOLVED),
        "rtl_kept_after_end": f.mode_kept(AP.MODE_RTL, t1, end) if np.isfinite(t_rtl) else 0.0,
        "disarm_s": (f.disarm_us - t0) * 1e-6 if f.disarm_us >= t0 else float("nan"),
        "final_home_dist_m": float(np.hypot(f.n[last], f.e[last])),
    }


# --- the rest of SITL's catalogue (labels 5-13) ----------------------------------------------


def _rel_s(t_us: float, ref_us: float) -> float:
    """Seconds of ``t_us`` after ``ref_us`` (NaN stays NaN)."""
    return (t_us - ref_us) * 1e-6


def _instances(fault: Mapping[str, Any], names: Sequence[str], default: Sequence[int]
               ) -> list[int]:
    """Sensor instances a fault sets: instance k where ``params_start[names[k]]`` is non-zero."""
    ps = fault.get("params_start") or {}
    out = [k for k, n in enumerate(names) if ps.get(n)]
    return out or list(default)


def _mask_instances(fault: Mapping[str, Any], name: str, default: int = 1) -> list[int]:
    """Instances of the bits of a mask parameter (``SIM_GYR_FAIL_MSK`` 1 -> [0])."""
    v = int((fault.get("params_start") or {}).get(name, default))
    return [k for k in range(8) if v >> k & 1] or [0]


def _flag_times(d: pd.DataFrame, col: str, t0: float, t1: float) -> tuple[float, float]:
    """(first row in [t0, t1] where ``col`` is 0, first row after it where it is 1 again)
    as TimeUS, NaN where none."""
    inst = d.sort_values("TimeUS")
    down = inst[(inst.TimeUS >= t0) & (inst.TimeUS <= t1) & (inst[col] == 0)].TimeUS
    if not len(down):
        return float("nan"), float("nan")
    up = inst[(inst.TimeUS > down.iloc[0]) & (inst[col] != 0)].TimeUS
    return float(down.iloc[0]), float(up.iloc[0]) if len(up) else float("nan")


def _std3(d: pd.DataFrame, cols: Sequence[str]) -> float:
    """Largest standard deviation of ``cols`` (NaN for fewer than two rows)."""
    return float(max(d[c].std() for c in cols)) if len(d) > 1 else float("nan")


def _mean(s: pd.Series) -> float:
    return float(s.mean()) if len(s) else float("nan")


def _lane_changes(f: Flight, t0: float, t1: float) -> float:
    """Changes of the EKF primary core (``XKF4.PI`` of core 0) in [t0, t1]."""
    x = f.t.get("XKF4")
    if x is None or "PI" not in x:
        return float("nan")
    x = x[x.C == 0].sort_values("TimeUS") if "C" in x else x.sort_values("TimeUS")
    pi = x[x.TimeUS <= t1].PI.to_numpy(int)
    t = x[x.TimeUS <= t1].TimeUS.to_numpy(float)
    ch = np.flatnonzero(np.diff(pi) != 0) + 1
    return float(np.sum(t[ch] >= t0))


def _ekf_max(f: Flight, t0: float, t1: float) -> float:
    tp, err = f.ekf_error()
    w = (tp >= t0) & (tp <= t1)
    return float(err[w].max()) if w.any() else float("nan")


def _sample_loss(f: Flight, t0: float, t1: float, fault: Mapping[str, Any], mask: str,
                 flag: str, cols: Sequence[str]) -> dict[str, float]:
    """Gyro (``GH``, GyrX/Y/Z) or accelerometer (``AH``, AccX/Y/Z) sample loss."""
    imu = f.t["IMU"]
    m = EDGE_MARGIN_S * 1e6
    lost = _mask_instances(fault, mask)
    out: dict[str, float] = {}
    for i in lost:
        d = imu[imu.I == i]
        down, up = _flag_times(d, flag, t0, t1)
        out[f"imu{i}_{flag.lower()}_drop_s"] = _rel_s(down, t0)
        out[f"imu{i}_{flag.lower()}_restore_s"] = _rel_s(up, t0)
        out[f"imu{i}_std_in"] = _std3(time_window(d, t0 + m, t1), cols)
        out[f"imu{i}_std_before"] = _std3(time_window(d, t0 - BEFORE_S * 1e6, t0), cols)
    for i in sorted(set(imu.I.unique().astype(int)) - set(lost)):
        d = time_window(imu[imu.I == i], t0, t1)
        out[f"imu{i}_healthy_frac_in"] = float((d[flag] != 0).mean()) if len(d) else \
            float("nan")
    sel = f.sel(t0, t1)
    out.update({
        "err24_ekf_primary": f.err_count(AP.ERR_EKF_PRIMARY, t0, t1 + AFTER_S * 1e6),
        "lane_changes": _lane_changes(f, t0, t1 + AFTER_S * 1e6),
        "ekf_err_max_m": _ekf_max(f, t0, t1),
        "roll_max_deg": float(np.abs(f.roll[sel]).max()) if sel.any() else float("nan"),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    })
    return out


def gyro_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                 route: np.ndarray | None) -> dict[str, float]:
    """Gyro sample loss (``SIM_GYR_FAIL_MSK``: IMU.GH, GyrX/Y/Z)."""
    return _sample_loss(f, t0, t1, fault, "SIM_GYR_FAIL_MSK", "GH", ("GyrX", "GyrY", "GyrZ"))


def accel_samples_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                          route: np.ndarray | None) -> dict[str, float]:
    """Accelerometer sample loss (``SIM_ACC_FAIL_MSK``: IMU.AH, AccX/Y/Z)."""
    return _sample_loss(f, t0, t1, fault, "SIM_ACC_FAIL_MSK", "AH", ("AccX", "AccY", "AccZ"))


def baro_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                 route: np.ndarray | None) -> dict[str, float]:
    baro = f.t["BARO"]
    lost = _instances(fault, ("SIM_BARO_DISABLE", "SIM_BAR2_DISABLE"), (0, 1))
    downs, ups = [], []
    for i in lost:
        down, up = _flag_times(baro[baro.I == i], "H", t0, t1)
        downs.append(down)
        ups.append(up)
    ctun = f.t["CTUN"]
    inv = ctun[(ctun.TimeUS >= t0) & (ctun.TimeUS <= t1) & (ctun.Alt.abs() < 1e-3)].TimeUS
    sel = f.sel(t0, t1)
    h0 = float(f.h[sel][0]) if sel.any() else float("nan")
    vz = f.vertical_speed()
    after = f.sel(t1, t1 + AFTER_S * 1e6)
    back = f.first_time(np.abs(f.h - h0) <= BACK_M, t1 + 1e6)
    return {
        "baro_h_drop_s": _rel_s(min(downs), t0),
        "baro_h_restore_s": _rel_s(max(ups), t0),
        "err18_4_s": _rel_s(f.first_err(AP.ERR_BARO, AP.ERR_CODE_UNHEALTHY, t0, t1), t0),
        "err18_0_s": _rel_s(f.first_err(AP.ERR_BARO, AP.ERR_CODE_RESOLVED, t0), t0),
        "alt_invalid_s": _rel_s(float(inv.iloc[0]) if len(inv) else float("nan"), t0),
        "climb_m": float(f.h[sel].max() - h0) if sel.any() else float("nan"),
        "climb_rate_max_ms": float(np.nanmax(vz[sel])) if sel.any() else float("nan"),
        "thr_mean_before": _mean(time_window(ctun, t0 - BEFORE_S * 1e6, t0).ThO),
        "thr_mean_in": _mean(time_window(ctun, t0, t1).ThO),
        "descent_rate_max_ms": float(-np.nanmin(vz[after])) if after.any() else float("nan"),
        "back_after_end_s": _rel_s(back, t1),
        "route_dev_max_m": f.route_distance(route, t0, t1 + 5e6),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1 + AFTER_S * 1e6),
    }


def compass_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                    route: np.ndarray | None) -> dict[str, float]:
    mag = f.t["MAG"]
    m = EDGE_MARGIN_S * 1e6
    lost = _instances(fault, ("SIM_MAG1_FAIL", "SIM_MAG2_FAIL", "SIM_MAG3_FAIL"), (0,))
    out: dict[str, float] = {}
    for i in lost:
        d = mag[mag.I == i]
        down, up = _flag_times(d, "Health", t0, t1)
        out[f"mag{i}_health_drop_s"] = _rel_s(down, t0)
        out[f"mag{i}_health_restore_s"] = _rel_s(up, t0)
        out[f"mag{i}_std_in"] = _std3(time_window(d, down + m if np.isfinite(down) else t0 + m,
                                                  t1), ("MagX", "MagY", "MagZ"))
    for i in sorted(set(mag.I.unique().astype(int)) - set(lost)):
        d = time_window(mag[mag.I == i], t0, t1)
        out[f"mag{i}_healthy_frac_in"] = float((d.Health != 0).mean()) if len(d) else \
            float("nan")
    out.update({
        "err3_4_s": _rel_s(f.first_err(AP.ERR_COMPASS, AP.ERR_CODE_UNHEALTHY, t0, t1), t0),
        "err3_0_s": _rel_s(f.first_err(AP.ERR_COMPASS, AP.ERR_CODE_RESOLVED, t0), t0),
        "err24_ekf_primary": f.err_count(AP.ERR_EKF_PRIMARY, t0, t1),
        "lane_changes": _lane_changes(f, t0, t1 + AFTER_S * 1e6),
        "sm_max": _max(time_window(f.t["XKF4"], t0, t1).SM) if "XKF4" in f.t else float("nan"),
        "ekf_err_max_m": _ekf_max(f, t0, t1),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    })
    out.update(_compass_switch(f, t0, lost))
    return out


def _compass_switch(f: Flight, t0: float, lost: Sequence[int]) -> dict[str, float]:
    """When the EKF cores leave a failed compass: the first ``XKFS`` row after ``t0`` whose
    compass index ``MI`` is none of ``lost`` (s after t0), and that index (NaN when the log
    has no XKFS or no switch)."""
    xs = f.t.get("XKFS")
    if xs is None or not len(xs):
        return {"switch_compass_s": float("nan"), "switch_compass_to": float("nan")}
    xs = xs.sort_values("TimeUS", kind="stable")
    moved = xs[(xs.TimeUS > t0) & ~xs.MI.isin(list(lost))]
    if not len(moved):
        return {"switch_compass_s": float("nan"), "switch_compass_to": float("nan")}
    return {"switch_compass_s": _rel_s(float(moved.TimeUS.iloc[0]), t0),
            "switch_compass_to": float(moved.MI.iloc[0])}


def _gps_truth_offset(f: Flight, t0: float, t1: float) -> tuple[float, float]:
    """Mean (north, east) [m] of the logged GPS position minus the truth in [t0, t1]."""
    gps = _gps1(f)
    g = time_window(gps[gps.Status >= 3], t0, t1)
    if not len(g):
        return float("nan"), float("nan")
    n, e = latlon_to_ne(g.Lat.to_numpy(float), g.Lng.to_numpy(float), *f.home)
    tg = g.TimeUS.to_numpy(float)
    return (float(np.mean(np.asarray(n) - np.interp(tg, f.sim_t, f.n))),
            float(np.mean(np.asarray(e) - np.interp(tg, f.sim_t, f.e))))


def gps_glitch_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                       route: np.ndarray | None) -> dict[str, float]:
    on, on_end = t0 + 1e6, t1 + AFTER_S * 1e6
    dn, de = _gps_truth_offset(f, on, t1)
    g2 = f.first_err(AP.ERR_GPS, AP.ERR_CODE_GPS_GLITCH, t0, t1)
    g2_end = f.first_err(AP.ERR_GPS, AP.ERR_CODE_GPS_GLITCH, t1, on_end)
    return {
        "gps_offset_n_m": dn,
        "gps_offset_e_m": de,
        "gps_offset_m": float(np.hypot(dn, de)),
        "err24_first_s": _rel_s(f.first_err(AP.ERR_EKF_PRIMARY, None, t0, t1), t0),
        "err11_2_s": _rel_s(g2, t0),
        "err11_0_s": _rel_s(f.first_err(AP.ERR_GPS, AP.ERR_CODE_RESOLVED,
                                        g2 if np.isfinite(g2) else t0,
                                        t1), t0),
        "ekf_err_max_m": _ekf_max(f, t0, t1),
        "route_dev_max_m": f.route_distance(route, t0, t1),
        "err11_2_after_end_s": _rel_s(g2_end, t1),
        "err11_0_after_end_s": _rel_s(f.first_err(
            AP.ERR_GPS, AP.ERR_CODE_RESOLVED, g2_end if np.isfinite(g2_end) else t1, on_end), t1),
        "ekf_err_max_after_end_m": _ekf_max(f, t1, t1 + RESUME_S * 1e6),
        "lane_changes": _lane_changes(f, t0, t1 + RESUME_S * 1e6),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    }


def motor_partial_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                          route: np.ndarray | None) -> dict[str, float]:
    ground = f.first_time(f.h <= GROUND_H_M, t0, t1)
    fall_end = ground + 1e6 if np.isfinite(ground) else t1
    gps = time_window(f.t["GPS"], t0, fall_end)
    mask = int((fault.get("params_start") or {}).get("SIM_ENGINE_FAIL", 1))
    rcou = time_window(f.t["RCOU"], t0, t1)
    motors = [f"C{k + 1}" for k in range(8) if mask >> k & 1 and f"C{k + 1}" in rcou] or ["C1"]
    up1 = f.first_time(f.h > 1.0, t1)
    up10 = f.first_time(f.h > 10.0, t1)
    sel = f.sel(t0, ground if np.isfinite(ground) else t1)
    return {
        "thr_mean_in": _mean(time_window(f.t["CTUN"], t0, t1).ThO),
        "rcou_failed_mean": float(rcou[motors].to_numpy(float).mean()) if len(rcou)
        else float("nan"),
        "err25_s": _rel_s(f.first_err(AP.ERR_THRUST_LOSS_CHECK, None, t0, t1), t0),
        "ground_s": _rel_s(ground, t0),
        "impact_speed_ms": _max(gps.VZ),
        "roll_max_deg": float(np.abs(f.roll[sel]).max()) if sel.any() else float("nan"),
        "armed_kept": 1.0 - f.disarmed_in(t0, t1),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
        "liftoff_1m_after_end_s": _rel_s(up1, t1),
        "above_10m_after_end_s": _rel_s(up10, t1),
    }


def vibration_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                      route: np.ndarray | None) -> dict[str, float]:
    vibe = f.t["VIBE"]
    out: dict[str, float] = {}
    for i in sorted(vibe.IMU.unique().astype(int)):
        d = vibe[vibe.IMU == i]
        w = time_window(d, t0, t1)
        axes = w[["VibeX", "VibeY", "VibeZ"]].to_numpy(float)
        out[f"vibe{i}_mean"] = float(axes.mean()) if len(w) else float("nan")
        out[f"vibe{i}_max"] = float(axes.max()) if len(w) else float("nan")
        b = time_window(d, t0 - BEFORE_S * 1e6, t0)
        out[f"vibe{i}_before_max"] = float(b[["VibeX", "VibeY", "VibeZ"]].to_numpy(float).max()
                                           ) if len(b) else float("nan")
        out[f"clip{i}_in"] = float(w.Clip.max() - w.Clip.min()) if len(w) else float("nan")
    imu = f.t["IMU"]
    imu0 = imu[imu.I == 0]
    ctun = f.t["CTUN"]
    out.update({
        "accz_std_before": float(time_window(imu0, t0 - BEFORE_S * 1e6, t0).AccZ.std()),
        "accz_std_in": float(time_window(imu0, t0, t1).AccZ.std()),
        "thr_mean_in": _mean(time_window(ctun, t0, t1).ThO),
        "err29_vibe_fs": f.err_count(AP.ERR_FAILSAFE_VIBE, t0, t1),
        "ekf_err_max_m": _ekf_max(f, t0, t1),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    })
    return out


def prop_damage_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                        route: np.ndarray | None) -> dict[str, float]:
    """A damaged propeller (``prop_damage``): the imbalanced motor's excess output over the
    frame's mean [us] before and in the fault (its thrust loss), the in-plane accel and VIBE
    before and in it (the imbalance turns in the body x-y plane), and whether the mission
    went on."""
    motor = int((fault.get("params_start") or {}).get("TLM_VIB_IMB_MOT", 1))
    rcou = f.t["RCOU"]
    cols = [c for c in (f"C{k}" for k in range(1, 9)) if c in rcou and rcou[c].max() > 0]

    def excess(w: pd.DataFrame) -> float:
        if not len(w) or f"C{motor}" not in cols:
            return float("nan")
        out = w[cols].to_numpy(float)
        return float((out[:, cols.index(f"C{motor}")] - out.mean(axis=1)).mean())

    before = (t0 - BEFORE_S * 1e6, t0)
    inside = (t0 + EARLY_S * 1e6, t1)
    imu0 = f.t["IMU"][f.t["IMU"].I == 0]
    vibe = f.t["VIBE"]
    vibe0 = vibe[vibe.IMU == 0] if "IMU" in vibe else vibe
    out = {
        "rcou_excess_before_us": excess(time_window(rcou, *before)),
        "rcou_excess_in_us": excess(time_window(rcou, *inside)),
        "accxy_std_before": _std3(time_window(imu0, *before), ("AccX", "AccY")),
        "accxy_std_in": _std3(time_window(imu0, *inside), ("AccX", "AccY")),
    }
    for when, (a, b) in (("before", before), ("in", inside)):
        w = time_window(vibe0, a, b)
        out[f"vibexy_{when}"] = float(w[["VibeX", "VibeY"]].to_numpy(float).mean()) if len(w) \
            else float("nan")
    out.update({
        "thr_mean_in": _mean(time_window(f.t["CTUN"], *inside).ThO),
        "armed_kept": 1.0 - f.disarmed_in(t0, t1),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    })
    return out


def battery_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                    route: np.ndarray | None) -> dict[str, float]:
    bat = f.t["BAT"]
    ctun = f.t["CTUN"]
    on = t0 + EARLY_S * 1e6
    return {
        "volt_before": _mean(time_window(bat, t0 - BEFORE_S * 1e6, t0).Volt),
        "volt_in": _mean(time_window(bat, t0 + 1e6, t1).Volt),
        "volt_after": _mean(time_window(bat, t1 + 5e6, t1 + 25e6).Volt),
        "thr_before": _mean(time_window(ctun, t0 - BEFORE_S * 1e6, t0).ThO),
        "thr_in": _mean(time_window(ctun, on, t1).ThO),
        "thr_after": _mean(time_window(ctun, t1 + 5e6, t1 + 25e6).ThO),
        "err6_1_s": _rel_s(f.first_err(AP.ERR_FAILSAFE_BATT, AP.ERR_CODE_FAILSAFE, t0, t1), t0),
        "err6_0_after_end": f.err_count(AP.ERR_FAILSAFE_BATT, t1, t1 + AFTER_S * 1e6,
                                        AP.ERR_CODE_RESOLVED),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    }


def _gps_truth_distance(f: Flight, t0: float, t1: float) -> np.ndarray:
    """Horizontal distance [m] of every GPS 1 row in [t0, t1] (with or without a fix) from the
    truth (SIM) at its time."""
    g = time_window(_gps1(f), t0, t1)
    n, e = latlon_to_ne(g.Lat.to_numpy(float), g.Lng.to_numpy(float), *f.home)
    tg = g.TimeUS.to_numpy(float)
    return np.hypot(np.asarray(n) - np.interp(tg, f.sim_t, f.n),
                    np.asarray(e) - np.interp(tg, f.sim_t, f.e))


def gps_jam_metrics(f: Flight, t0: float, t1: float, fault: Mapping[str, Any],
                    route: np.ndarray | None) -> dict[str, float]:
    inside, outside = _gps_rows(f, t0, t1, 10e6)
    window = time_window(_gps1(f), t0, t1)
    dist = _gps_truth_distance(f, t0, t1)
    return {
        "nofix_frac": float((window.Status < 3).mean()) if len(window) else float("nan"),
        "gps_truth_med_m": float(np.median(dist)) if len(dist) else float("nan"),
        "gps_truth_max_m": float(dist.max()) if len(dist) else float("nan"),
        "err11_2_s": _rel_s(f.first_err(AP.ERR_GPS, AP.ERR_CODE_GPS_GLITCH, t0, t1), t0),
        "offroute_max_m": f.route_distance(route, t0, t1 + JAM_AFTER_S * 1e6),
        "fix_frac_in": float((inside.Status >= 3).mean()) if len(inside) else float("nan"),
        "fix_frac_out": float((outside.Status >= 3).mean()) if len(outside) else float("nan"),
        "nsats_min_in": float(inside.NSats.min()) if len(inside) else float("nan"),
        "nsats_max_in": _max(inside.NSats),
        "hdop_max_in": _max(inside.HDop),
        "ekf_err_max_m": _ekf_max(f, t0, t1),
        "auto_kept": f.mode_kept(AP.MODE_AUTO, t0, t1),
    }


def route_from_tables(tables: Mapping[str, pd.DataFrame]) -> np.ndarray | None:
    """The mission's waypoints (lat, lon rows) from a log's CMD messages (the last upload's
    NAV_WAYPOINT items), None without CMD."""
    cmd = tables.get("CMD")
    if cmd is None or not len(cmd):
        return None
    last = cmd.sort_values("TimeUS").drop_duplicates("CNum", keep="last").sort_values("CNum")
    wp = last[(last.CId == AP.MAV_CMD_NAV_WAYPOINT) & (last.CNum > 0)]
    return wp[["Lat", "Lng"]].to_numpy(float) if len(wp) > 1 else None


def truth_timeline(tables: Mapping[str, pd.DataFrame]) -> pd.DataFrame:
    """The truth (SIM) as plotted next to a signature.

    Returns:
        DataFrame with TimeUS, ``h_m`` (height above home), ``roll_deg``, ``pitch_deg`` and
        ``speed_ms`` (true ground speed), one row per SIM row.
    """
    f = Flight(tables)
    return pd.DataFrame({"TimeUS": f.sim_t, "h_m": f.h, "roll_deg": f.roll,
                         "pitch_deg": f.pitch, "speed_ms": f.ground_speed()})
