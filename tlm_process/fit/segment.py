"""Steady segments of a log: where a copter hovers or cruises without manoeuvring, the part of
a flight whose noise says most about the vehicle (``tlm fit``, issue 40).

A window of :data:`WINDOW_S` seconds, stepped by :data:`STEP_S`, is steady when the copter is
airborne and upright (mean throttle above :data:`AIRBORNE_THR`, mean |roll| and |pitch| below
:data:`UPRIGHT_MAX_DEG`), holds one flight mode, and neither it nor its pilot moves much: the
standard deviations of the desired roll and pitch (ATT ``DesRoll``/``DesPitch``) stay below
:data:`DES_STD_MAX_DEG` and of the altitude (CTUN ``Alt``) below :data:`ALT_STD_MAX_M`.
Overlapping steady windows merge into segments.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from tlm_process.fit.stats import StatsError

__all__ = ["AIRBORNE_THR", "ALT_STD_MAX_M", "DES_STD_MAX_DEG", "LEVEL_MODES", "POSITION_MODES",
           "STEP_S",
           "UPRIGHT_MAX_DEG", "WINDOW_S", "parse_segment", "segment_mode", "steady_segments"]

WINDOW_S = 6.0
STEP_S = 1.0
AIRBORNE_THR = 0.2
DES_STD_MAX_DEG = 1.5
ALT_STD_MAX_M = 0.5
UPRIGHT_MAX_DEG = 30.0


def _col(df: pd.DataFrame, *names: str) -> pd.Series | None:
    for n in names:
        if n in df:
            return pd.to_numeric(df[n], errors="coerce")
    return None


def steady_segments(tables: Mapping[str, pd.DataFrame]) -> list[tuple[float, float]]:
    """The log's steady segments ``(t0_us, t1_us)``, longest first (empty when none)."""
    att, ctun = tables.get("ATT"), tables.get("CTUN")
    if att is None or ctun is None or not len(att) or not len(ctun):
        return []
    thr = _col(ctun, "ThO")
    if thr is None:
        thr = _col(ctun, "ThrOut")
        thr = None if thr is None else thr / 1000.0
    alt = _col(ctun, "Alt")
    if thr is None or alt is None:
        return []
    t_att = att.TimeUS.to_numpy(float)
    t_ctun = ctun.TimeUS.to_numpy(float)
    start, end = max(t_att[0], t_ctun[0]), min(t_att[-1], t_ctun[-1])
    mode = tables.get("MODE")
    changes = (mode.TimeUS.to_numpy(float) if mode is not None and "TimeUS" in mode
               else np.array([]))
    steady = []
    t = start
    w, step = WINDOW_S * 1e6, STEP_S * 1e6
    while t + w <= end:
        a = att[(t_att >= t) & (t_att < t + w)]
        c = (t_ctun >= t) & (t_ctun < t + w)
        ok = (len(a) > 5 and c.sum() > 5 and float(thr[c].mean()) > AIRBORNE_THR
              and not ((changes > t) & (changes < t + w)).any()
              and float(a.Roll.abs().mean()) < UPRIGHT_MAX_DEG
              and float(a.Pitch.abs().mean()) < UPRIGHT_MAX_DEG
              and float(a.DesRoll.std()) < DES_STD_MAX_DEG
              and float(a.DesPitch.std()) < DES_STD_MAX_DEG
              and float(alt[c].std()) < ALT_STD_MAX_M)
        if ok:
            steady.append(t)
        t += step
    segments: list[list[float]] = []
    for s in steady:
        if segments and s <= segments[-1][1]:
            segments[-1][1] = s + w
        else:
            segments.append([s, s + w])
    return sorted(((a, b) for a, b in segments), key=lambda ab: ab[0] - ab[1])


def parse_segment(text: str) -> tuple[float, float]:
    """``START:END`` in seconds of log time -> (t0_us, t1_us); raises StatsError."""
    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise StatsError(f"--segment wants START:END in seconds, got {text!r}") from None
    if not (np.isfinite(a) and np.isfinite(b) and b > a >= 0):
        raise StatsError(f"--segment {text}: END must be after START")
    return a * 1e6, b * 1e6


#: flight modes that hold the horizontal position, as the fit's hovers (AUTO) do: AUTO,
#: GUIDED, LOITER, RTL, CIRCLE, LAND, POSHOLD, BRAKE
POSITION_MODES = frozenset({3, 4, 5, 6, 7, 9, 16, 17})
#: flight modes that level the copter from the sticks but hold no position: STABILIZE and
#: ALT_HOLD. A segment flown in one is fitted with ALT_HOLD hovers (a script can fly ALT_HOLD;
#: STABILIZE's height is the pilot's, and a hovering pilot holds it)
LEVEL_MODES = frozenset({0, 2})


def segment_mode(tables: Mapping[str, pd.DataFrame], t0_us: float) -> int | None:
    """The flight mode (MODE.ModeNum) at ``t0_us``: the last MODE row at or before it; None
    without MODE rows before it."""
    mode = tables.get("MODE")
    if mode is None or not len(mode) or "ModeNum" not in mode:
        return None
    before = mode[mode["TimeUS"] <= t0_us]
    return int(before["ModeNum"].iloc[-1]) if len(before) else None
