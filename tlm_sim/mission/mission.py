"""The :class:`Mission` value: home, waypoints, the mission items they stand for, and how they
were made.

Frames and units: latitude/longitude in degrees (WGS-84 as ArduPilot treats them), waypoint
altitude in metres *relative to home* (MAV_FRAME_GLOBAL_RELATIVE_ALT, positive up), home
altitude in metres AMSL. :meth:`Mission.ned` gives the waypoints in the NED earth frame whose
origin is home (flat earth, :mod:`tlm_sim.geo`).

Mission items (ArduCopter's AUTO, ``ModeAuto`` / ``AP_Mission``): each waypoint row is one
navigation item, MAV_CMD_NAV_WAYPOINT (16; the default), MAV_CMD_NAV_LOITER_TIME (19) or, as the
last row only, MAV_CMD_NAV_LAND (21) (:attr:`Mission.commands`), with a hold time in whole
seconds (:attr:`Mission.hold_s`: NAV_WAYPOINT's and NAV_LOITER_TIME's param1) and an optional
MAV_CMD_DO_CHANGE_SPEED item right before it (:attr:`Mission.speed_changes`: the horizontal
speed it sets, m/s). :meth:`Mission.items` lists the whole mission as ArduCopter stores it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from tlm_sim.ardupilot import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TIME,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
)
from tlm_sim.geo import HOME_CMAC, latlon_to_ne
from tlm_sim.mission.errors import MissionError

__all__ = [
    "ITEM_FIELDS",
    "MAX_ALT_M",
    "MAX_HOLD_S",
    "MAX_HOME_DISTANCE_M",
    "MAX_SPEED_MPS",
    "MIN_SPEED_MPS",
    "Mission",
    "NAV_COMMANDS",
    "SPEED_TYPE_GROUNDSPEED",
    "path_length_horizontal_m",
]

#: highest allowed waypoint / takeoff altitude above home, metres
MAX_ALT_M: float = 10_000.0
#: farthest allowed waypoint from home (horizontal, flat earth), metres
MAX_HOME_DISTANCE_M: float = 50_000.0

#: the navigation commands a waypoint row can be (:attr:`Mission.commands`)
NAV_COMMANDS: dict[int, str] = {MAV_CMD_NAV_WAYPOINT: "NAV_WAYPOINT",
                                MAV_CMD_NAV_LOITER_TIME: "NAV_LOITER_TIME",
                                MAV_CMD_NAV_LAND: "NAV_LAND"}
#: longest hold: ArduPilot stores a hold time in 16 bits of whole seconds (AP_Mission cmd.p1)
MAX_HOLD_S: float = 65535.0
#: DO_CHANGE_SPEED's range, m/s: AC_WPNav ignores speeds below WPNAV_WP_SPEED_MIN (10 cm/s);
#: the upper bound is tlm's sanity limit
MIN_SPEED_MPS, MAX_SPEED_MPS = 0.1, 100.0
#: DO_CHANGE_SPEED param1 tlm writes: ground speed (a copter flies air and ground speed alike)
SPEED_TYPE_GROUNDSPEED = 1
#: the columns of :meth:`Mission.items`, as ArduCopter's CMD / MISE messages name them
ITEM_FIELDS: tuple[str, ...] = ("CId", "Prm1", "Prm2", "Prm3", "Prm4", "Lat", "Lng", "Alt",
                                "Frame")


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
        commands: (N,) int MAV_CMD of each waypoint row: 16 NAV_WAYPOINT, 19 NAV_LOITER_TIME,
            or 21 NAV_LAND (last row only: the mission ends with a landing there instead of
            NAV_RETURN_TO_LAUNCH; the row's altitude is 0, the ground, as ArduCopter flies to
            the landing point at the altitude it comes from, then descends). None: all 16.
        hold_s: (N,) whole seconds the copter holds at each row once it has reached it
            (NAV_WAYPOINT's delay, NAV_LOITER_TIME's time; 0 for a LAND row), 0 to 65535.
            None: no holds.
        speed_changes: (N,) m/s: the horizontal speed a MAV_CMD_DO_CHANGE_SPEED item right
            before row i sets (AC_WPNav's WPNAV_SPEED, from the leg to row i on, until the
            next change; RTL flies at RTL_SPEED all the same), NaN where there is none. None:
            no speed changes.

    The three item arrays hold None when they say nothing (all 16, all 0, all NaN); arrays
    given with only defaults become None, so such missions compare equal.

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
    commands: np.ndarray | None = None
    hold_s: np.ndarray | None = None
    speed_changes: np.ndarray | None = None

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
        set_(self, "commands",
             _item_array(self.commands, len(wp), "commands", MAV_CMD_NAV_WAYPOINT))
        set_(self, "hold_s", _item_array(self.hold_s, len(wp), "hold_s", 0.0))
        set_(self, "speed_changes",
             _item_array(self.speed_changes, len(wp), "speed_changes", math.nan))
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
        self._validate_items()

    def _validate_items(self) -> None:
        """The item arrays: known commands, LAND last and on the ground, whole-second holds
        within 0..65535 s (none at a LAND), speed changes within 0.1..100 m/s."""
        if self.commands is not None:
            bad = np.flatnonzero(~np.isin(self.commands, list(NAV_COMMANDS)))
            if bad.size:
                i = int(bad[0])
                raise MissionError(
                    f"waypoint {i} has command {self.commands[i]:g}; a waypoint row is one of "
                    + ", ".join(f"{k} {v}" for k, v in NAV_COMMANDS.items()))
        cmds, hold = self.nav_commands, self.holds
        land = np.flatnonzero(cmds == MAV_CMD_NAV_LAND)
        if land.size and int(land[0]) != len(cmds) - 1:
            raise MissionError(f"waypoint {int(land[0])} is a NAV_LAND but not the last row: "
                               "a LAND ends the mission")
        if land.size and self.waypoints[-1, 2] != 0.0:
            raise MissionError(
                f"waypoint {len(cmds) - 1} is a NAV_LAND at {self.waypoints[-1, 2]:g} m: a "
                "landing point's altitude is 0 (ArduCopter flies to it at the altitude it "
                "comes from, then descends)")
        _check_finite(hold, "waypoint", "hold time")
        bad = np.flatnonzero((hold < 0.0) | (hold > MAX_HOLD_S) | (hold != np.round(hold)))
        if bad.size:
            i = int(bad[0])
            raise MissionError(f"waypoint {i} has hold time {hold[i]:g} s: ArduCopter holds "
                               f"whole seconds, 0 to {MAX_HOLD_S:.0f}")
        if land.size and hold[-1] != 0.0:
            raise MissionError(f"waypoint {len(cmds) - 1} is a NAV_LAND with a hold time: a "
                               "LAND has none")
        sp = self.speed_changes
        if sp is not None:
            bad = np.flatnonzero(~np.isnan(sp) & ~((sp >= MIN_SPEED_MPS) & (sp <= MAX_SPEED_MPS)))
            if bad.size:
                i = int(bad[0])
                raise MissionError(f"speed change before waypoint {i} is {sp[i]:g} m/s, outside "
                                   f"[{MIN_SPEED_MPS:g}, {MAX_SPEED_MPS:g}] m/s")

    # ------------------------------------------------------------- derived
    @property
    def n_waypoints(self) -> int:
        """Number of waypoints N (home, takeoff, RTL and DO_CHANGE_SPEED items not counted; a
        final NAV_LAND is a waypoint row)."""
        return int(len(self.waypoints))

    @property
    def nav_commands(self) -> np.ndarray:
        """(N,) int64 MAV_CMD of each waypoint row (:attr:`commands`, 16 where None)."""
        if self.commands is None:
            return np.full(len(self.waypoints), MAV_CMD_NAV_WAYPOINT, dtype=np.int64)
        return self.commands.astype(np.int64)

    @property
    def holds(self) -> np.ndarray:
        """(N,) float64 hold time at each waypoint row, seconds (:attr:`hold_s`, 0 where None)."""
        return np.zeros(len(self.waypoints)) if self.hold_s is None else self.hold_s.copy()

    @property
    def lands(self) -> bool:
        """Whether the mission ends with NAV_LAND (else with NAV_RETURN_TO_LAUNCH)."""
        return bool(self.nav_commands[-1] == MAV_CMD_NAV_LAND)

    @property
    def has_items(self) -> bool:
        """Whether any row is more than a plain waypoint (a hold, LOITER_TIME, LAND or a speed
        change): missions without are flown exactly as before these items existed."""
        return not (self.commands is None and self.hold_s is None
                    and self.speed_changes is None)

    def stops(self) -> np.ndarray:
        """(N,) bool: rows where the copter comes to rest, as ArduCopter's AUTO does: a hold
        time (ModeAuto::set_next_wp plans no next leg then), a NAV_LOITER_TIME (it never plans
        one), the row before a NAV_LAND (it always stops before a landing), and the last
        row."""
        cmds = self.nav_commands
        out = (self.holds > 0.0) | (cmds == MAV_CMD_NAV_LOITER_TIME)
        out[:-1] |= cmds[1:] == MAV_CMD_NAV_LAND
        out[-1] = True
        return out

    def leg_speeds(self) -> np.ndarray:
        """(N,) float64 horizontal speed [m/s] the speed changes set for the leg that ends at
        each row (held until the next change), NaN before the first change."""
        out = np.full(len(self.waypoints), math.nan)
        if self.speed_changes is not None:
            cur = math.nan
            for i, v in enumerate(self.speed_changes):
                cur = cur if math.isnan(v) else float(v)
                out[i] = cur
        return out

    def items(self) -> np.ndarray:
        """The mission as ArduCopter stores it and logs it (CMD, MISE): one row per item,
        columns :data:`ITEM_FIELDS` (CId, Prm1-4, Lat, Lng, Alt, Frame); the row index is the
        item number (CNum).

        0 home (MAV_FRAME_GLOBAL, no position, as the reference logs' CMD rows), 1
        NAV_TAKEOFF to :attr:`takeoff_alt`, then per waypoint row an optional
        DO_CHANGE_SPEED (Prm1 1 ground speed, Prm2 the speed; frame 0, no position) and the
        row's navigation item (relative altitudes, MAV_FRAME_GLOBAL_RELATIVE_ALT; Prm1 the
        hold time; NAV_LOITER_TIME's Prm3 1 and NAV_LAND's Prm4 1 as
        AP_Mission::mission_cmd_to_mavlink_int writes their direction flags), then
        NAV_RETURN_TO_LAUNCH (MAV_FRAME_GLOBAL) unless the mission lands.
        """
        rows: list[list[float]] = [[MAV_CMD_NAV_WAYPOINT, 0, 0, 0, 0, 0, 0, 0, MAV_FRAME_GLOBAL],
                                   [MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0,
                                    float(self.takeoff_alt or 0.0), MAV_FRAME_GLOBAL_RELATIVE_ALT]]
        speeds = self.speed_changes
        for i, (cmd, hold) in enumerate(zip(self.nav_commands, self.holds, strict=True)):
            if speeds is not None and not math.isnan(speeds[i]):
                rows.append([MAV_CMD_DO_CHANGE_SPEED, SPEED_TYPE_GROUNDSPEED, float(speeds[i]),
                             0, 0, 0, 0, 0, MAV_FRAME_GLOBAL])
            lat, lon, alt = (float(v) for v in self.waypoints[i])
            p3 = 1.0 if cmd == MAV_CMD_NAV_LOITER_TIME else 0.0
            p4 = 1.0 if cmd == MAV_CMD_NAV_LAND else 0.0
            rows.append([int(cmd), float(hold), 0, p3, p4, lat, lon, alt,
                         MAV_FRAME_GLOBAL_RELATIVE_ALT])
        if not self.lands:
            rows.append([MAV_CMD_NAV_RETURN_TO_LAUNCH, 0, 0, 0, 0, 0, 0, 0, MAV_FRAME_GLOBAL])
        return np.array(rows, dtype=np.float64)

    def item_numbers(self) -> np.ndarray:
        """(N,) int64 item number (CNum, :meth:`items`) of each waypoint row's navigation
        item."""
        extra = np.zeros(len(self.waypoints), dtype=np.int64)
        if self.speed_changes is not None:
            extra = np.cumsum(~np.isnan(self.speed_changes)).astype(np.int64)
        return 2 + np.arange(len(self.waypoints), dtype=np.int64) + extra

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
            and _opt_equal(self.commands, other.commands)
            and _opt_equal(self.hold_s, other.hold_s)
            and _opt_equal(self.speed_changes, other.speed_changes, nan_equal=True)
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
            takeoff_alt=m.get("takeoff_alt"),
            **_items_from_doc(m),
        )

    def to_json(self) -> dict[str, Any]:
        """The JSON form (:meth:`from_dict` reads it back): the fields by name, arrays as
        lists, a missing speed change as null (JSON has no NaN)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else v
        if self.commands is not None:
            out["commands"] = [int(v) for v in self.commands]
        if self.speed_changes is not None:
            out["speed_changes"] = [None if math.isnan(v) else v for v in out["speed_changes"]]
        return out

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any]) -> Mission:
        """A Mission from its JSON form: the ``mission`` object of a flight's ``meta.json``
        (:func:`tlm_sim.flightlog.to_jsonable` of a Mission: the dataclass fields by name; the
        item arrays may be missing or null, a speed change may be null for none)."""
        if not isinstance(doc, Mapping) or "waypoints" not in doc:
            raise MissionError("a mission object needs 'waypoints'")
        sg = doc.get("savgol") or (21, 3)
        try:
            return cls(
                waypoints=np.asarray(doc["waypoints"], dtype=np.float64),
                home=tuple(doc.get("home") or HOME_CMAC),  # type: ignore[arg-type]
                raw_waypoints=doc.get("raw_waypoints"),
                altitudes_raw=doc.get("altitudes_raw"),
                name=str(doc.get("name") or ""),
                seed=doc.get("seed"),
                savgol=(int(sg[0]), int(sg[1])),
                takeoff_alt=doc.get("takeoff_alt"),
                **_items_from_doc(doc),
            )
        except (TypeError, ValueError, IndexError) as exc:
            if isinstance(exc, MissionError):
                raise
            raise MissionError(f"bad mission object: {exc}") from None


def _opt_equal(a: np.ndarray | None, b: np.ndarray | None, nan_equal: bool = False) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return bool(np.array_equal(a, b, equal_nan=nan_equal))


def _items_from_doc(doc: Mapping[str, Any]) -> dict[str, Any]:
    """The item arrays of a JSON mission object (null speed changes -> NaN)."""
    out: dict[str, Any] = {k: doc.get(k) for k in ("commands", "hold_s")}
    sp = doc.get("speed_changes")
    out["speed_changes"] = None if sp is None else [math.nan if v is None else v for v in sp]
    return out


def _item_array(values: Any, n: int, what: str, default: float) -> np.ndarray | None:
    """A per-waypoint item array (N,) float64, read-only; None when ``values`` is None or holds
    only ``default`` (NaN matches NaN)."""
    if values is None:
        return None
    try:
        a = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise MissionError(f"{what} is not numeric: {exc}") from None
    if a.shape != (n,):
        raise MissionError(f"{what} must have shape ({n},) like the waypoints, got {a.shape}")
    same = np.isnan(a) if math.isnan(default) else a == default
    if bool(np.all(same)):
        return None
    return _readonly(a)


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
