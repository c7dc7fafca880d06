"""Steady segments of a log: where a copter hovers or cruises without manoeuvring, the part of
a flight whose noise says most about the vehicle (``tlm fit``, issue 40).

A window of :data:`WINDOW_S` seconds, stepped by :data:`STEP_S`, is steady when the copter is
airborne and upright (mean throttle above :data:`AIRBORNE_THR`, mean |roll| and |pitch| below
:data:`UPRIGHT_MAX_DEG`), holds one flight mode, and neither it nor its pilot moves much: the
standard deviations of the desired roll and pitch (ATT ``DesRoll``/``DesPitch``) stay below
:data:`DES_STD_MAX_DEG` and of the altitude (CTUN ``Alt``) below :data:`ALT_STD_MAX_M`, and
(where the log has RCIN) the pilot's roll, pitch and yaw sticks have rested for
:data:`SETTLE_S` before it and rest through it (:func:`sticks_rest`): after a stick release
LOITER and POSHOLD brake for seconds, a manoeuvre's tail, not the vehicle's noise.
Overlapping steady windows merge into segments, hovers and cruise apart: a window is a hover
when the copter's mean GPS ground speed in it stays below :data:`HOVER_SPEED_MS` (leaning into
the wind, standing still), or, in a mode that levels the copter but holds no position
(:data:`LEVEL_MODES`), when its desired roll and pitch stay within :data:`HOVER_LEAN_DEG` on
average (drifting with the air, hovering in it); cruise otherwise. Hovers come first (unless
the log's longest cruise is more than :data:`HOVER_PREFERENCE` times its longest hover): the fit
flies hovers, and a cruise's drag, lean and motor commands are not a hover's.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from tlm_process.fit.stats import StatsError
from tlm_process.pilot.signature import STICK_CHANNELS as _SEGMENT_STICKS

__all__ = ["AIRBORNE_THR", "ALT_STD_MAX_M", "DES_STD_MAX_DEG", "HOVER_LEAN_DEG", "HOVER_PREFERENCE",
           "HOVER_SPEED_MS", "LEVEL_MODES", "POSITION_MODES", "SETTLE_S", "STEP_S",
           "STICK_CHANNELS", "STICK_REST_PWM", "UPRIGHT_MAX_DEG", "WINDOW_S", "is_hover",
           "parse_segment", "segment_mode", "segment_speed", "steady_segments", "sticks_rest"]

WINDOW_S = 6.0
STEP_S = 1.0
AIRBORNE_THR = 0.2
DES_STD_MAX_DEG = 1.5
ALT_STD_MAX_M = 0.5
UPRIGHT_MAX_DEG = 30.0
#: a window whose mean GPS ground speed is below this is a hover [m/s]
HOVER_SPEED_MS = 1.0
#: hovers come first unless the longest cruise segment is more than this many times the longest
#: hover (a mission log: cruise legs of a minute, a hover of seconds before its landing)
HOVER_PREFERENCE = 4.0
#: in STABILIZE or ALT_HOLD a window whose mean desired roll and pitch are within this is a
#: hover whatever its ground speed (the air carries it) [deg]
HOVER_LEAN_DEG = 3.0
#: a steady window starts this long [s] after the pilot last moved a roll, pitch or yaw stick:
#: LOITER brakes a released stick's speed after LOIT_BRK_DELAY (1 s) at up to LOIT_BRK_ACCEL,
#: POSHOLD over PHLD_BRAKE_RATE's few seconds. log171's pilot let go of the roll stick at
#: 196.3 s from 3 m/s; its LOITER leaned 12.8 deg at 197.1 s and 7.1 deg at 197.6 s, settled
#: by 198.2 s
SETTLE_S = 3.0
#: RCIN's roll, pitch and yaw channels (ArduPilot's default RCMAP), the stick segments' own
STICK_CHANNELS = tuple(_SEGMENT_STICKS.values())
#: a stick within this of its median over the window rests there [us] (Copter's default RC1_DZ,
#: RC2_DZ, RC4_DZ: within it the sticks ask for nothing)
STICK_REST_PWM = 20.0


def _col(df: pd.DataFrame, *names: str) -> pd.Series | None:
    for n in names:
        if n in df:
            return pd.to_numeric(df[n], errors="coerce")
    return None


def segment_speed(tables: Mapping[str, pd.DataFrame], t0_us: float, t1_us: float) -> float:
    """The mean GPS ground speed (GPS instance 0's ``Spd``) over ``[t0_us, t1_us)`` [m/s]; NaN
    without GPS rows there."""
    gps = tables.get("GPS")
    if gps is None or not len(gps) or "Spd" not in gps:
        return float("nan")
    if "I" in gps:
        gps = gps[gps["I"] == 0]
    t = gps.TimeUS.to_numpy(float)
    v = pd.to_numeric(gps.Spd, errors="coerce").to_numpy(float)[(t >= t0_us) & (t < t1_us)]
    v = v[np.isfinite(v)]
    return float(v.mean()) if len(v) else float("nan")


def is_hover(tables: Mapping[str, pd.DataFrame], t0_us: float, t1_us: float) -> bool:
    """Whether the copter hovers over ``[t0_us, t1_us)``: its mean GPS ground speed below
    :data:`HOVER_SPEED_MS` (or no GPS rows), or in a :data:`LEVEL_MODES` mode its mean desired
    roll and pitch (ATT) within :data:`HOVER_LEAN_DEG` (drifting with the air)."""
    att = tables.get("ATT")
    if segment_mode(tables, t0_us) in LEVEL_MODES and att is not None and len(att):
        a = att[(att.TimeUS >= t0_us) & (att.TimeUS < t1_us)]
        if (len(a) and abs(float(a.DesRoll.mean())) < HOVER_LEAN_DEG
                and abs(float(a.DesPitch.mean())) < HOVER_LEAN_DEG):
            return True
    return not segment_speed(tables, t0_us, t1_us) >= HOVER_SPEED_MS


def sticks_rest(tables: Mapping[str, pd.DataFrame], t0_us: float, t1_us: float) -> bool:
    """Whether the pilot's roll, pitch and yaw sticks (RCIN :data:`STICK_CHANNELS`) rest over
    ``[t0_us - SETTLE_S, t1_us)``: every row within :data:`STICK_REST_PWM` of the stick's
    median over ``[t0_us, t1_us)`` (its rest, whatever the trim). True without RCIN rows
    there (a log without a receiver's record, or an AUTO flight's idle sticks)."""
    return _sticks_rest(_stick_rows(tables), t0_us, t1_us)


def _stick_rows(tables: Mapping[str, pd.DataFrame]) -> tuple[np.ndarray, np.ndarray] | None:
    """RCIN's times [us] and its :data:`STICK_CHANNELS` that the log has, as PWM columns
    [us], read once for every window; None without RCIN rows."""
    rcin = tables.get("RCIN")
    if rcin is None or not len(rcin):
        return None
    cols = [pd.to_numeric(rcin[ch], errors="coerce").to_numpy(float)
            for ch in STICK_CHANNELS if ch in rcin]
    pwm = np.column_stack(cols) if cols else np.empty((len(rcin), 0))
    return rcin.TimeUS.to_numpy(float), pwm


def _sticks_rest(rows: tuple[np.ndarray, np.ndarray] | None, t0_us: float,
                 t1_us: float) -> bool:
    """:func:`sticks_rest` on :func:`_stick_rows` (RCIN rows are in time order)."""
    if rows is None:
        return True
    t, pwm = rows
    a, k0, k1 = np.searchsorted(t, (t0_us - SETTLE_S * 1e6, t0_us, t1_us))
    if k1 <= k0:
        return True
    rest = np.median(pwm[k0:k1], axis=0)
    return not (np.abs(pwm[a:k1] - rest) > STICK_REST_PWM).any()


def steady_segments(tables: Mapping[str, pd.DataFrame]) -> list[tuple[float, float]]:
    """The log's steady segments ``(t0_us, t1_us)``: the hovers, longest first, then the
    cruise segments, longest first; longest first whatever their kind when the longest cruise
    is more than :data:`HOVER_PREFERENCE` times the longest hover (empty when none; a log
    without GPS: all hovers)."""
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
    sticks = _stick_rows(tables)
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
              and float(alt[c].std()) < ALT_STD_MAX_M
              and _sticks_rest(sticks, t, t + w))
        if ok:
            steady.append((t, is_hover(tables, t, t + w)))
        t += step
    segments: list[list[float]] = []
    for s, hover in steady:
        if segments and s <= segments[-1][1] and hover == segments[-1][2]:
            segments[-1][1] = s + w
        else:
            segments.append([s, s + w, hover])
    longest = sorted(segments, key=lambda s: s[0] - s[1])
    hovers = [s for s in longest if s[2]]
    if hovers and (hovers[0][1] - hovers[0][0]) * HOVER_PREFERENCE >= (
            longest[0][1] - longest[0][0]):
        longest = hovers + [s for s in longest if not s[2]]
    return [(a, b) for a, b, _ in longest]


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
