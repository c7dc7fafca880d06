"""Mission generation: the paper's Algorithm 1 plus Savitzky-Golay altitudes (TLM paper §3.2).

The scheme below reproduces the reference SITL sidecars bit for bit (see tests/test_mission.py):

1. **Raw points.** Home plus five points on a jittered loop within ~400 m of home
   (:func:`random_loop`); the path does not close back to home (RTL does that).
2. **Interpolation** (:func:`interpolate_waypoints`). The raw polyline's segments get
   ``round(L_i / L * (n - 1))`` intervals each, ``L_i`` the segment's horizontal flat-earth
   length; each segment is filled with ``np.linspace`` (per coordinate) from its start to its
   end, consecutive segments share their joint, so every raw point is a waypoint and the count
   is ``1 + sum(intervals)``: *about* n (89-91 for n = 90 in the reference flights).
   ``exact_count=True`` uses largest-remainder rounding instead and returns exactly n.
3. **Altitudes** (:func:`smooth_altitudes`). ``rng.uniform(15, 25, N)`` from the same
   ``numpy.random.default_rng(seed)`` that drew the loop (the draws continue the stream),
   smoothed with ``scipy.signal.savgol_filter(window_length=21, polyorder=3)`` (mode
   ``interp``) and rounded to 0.01 m. The sidecars store the raw draws rounded to 0.001 m,
   so smoothing *those* can differ from the stored column by 0.01 m at a handful of points.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.signal import savgol_filter

from tlm_sim.geo import HOME_CMAC, latlon_to_ne, ne_to_latlon
from tlm_sim.mission.errors import MissionError
from tlm_sim.mission.mission import Mission, path_length_horizontal_m

__all__ = [
    "allocate_intervals",
    "interpolate_waypoints",
    "make_mission",
    "random_loop",
    "segment_lengths_m",
    "smooth_altitudes",
]


def segment_lengths_m(raw_latlon: np.ndarray) -> np.ndarray:
    """Horizontal flat-earth lengths (M-1,) in metres of the segments of a (M, 2) polyline.

    Points are projected about the first raw point (home in the reference missions).
    """
    raw = _as_latlon(raw_latlon, "raw_latlon")
    n, e = latlon_to_ne(raw[:, 0], raw[:, 1], raw[0, 0], raw[0, 1])
    return np.hypot(np.diff(n), np.diff(e))


def allocate_intervals(
    lengths: np.ndarray, n_intervals: int, *, exact_count: bool = False
) -> np.ndarray:
    """Split ``n_intervals`` interpolation steps over segments in proportion to their length.

    Args:
        lengths: (S,) segment lengths, metres (>= 0).
        n_intervals: the target total number of intervals (n_waypoints - 1).
        exact_count: False: ``rint(share)`` per segment, as the reference driver did (the total
            can differ from ``n_intervals`` by up to S/2). True: largest-remainder rounding,
            the total is exactly ``n_intervals``.

    Returns:
        (S,) int64 interval counts. Zero-length segments get 0; every other segment at least 1
        (so each raw point stays a waypoint), taken from the longest-allocated segments in
        exact mode.
    """
    lengths = np.asarray(lengths, dtype=np.float64)
    nonzero = lengths > 0.0
    total = float(lengths.sum())
    if total <= 0.0:
        return np.zeros(len(lengths), dtype=np.int64)
    share = lengths / total * n_intervals
    if not exact_count:
        k = np.rint(share).astype(np.int64)
        k[nonzero & (k < 1)] = 1
        return k
    if n_intervals < int(nonzero.sum()):
        raise MissionError(
            f"{n_intervals + 1} waypoints cannot keep all {int(nonzero.sum()) + 1} distinct "
            "raw points"
        )
    k = np.floor(share).astype(np.int64)
    frac = share - k
    short = n_intervals - int(k.sum())
    if short > 0:
        k[np.argsort(-frac, kind="stable")[:short]] += 1
    for i in np.flatnonzero(nonzero & (k < 1)):
        donor = int(np.argmax(k - share))  # the most over-allocated segment with k >= 2
        if k[donor] < 2:
            donor = int(np.argmax(k))
        k[donor] -= 1
        k[i] += 1
    return k


def interpolate_waypoints(
    raw_latlon: np.ndarray, n_waypoints: int = 90, *, exact_count: bool = False
) -> np.ndarray:
    """The paper's Algorithm 1: linear interpolation between consecutive raw points.

    Args:
        raw_latlon: (M, 2) [lat, lon] degrees, in flight order (home first in the reference).
        n_waypoints: target number of output points (>= 2 unless M == 1).
        exact_count: see :func:`allocate_intervals`; False reproduces the reference driver.

    Returns:
        (N, 2) float64 [lat, lon] degrees. Starts at the first raw point, ends at the last,
        contains every raw point (consecutive duplicates once), points equally spaced within
        each segment. The path is not closed back to the first point.
    """
    raw = _as_latlon(raw_latlon, "raw_latlon")
    if len(raw) == 1:
        return raw.copy()
    n_waypoints = int(n_waypoints)
    if n_waypoints < 2:
        raise MissionError(f"n_waypoints must be >= 2 for {len(raw)} raw points, got {n_waypoints}")
    lengths = segment_lengths_m(raw)
    if not np.any(lengths > 0.0):
        raise MissionError("all raw waypoints are at the same position")
    k = allocate_intervals(lengths, n_waypoints - 1, exact_count=exact_count)
    parts = []
    for i, ki in enumerate(k):
        if ki <= 0:
            continue
        a, b = raw[i], raw[i + 1]
        lat = np.linspace(a[0], b[0], ki + 1)[:-1]
        lon = np.linspace(a[1], b[1], ki + 1)[:-1]
        parts.append(np.column_stack([lat, lon]))
    parts.append(raw[-1:].copy())
    return np.concatenate(parts, axis=0)


def smooth_altitudes(
    alt_raw: np.ndarray,
    window_length: int = 21,
    polyorder: int = 3,
    decimals: int | None = 2,
) -> np.ndarray:
    """Savitzky-Golay smoothing of random altitudes, as the paper (Fig. 4) and reference did.

    Args:
        alt_raw: (N,) altitudes, metres relative to home.
        window_length, polyorder: ``scipy.signal.savgol_filter`` settings (mode ``interp``).
            If N < window_length the window shrinks to the largest odd number <= N; if that is
            not greater than polyorder the altitudes are returned unsmoothed.
        decimals: round the result to this many decimals (2 = 0.01 m, as the reference
            missions); None keeps full precision.

    Returns:
        (N,) float64 smoothed altitudes, metres relative to home.
    """
    a = np.asarray(alt_raw, dtype=np.float64)
    if a.ndim != 1:
        raise MissionError(f"alt_raw must be 1-D, got shape {a.shape}")
    if window_length < 1 or window_length % 2 == 0 or not 0 <= polyorder < window_length:
        raise MissionError(
            f"savgol window_length={window_length}, polyorder={polyorder}: need an odd window "
            "greater than polyorder >= 0"
        )
    win = min(int(window_length), len(a) if len(a) % 2 else len(a) - 1)
    out = savgol_filter(a, win, polyorder, mode="interp") if win > polyorder else a.copy()
    return np.round(out, decimals) if decimals is not None else out


def make_mission(
    raw_latlon: np.ndarray,
    n_waypoints: int = 90,
    alt_range: tuple[float, float] = (15.0, 25.0),
    seed: int | None = 0,
    savgol: tuple[int, int] = (21, 3),
    home: Sequence[float] = HOME_CMAC,
    *,
    rng: np.random.Generator | None = None,
    name: str = "",
    exact_count: bool = False,
) -> Mission:
    """Build a mission the reference way: Algorithm 1, uniform random altitudes, SG smoothing.

    Args:
        raw_latlon: (M, 2) raw [lat, lon] degrees (home first in the reference missions).
        n_waypoints: target waypoint count (see :func:`interpolate_waypoints`).
        alt_range: (low, high) metres relative to home for ``rng.uniform``.
        seed: seeds ``np.random.default_rng`` when ``rng`` is None; stored on the mission.
        savgol: (window_length, polyorder).
        home: (lat deg, lon deg, alt m AMSL).
        rng: draw altitudes from this generator instead (e.g. the one that drew the loop,
            which is what reproduces the reference sidecars).
        name: label stored on the mission.
        exact_count: see :func:`interpolate_waypoints`.

    Returns:
        A validated :class:`Mission`; ``altitudes_raw`` holds the unrounded draws.
    """
    lo, hi = float(alt_range[0]), float(alt_range[1])
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo <= hi):
        raise MissionError(f"alt_range must be finite with 0 <= low <= high, got {alt_range}")
    if rng is None:
        rng = np.random.default_rng(seed)
    latlon = interpolate_waypoints(raw_latlon, n_waypoints, exact_count=exact_count)
    alt_raw = rng.uniform(lo, hi, len(latlon))
    alt = smooth_altitudes(alt_raw, int(savgol[0]), int(savgol[1]))
    return Mission(
        waypoints=np.column_stack([latlon, alt]),
        home=tuple(float(v) for v in home),  # type: ignore[arg-type]
        raw_waypoints=np.asarray(raw_latlon, dtype=np.float64),
        altitudes_raw=alt_raw,
        name=name,
        seed=seed,
        savgol=(int(savgol[0]), int(savgol[1])),
    )


def random_loop(
    home: Sequence[float] = HOME_CMAC,
    rng: np.random.Generator | int | None = None,
    *,
    n_points: int = 5,
    max_radius_m: float = 400.0,
    min_radius_m: float = 80.0,
    length_range_m: tuple[float, float] = (1100.0, 1300.0),
    max_tries: int = 10_000,
) -> np.ndarray:
    """Raw points for a random mission: home plus ``n_points`` on a jittered loop.

    Each try draws a circle whose centre lies 60-170 m from home in a random direction and
    whose radius is 170-250 m (home is inside it), a turning direction, a start angle and a
    sweep of 200-300 degrees; the points sit at equal angular steps along the sweep, each
    jittered by +-15 % of a step in angle and +-15 % in radius. A try is kept when every point
    is between ``min_radius_m`` and ``max_radius_m`` from home and the open polyline
    home -> p1 -> ... -> pn (what :func:`interpolate_waypoints` follows) is within
    ``length_range_m``; otherwise it is drawn again. Every try consumes exactly
    ``6 + 2 * n_points`` uniforms from ``rng``.

    Args:
        home: (lat deg, lon deg[, alt]) of home; only lat/lon are used.
        rng: a numpy Generator, or a seed for ``np.random.default_rng``.
        n_points: loop points besides home.
        max_radius_m: no point farther than this from home, metres.
        min_radius_m: no loop point nearer than this to home, metres (keeps the loop off home).
        length_range_m: accepted (min, max) horizontal path length, metres.
        max_tries: give up with :class:`MissionError` after this many tries.

    Returns:
        (n_points + 1, 2) float64 [lat, lon] degrees, home first.
    """
    if not isinstance(rng, np.random.Generator):
        rng = np.random.default_rng(rng)
    if n_points < 1:
        raise MissionError(f"n_points must be >= 1, got {n_points}")
    lat0, lon0 = float(home[0]), float(home[1])
    lo, hi = length_range_m
    for _ in range(max_tries):
        u = rng.random(6 + 2 * n_points)
        c_brg = 2.0 * math.pi * u[0]
        c_dist = 60.0 + 110.0 * u[1]
        radius = 170.0 + 80.0 * u[2]
        turn = 1.0 if u[3] < 0.5 else -1.0
        start = 2.0 * math.pi * u[4]
        sweep = math.radians(200.0 + 100.0 * u[5])
        step = sweep / max(n_points - 1, 1)
        k = np.arange(n_points)
        ang = start + turn * step * (k + 0.3 * (u[6 : 6 + n_points] - 0.5))
        rad = radius * (1.0 + 0.3 * (u[6 + n_points :] - 0.5))
        north = c_dist * math.cos(c_brg) + rad * np.cos(ang)
        east = c_dist * math.sin(c_brg) + rad * np.sin(ang)
        dist = np.hypot(north, east)
        if np.any(dist > max_radius_m) or np.any(dist < min_radius_m):
            continue
        lat, lon = ne_to_latlon(north, east, lat0, lon0)
        raw = np.vstack([[lat0, lon0], np.column_stack([lat, lon])])
        length = path_length_horizontal_m(raw, lat0, lon0)
        if lo <= length <= hi:
            return raw
    raise MissionError(
        f"random_loop found no loop of length {lo:g}-{hi:g} m within {max_radius_m:g} m "
        f"of home in {max_tries} tries"
    )


def _as_latlon(a: np.ndarray, what: str) -> np.ndarray:
    try:
        arr = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MissionError(f"{what} is not numeric: {exc}") from None
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < 1:
        raise MissionError(f"{what} must have shape (M, 2) with M >= 1, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        i = int(np.flatnonzero(~np.all(np.isfinite(arr), axis=1))[0])
        raise MissionError(f"{what} point {i} is not finite")
    return arr
