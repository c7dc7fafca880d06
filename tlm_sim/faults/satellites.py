"""Satellite-count jitter of the TLM paper (§3.3, Eq. 3, Figs. 7 and 8).

SITL's u-blox reports a constant satellite count (10 with a fix, 3 during a GPS fault), which
makes the GPS fault trivially visible in ``GPS.NSats``. The paper replaces it by a draw from

    f(x) = Max / (sqrt(2 pi) mu) * exp(-((x - Max) / (2 mu^2))^2),   x = Min, ..., Max

normalised over the integers, with (Min, Max) = (8, 20) while the GPS works and (3, 10)
during a GPS fault. ``f`` peaks at ``x = Max`` and falls off below it like a Gaussian with
standard deviation ``sqrt(2) mu^2`` (the exponent is ``-(x - Max)^2 / (4 mu^4)``), so a larger
``mu`` spreads the counts further down from ``Max``.

Default ``mu``: :data:`DEFAULT_MU` = 1.5. The paper gives no value, only the counts it aims
at: "between 15 and 20" in normal flight and "between 5 and 10" during a GPS failure (its
reference [20]). With ``mu = 1.5`` (fall-off sigma 3.2 satellites) 93 % of the normal draws lie
in 15..20 (mean 17.8, std 2.0) and 94 % of the fault draws in 5..10 (mean 7.9, std 1.8): the
widest spread that keeps about 19 in 20 draws inside the paper's ranges. ``mu = 1`` gives
nearly constant counts (std 0.9, 44 % of fault draws exactly 10), ``mu = 2`` puts 29 % of the
normal draws below 15.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = [
    "DEFAULT_MU",
    "FAULT_SATS",
    "NORMAL_SATS",
    "jitter_nsats",
    "satellite_curve",
    "satellite_weights",
]

#: (Min, Max) satellites while the GPS has a 3D fix (paper §3.3).
NORMAL_SATS: tuple[int, int] = (8, 20)
#: (Min, Max) satellites during a GPS fault (paper §3.3).
FAULT_SATS: tuple[int, int] = (3, 10)
#: Default curvature ``mu`` of Eq. 3 (see the module docstring for why 1.5).
DEFAULT_MU = 1.5
#: ``GPS.Status`` from which a row counts as "GPS working" (3 = 3D fix; SITL reports 6).
FIX_3D = 3
#: Second word of the jitter's random seed, separating its stream from the flight's others.
_SEED_TAG = 0x5A7


def _check_mu(mu: float) -> float:
    if isinstance(mu, bool) or not isinstance(mu, numbers.Real) or not (
            math.isfinite(float(mu)) and float(mu) > 0):
        raise ValueError(f"mu must be a finite number > 0, got {mu!r}")
    return float(mu)


def satellite_curve(x: np.ndarray | float, max_sats: int, mu: float) -> np.ndarray:
    """Eq. 3 of the paper, ``f(x)`` (unnormalised; ``f(max_sats) = max_sats/(sqrt(2 pi) mu)``)."""
    mu = _check_mu(mu)
    x = np.asarray(x, dtype=np.float64)
    return max_sats / (math.sqrt(2.0 * math.pi) * mu) * np.exp(
        -(((x - max_sats) / (2.0 * mu * mu)) ** 2))


def satellite_weights(min_sats: int, max_sats: int, mu: float) -> np.ndarray:
    """Probabilities of ``min_sats, min_sats + 1, ..., max_sats`` satellites: Eq. 3 over
    those integers, normalised to sum 1 (float64, length ``max_sats - min_sats + 1``)."""
    for name, v in (("min_sats", min_sats), ("max_sats", max_sats)):
        if isinstance(v, bool) or not isinstance(v, numbers.Integral) or not 0 <= v <= 255:
            raise ValueError(f"{name} must be a whole number in 0..255, got {v!r}")
    if min_sats > max_sats:
        raise ValueError(f"min_sats {min_sats} is above max_sats {max_sats}")
    f = satellite_curve(np.arange(min_sats, max_sats + 1), int(max_sats), mu)
    return f / f.sum()  # f(max_sats) > 0, so the sum is never 0


def jitter_nsats(status: np.ndarray, seed: int, mu: float = DEFAULT_MU) -> np.ndarray:
    """Jittered satellite counts for GPS rows with fix ``status`` (``GPS.Status``).

    Rows with ``status >= 3`` (3D fix) draw from the normal-state distribution (8..20), the
    others from the fault-state one (3..10), with ``numpy.random.default_rng([seed, 0x5A7])``.
    Both distributions are drawn for every row and the status picks one, so a row's count
    depends only on ``seed``, its position and its own status. Returns uint8, the shape of
    ``status``.
    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"seed must be a whole number >= 0, got {seed!r}")
    status = np.asarray(status)
    if status.dtype.kind not in "iu":
        if status.dtype.kind != "f" or not np.all(np.isfinite(status)):
            raise ValueError(f"status must hold finite numbers, got dtype {status.dtype}")
    rng = np.random.default_rng([int(seed), _SEED_TAG])
    counts = []
    for lo, hi in (NORMAL_SATS, FAULT_SATS):
        values = np.arange(lo, hi + 1, dtype=np.uint8)
        counts.append(rng.choice(values, size=status.shape, p=satellite_weights(lo, hi, mu)))
    return np.where(status >= FIX_3D, counts[0], counts[1]).astype(np.uint8)
