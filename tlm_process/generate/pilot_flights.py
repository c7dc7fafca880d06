"""Pilot-flown flights of a generated data set (issue 42): a stick script drawn per flight.

A pilot-flown flight arms by the rudder gesture in its mode (ALT_HOLD, LOITER or POSHOLD, by
their shares; STABILIZE when asked for), climbs to a drawn height, flies a drawn **pattern** of
stick segments for a drawn time, descends, lands and disarms by the rudder gesture (still
armed 20 s after the throttle went down, a fault having taken it higher or the wind keeping
the land detector from completing, the ground station selects LAND, which lands and disarms
it). The patterns:

* ``hover``: sticks centred throughout (the pilot holds position; the mode does the rest);
* ``lines``: pitch forward, release, pitch back, release, ... (out-and-back lines);
* ``box``: pitch forward, roll right, pitch back, roll left, each followed by a release;
* ``yaw_turns``: yaw right / left turns of a drawn rate and length between hovers;
* ``freestyle``: roll, pitch and yaw at once, each uniform in +-the drawn deflection (a pilot
  repositioning, as log171's pilot flew LOITER: roll, pitch and yaw 50-70 % together).

Each segment's stick deflection is uniform in ``stick`` (fraction of full stick), its length in
``leg_s`` [s], the release after it in ``release_s`` [s]. The ground station selects the mode
1 s after boot (MAVLink; the mode switch stays where SITL's idle receiver has it), so a
vehicle's own ``FLTMODEn`` (``--params``) need not hold it. In STABILIZE (a share of 0 unless
``modes`` gives it one) the pilot's hand works the throttle (stick script ``height`` /
``land``, :func:`tlm_sim.sensors.rc.pilot_hand`): it climbs to the height and holds it through
the pattern, lands at 0.7 m/s and puts the stick down on touchdown; auto-disarm
(``DISARM_DELAY``) or the gesture then disarms it. ACRO is not drawn: a held stick is a rate
there, and a script has no pilot closing the attitude loop.

The script's **origin** (the start of the pattern, after the climb) is where the fault draws
start counting, as AUTO's start does for missions; faults that would end after the descent
starts are dropped.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from tlm_process.generate.checks import fraction, known_keys, shares, value_range
from tlm_process.generate.errors import GenerateError
from tlm_sim.sensors.rc import HAND_CLIMB_MS, HAND_DESCENT_MS

__all__ = ["DEFAULT_PILOT", "PATTERNS", "PILOT_MODES", "draw_pilot", "pilot_script",
           "validate_pilot"]

#: the modes a drawn script flies by default (they hold the height themselves)
PILOT_MODES: tuple[str, ...] = ("ALT_HOLD", "LOITER", "POSHOLD")
#: and the ones a configuration may give a share: STABILIZE, its height held by the pilot's hand
KNOWN_PILOT_MODES: tuple[str, ...] = (*PILOT_MODES, "STABILIZE")
PATTERNS: tuple[str, ...] = ("hover", "lines", "box", "yaw_turns", "freestyle")
#: Default: no pilot-flown flights (``--pilot-share``); when there are, every mode and pattern
#: alike, sticks 20-60 %, heights 5-20 m, 150-400 s of pattern, legs 4-10 s, releases 5-10 s.
DEFAULT_PILOT: dict[str, Any] = {
    "share": 0.0, "modes": dict.fromkeys(PILOT_MODES, 1.0),
    "patterns": dict.fromkeys(PATTERNS, 1.0), "stick": (0.2, 0.6), "alt": (5.0, 20.0),
    "duration": (150.0, 400.0), "leg_s": (4.0, 10.0), "release_s": (5.0, 10.0)}
#: the script's timeline [s since boot]: the rudder gesture, the throttle up
ARM_GESTURE_S = 15.0
GESTURE_HOLD_S = 3.5
CLIMB_STICK = 0.8  # 1.26 m/s with the default PILOT_SPEED_UP and THR_DZ
CLIMB_MS = 1.26
DESCENT_STICK = 0.15  # -1.69 m/s
DESCENT_MS = 1.69
#: the arming delay, spool-up and takeoff before the climb rate holds [s]
TAKEOFF_LAG_S = 4.0
SETTLE_S = 5.0  # hover after the climb before the pattern
GCS_MODE_S = 1.0  # the ground station selects the mode
#: still armed this long after the throttle went down: the ground station selects LAND [s]
LAND_FALLBACK_S = 20.0


def _weights(d: Any, known: tuple[str, ...], what: str) -> dict[str, float]:
    """Validated shares (:func:`~tlm_process.generate.checks.shares`); mode names in any
    case, ACRO refused with why."""
    if isinstance(d, Mapping):
        d = {str(k).strip().upper() if what == "modes" else str(k).strip().lower(): v
             for k, v in d.items()}
        if "ACRO" in d:
            raise GenerateError("pilot modes: ACRO is not drawn (a held stick is a rate, and a "
                                f"script closes no attitude loop); choose from "
                                f"{', '.join(known)}")
    return shares(d, known, f"pilot {what}")


def validate_pilot(v: Any) -> dict[str, Any] | None:
    """The validated ``pilot`` setting of a scenario configuration (missing keys take
    :data:`DEFAULT_PILOT`'s); None: no pilot-flown flights drawn."""
    if v is None:
        return None
    if not isinstance(v, Mapping):
        raise GenerateError(f"pilot must be a mapping (share, modes, patterns, ...) or null, "
                            f"got {v!r}")
    known_keys(v, tuple(DEFAULT_PILOT), "pilot")
    share = fraction(v.get("share", DEFAULT_PILOT["share"]), "pilot share (--pilot-share)")
    out: dict[str, Any] = {"share": share,
                           "modes": _weights(v.get("modes", DEFAULT_PILOT["modes"]),
                                             KNOWN_PILOT_MODES, "modes"),
                           "patterns": _weights(v.get("patterns", DEFAULT_PILOT["patterns"]),
                                                PATTERNS, "patterns")}
    for key, lo_min in (("stick", 0.0), ("alt", 2.0), ("duration", 10.0), ("leg_s", 0.5),
                        ("release_s", 0.5)):
        out[key] = value_range(v.get(key, DEFAULT_PILOT[key]), f"pilot {key}", lo_min)
    if out["stick"][1] > 1.0:
        raise GenerateError("pilot stick is a fraction of full stick: at most 1")
    if out["alt"][1] > 100.0:
        raise GenerateError("pilot alt: at most 100 m")
    return out


def _pick(rng: np.random.Generator, shares: Mapping[str, float]) -> str:
    names = list(shares)
    w = np.array([shares[n] for n in names], dtype=np.float64)
    i = int(np.searchsorted(np.cumsum(w) / w.sum(), rng.random(), side="right"))
    return names[min(i, len(names) - 1)]


def draw_pilot(rng: np.random.Generator, cfg: Mapping[str, Any]) -> dict[str, Any] | None:
    """One flight's draw (the scenario's pilot stream): None for a mission flight (by the
    share; one uniform draw), else the mode, pattern, height, pattern length and the
    segments ``[[roll, pitch, yaw, length s, release s], ...]`` (rounded to 0.01 / 0.1 s)."""
    if float(rng.random()) >= cfg["share"]:
        return None
    mode = _pick(rng, cfg["modes"])
    pattern = _pick(rng, cfg["patterns"])
    alt = round(float(rng.uniform(*cfg["alt"])), 1)
    duration = round(float(rng.uniform(*cfg["duration"])), 1)
    segs: list[list[float]] = []
    t = 0.0
    k = 0
    while t < duration:
        s = round(float(rng.uniform(*cfg["stick"])), 2)
        leg = round(float(rng.uniform(*cfg["leg_s"])), 1)
        rel = round(float(rng.uniform(*cfg["release_s"])), 1)
        u = float(rng.random())
        axes = tuple(float(x) for x in rng.random(2)) if pattern == "freestyle" else (0.5, 0.5)
        roll, pitch, yaw = _stick(pattern, k, s, u, axes)
        segs.append([roll, pitch, yaw, leg, rel])
        t += leg + rel
        k += 1
    return {"mode": mode, "pattern": pattern, "alt": alt, "duration": duration,
            "segments": segs}


def _stick(pattern: str, k: int, s: float, u: float, axes: tuple[float, float] = (0.5, 0.5)
           ) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of segment k of a pattern, deflection s; u: a uniform draw (the
    yaw turn's direction, freestyle's yaw), ``axes``: two more (freestyle's roll and pitch)."""
    if pattern == "hover":
        return 0.0, 0.0, 0.0
    if pattern == "freestyle":
        return tuple(round(s * (2.0 * v - 1.0), 2) for v in (*axes, u))  # type: ignore[return-value]
    if pattern == "lines":
        return 0.0, s if k % 2 == 0 else -s, 0.0
    if pattern == "box":
        return ((0.0, s, 0.0), (s, 0.0, 0.0), (0.0, -s, 0.0), (-s, 0.0, 0.0))[k % 4]
    return 0.0, 0.0, s if u < 0.5 else -s


def pilot_script(draw: Mapping[str, Any]) -> tuple[list[dict[str, Any]], float, float]:
    """The stick script rows of a draw (:func:`draw_pilot`), the pattern's start (the fault
    draws' origin) and the descent's start [s since boot]."""
    rows: list[dict[str, Any]] = [
        {"t": GCS_MODE_S, "gcs_mode": draw["mode"]},
        {"t": ARM_GESTURE_S, "yaw": 1.0, "ramp": 0.0},
        {"t": ARM_GESTURE_S + GESTURE_HOLD_S, "yaw": 0.0, "ramp": 0.0},
    ]
    t_up = ARM_GESTURE_S + GESTURE_HOLD_S + 0.5
    hand = draw["mode"] == "STABILIZE"  # the pilot's hand climbs, holds and lands
    if hand:
        rows.append({"t": t_up, "height": float(draw["alt"])})
        t_hold = round(t_up + TAKEOFF_LAG_S + float(draw["alt"]) / HAND_CLIMB_MS, 1)
    else:
        rows.append({"t": t_up, "throttle": CLIMB_STICK, "ramp": 0.0})
        t_hold = round(t_up + TAKEOFF_LAG_S + float(draw["alt"]) / CLIMB_MS, 1)
        rows.append({"t": t_hold, "throttle": 0.5})
    t = round(t_hold + SETTLE_S, 1)
    origin = t
    for roll, pitch, yaw, leg, rel in draw["segments"]:
        if roll or pitch or yaw:
            rows.append({"t": t, "roll": roll, "pitch": pitch, "yaw": yaw})
            rows.append({"t": round(t + leg, 1), "roll": 0.0, "pitch": 0.0, "yaw": 0.0})
        t = round(t + leg + rel, 1)
    descent = t
    if hand:  # the hand puts the stick down on touchdown
        rows.append({"t": descent, "throttle": "land"})
        t_down = round(descent + (float(draw["alt"]) + 2.0) / HAND_DESCENT_MS + 4.0, 1)
    else:
        rows.append({"t": descent, "throttle": DESCENT_STICK})
        t_down = round(descent + (float(draw["alt"]) + 2.0) / DESCENT_MS + 4.0, 1)
        rows.append({"t": t_down, "throttle": 0.0, "ramp": 0.0})
    rows.append({"t": t_down + 1.0, "yaw": -1.0, "ramp": 0.0})
    rows.append({"t": t_down + 1.0 + GESTURE_HOLD_S, "yaw": 0.0, "ramp": 0.0})
    # a pilot whose copter is still flying (a fault took it higher, the wind held it off the
    # ground) hands over to LAND, which lands and disarms it
    rows.append({"t": t_down + LAND_FALLBACK_S, "gcs_mode": "LAND"})
    return rows, origin, descent

