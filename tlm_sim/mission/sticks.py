"""Stick scripts: what a pilot's transmitter sends over time (issue 42, part 2).

A script is a list of keyframes. Each row is a time ``t`` [s since boot, the log's
``TimeUS / 1e6``] and any of:
- ``roll``, ``pitch``, ``yaw`` in -1..1 (right, nose forward, yaw right positive);
- ``throttle`` in 0..1, or ``hold`` / ``land``: the pilot's hand flies the throttle stick from
  then on, holding the height the copter has, or descending at 0.7 m/s and putting the stick
  down on touchdown (as a pilot flying STABILIZE or ACRO does;
  :func:`tlm_sim.sensors.rc.pilot_hand`); a number afterwards takes the stick back at once;
- ``height`` [m above home, 0..100] instead of ``throttle``: the hand climbs (1.5 m/s) or
  descends (0.7 m/s) to it and holds it;
- ``mode``, a flight-mode name, set on the mode switch;
- ``gcs_mode``, a flight-mode name the ground station asks for over MAVLink at ``t`` (the
  switch stays where it is);
- ``ramp`` [s], the time each stick given on that row takes to move to its new position,
  linearly (default :data:`DEFAULT_RAMP_S`, the reference pilot flights' 0.5 s; 0 is a step).

A stick keeps its last position until a row moves it. Before the first row they are centred,
with the throttle at 0.

They become RC channels as a receiver delivers them (:meth:`StickScript.channels`), in PWM
[us] on the default RCMAP (C1 roll, C2 pitch with forward = low PWM, C3 throttle, C4 yaw; 1000
to 2000), and the mode switch on ``FLTMODE_CH``. The mode is put at the centre of the
switch position whose ``FLTMODEn`` holds it; ArduPilot's positions are split at
1231 / 1361 / 1491 / 1621 / 1750 us.

Files: YAML or JSON ``{"sticks": [{"t": 0, "mode": "LOITER"}, {"t": 60, "pitch": 0.4}, ...]}``,
or CSV with a header (``t,roll,pitch,throttle,yaw,mode,ramp``; an empty cell leaves that
stick where it is). Errors are :class:`StickScriptError` (a ``ValueError``) with a one-line
message naming the row.

This module reads and renders scripts; ``tlm fly --sticks`` and ``fly(None, sticks=...)`` fly
them in the pilot modes (:mod:`tlm_sim.control.pilot_modes`, docs/pilot.md).
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tlm_sim.ardupilot import MODE_NAMES, RC_IDLE_PWM
from tlm_sim.textfile import TextFileError, read_text

__all__ = ["AXES", "DEFAULT_RAMP_S", "HAND", "HEIGHT_PWM", "HOLD_PWM", "LAND_PWM", "StickScript",
           "StickScriptError", "height_code", "mode_pwm"]

#: the stick axes of a row, with their range
AXES: dict[str, tuple[float, float]] = {"roll": (-1.0, 1.0), "pitch": (-1.0, 1.0),
                                        "throttle": (0.0, 1.0), "yaw": (-1.0, 1.0)}
#: the reference pilot flights' ramp per step [s]
DEFAULT_RAMP_S = 0.5
#: a ramp this short or shorter is a step [s]
MIN_RAMP_S = 1e-9
#: RC channel (1-based) of each axis, ArduPilot's default RCMAP
CHANNEL: dict[str, int] = {"roll": 1, "pitch": 2, "throttle": 3, "yaw": 4}
#: the 6-position mode switch's upper PWM bounds (RC_Channel::read_6pos_switch) and each
#: position's centre [us]
SWITCH_BOUNDS: tuple[float, ...] = (1231.0, 1361.0, 1491.0, 1621.0, 1750.0)
SWITCH_CENTRES: tuple[float, ...] = (1165.0, 1295.0, 1425.0, 1555.0, 1685.0, 1815.0)
_KEYS = ("t", *AXES, "height", "mode", "gcs_mode", "ramp")
#: the pilot's hand holds heights up to this [m above home]
MAX_HAND_HEIGHT_M = 100.0
_MODES = {name: num for num, name in MODE_NAMES.items()}
#: throttle codes of an RC table (never a PWM; :func:`tlm_sim.sensors.rc.pilot_hand` flies
#: them): the pilot's hand holds the height, lands, or flies to the height -(code) - 10 m
HOLD_PWM = -1.0
LAND_PWM = -2.0
HEIGHT_PWM = -10.0
#: the throttle words: the pilot's hand flies the stick (their codes stand in the rendering)
HAND: dict[str, float] = {"hold": HOLD_PWM, "land": LAND_PWM}


def height_code(height_m: float) -> float:
    """The RC table's throttle code for "fly to ``height_m`` [m above home] and hold it"."""
    return HEIGHT_PWM - height_m


class StickScriptError(ValueError):
    """A stick script or its file is invalid; the message names the row (0-based)."""


def mode_pwm(mode: str, params: Mapping[str, float]) -> float:
    """PWM [us] of the switch position whose FLTMODEn is ``mode`` (a name of
    :data:`tlm_sim.ardupilot.MODE_NAMES`), StickScriptError when no position holds it."""
    num = _MODES.get(str(mode).strip().upper())
    if num is None:
        raise StickScriptError(f"unknown flight mode {mode!r}; known: {', '.join(_MODES)}")
    for k in range(6):
        if int(params[f"FLTMODE{k + 1}"]) == num:
            return SWITCH_CENTRES[k]
    slots = ", ".join(f"FLTMODE{k + 1} {MODE_NAMES.get(int(params[f'FLTMODE{k + 1}']), '?')}"
                      for k in range(6))
    raise StickScriptError(f"no mode switch position is {mode.upper()} ({slots}): set one "
                           f"FLTMODEn to {num}")


@dataclass(frozen=True)
class StickScript:
    """Keyframes ``rows`` (time-ordered dicts with ``t`` and the keys they set, each value
    checked; see the module docstring)."""

    rows: tuple[Mapping[str, Any], ...]

    def __post_init__(self) -> None:
        if isinstance(self.rows, str | bytes | Mapping) or not isinstance(self.rows, Sequence):
            raise StickScriptError("a stick script is a list of rows {t: s, roll: .., ...}")
        if not self.rows:
            raise StickScriptError("a stick script needs at least one row")
        clean = []
        last_t = -math.inf
        for i, row in enumerate(self.rows):
            r = _check_row(row, i)
            if r["t"] < last_t:
                raise StickScriptError(f"row {i}: t {r['t']:g} s is before the row above "
                                       f"({last_t:g} s); list rows in time order")
            last_t = r["t"]
            clean.append(r)
        object.__setattr__(self, "rows", tuple(clean))

    # -- files ----------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | Sequence[Mapping[str, Any]]) -> StickScript:
        """From ``{"sticks": [...]}`` or the list itself."""
        rows = d.get("sticks") if isinstance(d, Mapping) else d
        if rows is None:
            raise StickScriptError("expected a mapping with 'sticks': [rows]")
        return cls(tuple(rows))

    @classmethod
    def from_file(cls, path: str | Path) -> StickScript:
        """Read a ``.yaml`` / ``.yml`` / ``.json`` / ``.csv`` stick script."""
        p = Path(path)
        try:
            text = read_text(p)
        except TextFileError as exc:
            raise StickScriptError(f"{p}: {exc}") from None
        suffix = p.suffix.lower()
        if suffix == ".csv":
            return cls(tuple(_csv_rows(text, p)))
        if suffix not in (".yaml", ".yml", ".json"):
            raise StickScriptError(f"{p}: a stick script is .yaml, .yml, .json or .csv")
        try:
            import yaml

            doc = json.loads(text) if suffix == ".json" else yaml.safe_load(text)
        except (ValueError, yaml.YAMLError) as exc:
            raise StickScriptError(f"{p}: not valid {suffix[1:].upper()}: "
                                   f"{str(exc).splitlines()[0]}") from None
        try:
            return cls.from_dict(doc)
        except StickScriptError as exc:
            raise StickScriptError(f"{p}: {exc}") from None

    def to_dict(self) -> dict[str, Any]:
        """File form (:meth:`from_dict` reads it back to an equal script)."""
        return {"sticks": [dict(r) for r in self.rows]}

    # -- rendering ------------------------------------------------------------------------
    def sticks(self, t_s: float) -> dict[str, float]:
        """Each axis's position at time ``t_s`` [s]: a row moves a stick linearly from where
        it is at the row's time (mid-ramp, if an earlier move has not ended) to the new
        position over the row's ramp. The throttle is :data:`HAND`'s code (negative) while
        the pilot's hand flies it."""
        t = np.array([float(t_s)])
        return {axis: float(self._axis_at(axis, t)[0]) for axis in AXES}

    def mode(self, t_s: float) -> str | None:
        """The flight mode the switch is set to at ``t_s`` [s] (None before any row sets one)."""
        out = None
        for r in self.rows:
            if r["t"] > t_s:
                break
            out = r.get("mode", out)
        return out

    def channels(self, t_s: float, params: Mapping[str, float]) -> np.ndarray:
        """RC channels 1-8 [us] at ``t_s`` as the receiver delivers them: the sticks on the
        default RCMAP, over each channel's own range (``RCn_MIN`` / ``_TRIM`` / ``_MAX``: a
        centred stick at the trim, full stick at the end, throttle 0..1 over MIN..MAX), the
        mode switch on ``FLTMODE_CH`` (its position's centre) once a row sets a mode, SITL's
        idle values on the other channels (5: 1800, 6: 1000, 7: 1000, 8: 1800)."""
        ch = np.array(RC_IDLE_PWM)
        pos = self.sticks(t_s)
        for axis in AXES:
            ch[CHANNEL[axis] - 1] = _pwm(axis, np.array([pos[axis]]), params)[0]
        mode = self.mode(t_s)
        sw = int(params["FLTMODE_CH"])
        if mode is not None and 1 <= sw <= 8:
            ch[sw - 1] = mode_pwm(mode, params)
        return np.round(ch)

    def gcs_modes(self) -> np.ndarray:
        """The ground station's mode requests: rows (t [s since boot], mode number)."""
        rows = [(r["t"], float(_MODES[r["gcs_mode"]])) for r in self.rows if "gcs_mode" in r]
        return np.array(rows, dtype=np.float64).reshape(-1, 2)

    def table(self, params: Mapping[str, float], t_end_s: float,
              rate_hz: float = 50.0) -> np.ndarray:
        """Rows ``(t_s, C1..C8)`` every ``1 / rate_hz`` s from 0 to ``t_end_s`` (SITL's RC input
        comes at 50 Hz): what the simulation loop will read; each row what :meth:`channels`
        gives at its time (computed for all rows at once)."""
        n = int(math.floor(t_end_s * rate_hz)) + 1
        t = np.arange(n) / rate_hz
        out = np.empty((n, 9))
        out[:, 0] = t
        out[:, 1:] = np.array(RC_IDLE_PWM)
        for axis in AXES:
            out[:, CHANNEL[axis]] = _pwm(axis, self._axis_at(axis, t), params)
        sw = int(params["FLTMODE_CH"])
        mode_rows = [r for r in self.rows if "mode" in r]
        if mode_rows and 1 <= sw <= 8:
            starts = np.array([r["t"] for r in mode_rows])
            pwm = np.array([mode_pwm(r["mode"], params) for r in mode_rows])
            k = np.searchsorted(starts, t, side="right") - 1
            out[:, sw] = np.where(k >= 0, pwm[np.maximum(k, 0)], out[:, sw])
        out[:, 1:] = np.round(out[:, 1:])
        return out

    def _axis_at(self, axis: str, t: np.ndarray) -> np.ndarray:
        """Stick ``axis`` at every time of ``t`` (sorted) [s] (see :meth:`sticks`): the moves
        (start, from, to, ramp) worked out row by row, each from where the stick is at its
        start, then each time's latest move evaluated."""
        moves = []
        move = (0.0, 0.0, 0.0, 0.0)
        for r in self.rows:
            if axis == "throttle" and "height" in r:
                r = {**r, "throttle": height_code(r["height"])}
            if axis in r:
                t0, v0, v1, ramp = move
                frac = 1.0 if ramp <= MIN_RAMP_S else min(max((r["t"] - t0) / ramp, 0.0),
                                                          1.0)
                to = HAND.get(r[axis], r[axis]) if isinstance(r[axis], str) else r[axis]
                if axis == "throttle" and (to < 0.0 or v1 < 0.0):  # into or out of the
                    # pilot's hand (its codes are negative): a step
                    move = (r["t"], to, to, 0.0)
                else:
                    move = (r["t"], v0 + (v1 - v0) * frac, to, r.get("ramp", DEFAULT_RAMP_S))
                moves.append(move)
        out = np.zeros(len(t))
        if not moves:
            return out
        m = np.array(moves)
        k = np.searchsorted(m[:, 0], t, side="right") - 1
        ok = k >= 0
        t0, v0, v1, ramp = (m[k[ok], j] for j in range(4))
        step = ramp <= MIN_RAMP_S
        frac = np.where(step, 1.0, np.clip((t[ok] - t0) / np.where(step, 1.0, ramp), 0.0, 1.0))
        out[ok] = v0 + (v1 - v0) * frac
        return out


def stick_pwm(axis: str, pos: Any, params: Mapping[str, float]) -> Any:
    """PWM [us] of stick ``axis`` at ``pos`` (a number or an array) on its channel's range:
    roll and yaw from ``RCn_TRIM`` towards ``RCn_MAX`` (right) or ``RCn_MIN``, pitch the other
    way (forward is low PWM), the throttle from ``RCn_MIN`` (0) to ``RCn_MAX`` (1); SITL's
    1000 / 1500 / 2000 where ``params`` lacks them."""
    ch = CHANNEL[axis]
    lo = params.get(f"RC{ch}_MIN", 1000.0)
    hi = params.get(f"RC{ch}_MAX", 2000.0)
    if axis == "throttle":
        return lo + (hi - lo) * pos
    trim = params.get(f"RC{ch}_TRIM", 1500.0)
    p = -pos if axis == "pitch" else pos
    return np.where(p >= 0.0, trim + p * (hi - trim), trim + p * (trim - lo))


def _pwm(axis: str, pos: np.ndarray, params: Mapping[str, float]) -> np.ndarray:
    """:func:`stick_pwm`, the pilot's-hand codes of the throttle passed through."""
    pwm = np.asarray(stick_pwm(axis, pos, params), dtype=np.float64)
    return np.where(pos < 0.0, pos, pwm) if axis == "throttle" else pwm


def _number(v: Any, what: str, i: int) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(float(v)):
        raise StickScriptError(f"row {i}: {what} must be a finite number, got {v!r}")
    return float(v)


def _axis_value(row: Mapping[str, Any], key: str, i: int, bounds: tuple[float, float]
                ) -> float | str:
    """Row i's checked ``key``: a number within bounds, or a throttle word of :data:`HAND`."""
    if key == "throttle" and isinstance(row[key], str):
        word = row[key].strip().lower()
        if word not in HAND:
            raise StickScriptError(f"row {i}: throttle {row[key]!r} is not a number, 'hold' "
                                   f"or 'land'")
        return word
    v = _number(row[key], key, i)
    lo, hi = bounds
    if not lo <= v <= hi:
        raise StickScriptError(f"row {i}: {key} {v:g} is outside {lo:g}..{hi:g}")
    return v


def _check_row(row: Any, i: int) -> dict[str, Any]:
    if not isinstance(row, Mapping):
        raise StickScriptError(f"row {i}: expected a mapping like {{t: 60, pitch: 0.4}}, "
                               f"got {row!r}")
    unknown = [k for k in row if k not in _KEYS]
    if unknown:
        raise StickScriptError(f"row {i}: unknown key {unknown[0]!r}; keys: {', '.join(_KEYS)}")
    if "t" not in row:
        raise StickScriptError(f"row {i}: missing 't' (seconds since boot)")
    out: dict[str, Any] = {"t": _number(row["t"], "t", i)}
    if out["t"] < 0:
        raise StickScriptError(f"row {i}: t must be >= 0 s, got {out['t']:g}")
    for axis, (lo, hi) in AXES.items():
        if axis in row:
            out[axis] = _axis_value(row, axis, i, (lo, hi))
    if "height" in row:
        if "throttle" in row:
            raise StickScriptError(f"row {i}: give throttle or height, not both")
        out["height"] = _axis_value(row, "height", i, (0.0, MAX_HAND_HEIGHT_M))
    for key in ("mode", "gcs_mode"):
        if key in row:
            name = str(row[key]).strip().upper()
            if name not in _MODES:
                raise StickScriptError(f"row {i}: unknown flight mode {row[key]!r}; known: "
                                       f"{', '.join(_MODES)}")
            out[key] = name
    if "ramp" in row:
        r = _number(row["ramp"], "ramp", i)
        if r < 0:
            raise StickScriptError(f"row {i}: ramp must be >= 0 s, got {r:g}")
        out["ramp"] = r
    if len(out) == 1 or set(out) == {"t", "ramp"}:
        raise StickScriptError(f"row {i}: sets nothing (give a stick or a mode)")
    return out


def _csv_rows(text: str, path: Path) -> list[dict[str, Any]]:
    """Rows of a CSV stick script (header ``t,roll,pitch,throttle,yaw,mode,ramp``, any
    subset in any order; empty cells are not set)."""
    reader = csv.DictReader(io.StringIO(text))
    if not reader.fieldnames or "t" not in reader.fieldnames:
        raise StickScriptError(f"{path}: the CSV needs a header with a 't' column and the "
                               f"sticks (t,roll,pitch,throttle,yaw,mode,ramp)")
    rows = []
    for i, rec in enumerate(reader):
        row: dict[str, Any] = {}
        for k, v in rec.items():
            if k is None or v is None or not str(v).strip():
                continue
            if k in ("mode", "gcs_mode") or (k == "throttle" and v.strip().lower() in HAND):
                row[k] = v.strip()
                continue
            try:
                row[k] = float(v)
            except ValueError:
                raise StickScriptError(f"{path}: row {i}: {k} {v!r} is not a number") from None
        rows.append(row)
    return rows
