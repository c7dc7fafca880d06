"""QGC WPL 110 mission files (the plain-text format of QGroundControl, MAVProxy, Mission Planner).

Layout written, as the reference SITL missions had it (see the logs' ``CMD`` messages)::

    QGC WPL 110
    0  1  0  16  0 0 0 0  home_lat  home_lon  home_alt_amsl  1    home (frame 0, absolute)
    1  0  3  22  0 0 0 0  0         0         takeoff_alt    1    MAV_CMD_NAV_TAKEOFF
    2  0  3  16  0 0 0 0  lat       lon       alt_rel        1    waypoints (frame 3)
    ...
    N+2 0 0  20  0 0 0 0  0         0         0              1    MAV_CMD_NAV_RETURN_TO_LAUNCH

Columns are tab-separated: ``seq current frame command p1 p2 p3 p4 lat lon alt autocontinue``.
Numbers are written as the shortest decimal that reads back to the same float64, so a
write/read round trip is exact.

The items tlm flies, as ArduCopter's AUTO does (``ModeAuto``, ``AP_Mission``; see
:class:`~tlm_sim.mission.Mission`): NAV_WAYPOINT (16; param1 the hold time in whole seconds),
NAV_LOITER_TIME (19; param1 the time), NAV_LAND (21; the last navigation item: land there,
or where the copter is when lat = lon = 0, and disarm), DO_CHANGE_SPEED (178; param1 speed
type 0 air / 1 ground speed, param2 the horizontal speed in m/s, -1 or 0 keeps it),
NAV_TAKEOFF (22) and NAV_RETURN_TO_LAUNCH (20). A parameter tlm does not fly (a waypoint's
acceptance radius, pass radius or yaw, a climb-speed change, ...) is refused with the file,
line and parameter named, never ignored; so is every other command. As ArduCopter, a
waypoint or loiter at lat = lon = 0 is where the copter comes from (the previous item's
position, home after the takeoff) and one at altitude 0 keeps the altitude it comes from.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tlm_sim.ardupilot import (
    MAV_CMD_DO_CHANGE_SPEED,
    MAV_CMD_NAV_LAND,
    MAV_CMD_NAV_LOITER_TIME,
    MAV_CMD_NAV_RETURN_TO_LAUNCH,
    MAV_CMD_NAV_TAKEOFF,
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL,
    MAV_FRAME_GLOBAL_INT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
)
from tlm_sim.geo import HOME_CMAC
from tlm_sim.mission.errors import MissionError
from tlm_sim.mission.mission import (
    MAX_HOLD_S,
    MAX_SPEED_MPS,
    MIN_SPEED_MPS,
    Mission,
)
from tlm_sim.textfile import TextFileError, read_text

__all__ = [
    "mission_from_items",
    "SUPPORTED_COMMANDS",
    "WPL_HEADER",
    "read_wpl",
    "write_wpl",
]

WPL_HEADER = "QGC WPL 110"

_ABSOLUTE_FRAMES = (MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_INT)
_RELATIVE_FRAMES = (MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)

#: the commands read_wpl takes, and their names in messages
SUPPORTED_COMMANDS: dict[int, str] = {
    MAV_CMD_NAV_WAYPOINT: "NAV_WAYPOINT",
    MAV_CMD_NAV_LOITER_TIME: "NAV_LOITER_TIME",
    MAV_CMD_NAV_RETURN_TO_LAUNCH: "NAV_RETURN_TO_LAUNCH",
    MAV_CMD_NAV_LAND: "NAV_LAND",
    MAV_CMD_NAV_TAKEOFF: "NAV_TAKEOFF",
    MAV_CMD_DO_CHANGE_SPEED: "DO_CHANGE_SPEED",
}
_SUPPORTED_TEXT = ", ".join(f"{k} {v}" for k, v in SUPPORTED_COMMANDS.items())

#: the parameters (param1..param4) of each command that tlm does NOT fly, by MAVLink's names;
#: a value other than 0 (or NaN, MAVLink's "unset"; -1 for DO_CHANGE_SPEED's throttle) there
#: is refused. param1 of NAV_WAYPOINT / NAV_LOITER_TIME and param1-2 of DO_CHANGE_SPEED are
#: flown.
_UNFLOWN: dict[int, dict[int, str]] = {
    MAV_CMD_NAV_WAYPOINT: {2: "acceptance radius", 3: "pass radius", 4: "yaw"},
    MAV_CMD_NAV_LOITER_TIME: {2: "heading required", 3: "radius", 4: "xtrack location"},
    MAV_CMD_NAV_LAND: {1: "abort altitude", 2: "precision land mode", 3: "param3", 4: "yaw"},
    MAV_CMD_NAV_TAKEOFF: {1: "minimum pitch", 2: "param2", 3: "param3", 4: "yaw"},
    MAV_CMD_NAV_RETURN_TO_LAUNCH: {1: "param1", 2: "param2", 3: "param3", 4: "param4"},
    MAV_CMD_DO_CHANGE_SPEED: {3: "throttle", 4: "param4"},
}
_SPEED_TYPES = {0: "airspeed", 1: "ground speed", 2: "climb speed", 3: "descent speed"}


@dataclass(frozen=True)
class _Item:
    """One parsed line: its number in the file, frame, command, params, position."""

    lineno: int
    frame: int
    cmd: int
    p: tuple[float, float, float, float]
    lat: float
    lon: float
    alt: float


def _num(x: float) -> str:
    """Shortest positional decimal that reads back as the same float64."""
    return np.format_float_positional(float(x), unique=True, trim="-")


def write_wpl(
    mission: Mission, path: str | Path, *, takeoff: bool = True, rtl: bool = True
) -> Path:
    """Write ``mission`` as a QGC WPL 110 file.

    Args:
        mission: the mission (:meth:`Mission.items`: home altitude AMSL, waypoint and takeoff
            altitudes relative to home; hold times as param1, speed changes as
            DO_CHANGE_SPEED ground speed items, a final NAV_LAND as such).
        path: output file.
        takeoff: write the NAV_TAKEOFF item (alt = ``mission.takeoff_alt``).
        rtl: end with a NAV_RETURN_TO_LAUNCH item (a mission that lands has none).

    Returns:
        The path written.

    Raises:
        MissionError: a waypoint at altitude 0 or at lat = lon = 0, which ArduCopter (and
            :func:`read_wpl`) would read as "where the copter is".
    """
    path = Path(path)
    cmds = mission.nav_commands
    for i, (lat, lon, alt) in enumerate(mission.waypoints):
        if cmds[i] != MAV_CMD_NAV_LAND and (alt == 0.0 or (lat == 0.0 and lon == 0.0)):
            raise MissionError(
                f"waypoint {i} is at {'altitude 0' if alt == 0.0 else 'lat = lon = 0'}, which "
                "a mission file means as 'where the copter is': it cannot be written")
    items = mission.items()
    items[:, 3:5] = 0.0  # (the direction flags ArduCopter logs are not upload parameters)
    items[0, 5:8] = mission.home
    keep = np.ones(len(items), dtype=bool)
    keep[1] = takeoff
    if items[-1, 0] == MAV_CMD_NAV_RETURN_TO_LAUNCH:
        keep[-1] = rtl
    rows = [WPL_HEADER]
    for seq, it in enumerate(items[keep]):
        fields = [str(seq), "1" if seq == 0 else "0", str(int(it[8])), str(int(it[0]))]
        fields += [_num(v) for v in it[1:8]] + ["1"]
        rows.append("\t".join(fields))
    path.write_text("\n".join(rows) + "\n")
    return path


def read_wpl(
    path: str | Path, *, home: tuple[float, float, float] | None = None, name: str | None = None
) -> Mission:
    """Read a QGC WPL 110 file into a :class:`Mission`.

    Item 0 is home (command 16, frame 0, altitude AMSL). A NAV_TAKEOFF item gives the takeoff
    altitude (default: first waypoint's); NAV_WAYPOINT and NAV_LOITER_TIME items are the
    waypoints (frames 3/6 relative, or 0/5 absolute, converted to relative with the home
    altitude) with their hold times (param1, whole seconds); DO_CHANGE_SPEED items set the
    speed from the next waypoint on; a final NAV_RETURN_TO_LAUNCH, or a NAV_LAND as the last
    navigation item, ends the mission (see the module docstring). Takeoff and RTL may be
    missing (tlm flies the RTL then all the same).

    Args:
        path: the file.
        home: (lat, lon, alt_amsl) to use instead of the file's item 0. Also used when the
            file's home is at lat = lon = 0 (ArduPilot's "home not set"); CMAC if None then.
        name: mission name; default the file stem.

    Raises:
        MissionError: unreadable file, bad header, a malformed line, an unsupported command,
            frame or parameter, or an invalid mission; the message names the file and line.
    """
    path = Path(path)
    items = _read_items(path)
    first = items[0]
    if first.cmd != MAV_CMD_NAV_WAYPOINT or first.frame not in _ABSOLUTE_FRAMES:
        raise MissionError(
            f"{path}:{first.lineno}: item 0 must be home (command 16, frame 0), got command "
            f"{first.cmd} frame {first.frame}"
        )
    if home is None:
        home = HOME_CMAC if (first.lat == 0.0 and first.lon == 0.0) else (
            first.lat, first.lon, first.alt)
    home = (float(home[0]), float(home[1]), float(home[2]))
    b = _Builder(path, home)
    for it in items[1:]:
        b.add(it)
    return b.mission(path.stem if name is None else name)


def mission_from_items(
    rows: Sequence[Mapping[str, float]], home: tuple[float, float, float], name: str = "",
    source: str = "mission",
) -> Mission:
    """A :class:`Mission` from mission items after home as ArduPilot stores them (a log's CMD
    rows: ``CId``, ``Frame``, ``Prm1``..``Prm4``, ``Lat``, ``Lng``, ``Alt``; ``CNum`` names
    the item in errors), with :func:`read_wpl`'s rules: what tlm flies is kept (hold times,
    speed changes, LAND), anything else is refused (MissionError naming ``source`` and the
    item), never dropped."""
    b = _Builder(Path(source), (float(home[0]), float(home[1]), float(home[2])))
    for r in rows:
        b.add(_Item(lineno=int(r.get("CNum", 0)), frame=int(r["Frame"]), cmd=int(r["CId"]),
                    p=(float(r["Prm1"]), float(r["Prm2"]), float(r["Prm3"]), float(r["Prm4"])),
                    lat=float(r["Lat"]), lon=float(r["Lng"]), alt=float(r["Alt"])))
    return b.mission(name)


def _read_items(path: Path) -> list[_Item]:
    """The file's items after its header (at least one), sequence numbers checked."""
    try:
        text = read_text(path, encoding="utf-8-sig")
    except TextFileError as exc:
        raise MissionError(f"{path}: cannot read: {exc}") from None
    items: list[_Item] = []
    header_seen = False
    for lineno, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s:
            continue
        if not header_seen:
            if s.split() != WPL_HEADER.split():
                raise MissionError(f"{path}:{lineno}: expected header '{WPL_HEADER}', got {s!r}")
            header_seen = True
            continue
        items.append(_parse_line(path, lineno, s, expected_seq=len(items)))
    if not header_seen:
        raise MissionError(f"{path}: empty file (no '{WPL_HEADER}' header)")
    if not items:
        raise MissionError(f"{path}: no mission items (need home and at least one waypoint)")
    return items


class _Builder:
    """Collects a file's items after home into a Mission, checking each as it comes."""

    def __init__(self, path: Path, home: tuple[float, float, float]) -> None:
        self.path, self.home = path, home
        self.takeoff_alt: float | None = None
        self.rows: list[tuple[float, float, float]] = []
        self.lines: list[int] = []
        self.cmds: list[int] = []
        self.holds: list[float] = []
        self.speeds: list[float] = []
        self.speed_line: int | None = None  # a DO_CHANGE_SPEED waiting for its waypoint
        self.speed: float = math.nan
        self.end_line: int | None = None  # RTL or LAND
        self.end_name = ""

    def fail(self, it: _Item, msg: str) -> MissionError:
        return MissionError(f"{self.path}:{it.lineno}: {msg}")

    def add(self, it: _Item) -> None:
        """Take one item after home."""
        if it.cmd not in SUPPORTED_COMMANDS:
            raise self.fail(it, f"unsupported command {it.cmd} (tlm flies {_SUPPORTED_TEXT})")
        name = SUPPORTED_COMMANDS[it.cmd]
        if self.end_line is not None:
            raise self.fail(it, f"{name} item after {self.end_name} (line {self.end_line}) is "
                            "not supported: RETURN_TO_LAUNCH or LAND ends the mission")
        self._check_unflown(it, name)
        if it.cmd == MAV_CMD_DO_CHANGE_SPEED:
            self._speed_change(it)
        elif it.cmd == MAV_CMD_NAV_RETURN_TO_LAUNCH:
            if self.speed_line is not None:
                raise self._speed_before_end(it)
            self.end_line, self.end_name = it.lineno, "RETURN_TO_LAUNCH"
        elif it.cmd == MAV_CMD_NAV_TAKEOFF:
            if self.takeoff_alt is not None or self.rows:
                raise self.fail(it, "TAKEOFF must come once, before waypoints")
            self.takeoff_alt = self._alt_rel(it)
        else:
            self._nav_item(it, name)

    def _check_unflown(self, it: _Item, name: str) -> None:
        """Refuse a parameter tlm does not fly that is set."""
        for k, what in _UNFLOWN[it.cmd].items():
            v = it.p[k - 1]
            default = v == 0.0 or math.isnan(v) or (
                it.cmd == MAV_CMD_DO_CHANGE_SPEED and k == 3 and v == -1.0)
            if not default:
                raise self.fail(it, f"{name} param{k} ({what}) is {v:g}: tlm does not fly it "
                                "and refuses it rather than ignore it; set it to 0")

    def _speed_change(self, it: _Item) -> None:
        """DO_CHANGE_SPEED: a horizontal speed for the next waypoint on (-1 or 0 keeps it)."""
        kind, v = it.p[0], it.p[1]
        if self.speed_line is not None:
            raise self.fail(it, f"a second DO_CHANGE_SPEED (after line {self.speed_line}) before "
                            "the same waypoint: give one")
        if kind not in (0.0, 1.0):
            what = _SPEED_TYPES.get(int(kind), "unknown") if kind == int(kind) else "unknown"
            raise self.fail(it, f"DO_CHANGE_SPEED param1 (speed type) is {kind:g} ({what}): tlm "
                            "flies only 0 airspeed and 1 ground speed (the horizontal speed)")
        if math.isnan(v) or (v not in (-1.0, 0.0) and not MIN_SPEED_MPS <= v <= MAX_SPEED_MPS):
            raise self.fail(it, f"DO_CHANGE_SPEED param2 (speed) is {v:g} m/s: give "
                            f"{MIN_SPEED_MPS:g} to {MAX_SPEED_MPS:g} m/s, or -1 / 0 to keep the "
                            "speed")
        if v > 0.0:
            self.speed_line, self.speed = it.lineno, float(v)

    def _speed_before_end(self, it: _Item) -> MissionError:
        return self.fail(it, f"DO_CHANGE_SPEED on line {self.speed_line} has no waypoint after "
                         "it: ArduCopter's RTL flies at RTL_SPEED, so it would change nothing; "
                         "set RTL_SPEED instead")

    def _alt_rel(self, it: _Item) -> float:
        """The item's altitude relative to home [m] (frames 0/5 absolute, 3/6 relative)."""
        if it.frame in _RELATIVE_FRAMES:
            return it.alt
        if it.frame in _ABSOLUTE_FRAMES:
            return it.alt - self.home[2]
        raise self.fail(it, f"unsupported frame {it.frame} (use 0 or 3)")

    def _previous(self, it: _Item) -> tuple[float, float, float]:
        """Where the copter comes from: the last waypoint, or above home after the takeoff."""
        if self.rows:
            return self.rows[-1]
        if self.takeoff_alt is None:
            raise self.fail(it, "a first waypoint at lat = lon = 0 or altitude 0 (the "
                            "copter's position) needs a NAV_TAKEOFF item before it")
        return (self.home[0], self.home[1], self.takeoff_alt)

    def _nav_item(self, it: _Item, name: str) -> None:
        """NAV_WAYPOINT, NAV_LOITER_TIME or NAV_LAND: a waypoint row."""
        alt = self._alt_rel(it)
        lat, lon = it.lat, it.lon
        hold = 0.0
        if it.cmd == MAV_CMD_NAV_LAND:
            if it.alt != 0.0:
                raise self.fail(it, f"NAV_LAND altitude is {it.alt:g} m: set it to 0 (ArduCopter "
                                "flies to the landing point at its current altitude and lands)")
            self.end_line, self.end_name, alt = it.lineno, "LAND", 0.0
        else:
            hold = it.p[0]
            if math.isnan(hold) or hold < 0.0 or hold > MAX_HOLD_S or hold != round(hold):
                raise self.fail(it, f"{name} param1 (hold time) is {hold:g} s: ArduCopter holds "
                                f"whole seconds, 0 to {MAX_HOLD_S:.0f}")
            if it.alt == 0.0:
                alt = self._previous(it)[2]
        if lat == 0.0 and lon == 0.0:
            lat, lon = self._previous(it)[:2]
        self.rows.append((lat, lon, alt))
        self.lines.append(it.lineno)
        self.cmds.append(it.cmd)
        self.holds.append(float(hold))
        self.speeds.append(self.speed)
        self.speed_line, self.speed = None, math.nan

    def mission(self, name: str) -> Mission:
        if not self.rows:
            raise MissionError(f"{self.path}: no waypoints (NAV_WAYPOINT, NAV_LOITER_TIME or "
                               "NAV_LAND items after home)")
        if self.speed_line is not None:
            raise MissionError(f"{self.path}:{self.speed_line}: DO_CHANGE_SPEED has no waypoint "
                               "after it, so it would change nothing")
        try:
            return Mission(
                waypoints=np.asarray(self.rows, dtype=np.float64),
                home=self.home,
                name=name,
                takeoff_alt=self.takeoff_alt,
                commands=self.cmds,
                hold_s=self.holds,
                speed_changes=self.speeds,
            )
        except MissionError as exc:
            m = re.match(r"(?:speed change before )?waypoint (\d+) ", str(exc))
            where = f"{self.path}:{self.lines[int(m.group(1))]}" if m else str(self.path)
            raise MissionError(f"{where}: {exc}") from None


def _parse_line(path: Path, lineno: int, s: str, expected_seq: int) -> _Item:
    fields = s.split("\t") if s.count("\t") == 11 else s.split()
    if len(fields) != 12:
        raise MissionError(f"{path}:{lineno}: expected 12 fields, got {len(fields)}")
    try:
        seq, _current, frame, cmd = (int(f) for f in fields[:4])
        p1, p2, p3, p4 = (float(f) for f in fields[4:8])
        lat, lon, alt = (float(f) for f in fields[8:11])
        int(fields[11])
    except ValueError as exc:
        raise MissionError(f"{path}:{lineno}: bad number: {exc}") from None
    if seq != expected_seq:
        raise MissionError(f"{path}:{lineno}: sequence number {seq}, expected {expected_seq}")
    return _Item(lineno, frame, cmd, (p1, p2, p3, p4), lat, lon, alt)
