"""The whole-log detector's features: trailing-window statistics of each channel.

For every grid row (:mod:`.channels`, :data:`~.channels.GRID_HZ`) and channel, over trailing
windows of :data:`WINDOW_S` (2 s and 10 s: a fault's onset, and how it develops):

* ``level`` channels: the value, and per window its mean, standard deviation, minimum,
  maximum, mean absolute row-to-row change and change over the window (last minus first);
* ``delta`` channels: per window the standard deviation, mean absolute change and change
  (nothing that depends on the level);
* ``state`` channels: the value, the seconds since it last changed (at most
  :data:`STATE_MEMORY_S`, and that before its first change: the first mode is no change,
  so no feature says how long ago the flight started) and how many times it changed in the trailing
  :data:`STATE_MEMORY_S` (an event's history: a GPS glitch is flagged and cleared, ERR 11/2
  then 11/0, when it starts and again when it ends, so the second flag within a minute is
  the glitch's end and a clear with one flag before it the glitch still on).

All windows end at the row (causal). A channel's rows before its first finite value are NaN
in every feature (nothing is filled from the future); a NaN inside (a NaN the log holds) repeats
the last finite value. The statistics are those of ``tlm evaluate``'s window models
(:func:`tlm_process.evaluate.temporal._trailing_stats`, one numba pass).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from tlm_process.detect.channels import CHANNELS, GRID_HZ
from tlm_process.evaluate.temporal import _trailing_stats

__all__ = ["STATE_MEMORY_S", "WINDOW_S", "feature_matrix", "feature_names"]

#: Trailing window lengths [s].
WINDOW_S: tuple[float, ...] = (2.0, 10.0)
#: Seconds-since-change of a state channel are capped here, and its changes are counted over
#: this trailing window [s].
STATE_MEMORY_S: float = 60.0

_KIND = {c.name: c.kind for c in CHANNELS}
_LEVEL_STATS = ("mean", "std", "min", "max", "absdiff", "change")
_DELTA_STATS = ("std", "absdiff", "change")
_DELTA_COLS = (1, 4, 5)  # their columns in _trailing_stats' output


def feature_names(channels: Sequence[str]) -> list[str]:
    """Feature column names of ``channels``, in :func:`feature_matrix`'s order."""
    out: list[str] = []
    for c in channels:
        kind = _KIND[c]
        if kind == "state":
            out += [c, f"{c}_age", f"{c}_changes{STATE_MEMORY_S:g}s"]
            continue
        if kind == "level":
            out.append(c)
        stats = _LEVEL_STATS if kind == "level" else _DELTA_STATS
        for s in WINDOW_S:
            out += [f"{c}_{st}{s:g}s" for st in stats]
    return out


def _ffill(v: np.ndarray) -> tuple[np.ndarray, int]:
    """(``v`` with interior NaNs replaced by the last finite value, index of the first finite
    value; ``len(v)`` when none)."""
    ok = np.isfinite(v)
    if not ok.any():
        return v, len(v)
    first = int(np.argmax(ok))
    idx = np.where(ok, np.arange(len(v)), 0)
    np.maximum.accumulate(idx, out=idx)
    return v[idx], first


def _value_changes(v: np.ndarray) -> np.ndarray:
    """Per row, whether ``v`` changed there from one value to another (bool). The first value
    after none (the flight mode's first MODE row, at arming or takeoff) is no change: taken
    as one, it would tell the detector how long ago the flight started."""
    change = np.zeros(len(v), dtype=bool)
    if len(v) > 1:
        a, b = v[1:], v[:-1]
        change[1:] = (a != b) & np.isfinite(a) & np.isfinite(b)
    return change


def _state_age(v: np.ndarray, hz: float) -> np.ndarray:
    """Seconds since ``v`` last changed (:func:`_value_changes`), capped at
    :data:`STATE_MEMORY_S`; the cap before its first change (nothing happened: as long ago as
    the detector remembers)."""
    n = len(v)
    change = _value_changes(v)
    last = np.where(change, np.arange(n), -1)
    np.maximum.accumulate(last, out=last)
    age = (np.arange(n) - last) / hz
    age[last < 0] = STATE_MEMORY_S
    return np.minimum(age, STATE_MEMORY_S)


def _state_changes(v: np.ndarray, hz: float) -> np.ndarray:
    """How many times ``v`` changed (:func:`_value_changes`) within the trailing
    :data:`STATE_MEMORY_S` (the rows up to and including each)."""
    total = np.cumsum(_value_changes(v), dtype=np.float64)
    w = max(1, int(round(STATE_MEMORY_S * hz)))
    out = total.copy()
    out[w:] -= total[:-w]
    return out


def feature_matrix(channels_df: pd.DataFrame, channels: Sequence[str],
                   hz: float = GRID_HZ) -> np.ndarray:
    """Features (float32, rows of ``channels_df`` in order, :func:`feature_names` columns) of
    one log's channel table (:func:`~.channels.channel_table`; its rows on the grid of
    ``hz``)."""
    n = len(channels_df)
    widths = [max(2, int(round(s * hz))) for s in WINDOW_S]
    cols: list[np.ndarray] = []
    for c in channels:
        kind = _KIND[c]
        raw = channels_df[c].to_numpy(np.float64)
        if kind == "state":
            cols += [raw, _state_age(raw, hz), _state_changes(raw, hz)]
            continue
        v, first = _ffill(raw)
        k = len(_LEVEL_STATS) if kind == "level" else len(_DELTA_STATS)
        block = np.full((n, (1 if kind == "level" else 0) + k * len(widths)), np.nan)
        if first < n:
            seg = v[first:]
            parts = [seg[:, None]] if kind == "level" else []
            for w in widths:
                st = _trailing_stats(np.ascontiguousarray(seg), w, 0, len(seg))
                parts.append(st if kind == "level" else st[:, _DELTA_COLS])
            block[first:] = np.column_stack(parts)
        cols.extend(block.T)
    if not cols:
        return np.empty((n, 0), dtype=np.float32)
    return np.column_stack(cols).astype(np.float32)
