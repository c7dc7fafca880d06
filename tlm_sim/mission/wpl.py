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
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from tlm_sim.geo import HOME_CMAC
from tlm_sim.mission.errors import MissionError
from tlm_sim.mission.mission import Mission
from tlm_sim.textfile import TextFileError, read_text

__all__ = [
    "MAV_CMD_NAV_RETURN_TO_LAUNCH",
    "MAV_CMD_NAV_TAKEOFF",
    "MAV_CMD_NAV_WAYPOINT",
    "WPL_HEADER",
    "read_wpl",
    "write_wpl",
]

WPL_HEADER = "QGC WPL 110"
MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_NAV_RETURN_TO_LAUNCH = 20
MAV_CMD_NAV_TAKEOFF = 22

MAV_FRAME_GLOBAL = 0
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
MAV_FRAME_GLOBAL_INT = 5
MAV_FRAME_GLOBAL_RELATIVE_ALT_INT = 6
_ABSOLUTE_FRAMES = (MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_INT)
_RELATIVE_FRAMES = (MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)


def _num(x: float) -> str:
    """Shortest positional decimal that reads back as the same float64."""
    return np.format_float_positional(float(x), unique=True, trim="-")


def _row(seq: int, current: int, frame: int, cmd: int, lat: float, lon: float, alt: float) -> str:
    fields = [str(seq), str(current), str(frame), str(cmd), "0", "0", "0", "0"]
    fields += [_num(lat), _num(lon), _num(alt), "1"]
    return "\t".join(fields)


def write_wpl(
    mission: Mission, path: str | Path, *, takeoff: bool = True, rtl: bool = True
) -> Path:
    """Write ``mission`` as a QGC WPL 110 file.

    Args:
        mission: the mission; home altitude is written AMSL, waypoint and takeoff altitudes
            relative to home.
        path: output file.
        takeoff: write the NAV_TAKEOFF item (alt = ``mission.takeoff_alt``).
        rtl: end with a NAV_RETURN_TO_LAUNCH item.

    Returns:
        The path written.
    """
    path = Path(path)
    lat0, lon0, alt0 = mission.home
    rows = [WPL_HEADER, _row(0, 1, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, lat0, lon0, alt0)]
    if takeoff:
        rows.append(
            _row(
                len(rows) - 1,
                0,
                MAV_FRAME_GLOBAL_RELATIVE_ALT,
                MAV_CMD_NAV_TAKEOFF,
                0.0,
                0.0,
                float(mission.takeoff_alt),  # type: ignore[arg-type]
            )
        )
    for lat, lon, alt in mission.waypoints:
        rows.append(
            _row(
                len(rows) - 1, 0, MAV_FRAME_GLOBAL_RELATIVE_ALT, MAV_CMD_NAV_WAYPOINT, lat, lon, alt
            )
        )
    if rtl:
        rows.append(
            _row(len(rows) - 1, 0, MAV_FRAME_GLOBAL, MAV_CMD_NAV_RETURN_TO_LAUNCH, 0.0, 0.0, 0.0)
        )
    path.write_text("\n".join(rows) + "\n")
    return path


def read_wpl(
    path: str | Path, *, home: tuple[float, float, float] | None = None, name: str | None = None
) -> Mission:
    """Read a QGC WPL 110 file into a :class:`Mission`.

    Item 0 is home (command 16, frame 0, altitude AMSL). A NAV_TAKEOFF item gives the takeoff
    altitude (default: first waypoint's); NAV_WAYPOINT items are the waypoints (frames 3/6
    relative, or 0/5 absolute, converted to relative with the home altitude); a final
    NAV_RETURN_TO_LAUNCH is accepted. Takeoff and RTL may be missing. Waypoint params p1-p4
    (hold time, acceptance radius, ...) are ignored.

    Args:
        path: the file.
        home: (lat, lon, alt_amsl) to use instead of the file's item 0. Also used when the
            file's home is at lat = lon = 0 (ArduPilot's "home not set"); CMAC if None then.
        name: mission name; default the file stem.

    Raises:
        MissionError: unreadable file, bad header, a malformed line (message gives the line
            number), unsupported command or frame, or an invalid mission.
    """
    path = Path(path)
    try:
        text = read_text(path, encoding="utf-8-sig")
    except TextFileError as exc:
        raise MissionError(f"{path}: cannot read: {exc}") from None
    lines = text.splitlines()
    items: list[tuple[int, int, int, int, float, float, float]] = []  # lineno + fields
    header_seen = False
    for lineno, line in enumerate(lines, start=1):
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

    lineno, frame, cmd, _, lat, lon, alt = items[0]
    if cmd != MAV_CMD_NAV_WAYPOINT or frame not in _ABSOLUTE_FRAMES:
        raise MissionError(
            f"{path}:{lineno}: item 0 must be home (command 16, frame 0), got command {cmd} "
            f"frame {frame}"
        )
    file_home = (lat, lon, alt)
    if home is None:
        home = HOME_CMAC if (lat == 0.0 and lon == 0.0) else file_home
    home_alt = float(home[2])

    takeoff_alt: float | None = None
    wps: list[tuple[float, float, float]] = []
    wp_lines: list[int] = []
    rtl_line: int | None = None
    for lineno, frame, cmd, _, lat, lon, alt in items[1:]:
        if rtl_line is not None:
            raise MissionError(
                f"{path}:{lineno}: item after RETURN_TO_LAUNCH (line {rtl_line}) is not supported"
            )
        if cmd == MAV_CMD_NAV_RETURN_TO_LAUNCH:
            rtl_line = lineno
            continue
        if cmd not in (MAV_CMD_NAV_WAYPOINT, MAV_CMD_NAV_TAKEOFF):
            raise MissionError(
                f"{path}:{lineno}: unsupported command {cmd} (only 16 waypoint, 22 takeoff, 20 RTL)"
            )
        if frame in _RELATIVE_FRAMES:
            alt_rel = alt
        elif frame in _ABSOLUTE_FRAMES:
            alt_rel = alt - home_alt
        else:
            raise MissionError(f"{path}:{lineno}: unsupported frame {frame} (use 0 or 3)")
        if cmd == MAV_CMD_NAV_TAKEOFF:
            if takeoff_alt is not None or wps:
                raise MissionError(f"{path}:{lineno}: TAKEOFF must come once, before waypoints")
            takeoff_alt = alt_rel
        else:
            wps.append((lat, lon, alt_rel))
            wp_lines.append(lineno)
    if not wps:
        raise MissionError(f"{path}: no waypoints (command 16 items after home)")
    try:
        return Mission(
            waypoints=np.asarray(wps, dtype=np.float64),
            home=tuple(float(v) for v in home),  # type: ignore[arg-type]
            name=path.stem if name is None else name,
            takeoff_alt=takeoff_alt,
        )
    except MissionError as exc:
        m = re.match(r"waypoint (\d+) ", str(exc))
        where = f"{path}:{wp_lines[int(m.group(1))]}" if m else str(path)
        raise MissionError(f"{where}: {exc}") from None


def _parse_line(
    path: Path, lineno: int, s: str, expected_seq: int
) -> tuple[int, int, int, int, float, float, float]:
    fields = s.split("\t") if s.count("\t") == 11 else s.split()
    if len(fields) != 12:
        raise MissionError(f"{path}:{lineno}: expected 12 fields, got {len(fields)}")
    try:
        seq, _current, frame, cmd = (int(f) for f in fields[:4])
        lat, lon, alt = (float(f) for f in fields[8:11])
        for f in fields[4:8]:
            float(f)
        int(fields[11])
    except ValueError as exc:
        raise MissionError(f"{path}:{lineno}: bad number: {exc}") from None
    if seq != expected_seq:
        raise MissionError(f"{path}:{lineno}: sequence number {seq}, expected {expected_seq}")
    return lineno, frame, cmd, seq, lat, lon, alt
