"""Per-channel comparison of a tlm flight with a SITL log of the same scenario.

Both flights are aligned at arming (EV 10, or ``logread.arming_time_us``'s ARM or motor rule
for a log without it): ``t = TimeUS - armed`` on each side. Truth comes
from the SIM table on both sides (SITL logs its simulator state there; tlm logs its own).
Fault windows are each side's own (SITL: the sidecar/PARM times; tlm: its fault records).

Metrics (``crosscheck_metrics``), each ``{"tlm": x, "sitl": y}`` unless noted:

* ``flight_time_s``: armed time (EV 10 to the last EV 11).
* ``trajectory_rms_m`` (one number): RMS over tlm's armed true positions outside its fault
  windows of the horizontal distance to the nearest point of SITL's armed true path (SIM,
  densified to 0.25 m): path-based, so timing drift does not count twice.
  ``trajectory_rms_settled_m``: the same without the ``RECOVERY_S`` after each fault, when
  the vehicle flies back to its path from wherever the fault left it.
* ``altitude_rms_m`` / ``speed_rms_ms`` (one number each): RMS difference of the altitude
  above home (SIM) and the GPS ground speed on the common armed time base (10 Hz) outside
  fault windows; ``max_alt_m``, ``mean_speed_ms`` per side.
* ``hover_throttle``: the last learned CTUN.ThH while armed; ``cruise_throttle``.
* ``imu_acc_std`` / ``imu_gyr_std``: IMU0 AccZ [m/s/s] and GyrX [rad/s] standard deviation on
  the ground before arming (sensor noise) and ``imu_acc_psd_*``: Welch power of IMU0 AccZ in
  cruise in three bands of the 25 Hz log (0-2, 2-6, 6-12.5 Hz) [(m/s/s)^2].
* ``vibe_x/y/z``: mean VIBE of IMU0 in cruise [m/s/s].
* ``att_roll_mean_deg`` / ``att_roll_std_deg`` / ``att_pitch_mean_deg`` /
  ``att_pitch_std_deg``: ATT roll and pitch in cruise outside fault windows [deg]: what wind
  and turbulence do to the attitude (SITL's normal_wind_s41: roll std 3.7 deg against 2.5 in
  calm normal_s11, pitch mean -8.4 deg with std 6.6 against -6.4 / 2.5; the cruise span
  includes the turns and the return).
* ``rate_err_roll/pitch/yaw``: RMS of RATE.xDes - x in cruise [deg/s].
* ``gps_status_ok``: share of armed GPS rows with Status >= 3; ``gps_nsats`` / ``gps_hdop``:
  medians with a fix.
* ``faults``: one entry per fault: type, label, ``tlm_process.fault_signatures`` metrics for
  both sides (``tlm``, ``sitl``; empty for a type it does not measure) and ``rows``
  (:func:`signature_rows`: each metric's relative difference and pass/fail), ``passed`` /
  ``compared``.

Signature pass/fail (:func:`signature_rows`): a metric passes when tlm is within
:data:`SIGNATURE_REL_TOL` (35 %, issue 19) of SITL's value, or within an absolute floor for
values near zero (:data:`SIGNATURE_FLOORS`, by the metric's unit suffix: 0.25 s, 1 m,
0.25 m/s, 2 deg, 0.02 for fractions, 0.001 for standard deviations, else 0.01); flags
(``*_kept``, ``auto_after_end``, ``rtl_reason``, NSats) must be equal; ERR counts compare
presence (both > 0 or both 0); both NaN (neither log has the event) passes, one NaN fails.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy.signal import welch
from scipy.spatial import cKDTree

from tlm_process.reference import time_window

__all__ = ["crosscheck_metrics", "armed_span_us", "true_ne", "PSD_BANDS", "signature_rows",
           "SIGNATURE_REL_TOL", "SIGNATURE_FLOORS"]

ARMED, DISARMED, AUTO = 10, 11, 3
PSD_BANDS = ((0.0, 2.0), (2.0, 6.0), (6.0, 12.5))
#: Seconds after a fault's end left out of ``trajectory_rms_settled_m``.
RECOVERY_S = 30.0
#: A signature metric passes within this fraction of SITL's value (issue 19: 35 %).
SIGNATURE_REL_TOL = 0.35
#: ... or within this absolute difference, by the metric name's suffix (first match).
SIGNATURE_FLOORS: tuple[tuple[str, float], ...] = (
    ("_ms", 0.25), ("_s", 0.25), ("_m", 1.0), ("_deg", 2.0), ("_before", 0.001),
    ("_std_in", 0.001), ("frac_in", 0.02), ("frac_out", 0.02), ("", 0.01))
#: Metrics that must be equal (besides ``*_kept``).
SIGNATURE_EXACT = frozenset({"rtl_reason", "auto_after_end", "nsats_max_in", "nsats_min_out"})


def _is_count(metric: str) -> bool:
    return metric.startswith("err") and not metric.endswith("_s")


def _floor(metric: str) -> float:
    if "std" in metric:
        return 0.001
    return next(v for suffix, v in SIGNATURE_FLOORS if metric.endswith(suffix))


def signature_rows(tlm: Mapping[str, float], sitl: Mapping[str, float],
                   rel_tol: float = SIGNATURE_REL_TOL) -> list[dict[str, Any]]:
    """One row per SITL signature metric: ``metric``, ``tlm``, ``sitl``, ``rel_diff``
    (|tlm - SITL| / |SITL|, NaN where SITL is 0 or either is NaN) and ``pass`` (see the module
    docstring)."""
    rows = []
    for k, b in sitl.items():
        a = tlm.get(k, float("nan"))
        a, b = float(a), float(b)
        nan_a, nan_b = np.isnan(a), np.isnan(b)
        rel = abs(a - b) / abs(b) if not (nan_a or nan_b) and b != 0 else float("nan")
        if nan_a or nan_b:
            ok = nan_a and nan_b
        elif _is_count(k):
            ok = (a > 0) == (b > 0)
        elif k.endswith("_kept") or k in SIGNATURE_EXACT:
            ok = a == b
        else:
            ok = abs(a - b) <= max(rel_tol * abs(b), _floor(k))
        rows.append({"metric": k, "tlm": a, "sitl": b, "rel_diff": rel, "pass": bool(ok)})
    return rows


def armed_span_us(tables: Mapping[str, pd.DataFrame]) -> tuple[float, float]:
    """(arming, last EV 11 after it) TimeUS [µs]: the arming time of
    :func:`tlm_process.logread.arming_time_us` (the first EV 10, else ARM ArmState 1, else
    the motor outputs of a log that starts at arming); the end: the last EV 11 after it, else
    the first ARM ArmState 0 after it, else the last GPS row.

    Raises:
        ValueError: the log never armed.
    """
    from tlm_process.logread import arming_time_us, disarm_time_us

    a_us, how = arming_time_us(dict(tables))
    if a_us is None:
        raise ValueError(f"the log never armed ({how}: no EV 10, ARM or motor output rise)")
    a = float(a_us)
    ev = tables.get("EV")
    d = ev[(ev.Id == DISARMED) & (ev.TimeUS > a)].TimeUS if ev is not None and len(ev) \
        else pd.Series([], dtype=float)
    if len(d):
        return a, float(d.iloc[-1])
    end, how = disarm_time_us({"ARM": tables["ARM"]} if "ARM" in tables else {}, None, a_us)
    return a, float(end) if how.startswith("ARM") else float(tables["GPS"].TimeUS.max())


def true_ne(sim: pd.DataFrame, home: Sequence[float]) -> np.ndarray:
    """SIM truth as [t_us, north_m, east_m, alt_above_home_m] rows."""
    from tlm_sim.geo import latlon_to_ne

    n, e = latlon_to_ne(sim.Lat.to_numpy(float), sim.Lng.to_numpy(float), home[0], home[1])
    return np.column_stack([sim.TimeUS.to_numpy(float), n, e, sim.Alt.to_numpy(float) - home[2]])


def _outside(t_us: np.ndarray, windows: Sequence[tuple[float, float]]) -> np.ndarray:
    keep = np.ones(len(t_us), dtype=bool)
    for a, b in windows:
        keep &= ~((t_us >= a) & (t_us <= b))
    return keep


def _densify(path: np.ndarray, step: float = 0.25) -> np.ndarray:
    """Points along the polyline ``path`` [N, 2] at most ``step`` metres apart."""
    if len(path) < 2:
        return path
    seg = np.diff(path, axis=0)
    n = np.maximum(1, np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / step).astype(int))
    pieces = [path[k] + seg[k] * (np.arange(n[k])[:, None] / n[k]) for k in range(len(seg))]
    return np.vstack([*pieces, path[-1:]])


def _windows(faults: Sequence[Mapping[str, Any]], end_us: float) -> list[tuple[float, float]]:
    return [(float(f["start_time_us"]), float(f["end_time_us"]) if f.get("end_time_us")
             is not None else end_us) for f in faults if f.get("start_time_us") is not None]


def _cruise(tables: Mapping[str, pd.DataFrame], span: tuple[float, float]) -> tuple[float, float]:
    mode = tables["MODE"]
    auto = mode[(mode.ModeNum == AUTO) & (mode.TimeUS >= span[0] - 1e6)]
    c0 = float(auto.TimeUS.iloc[0]) + 20e6 if len(auto) else span[0] + 30e6
    return c0, span[1] - 60e6


def _side(tables: Mapping[str, pd.DataFrame], home: Sequence[float],
          windows: list[tuple[float, float]]) -> dict[str, Any]:
    span = armed_span_us(tables)
    c0, c1 = _cruise(tables, span)
    out: dict[str, Any] = {"span": span}
    truth = true_ne(time_window(tables["SIM"], *span), home)
    out["truth"] = truth
    out["outside"] = _outside(truth[:, 0], windows)
    gps = tables["GPS"]
    out["gps"] = time_window(gps, *span)
    ctun = time_window(tables["CTUN"], *span)
    out["hover_throttle"] = float(ctun.ThH.iloc[-1]) if len(ctun) else float("nan")
    out["cruise_throttle"] = float(time_window(ctun, c0, c1).ThO.median())
    imu = tables["IMU"]
    imu0 = imu[imu.I == 0]
    ground = time_window(imu0, span[0] - 8e6, span[0] - 0.5e6)
    out["imu_acc_std"] = float(ground.AccZ.std())
    out["imu_gyr_std"] = float(ground.GyrX.std())
    cr = time_window(imu0, c0, c1)
    cr = cr[_outside(cr.TimeUS.to_numpy(float), windows)]
    if len(cr) > 256:
        f, p = welch(cr.AccZ.to_numpy(float) - cr.AccZ.mean(), fs=25.0, nperseg=256)
        out["psd"] = (f, p)
        for lo, hi in PSD_BANDS:
            sel = (f >= lo) & (f < hi) if hi < 12.5 else (f >= lo)
            out[f"imu_acc_psd_{lo:g}_{hi:g}hz"] = float(np.trapezoid(p[sel], f[sel]))
    vibe = time_window(tables["VIBE"], c0, c1)
    vibe = vibe[(vibe.IMU == 0) & _outside(vibe.TimeUS.to_numpy(float), windows)]
    for ax in "XYZ":
        out[f"vibe_{ax.lower()}"] = float(vibe[f"Vibe{ax}"].mean())
    att = time_window(tables["ATT"], c0, c1)
    att = att[_outside(att.TimeUS.to_numpy(float), windows)]
    for ax in ("Roll", "Pitch"):
        out[f"att_{ax.lower()}_mean_deg"] = float(att[ax].mean())
        out[f"att_{ax.lower()}_std_deg"] = float(att[ax].std())
    rate = time_window(tables["RATE"], c0, c1)
    rate = rate[_outside(rate.TimeUS.to_numpy(float), windows)]
    for ax, name in (("R", "roll"), ("P", "pitch"), ("Y", "yaw")):
        err = rate[f"{ax}Des"] - rate[ax]
        out[f"rate_err_{name}"] = float(np.sqrt(np.mean(err.to_numpy(float) ** 2)))
    g = out["gps"][_outside(out["gps"].TimeUS.to_numpy(float), windows)]
    fix = g[g.Status >= 3]
    out["gps_status_ok"] = float(len(fix) / max(len(g), 1))
    out["gps_nsats"] = float(fix.NSats.median())
    out["gps_hdop"] = float(fix.HDop.median())
    return out


def _on_grid(t_rel: np.ndarray, v: np.ndarray, grid: np.ndarray) -> np.ndarray:
    return np.interp(grid, t_rel, v, left=np.nan, right=np.nan)


def _fault_entry(tlm: Mapping[str, pd.DataFrame], sitl: Mapping[str, pd.DataFrame],
                 ft: Mapping[str, Any], fs: Mapping[str, Any], tlm_end: float, sitl_end: float,
                 route: Any) -> dict[str, Any]:
    """One fault's signatures on both sides and their comparison (a fault held to the end of
    the log is measured to the end of the armed flight)."""
    from tlm_process.fault_signatures import fault_signature, signature_types

    entry: dict[str, Any] = {"type": fs.get("type"), "label": fs.get("label"),
                             "tlm": {}, "sitl": {}}
    if fs.get("type") in signature_types():
        def until(f: Mapping[str, Any], end: float) -> dict[str, Any]:
            e = f.get("end_time_us")
            return dict(f, end_time_us=end if e is None or e <= f["start_time_us"] else e)

        entry["tlm"] = fault_signature(tlm, dict(until(ft, tlm_end), type=fs["type"]), route)
        entry["sitl"] = fault_signature(sitl, until(fs, sitl_end), route)
    rows = signature_rows(entry["tlm"], entry["sitl"])
    entry["rows"] = rows
    entry["passed"] = sum(r["pass"] for r in rows)
    entry["compared"] = len(rows)
    return entry


def crosscheck_metrics(tlm: Mapping[str, pd.DataFrame], sitl: Mapping[str, pd.DataFrame],
                       home: Sequence[float], tlm_faults: Sequence[Mapping[str, Any]],
                       sitl_faults: Sequence[Mapping[str, Any]],
                       route: Any = None) -> dict[str, Any]:
    """Compare two flights of one scenario; see the module docstring for the metrics.

    ``route``: the mission's waypoints as (lat, lon) rows (route deviation of the baro and
    GPS glitch signatures; None: each log's CMD messages).

    Returns a JSON-able dict (and, under ``_series``, arrays for the plots). A metric with
    nothing to measure (a log cut off before cruise: no cruise rows) is NaN, quietly (the
    report shows "-"; numpy's "Mean of empty slice" warnings are not printed).
    """
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.filterwarnings("ignore", r"Mean of empty slice", RuntimeWarning)
        warnings.filterwarnings("ignore", r"Degrees of freedom <= 0", RuntimeWarning)
        return _metrics(tlm, sitl, home, tlm_faults, sitl_faults, route)


def _metrics(tlm: Mapping[str, pd.DataFrame], sitl: Mapping[str, pd.DataFrame],
             home: Sequence[float], tlm_faults: Sequence[Mapping[str, Any]],
             sitl_faults: Sequence[Mapping[str, Any]], route: Any) -> dict[str, Any]:
    """``crosscheck_metrics`` (its warnings filtered there)."""
    ts, ss = armed_span_us(tlm), armed_span_us(sitl)
    tw, sw = _windows(tlm_faults, ts[1]), _windows(sitl_faults, ss[1])
    a, b = _side(tlm, home, tw), _side(sitl, home, sw)
    r: dict[str, Any] = {
        "flight_time_s": {"tlm": (ts[1] - ts[0]) * 1e-6, "sitl": (ss[1] - ss[0]) * 1e-6},
    }
    tree = cKDTree(_densify(b["truth"][:, 1:3]))
    pts = a["truth"][a["outside"], 1:3]
    d, _ = tree.query(pts)
    r["trajectory_rms_m"] = float(np.sqrt(np.mean(d**2))) if len(d) else float("nan")
    r["trajectory_max_m"] = float(d.max()) if len(d) else float("nan")
    # the same, also leaving out the RECOVERY_S after each fault (the return to the path)
    settled = _outside(a["truth"][:, 0], [(x, y + RECOVERY_S * 1e6) for x, y in tw])
    d2, _ = tree.query(a["truth"][settled, 1:3])
    r["trajectory_rms_settled_m"] = float(np.sqrt(np.mean(d2**2))) if len(d2) else float("nan")
    # profiles on a common time base since arming (10 Hz), outside both sides' fault windows
    grid = np.arange(0.0, min(ts[1] - ts[0], ss[1] - ss[0]) * 1e-6, 0.1)
    ta = (a["truth"][:, 0] - ts[0]) * 1e-6
    tb = (b["truth"][:, 0] - ss[0]) * 1e-6
    alt_a, alt_b = _on_grid(ta, a["truth"][:, 3], grid), _on_grid(tb, b["truth"][:, 3], grid)
    ga, gb = a["gps"], b["gps"]
    spd_a = _on_grid((ga.TimeUS.to_numpy(float) - ts[0]) * 1e-6, ga.Spd.to_numpy(float), grid)
    spd_b = _on_grid((gb.TimeUS.to_numpy(float) - ss[0]) * 1e-6, gb.Spd.to_numpy(float), grid)
    keep = (_outside(grid * 1e6 + ts[0], tw) & _outside(grid * 1e6 + ss[0], sw)
            & np.isfinite(alt_a) & np.isfinite(alt_b))
    r["altitude_rms_m"] = float(np.sqrt(np.nanmean((alt_a - alt_b)[keep] ** 2)))
    r["speed_rms_ms"] = float(np.sqrt(np.nanmean((spd_a - spd_b)[keep] ** 2)))
    r["max_alt_m"] = {"tlm": float(np.nanmax(a["truth"][:, 3])),
                      "sitl": float(np.nanmax(b["truth"][:, 3]))}
    r["mean_speed_ms"] = {"tlm": float(ga.Spd.mean()), "sitl": float(gb.Spd.mean())}
    for k in ("hover_throttle", "cruise_throttle", "imu_acc_std", "imu_gyr_std", "vibe_x",
              "vibe_y", "vibe_z", "att_roll_mean_deg", "att_roll_std_deg",
              "att_pitch_mean_deg", "att_pitch_std_deg", "rate_err_roll", "rate_err_pitch",
              "rate_err_yaw",
              "gps_status_ok", "gps_nsats", "gps_hdop",
              *[f"imu_acc_psd_{lo:g}_{hi:g}hz" for lo, hi in PSD_BANDS]):
        r[k] = {"tlm": a.get(k, float("nan")), "sitl": b.get(k, float("nan"))}
    r["faults"] = [_fault_entry(tlm, sitl, ft, fs, ts[1], ss[1], route)
                   for ft, fs in zip(tlm_faults, sitl_faults, strict=False)]
    r["_series"] = {
        "tlm_ne": a["truth"][:, 1:3], "sitl_ne": b["truth"][:, 1:3], "grid": grid,
        "alt": (alt_a, alt_b), "spd": (spd_a, spd_b), "psd": (a.get("psd"), b.get("psd")),
        "tlm_windows": [((x - ts[0]) * 1e-6, (y - ts[0]) * 1e-6) for x, y in tw],
    }
    return r
