"""Validation of scenario settings shared by :mod:`tlm_process.generate.scenario` and
:mod:`tlm_process.generate.pilot_flights`: shares by name and (low, high) ranges."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from tlm_process.generate.errors import GenerateError

__all__ = ["fraction", "known_keys", "shares", "value_range"]


def shares(d: Mapping[str, Any], known: tuple[str, ...], what: str) -> dict[str, float]:
    """Validated shares in ``known`` order (missing names get 0); at least one > 0."""
    if not isinstance(d, Mapping):
        raise GenerateError(f"{what} must be a mapping name -> share, got {type(d).__name__}")
    unknown = [k for k in d if k not in known]
    if unknown:
        raise GenerateError(f"{what}: unknown {unknown[0]!r}; choose from {', '.join(known)}")
    out = {}
    for k in known:
        v = d.get(k, 0.0)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or v < 0:
            raise GenerateError(f"{what}: share of {k!r} must be a number >= 0, got {v!r}")
        out[k] = float(v)
    if sum(out.values()) <= 0:
        raise GenerateError(f"{what}: at least one share must be > 0")
    return out


def value_range(v: Any, what: str, lo_min: float = 0.0) -> tuple[float, float]:
    """A validated (low, high) pair: finite, ``lo_min <= low <= high``."""
    try:
        lo, hi = (float(x) for x in v)
    except (TypeError, ValueError):
        raise GenerateError(f"{what} must be a pair (low, high), got {v!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)) or lo < lo_min or hi < lo:
        raise GenerateError(f"{what} must be finite with {lo_min:g} <= low <= high, got "
                            f"({lo:g}, {hi:g})")
    return lo, hi


def known_keys(d: Mapping[str, Any], known: tuple[str, ...], what: str) -> None:
    """GenerateError naming the first key of setting ``what`` that is not in ``known``."""
    unknown = [k for k in d if k not in known]
    if unknown:
        raise GenerateError(f"{what}: unknown setting {unknown[0]!r}; known: "
                            f"{', '.join(known)}")


def fraction(v: Any, what: str) -> float:
    """A share in [0, 1] (``what`` names it in the error)."""
    if isinstance(v, bool) or not isinstance(v, int | float) or not 0 <= v <= 1:
        raise GenerateError(f"{what} must be a number in [0, 1], got {v!r}")
    return float(v)
