"""What a pilot-flown flight does, segment by segment of its sticks (issue 42's measures).

A pilot-flown log (SITL's ``pilot/`` reference flights, a real vehicle's, later tlm's) is cut
into **stick segments**: spans where the roll, pitch and yaw sticks hold one position, from its
sidecar's ``stick_script`` (SITL's driver wrote when each step began and ended) or, without
one, from the log's RCIN (:func:`segments_from_rcin`). Each segment is then measured
(:func:`segment_metrics`) as the shared reference README reports it:

* ``pitch_mean_deg`` / ``roll_mean_deg``: the mean ATT attitude (nose down and left wing down
  negative), ``pitch_peak_deg`` / ``roll_peak_deg`` the largest magnitude;
* ``speed_max_ms``: the largest GPS ground speed [m/s] (GPS 1);
* ``alt_std_m`` and ``alt_range_m``: the standard deviation and the spread (max - min) of the
  altitude estimate CTUN.Alt [m] (a mode that holds height keeps both small);
* ``motor1_excess_us``: motor 1's output above the mean of the others, RCOU C1 - mean(C2..Cn)
  [us] (a yaw turn or a weakened motor 1);
* ``thr_out``: the mean throttle output CTUN.ThO (Copter 3.x: ThrOut / 1000).

Copter 3.x logs (RCOU Ch1.., CTUN ThrOut) are read as well.

:func:`pilot_signature` gives one row per segment and :func:`flight_time_s` the time from
arming to disarming. Checked against the reference README's figures
(``tests/test_pilot_signature.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.fit.stats import throttle_out
from tlm_process.logread import arming_time_us, disarm_time_us, motor_columns
from tlm_process.reference import time_window

__all__ = ["METRICS", "StickSegment", "airborne_us", "flight_time_s", "pilot_signature",
           "segment_metrics", "segments_from_rcin", "segments_from_sidecar"]

#: The metrics of :func:`segment_metrics`, in column order.
METRICS: tuple[str, ...] = ("pitch_mean_deg", "pitch_peak_deg", "roll_mean_deg",
                            "roll_peak_deg", "speed_max_ms", "alt_std_m", "alt_range_m",
                            "motor1_excess_us", "thr_out")
#: RCIN channels of roll, pitch and yaw (ArduPilot's default RCMAP) and the neutral PWM
STICK_CHANNELS: dict[str, str] = {"roll": "C1", "pitch": "C2", "yaw": "C4"}
NEUTRAL_PWM = 1500.0
#: half the PWM span of a stick (1000-2000 us)
HALF_SPAN_PWM = 500.0
#: a stick within this of where it was [us] holds its position (receiver jitter)
HOLD_TOL_PWM = 10.0
#: the throttle channel (RCMAP's default) and how far it may wander within one segment [us]:
#: a pilot holding height in STABILIZE moves it a little all the time, a climb or a descent
#: moves it far
THROTTLE_CHANNEL = "C3"
THROTTLE_TOL_PWM = 50.0
#: a throttle this far from mid-stick [us] (the other sticks centred) is a climb or descent
THROTTLE_MOVE_PWM = 100.0
#: the shortest stick segment :func:`segments_from_rcin` reports [s]
MIN_SEGMENT_S = 2.0
#: :func:`segments_from_rcin` starts this long [s] after the copter first climbs LIFTOFF_M
#: [m] above its height at arming: on the ground its attitude is the ground's, and the
#: liftoff's transient depends on the throttle within RCIN's rows (10 Hz), which a replay
#: cannot give back (a pilot's hand on a manual throttle: 0.3 s later in tlm's replay)
LIFTOFF_M = 1.0
LIFTOFF_SETTLE_S = 2.0


@dataclass(frozen=True)
class StickSegment:
    """One span of held sticks: ``name`` (``hover``, ``pitch_forward``, ``roll_right``,
    ``yaw_left``, ``neutral_2``, ...), log time ``start_us`` / ``end_us`` [us] and the stick
    positions ``sticks`` (``roll``, ``pitch``, ``yaw``, each -1..1; pitch > 0 forward, roll >
    0 right, yaw > 0 right)."""

    name: str
    start_us: int
    end_us: int
    sticks: Mapping[str, float] = field(default_factory=dict)


def segments_from_sidecar(sidecar: Mapping[str, Any]) -> list[StickSegment]:
    """The stick segments a reference sidecar's ``stick_script`` records (its ``start_time_us``
    and ``end_time_us``: when the driver began and ended each step)."""
    out = []
    for seg in sidecar.get("stick_script") or []:
        sticks = {k: float(v) for k, v in (seg.get("sticks") or {}).items()}
        out.append(StickSegment(str(seg["name"]), int(seg["start_time_us"]),
                                int(seg["end_time_us"]), sticks))
    return out


def _stick(pwm: np.ndarray, axis: str) -> np.ndarray:
    """Stick position -1..1 of an RCIN channel (pitch: low PWM is forward, so negated)."""
    s = (pwm - NEUTRAL_PWM) / HALF_SPAN_PWM
    return -s if axis == "pitch" else s


def _name(sticks: Mapping[str, float], throttle: float, counts: dict[str, int]) -> str:
    """``pitch_forward``, ``roll_left``, ... by the stick furthest out; held centre:
    ``climb`` / ``descend`` with the throttle (PWM ``throttle``) far from mid-stick, else
    ``hover`` the first time, then ``neutral_1``, ``neutral_2``, ..."""
    axis = max(sticks, key=lambda k: abs(sticks[k]))
    if abs(sticks[axis]) < 0.02 and abs(throttle - NEUTRAL_PWM) > THROTTLE_MOVE_PWM:
        name = "climb" if throttle > NEUTRAL_PWM else "descend"
        n = counts.get(name, 0)
        counts[name] = n + 1
        return name if n == 0 else f"{name}_{n + 1}"
    if abs(sticks[axis]) < 0.02:
        n = counts.get("neutral", -1) + 1
        counts["neutral"] = n
        return "hover" if n == 0 else f"neutral_{n}"
    word = {"pitch": ("back", "forward"), "roll": ("left", "right"),
            "yaw": ("left", "right")}[axis][sticks[axis] > 0]
    name = f"{axis}_{word}"
    n = counts.get(name, 0)
    counts[name] = n + 1
    return name if n == 0 else f"{name}_{n + 1}"


def segments_from_rcin(tables: Mapping[str, pd.DataFrame],
                       params: Mapping[str, float] | None = None) -> list[StickSegment]:
    """Stick segments from the log's RCIN between the liftoff (:func:`airborne_us`) and
    disarming: runs where C1, C2 and C4 (roll, pitch, yaw) each stay within
    :data:`HOLD_TOL_PWM` of the run's first sample, at least :data:`MIN_SEGMENT_S` long (a
    step's ramp falls between two runs); the throttle (C3) splits runs where it moves more
    than :data:`THROTTLE_TOL_PWM`. Arming and disarming as
    :func:`~tlm_process.logread.arming_time_us` finds them (``params``: the log's, for a log
    without an arming event). Empty without RCIN."""
    rcin = tables.get("RCIN")
    if rcin is None or not len(rcin):
        return []
    t0, _ = arming_time_us(dict(tables), dict(params or {}))
    t1, _ = disarm_time_us(dict(tables), dict(params or {}), armed_us=t0)
    t = rcin["TimeUS"].to_numpy(np.int64)
    keep = np.ones(len(t), bool)
    if t0 is not None:
        up = airborne_us(tables, t0)
        keep &= t >= (t0 if up is None else up)
    if t1 is not None:
        keep &= t <= t1
    rc = rcin[keep]
    if not len(rc):
        return []
    t = rc["TimeUS"].to_numpy(np.int64)
    pwm = {a: rc[c].to_numpy(float) for a, c in STICK_CHANNELS.items() if c in rc}
    thr = (rc[THROTTLE_CHANNEL].to_numpy(float) if THROTTLE_CHANNEL in rc
           else np.full(len(t), NEUTRAL_PWM))
    runs: list[tuple[int, int]] = []
    start = 0
    for k in range(1, len(t) + 1):
        if k == len(t) or any(abs(v[k] - v[start]) > HOLD_TOL_PWM for v in pwm.values()) or (
                abs(thr[k] - thr[start]) > THROTTLE_TOL_PWM):
            runs.append((start, k - 1))
            start = k
    out: list[StickSegment] = []
    counts: dict[str, int] = {}
    for a, b in runs:
        if (t[b] - t[a]) * 1e-6 < MIN_SEGMENT_S:
            continue
        sticks = {ax: round(float(np.median(_stick(v[a:b + 1], ax))), 3)
                  for ax, v in pwm.items()}
        name = _name(sticks, float(np.median(thr[a:b + 1])), counts)
        out.append(StickSegment(name, int(t[a]), int(t[b]), sticks))
    return out


def airborne_us(tables: Mapping[str, pd.DataFrame], armed_us: float) -> float | None:
    """:data:`LIFTOFF_SETTLE_S` after the copter first climbs :data:`LIFTOFF_M` above its
    CTUN.Alt at arming [us]; None without CTUN or a climb."""
    ctun = tables.get("CTUN")
    if ctun is None or not len(ctun) or "Alt" not in ctun:
        return None
    after = ctun[ctun["TimeUS"] >= armed_us]
    alt = after["Alt"].to_numpy(float)
    if not len(alt):
        return None
    up = np.flatnonzero(alt > alt[0] + LIFTOFF_M)
    if not len(up):
        return None
    return float(after["TimeUS"].iloc[up[0]]) + LIFTOFF_SETTLE_S * 1e6


def _nan_stat(s: pd.Series | None, how: str) -> float:
    if s is None or not len(s):
        return math.nan
    v = s.to_numpy(float)
    return float({"mean": np.mean, "absmax": lambda x: np.max(np.abs(x)), "max": np.max,
                  "std": np.std, "range": np.ptp}[how](v))


def segment_metrics(tables: Mapping[str, pd.DataFrame], seg: StickSegment,
                    params: Mapping[str, float] | None = None) -> dict[str, float]:
    """The :data:`METRICS` of one stick segment (NaN where the log lacks the table);
    ``params`` (the log's) give the frame's motors, RCOU's first N outputs
    (:func:`tlm_process.logread.motor_columns`: FRAME_CLASS; a quad without it)."""
    a, b = seg.start_us, seg.end_us
    att = time_window(tables.get("ATT"), a, b)
    gps = tables.get("GPS")
    if gps is not None and "I" in gps:
        gps = gps[gps["I"] == 0]
    gps = time_window(gps, a, b)
    ctun = time_window(tables.get("CTUN"), a, b)
    rcou = time_window(tables.get("RCOU"), a, b)
    motors = motor_columns(rcou, dict(params or {}))
    others = motors[1:]
    excess = (rcou[motors[0]] - rcou[others].mean(axis=1)) if len(rcou) and others else None
    thr = throttle_out(ctun) if len(ctun) and ("ThO" in ctun or "ThrOut" in ctun) else None
    return {
        "pitch_mean_deg": _nan_stat(att.get("Pitch"), "mean"),
        "pitch_peak_deg": _nan_stat(att.get("Pitch"), "absmax"),
        "roll_mean_deg": _nan_stat(att.get("Roll"), "mean"),
        "roll_peak_deg": _nan_stat(att.get("Roll"), "absmax"),
        "speed_max_ms": _nan_stat(gps.get("Spd"), "max"),
        "alt_std_m": _nan_stat(ctun.get("Alt"), "std"),
        "alt_range_m": _nan_stat(ctun.get("Alt"), "range"),
        "motor1_excess_us": _nan_stat(excess, "mean"),
        "thr_out": _nan_stat(thr, "mean"),
    }


def pilot_signature(tables: Mapping[str, pd.DataFrame], segments: Sequence[StickSegment],
                    params: Mapping[str, float] | None = None) -> pd.DataFrame:
    """One row per stick segment: ``segment``, ``start_s`` / ``end_s`` (log time [s]), the
    stick positions and the :data:`METRICS`; ``params`` (the log's) give the frame's motor
    count (FRAME_CLASS; a quad without it)."""
    rows = []
    for seg in segments:
        rows.append({"segment": seg.name, "start_s": seg.start_us * 1e-6,
                     "end_s": seg.end_us * 1e-6,
                     **{f"stick_{k}": v for k, v in seg.sticks.items()},
                     **segment_metrics(tables, seg, params)})
    return pd.DataFrame(rows)


def flight_time_s(tables: Mapping[str, pd.DataFrame],
                  params: Mapping[str, float] | None = None) -> float:
    """Arming to disarming [s] (NaN when the log shows no arming)."""
    a, _ = arming_time_us(dict(tables), dict(params or {}))
    b, _ = disarm_time_us(dict(tables), dict(params or {}), armed_us=a)
    return (b - a) * 1e-6 if a is not None and b is not None else math.nan
