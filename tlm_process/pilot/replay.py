"""Re-fly a pilot-flown log from its own RCIN (issue 42, part 3; ``tlm crosscheck`` on a log
without an AUTO mission).

A pilot-flown log carries what the pilot's transmitter sent: RCIN, channels 1..8 at the log's
rate (10 Hz in SITL's and most real logs). tlm flies it as it was sent (:func:`rc_table`: the
sticks interpolated between the rows onto tlm's 50 Hz receiver frames, so a stick moved over
half a second is not replayed 0-100 ms late; the mode switch and the other channels held
from row to row), from the log's parameters
(:func:`log_params`: a SITL log's PARM as it starts; a real vehicle's modelled parameters,
Copter 3.3 names translated, and its battery), with the sidecar's faults or the SIM_* changes
in PARM, on the log's own time line: the vehicle arms by the rudder gesture where the log's
pilot made it. A log armed another way (a ground station, an arming switch) gets the gesture
inserted before its arming time (:func:`with_arm_gesture`), the stick positions it replaces
are noted. The mode switch is in RCIN; the mode changes a ground station made (MODE rows with
reason GCS; in a log without reasons, the changes into a pilot mode the switch does not
select) are asked for again at their times (:func:`gcs_requests`).

The two flights are then measured per stick segment (:mod:`tlm_process.pilot.signature`: the
sidecar's script, else RCIN's held sticks) and judged (:func:`judge`): per segment, mean and
peak pitch and roll and the top speed within 15 % of the log's (or within a noise floor of
0.5 deg and 0.3 m/s, whichever is larger), the height held within 0.5 m (range of CTUN.Alt;
or as well as the log held it, if worse) in the modes that hold it, outside the pilot's
climbs and descents, motor 1's excess over
the others within 15 % (floor 5 us); the flight time within 5 %. A flight in random gusts
(``SIM_WIND_TURB`` > 0: a SITL log's, or a fitted vehicle's) is one draw of them: it is re-flown
with :data:`GUST_DRAWS` draws (seeds) and each measure judged on tlm's range over them, widened
by the tolerance.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.fit.segment import segment_mode
from tlm_process.pilot.signature import (
    StickSegment,
    flight_time_s,
    pilot_signature,
    segments_from_rcin,
    segments_from_sidecar,
)

__all__ = ["GUST_DRAWS", "PilotScenario", "REL_TOL", "format_report", "has_sticks",
           "is_pilot_flown", "judge", "log_params", "plot", "rc_table", "reconstruct_pilot",
           "replay", "with_arm_gesture"]

#: issue 42's tolerances: relative, per measure, and the noise floors below which a difference
#: is not judged relative (hover attitude ~0.1 deg, speed ~0.05 m/s, motor 1 +-1 us)
REL_TOL = 0.15
FLOORS: dict[str, float] = {"pitch_mean_deg": 0.5, "pitch_peak_deg": 0.5, "roll_mean_deg": 0.5,
                            "roll_peak_deg": 0.5, "speed_max_ms": 0.3, "motor1_excess_us": 5.0}
HEIGHT_HELD_M = 0.5
FLIGHT_TIME_REL_TOL = 0.05
#: draws of the gusts a log flown in SITL's random gusts (SIM_WIND_TURB > 0) is re-flown with:
#: its gusts are one draw, tlm's seeds others, so a measure is judged against tlm's range over
#: the draws (widened by the tolerance). A measure the gusts alone decide falls outside the
#: range of N draws with probability 2 / (N + 1) before the widening: 1/3 with 5 draws (an ACRO
#: flight in 4 m/s wind and 1 m/s gusts, re-flown with other seeds: 69/72, its drift speeds
#: outside), 2/11 with 10 (72/72 at two replay seeds)
GUST_DRAWS = 10
#: the modes that hold height (their segments' CTUN.Alt range is judged)
HEIGHT_MODES = (2, 5, 16)  # ALT_HOLD, LOITER, POSHOLD
#: the rudder gesture tlm inserts: this long before the log's arming time [s] (the gesture
#: arms after 3 s, at the next tick)
GESTURE_S = 3.02
CHANNELS = tuple(f"C{k}" for k in range(1, 9))
#: the receiver's frame rate the log's sticks are interpolated at [Hz] (tlm_sim.sensors.rc)
RC_FRAME_HZ = 50.0
#: rows further apart than this are not interpolated between [s]: the radio was lost
RC_INTERP_GAP_S = 0.25


def has_sticks(tables: Mapping[str, pd.DataFrame]) -> bool:
    """RCIN with the four sticks (C1-C4) and a row where the receiver delivered them."""
    rcin = tables.get("RCIN")
    sticks = ["C1", "C2", "C3", "C4"]
    if rcin is None or not len(rcin) or not set(sticks) <= set(rcin.columns):
        return False
    return bool((rcin[sticks].to_numpy(float) > 0).any())


def is_pilot_flown(tables: Mapping[str, pd.DataFrame]) -> bool:
    """A log flown by a pilot: RCIN with stick input (:func:`has_sticks`) and no AUTO in
    MODE."""
    mode = tables.get("MODE")
    if mode is not None and len(mode):
        from tlm_sim.ardupilot import MODE_AUTO

        if (pd.to_numeric(mode["ModeNum"], errors="coerce") == MODE_AUTO).any():
            return False
    return has_sticks(tables)


def rc_table(tables: Mapping[str, pd.DataFrame],
             params: Mapping[str, float] | None = None) -> np.ndarray:
    """The log's RCIN as tlm's RC table: rows (time since boot [s], channels 1..8 [us]) where
    the receiver delivered the sticks (rows with roll, pitch, throttle and yaw all 0, no
    radio, are dropped; a channel the log lacks or logs as 0 takes SITL's idle value), the
    stick channels (``params``' RCMAP_*, 1-4 by default) interpolated in between at
    :data:`RC_FRAME_HZ` (:func:`_interpolate_sticks`)."""
    from tlm_sim.ardupilot import RC_IDLE_PWM

    rcin = tables["RCIN"]
    sticks = rcin[["C1", "C2", "C3", "C4"]].to_numpy(float)
    keep = (sticks > 0).any(axis=1)
    r = rcin[keep]
    out = np.empty((len(r), 9))
    out[:, 0] = r["TimeUS"].to_numpy(float) * 1e-6
    for k, ch in enumerate(CHANNELS):
        v = r[ch].to_numpy(float) if ch in r else np.zeros(len(r))
        out[:, k + 1] = np.where(v > 0, v, RC_IDLE_PWM[k])
    p = params or {}
    cols = sorted({int(p.get(f"RCMAP_{a}", d)) for a, d in
                   (("ROLL", 1), ("PITCH", 2), ("THROTTLE", 3), ("YAW", 4))} & set(range(1, 9)))
    return _interpolate_sticks(out, cols)


def _interpolate_sticks(rows: np.ndarray, cols: Sequence[int]) -> np.ndarray:
    """``rows`` (time [s], channels 1..8) with rows added every 1/:data:`RC_FRAME_HZ` s
    between two rows at most :data:`RC_INTERP_GAP_S` apart: the channels ``cols``
    (1-based) linear between the two, the others the first row's (a switch is not moved
    through its middle positions). A gap longer than that (the radio lost) is held, as
    before."""
    if len(rows) < 2:
        return rows
    t = rows[:, 0]
    dt = np.diff(t)
    n = np.where((dt <= RC_INTERP_GAP_S) & (dt > 0.0),
                 np.ceil(dt * RC_FRAME_HZ - 1e-6).astype(int) - 1, 0)
    n = np.maximum(n, 0)
    src = np.repeat(np.arange(len(dt)), n)
    if not len(src):
        return rows
    j = np.arange(len(src)) - np.repeat(np.cumsum(n) - n, n) + 1
    frac = j / RC_FRAME_HZ / dt[src]
    added = rows[src].copy()
    added[:, 0] = t[src] + j / RC_FRAME_HZ
    c = np.asarray(cols, dtype=int)
    added[:, c] += frac[:, None] * (rows[src + 1][:, c] - rows[src][:, c])
    out = np.concatenate([rows, added])
    return out[np.argsort(out[:, 0], kind="stable")]


def _gesture_in_log(table: np.ndarray, arm_s: float, params: Mapping[str, float]) -> bool:
    """Whether the table shows the rudder arming gesture before ``arm_s``: yaw beyond 89 % of
    its travel with the throttle at its bottom through the 2.8 s before it (each row held until
    the next, sampled at 50 Hz; RCIN logged at 10 Hz may show the 3 s gesture 0.1 s late)."""
    yaw_ch = int(params.get("RCMAP_YAW", 4))
    thr_ch = int(params.get("RCMAP_THROTTLE", 3))
    times = np.arange(arm_s - 2.8, arm_s - 0.05, 0.02)  # (RCIN at 10 Hz lags the frames)
    idx = np.searchsorted(table[:, 0], times, side="right") - 1
    if len(times) == 0 or idx.min() < 0:
        return False
    held = table[idx]
    trim = params.get(f"RC{yaw_ch}_TRIM", 1500.0)
    hi = params.get(f"RC{yaw_ch}_MAX", 2000.0)
    lo_thr = params.get(f"RC{thr_ch}_MIN", 1000.0) + params.get(f"RC{thr_ch}_DZ", 30.0)
    yaw_right = held[:, yaw_ch] > trim + 0.89 * (hi - trim)
    thr_low = held[:, thr_ch] <= lo_thr
    return bool(np.all(yaw_right & thr_low))


def with_arm_gesture(table: np.ndarray, arm_s: float,
                     params: Mapping[str, float]) -> tuple[np.ndarray, str | None]:
    """The table with the rudder arming gesture (yaw full right, throttle at its bottom) in the
    :data:`GESTURE_S` before the log's arming time ``arm_s`` [s], unless the log shows one;
    returns (table, a note on what was inserted, or None)."""
    if _gesture_in_log(table, arm_s, params):
        return table, None
    yaw_ch = int(params.get("RCMAP_YAW", 4))
    thr_ch = int(params.get("RCMAP_THROTTLE", 3))
    t0 = arm_s - GESTURE_S
    before = table[table[:, 0] < t0]
    after = table[table[:, 0] > arm_s]
    last = table[table[:, 0] <= arm_s]
    base = last[-1].copy() if len(last) else table[0].copy()
    g = base.copy()
    g[0] = t0
    g[yaw_ch] = params.get(f"RC{yaw_ch}_MAX", 2000.0)
    g[thr_ch] = params.get(f"RC{thr_ch}_MIN", 1000.0)
    back = base.copy()
    back[0] = arm_s + 0.05
    rows = [before, g[None, :], back[None, :], after[after[:, 0] > arm_s + 0.05]]
    note = (f"the log arms at {arm_s:.1f} s without the rudder gesture: tlm's pilot makes it "
            f"from {t0:.1f} s (yaw full right, throttle down)")
    return np.concatenate(rows), note


def log_params(tables: Mapping[str, pd.DataFrame],
               log_values: Mapping[str, float]) -> tuple[dict[str, float], list[str]]:
    """The parameters to fly a log with, and notes: a SITL log's PARM at its start (the
    SIM_* too); a real vehicle's modelled parameters (Copter 3.3 names translated,
    out-of-range values dropped) and its battery (:mod:`tlm_process.fit.fit`)."""
    notes: list[str] = []
    if any(str(k).startswith("SIM_") for k in log_values):
        from tlm_process.crosscheck.scenario import _initial_params

        return _initial_params(tables["PARM"]), notes
    from tlm_process.fit.fit import log_battery, log_vehicle_params

    keep, dropped = log_vehicle_params(log_values)
    for name, why in dropped.items():
        notes.append(f"parameter {name} not flown: {why}")
    keep.update(log_battery(tables, log_values))
    return keep, notes


@dataclass
class PilotScenario:
    """What tlm needs to re-fly a pilot-flown log, and the log."""

    name: str
    tables: dict[str, pd.DataFrame]
    log_values: dict[str, float]
    params: dict[str, float]
    rc: np.ndarray
    changes: list[tuple[float, str, float]]
    segments: list[StickSegment]
    gcs: list[tuple[float, int]]
    seed: int
    arm_s: float
    notes: list[str] = field(default_factory=list)


def _sidecar(path: Path, sidecar: str | Path | None) -> dict[str, Any] | None:
    p = Path(sidecar) if sidecar is not None else path.with_suffix(".json")
    if not p.is_file():
        if sidecar is not None:
            raise FileNotFoundError(2, "no such sidecar", str(p))
        return None
    from tlm_sim.flightlog.sidecar import load_sidecar_json

    doc = load_sidecar_json(p)
    return doc if isinstance(doc, dict) else None


def _changes(doc: Mapping[str, Any] | None,
             tables: Mapping[str, pd.DataFrame]) -> list[tuple[float, str, float]]:
    """The faults as parameter changes on the log's time line: the sidecar's records, else
    the SIM_* changes of PARM after its start."""
    out: list[tuple[float, str, float]] = []
    faults = (doc or {}).get("faults") or []
    if faults:
        for f in faults:
            for key, t_key in (("params_start", "start_time_us"), ("params_end", "end_time_us")):
                t = f.get(t_key)
                if t is None:
                    continue
                out += [(float(t) * 1e-6, str(n), float(v)) for n, v in (f.get(key) or {}).items()]
        return out
    parm = tables.get("PARM")
    if parm is None or not len(parm):
        return out
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    for row in param_changes_from_parm(parm, exclude=()).itertuples():
        if str(row.Name).startswith("SIM_"):
            out.append((float(row.TimeUS) * 1e-6, str(row.Name), float(row.Value)))
    return out


def reconstruct_pilot(bin_path: str | Path, sidecar: str | Path | None = None,
                      seed: int | None = None) -> PilotScenario:
    """Read a pilot-flown log (and its sidecar) into a :class:`PilotScenario`."""
    from tlm_process.logread import arming_time_us, read_log_tables

    path = Path(bin_path)
    lt = read_log_tables(path)
    tables = dict(lt.tables)
    values = dict(lt.params)
    doc = _sidecar(path, sidecar)
    params, notes = log_params(tables, values)
    table = rc_table(tables, values)
    if not len(table):
        raise ValueError(f"{path}: RCIN has no stick input to replay")
    arm_us, _ = arming_time_us(tables, values)
    if arm_us is None:
        raise ValueError(f"{path.name}: the log never armed: there is no flight to replay")
    arm_s = arm_us * 1e-6
    table, note = with_arm_gesture(table, arm_s, {**_rc_defaults(), **values})
    if note:
        notes.append(note)
    segments = segments_from_sidecar(doc) if doc and doc.get("stick_script") else (
        segments_from_rcin(tables, values))
    gcs = gcs_requests(tables, values)
    notes += _mode_notes(tables.get("MODE"), arm_us, gcs)
    s = int(seed if seed is not None else (doc or {}).get("seed", 0) or 0)
    return PilotScenario(path.stem, tables, values, params, table, _changes(doc, tables),
                         segments, gcs, s, arm_s, notes)


def _mode_notes(mode: pd.DataFrame | None, arm_us: float,
                gcs: Sequence[tuple[float, int]]) -> list[str]:
    """Notes on the log's modes: those tlm does not fly from the sticks; in a log without
    mode reasons, the changes off the mode switch that are asked for at their times."""
    from tlm_sim import ardupilot as AP
    from tlm_sim.ardupilot import MODE_NAMES
    from tlm_sim.control.pilot_modes import PILOT_MODES

    if mode is None or not len(mode):
        return []
    out = []
    after = mode[mode["TimeUS"] >= arm_us - 1e6]
    flown = pd.to_numeric(after["ModeNum"], errors="coerce").dropna()
    unflown = sorted({int(m) for m in flown} - set(PILOT_MODES) - {AP.MODE_RTL, AP.MODE_LAND})
    if unflown:
        out.append("modes tlm does not fly from the sticks (it stays in the mode before): "
                   + ", ".join(MODE_NAMES.get(m, str(m)) for m in unflown))
    if gcs and "Rsn" not in mode:
        out.append("mode changes the mode switch does not select (the log has no reasons: a "
                   "ground station or an auxiliary switch), asked for at their times: "
                   + ", ".join(f"{MODE_NAMES.get(m, m)} at {t:.1f} s" for t, m in gcs))
    return out


def gcs_requests(tables: Mapping[str, pd.DataFrame],
                 values: Mapping[str, float] | None = None) -> list[tuple[float, int]]:
    """The mode changes a ground station made: (time [s], mode number) of the MODE rows with
    reason GCS (ModeReason 2). A log without reasons (Copter 3.x) gets its changes into a
    pilot mode that the mode switch does not explain (RCIN's position on ``FLTMODE_CH``, 5 if
    the log has none, is another ``FLTMODEn``: a ground station, an auxiliary switch); changes
    into RTL or LAND are left to tlm's failsafes."""
    from tlm_sim.ardupilot import RSN_GCS

    mode = tables.get("MODE")
    if mode is None or not len(mode):
        return []
    if "Rsn" in mode:
        gcs = mode[pd.to_numeric(mode["Rsn"], errors="coerce") == RSN_GCS]
        return [(float(t) * 1e-6, int(m)) for t, m in zip(gcs["TimeUS"], gcs["ModeNum"],
                                                           strict=True)]
    return _unswitched_changes(mode, tables.get("RCIN"), values or {})


def _unswitched_changes(mode: pd.DataFrame, rcin: pd.DataFrame | None,
                        values: Mapping[str, float]) -> list[tuple[float, int]]:
    """MODE rows after the first into a pilot mode tlm flies that RCIN's mode switch does not
    select at their time."""
    from tlm_sim.control.pilot import switch_position
    from tlm_sim.control.pilot_modes import PILOT_MODES

    ch = f"C{int(values.get('FLTMODE_CH', 5))}"
    if rcin is None or not len(rcin) or ch not in rcin:
        return []
    t_rc = rcin["TimeUS"].to_numpy(dtype=float)
    pwm = rcin[ch].to_numpy(dtype=float)
    out = []
    for t, m in zip(mode["TimeUS"].iloc[1:], mode["ModeNum"].iloc[1:], strict=True):
        if int(m) not in PILOT_MODES:
            continue
        k = int(np.searchsorted(t_rc, float(t), side="right")) - 1
        pos = switch_position(pwm[k]) if k >= 0 else -1
        if pos < 0 or int(values.get(f"FLTMODE{pos + 1}", -1)) != int(m):
            out.append((float(t) * 1e-6, int(m)))
    return out


def _rc_defaults() -> dict[str, float]:
    from tlm_sim.params import Params

    d = Params.defaults()
    return {k: float(v) for k, v in d.items() if k.startswith(("RC", "RCMAP_"))}


def judge(ref: pd.DataFrame, ours: pd.DataFrame, ref_tables: Mapping[str, pd.DataFrame],
          rel_tol: float = REL_TOL, draws: Sequence[pd.DataFrame] = ()) -> pd.DataFrame:
    """Per segment and measure: the log's value, tlm's, the tolerance and whether tlm is
    within it (see the module docstring). ``draws``: tlm's signatures with other draws of the
    gusts (``ours`` is one more): the measure passes when the log's value lies within their
    range widened by the tolerance (``tlm_min`` / ``tlm_max``; the height held: by the draw
    that held it best, and not in a ``climb`` or ``descend`` segment, where the pilot's
    throttle moves the height)."""
    rows = []
    sigs = [ours, *draws]
    for k, (_, a) in enumerate(ref.iterrows()):
        b = [sig.iloc[k] for sig in sigs]
        mode = segment_mode(ref_tables, a["start_s"] * 1e6)
        for m, floor in FLOORS.items():
            x, ys = float(a[m]), [float(v[m]) for v in b]
            if not (math.isfinite(x) and all(math.isfinite(y) for y in ys)):
                continue
            tol = max(rel_tol * abs(x), floor)
            lo, hi = min(ys), max(ys)
            rows.append({"segment": a["segment"], "measure": m, "log": x, "tlm": ys[0],
                         "tol": tol, "pass": lo - tol <= x <= hi + tol,
                         "tlm_min": lo, "tlm_max": hi})
        ys = [float(v["alt_range_m"]) for v in b]
        held = not str(a["segment"]).startswith(("climb", "descend"))  # the pilot's, not held
        if mode in HEIGHT_MODES and held and all(math.isfinite(y) for y in ys):
            # held within 0.5 m, or as well as the log held it (gusts move SITL's too)
            x = float(a["alt_range_m"])
            tol = max(HEIGHT_HELD_M, x) if math.isfinite(x) else HEIGHT_HELD_M
            rows.append({"segment": a["segment"], "measure": "alt_range_m", "log": x,
                         "tlm": ys[0], "tol": tol, "pass": min(ys) <= tol,
                         "tlm_min": min(ys), "tlm_max": max(ys)})
    return pd.DataFrame(rows, columns=["segment", "measure", "log", "tlm", "tol", "pass",
                                       "tlm_min", "tlm_max"])


def replay(bin_path: str | Path, sidecar: str | Path | None = None, seed: int | None = None,
           params: Mapping[str, float] | None = None) -> dict[str, Any]:
    """Re-fly a pilot-flown log from its RCIN and compare: returns ``scenario`` (what was
    flown), ``segments`` (the log's and tlm's signature tables), ``judged``
    (:func:`judge`), ``flight_time_s`` (log, tlm), ``checks`` and the flown ``_log``."""
    from tlm_sim import fly
    from tlm_sim.params import Params

    sc = reconstruct_pilot(bin_path, sidecar, seed)
    flown = {**sc.params, **dict(params or {})}

    def fly_seed(s: int) -> Any:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return fly(None, sc.changes or None, params=Params(flown), seed=s, sticks=sc.rc,
                       gcs_modes=sc.gcs)

    log = fly_seed(sc.seed)
    ours = {n: log.tables[n] for n in log.tables}
    ref_sig = pilot_signature(sc.tables, sc.segments, sc.log_values)
    tlm_sig = pilot_signature(ours, sc.segments, dict(log.params))
    gusts = float(Params(flown)["SIM_WIND_TURB"]) > 0.0
    draws = [pilot_signature(other.tables, sc.segments, dict(other.params))
             for other in (fly_seed(sc.seed + k) for k in range(1, GUST_DRAWS))] if gusts else []
    judged = judge(ref_sig, tlm_sig, sc.tables, draws=draws)
    ft_log = flight_time_s(sc.tables, sc.log_values)
    ft_tlm = flight_time_s(ours, dict(log.params))
    ft_ok = (math.isfinite(ft_log) and math.isfinite(ft_tlm)
             and abs(ft_tlm - ft_log) <= FLIGHT_TIME_REL_TOL * ft_log)
    n_pass = int(judged["pass"].sum()) if len(judged) else 0
    return {
        "scenario": {"log": str(bin_path), "name": sc.name, "seed": sc.seed,
                     "arm_s": sc.arm_s, "rc_rows": int(len(sc.rc)),
                     "faults": [list(c) for c in sc.changes], "notes": list(sc.notes),
                     "gcs_modes": [list(g) for g in sc.gcs],
                     "params_from_log": dict(sc.params),
                     "overrides": {k: float(v) for k, v in (params or {}).items()},
                     "end_reason": log.meta.get("end_reason"),
                     "gust_draws": 1 + len(draws)},
        "segments": {"log": ref_sig, "tlm": tlm_sig},
        "judged": judged,
        "flight_time_s": {"log": ft_log, "tlm": ft_tlm},
        "checks": {"segments": {"passed": n_pass, "judged": int(len(judged)),
                                "pass": n_pass == len(judged)},
                   "flight_time": {"pass": bool(ft_ok), "rel_tol": FLIGHT_TIME_REL_TOL}},
        "_log": log, "_tables": sc.tables,
    }


def _fmt(v: float) -> str:
    return "—" if not math.isfinite(v) else f"{v:.2f}"


def format_report(r: Mapping[str, Any]) -> str:
    """Markdown report of :func:`replay`: the scenario, the checks, the judged measures per
    segment and the overlay pictures (:func:`plot`)."""
    sc = r["scenario"]
    c = r["checks"]
    ft = r["flight_time_s"]
    lines = [f"# tlm crosscheck (replay from RCIN): {sc['name']}", "",
             f"Re-flown from the log's RCIN ({sc['rc_rows']} rows), seed {sc['seed']}, "
             f"arming at {_fmt(sc['arm_s'] or math.nan)} s; tlm's flight ended: "
             f"{sc['end_reason']}.", ""]
    for note in sc["notes"]:
        lines.append(f"- note: {note}")
    draws = int(sc.get("gust_draws", 1))
    if draws > 1:
        lines += ["", "The flight is flown in random gusts (SIM_WIND_TURB > 0: the log's SITL "
                  "setting, or a fitted vehicle's), of which the log holds one draw: tlm flew "
                  f"{draws} (seeds {sc['seed']}-{sc['seed'] + draws - 1}). A measure passes when "
                  "the log's value lies within tlm's range over the draws (min..max) widened by "
                  "the tolerance; tlm's column is the first draw's."]
    lines += ["", f"**Flight time**: log {_fmt(ft['log'])} s, tlm {_fmt(ft['tlm'])} s "
              f"({'pass' if c['flight_time']['pass'] else 'FAIL'}, within "
              f"{FLIGHT_TIME_REL_TOL:.0%}).", "",
              f"**Stick segments**: {c['segments']['passed']}/{c['segments']['judged']} "
              f"measures within tolerance ({REL_TOL:.0%} or the noise floor; height held "
              f"within {HEIGHT_HELD_M} m).", "",
              "| segment | measure | log | tlm | tolerance | |", "|---|---|---|---|---|---|"]
    if draws > 1:
        lines[-2:] = ["| segment | measure | log | tlm | tlm min..max | tolerance | |",
                      "|---|---|---|---|---|---|---|"]
    for row in r["judged"].to_dict("records"):
        spread = f" {_fmt(row['tlm_min'])}..{_fmt(row['tlm_max'])} |" if draws > 1 else ""
        lines.append(f"| {row['segment']} | {row['measure']} | {_fmt(row['log'])} | "
                     f"{_fmt(row['tlm'])} |{spread} {_fmt(row['tol'])} | "
                     f"{'pass' if row['pass'] else 'FAIL'} |")
    lines += ["", "![overlay](overlay.png)", ""]
    return "\n".join(lines)


def plot(r: Mapping[str, Any], out: Path) -> Path:
    """``overlay.png``: the log's and tlm's pitch, roll, ground speed and altitude over time,
    with the sticks below and the stick segments shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = r["_tables"]
    ours = {n: r["_log"].tables[n] for n in r["_log"].tables}
    fig, axes = plt.subplots(5, 1, figsize=(11, 11), sharex=True)
    panels = (("ATT", "Pitch", "pitch [deg]"), ("ATT", "Roll", "roll [deg]"),
              ("GPS", "Spd", "ground speed [m/s]"), ("CTUN", "Alt", "altitude [m]"))
    for ax, (msg, col, label) in zip(axes, panels, strict=False):
        for tables, name, style in ((ref, "log", "-"), (ours, "tlm", "--")):
            df = tables.get(msg)
            if df is None or col not in df:
                continue
            if msg == "GPS" and "I" in df:
                df = df[df["I"] == 0]
            ax.plot(df["TimeUS"] * 1e-6, df[col], style, lw=1, label=name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right")
    rc = ref.get("RCIN")
    if rc is not None:
        for ch, name in (("C1", "roll"), ("C2", "pitch"), ("C3", "throttle"), ("C4", "yaw")):
            if ch in rc:
                axes[4].plot(rc["TimeUS"] * 1e-6, rc[ch], lw=1, label=f"{ch} {name}")
        axes[4].set_ylabel("RCIN [us]")
        axes[4].legend(loc="upper right", ncol=4, fontsize=8)
    for k, seg in enumerate(r["segments"]["log"].itertuples()):
        for ax in axes:
            ax.axvspan(seg.start_s, seg.end_s, color="0.86" if k % 2 else "0.94", zorder=0)
    axes[-1].set_xlabel("time since boot [s]")
    fig.suptitle(f"{r['scenario']['name']}: log (solid) and tlm re-flown from RCIN (dashed)")
    fig.tight_layout()
    path = out / "overlay.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def summary_lines(r: Mapping[str, Any]) -> Sequence[str]:
    """The console lines of a replay."""
    c, ft = r["checks"], r["flight_time_s"]
    sc = r["scenario"]
    draws = int(sc.get("gust_draws", 1))
    gusts = (f"; {draws} draws of the gusts, seeds {sc['seed']}-{sc['seed'] + draws - 1}, a "
             "measure judged on their range" if draws > 1 else "")
    out = [f"replayed from RCIN: {sc['name']} (seed {sc['seed']}{gusts})"]
    out += [f"note: {n}" for n in r["scenario"]["notes"]]
    out.append(f"flight time: tlm {_fmt(ft['tlm'])} s, log {_fmt(ft['log'])} s "
               f"({'pass' if c['flight_time']['pass'] else 'FAIL'})")
    out.append(f"stick segments: {c['segments']['passed']}/{c['segments']['judged']} measures "
               "within tolerance")
    for row in r["judged"].to_dict("records"):
        if not row["pass"]:
            got = (f"tlm {_fmt(row['tlm_min'])}..{_fmt(row['tlm_max'])}" if draws > 1
                   else f"tlm {_fmt(row['tlm'])}")
            out.append(f"  outside: {row['segment']} {row['measure']}: log {_fmt(row['log'])}, "
                       f"{got} (tolerance {_fmt(row['tol'])})")
    return out
