"""The :class:`Mission` value: home, waypoints and how they were made.

Frames and units: latitude/longitude in degrees (WGS-84 as ArduPilot treats them), waypoint
altitude in metres *relative to home* (MAV_FRAME_GLOBAL_RELATIVE_ALT, positive up), home
altitude in metres AMSL. :meth:`Mission.ned` gives the waypoints in the NED earth frame whose
origin is home (flat earth, :mod:`tlm_sim.geo`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tlm_sim.geo import HOME_CMAC, latlon_to_ne
from tlm_sim.mission.errors import MissionError

__all__ = [
    "MAX_ALT_M",
    "MAX_HOME_DISTANCE_M",
    "Mission",
    "path_length_horizontal_m",
]

#: highest allowed waypoint / takeoff altitude above home, metres
MAX_ALT_M: float = 10_000.0
#: farthest allowed waypoint from home (horizontal, flat earth), metres
MAX_HOME_DISTANCE_M: float = 50_000.0


def path_length_horizontal_m(latlon: np.ndarray, home_lat: float, home_lon: float) -> float:
    """Horizontal length of the polyline through ``latlon`` (N, 2) degrees, metres.

    Each vertex is projected to flat-earth north/east about (home_lat, home_lon) and the
    straight-line distances between consecutive vertices are summed. This is the measure the
    reference sidecars' ``path_length_m`` uses (they print it rounded to 0.1 m).
    """
    latlon = np.asarray(latlon, dtype=np.float64)
    if len(latlon) < 2:
        return 0.0
    n, e = latlon_to_ne(latlon[:, 0], latlon[:, 1], home_lat, home_lon)
    return float(np.sum(np.hypot(np.diff(n), np.diff(e))))


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64, copy=True)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class Mission:
    """An AUTO mission: fly from home through ``waypoints`` in order, then RTL.

    Attributes:
        waypoints: (N, 3) float64 [lat deg, lon deg, alt m relative to home]. Read-only.
        home: (lat deg, lon deg, alt m AMSL).
        raw_waypoints: (M, 2) float64 [lat, lon] deg, the points Algorithm 1 interpolated
            between. Defaults to the waypoints' own lat/lon (every waypoint is a raw point).
        altitudes_raw: (N,) random altitudes (m, relative to home) before Savitzky-Golay
            smoothing, or None when unknown (e.g. a mission read from a file).
        name: free text label.
        seed: the seed the mission was generated from, or None.
        savgol: (window_length, polyorder) of the altitude smoothing.
        takeoff_alt: NAV_TAKEOFF altitude, m relative to home; defaults to the first
            waypoint's altitude (what the reference driver did).

    Construction validates everything (:meth:`validate`) and raises :class:`MissionError`
    naming the culprit; indices in messages are 0-based rows of the array named.
    """

    waypoints: np.ndarray
    home: tuple[float, float, float] = HOME_CMAC
    raw_waypoints: np.ndarray | None = None
    altitudes_raw: np.ndarray | None = None
    name: str = ""
    seed: int | None = None
    savgol: tuple[int, int] = (21, 3)
    takeoff_alt: float | None = field(default=None)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        try:
            wp = np.array(self.waypoints, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MissionError(f"waypoints are not numeric: {exc}") from None
        if wp.ndim != 2 or wp.shape[1] != 3:
            raise MissionError(f"waypoints must have shape (N, 3), got {wp.shape}")
        set_(self, "waypoints", _readonly(wp))
        try:
            home = tuple(float(v) for v in self.home)
        except (TypeError, ValueError) as exc:
            raise MissionError(f"home is not three numbers: {exc}") from None
        if len(home) != 3:
            raise MissionError(f"home must be (lat, lon, alt_amsl_m), got {len(home)} values")
        set_(self, "home", home)
        raw = wp[:, :2] if self.raw_waypoints is None else self.raw_waypoints
        try:
            raw = np.array(raw, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MissionError(f"raw_waypoints are not numeric: {exc}") from None
        if raw.ndim != 2 or raw.shape[1] != 2:
            raise MissionError(f"raw_waypoints must have shape (M, 2), got {raw.shape}")
        set_(self, "raw_waypoints", _readonly(raw))
        if self.altitudes_raw is not None:
            ar = np.array(self.altitudes_raw, dtype=np.float64)
            if ar.shape != (len(wp),):
                raise MissionError(
                    f"altitudes_raw must have shape ({len(wp)},) like the waypoints, got {ar.shape}"
                )
            set_(self, "altitudes_raw", _readonly(ar))
        sg = tuple(self.savgol)
        if len(sg) != 2 or not all(isinstance(v, int | np.integer) for v in sg):
            raise MissionError(f"savgol must be (window_length, polyorder) ints, got {sg}")
        set_(self, "savgol", (int(sg[0]), int(sg[1])))
        if self.takeoff_alt is None and len(wp) > 0:
            set_(self, "takeoff_alt", float(wp[0, 2]))
        elif self.takeoff_alt is not None:
            set_(self, "takeoff_alt", float(self.takeoff_alt))
        if self.seed is not None:
            set_(self, "seed", int(self.seed))
        set_(self, "name", str(self.name))
        self.validate()

    # ------------------------------------------------------------------ checks
    def validate(self) -> None:
        """Raise :class:`MissionError` if anything is out of range.

        Checks: at least one waypoint; no NaN/inf; |lat| <= 90, |lon| <= 180 (home,
        waypoints, raw waypoints); waypoint and takeoff altitudes within [0, 10 000] m above
        home; every waypoint and raw waypoint within 50 km of home; savgol window odd and
        greater than polyorder >= 0.
        """
        lat0, lon0, alt0 = self.home
        for what, v in (("latitude", lat0), ("longitude", lon0), ("altitude", alt0)):
            if not math.isfinite(v):
                raise MissionError(f"home has {_bad_word(v)} {what}")
        if abs(lat0) > 90.0:
            raise MissionError(f"home latitude {lat0} is outside [-90, 90]")
        if abs(lon0) > 180.0:
            raise MissionError(f"home longitude {lon0} is outside [-180, 180]")

        wp = self.waypoints
        if len(wp) < 1:
            raise MissionError("mission has no waypoints (need at least 1)")
        _check_latlon(wp[:, :2], "waypoint", lat0, lon0)
        alt = wp[:, 2]
        _check_finite(alt, "waypoint", "altitude")
        bad = np.flatnonzero((alt < 0.0) | (alt > MAX_ALT_M))
        if bad.size:
            i = int(bad[0])
            raise MissionError(
                f"waypoint {i} has altitude {alt[i]:g} m, outside [0, {MAX_ALT_M:g}] m above home"
            )
        raw = self.raw_waypoints
        if len(raw) < 1:
            raise MissionError("raw_waypoints is empty (need at least 1 point)")
        _check_latlon(raw, "raw waypoint", lat0, lon0)
        if self.altitudes_raw is not None:
            _check_finite(self.altitudes_raw, "raw altitude", "value")
        t = self.takeoff_alt
        if t is None or not math.isfinite(t) or not 0.0 <= t <= MAX_ALT_M:
            raise MissionError(f"takeoff altitude {t} m is outside [0, {MAX_ALT_M:g}] m")
        win, order = self.savgol
        if win < 1 or win % 2 == 0 or order < 0 or order >= win:
            raise MissionError(
                f"savgol (window_length={win}, polyorder={order}) needs an odd window "
                "greater than polyorder >= 0"
            )

    # ------------------------------------------------------------- derived
    @property
    def n_waypoints(self) -> int:
        """Number of waypoints N (home, takeoff and RTL items not counted)."""
        return int(len(self.waypoints))

    def ned(self) -> np.ndarray:
        """Waypoints in the NED earth frame about home: (N, 3) float64 metres, D = -alt."""
        n, e = latlon_to_ne(self.waypoints[:, 0], self.waypoints[:, 1], *self.home[:2])
        return np.column_stack([n, e, -self.waypoints[:, 2]])

    @property
    def path_length_m(self) -> float:
        """Horizontal (2-D, flat-earth) length of the waypoint polyline, metres.

        From the first waypoint to the last; the climb from the ground, the legs from/to home
        and altitude changes are not included. This is what the reference sidecars'
        ``path_length_m`` holds (to their 0.1 m rounding). See :attr:`path_length_3d_m`.
        """
        return path_length_horizontal_m(self.waypoints[:, :2], *self.home[:2])

    @property
    def path_length_3d_m(self) -> float:
        """Like :attr:`path_length_m` but including altitude changes, metres."""
        p = self.ned()
        return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1)))

    # ------------------------------------------------------------- equality
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Mission):
            return NotImplemented
        return (
            self.home == other.home
            and np.array_equal(self.waypoints, other.waypoints)
            and np.array_equal(self.raw_waypoints, other.raw_waypoints)
            and _opt_equal(self.altitudes_raw, other.altitudes_raw)
            and self.name == other.name
            and self.seed == other.seed
            and self.savgol == other.savgol
            and self.takeoff_alt == other.takeoff_alt
        )

    __hash__ = None  # type: ignore[assignment]

    # ------------------------------------------------------------- loaders
    @classmethod
    def from_sidecar(cls, path: str | Path) -> Mission:
        """Load the ``mission`` of a reference SITL sidecar JSON (``<name>.json``).

        Home comes from ``sitl.home`` when present (else CMAC); the name is the file stem.
        """
        path = Path(path)
        try:
            doc: dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:  # ValueError: JSON or UTF-8 decoding
            raise MissionError(f"{path}: cannot read sidecar JSON: {exc}") from None
        m = doc.get("mission")
        if not isinstance(m, dict) or "waypoints" not in m:
            raise MissionError(f"{path}: no 'mission.waypoints' in sidecar")
        home_doc = doc.get("sitl", {}).get("home")
        home = tuple(float(v) for v in home_doc[:3]) if home_doc else HOME_CMAC
        sg = m.get("savgol", {})
        return cls(
            waypoints=np.asarray(m["waypoints"], dtype=np.float64),
            home=home,  # type: ignore[arg-type]
            raw_waypoints=m.get("raw_waypoints"),
            altitudes_raw=m.get("altitudes_raw_m"),
            name=path.stem,
            seed=m.get("seed", doc.get("seed")),
            savgol=(int(sg.get("window_length", 21)), int(sg.get("polyorder", 3))),
        )


def _opt_equal(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(a, b))


def _bad_word(v: float) -> str:
    return "NaN" if math.isnan(v) else "infinite"


def _check_finite(col: np.ndarray, who: str, what: str) -> None:
    bad = np.flatnonzero(~np.isfinite(col))
    if bad.size:
        i = int(bad[0])
        raise MissionError(f"{who} {i} has {_bad_word(float(col[i]))} {what}")


def _check_latlon(latlon: np.ndarray, who: str, home_lat: float, home_lon: float) -> None:
    _check_finite(latlon[:, 0], who, "latitude")
    _check_finite(latlon[:, 1], who, "longitude")
    bad = np.flatnonzero(np.abs(latlon[:, 0]) > 90.0)
    if bad.size:
        i = int(bad[0])
        raise MissionError(f"{who} {i} has latitude {latlon[i, 0]:g}, outside [-90, 90]")
    bad = np.flatnonzero(np.abs(latlon[:, 1]) > 180.0)
    if bad.size:
        i = int(bad[0])
        raise MissionError(f"{who} {i} has longitude {latlon[i, 1]:g}, outside [-180, 180]")
    n, e = latlon_to_ne(latlon[:, 0], latlon[:, 1], home_lat, home_lon)
    d = np.hypot(n, e)
    bad = np.flatnonzero(d > MAX_HOME_DISTANCE_M)
    if bad.size:
        i = int(bad[0])
        raise MissionError(
            f"{who} {i} is {d[i]:.0f} m from home (limit {MAX_HOME_DISTANCE_M:.0f} m)"
        )
