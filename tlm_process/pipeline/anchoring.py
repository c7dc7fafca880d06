"""Fault Time Point Anchoring (paper Eq. 4): fault windows in log time, and row labels.

Two ways to find where a fault starts and ends in a log:

* **by recorded time** (:func:`anchor_by_time`): the record's ``start_time_us`` /
  ``end_time_us`` are log times (tlm writes the TimeUS at which its parameter change took
  effect, the SITL sidecars the TimeUS of the log's PARM message). Exact.
* **by recorded position** (:func:`anchor_by_position`, the paper's method): the record has
  the position a ground station read when the fault was set and cleared (DroneKit's
  ``global_relative_frame``: the vehicle's EKF estimate, altitude above home); the boundary is
  the GPS row nearest to it in metres (3-D: north, east, up). "Constrained to the right part
  of the flight": boundaries must follow one another in the records' order (fault 0 start <
  fault 0 end < fault 1 start < ...) and lie in the flight's armed phase; among all such
  assignments the one with the least total distance is chosen (dynamic programming), so a
  loop that passes the same spot twice cannot pull a boundary onto the wrong pass.

**RC labels** (:func:`extend_rc_failsafe`): the paper labels an RC fault from the radio's loss
to its return; the radio failsafe it started (RTL, MODE reason 3) goes on after that, and
after the first second the mode change is the only trace of it. ``rc_label="failsafe"``
(``tlm process --rc-label failsafe``) labels the failsafe's consequence too: the RC window runs
on to the end of the mode the failsafe started (landed: EV 18 LAND_COMPLETE, or disarmed, or
another mode), never into the next fault's window.

``method="auto"`` (the default) anchors by time when every record has its times, else by
position: on the reference SITL logs the position method puts the end of a GPS fault 14-20 s
early (the recorded position is the EKF's dead-reckoned estimate, 138-208 m from where the
GPS says the vehicle was) and the end of an engine fault 19-26 s early (the vehicle lies on
the ground during the whole fault, so every GPS row of that time is "nearest"). See
``docs/pipeline.md``. :func:`compare_methods` reports per fault how far the two disagree.

A window covers ``start_us <= TimeUS < end_us``; a fault held to the end of the log covers
every row from its start on. :func:`label_tables` writes the label (Table 6: gps 1, accel 2,
engine 3, rc 4; 0 elsewhere) on every row of every table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd

from tlm_process.pipeline.errors import AnchorError
from tlm_process.pipeline.ingest import FaultRecord, Flight
from tlm_sim import ardupilot as AP
from tlm_sim.geo import latlon_to_ne

__all__ = [
    "DEFAULT_MAX_MATCH_M",
    "AnchorComparison",
    "FaultWindow",
    "PositionMatch",
    "anchor_by_position",
    "anchor_by_time",
    "anchor_flight",
    "armed_span_us",
    "flight_armed_span_us",
    "RC_LABELS",
    "check_windows",
    "compare_methods",
    "extend_rc_failsafe",
    "home_altitude",
    "label_rows",
    "label_tables",
]

Method = Literal["auto", "time", "position"]
#: How RC fault rows are labelled: "window" (the paper's: while the radio is lost) or
#: "failsafe" (also the radio failsafe's mode, until it lands); see :func:`extend_rc_failsafe`
RC_LABELS = ("window", "failsafe")

#: A recorded position farther than this from every GPS row of the allowed part of the flight
#: [m] "matches nowhere" (position anchoring raises). On the reference logs correct matches are
#: within 1.3 m; the wrong matches after a GPS loss are within 5 m, so no threshold can catch
#: those.
DEFAULT_MAX_MATCH_M = 25.0


@dataclass(frozen=True, slots=True)
class FaultWindow:
    """One fault's window in log time: rows with ``start_us <= TimeUS < end_us`` get
    ``label``. ``end_us`` is ``inf`` for a fault held until the log ends. ``method``: "time"
    or "position" (how it was anchored)."""

    index: int
    type: str
    label: int
    start_us: float
    end_us: float
    method: str

    @property
    def name(self) -> str:
        """``fault N (TYPE)``, N = index + 1 (faults count from 1 in every message)."""
        return f"fault {self.index + 1} ({self.type})"

    def describe(self) -> str:
        end = "end of log" if not np.isfinite(self.end_us) else f"{self.end_us * 1e-6:.3f} s"
        return f"{self.name} {self.start_us * 1e-6:.3f} s - {end}"


@dataclass(frozen=True, slots=True)
class PositionMatch:
    """Where the paper's method puts one boundary: the GPS row (index into the GPS table),
    its TimeUS and its distance from the recorded position [m]."""

    row: int
    time_us: int
    distance_m: float


@dataclass(frozen=True, slots=True)
class AnchorComparison:
    """How far the position method is from the recorded times, for one fault.

    ``dt_*_s``: position-method time minus recorded time [s]. ``rows_*``: the same in GPS rows
    (matched row minus the first GPS row at or after the recorded time). ``match_*_m``:
    distance between the recorded position and the matched GPS row [m]. ``offset_*_m``:
    distance between the recorded position and the GPS position logged at the recorded time
    [m] — how far the recorded estimate was from the GPS (hundreds of metres after a GPS loss).
    End fields are None for a fault held to the end of the log.
    """

    index: int
    type: str
    dt_start_s: float
    dt_end_s: float | None
    rows_start: int
    rows_end: int | None
    match_start_m: float
    match_end_m: float | None
    offset_start_m: float
    offset_end_m: float | None

    def to_dict(self) -> dict[str, Any]:
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in asdict(self).items()}


# --------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------

def _gps(tables: Mapping[str, pd.DataFrame], source: str | None = None) -> pd.DataFrame:
    gps = tables.get("GPS")
    if gps is None or not len(gps):
        raise AnchorError("the log has no GPS rows: cannot anchor fault windows", source=source)
    return gps


def log_span_us(tables: Mapping[str, pd.DataFrame]) -> tuple[int, int]:
    """First and last TimeUS over all tables [µs]."""
    ts = [(int(df["TimeUS"].min()), int(df["TimeUS"].max()))
          for df in tables.values() if len(df) and "TimeUS" in df.columns]
    if not ts:
        raise AnchorError("the log has no rows")
    return min(t[0] for t in ts), max(t[1] for t in ts)


def armed_span_us(tables: Mapping[str, pd.DataFrame]) -> tuple[int, int] | None:
    """(first ARMED event, first DISARMED event after it, or the log's end) [µs], from EV
    (ids 10/11); None when the log has no EV table or no ARMED event."""
    ev = tables.get("EV")
    if ev is None or not len(ev):
        return None
    t = ev["TimeUS"].to_numpy(np.int64)
    ids = ev["Id"].to_numpy()
    armed = t[ids == AP.EV_ARMED]
    if not len(armed):
        return None
    t0 = int(armed[0])
    dis = t[(ids == AP.EV_DISARMED) & (t > t0)]
    t1 = int(dis[0]) if len(dis) else log_span_us(tables)[1]
    return t0, t1


def flight_armed_span_us(flight: Flight) -> tuple[int, int] | None:
    """The armed phase of a flight [µs]: ``flight.meta["armed_span_us"]`` when the reader
    found it without an EV 10 event (a log that starts at arming, or one with only ARM
    messages: :func:`tlm_process.logread.arming_time_us`), else :func:`armed_span_us` (EV
    10 to the first EV 11 after it or the log's end); None when the flight never armed."""
    span = flight.meta.get("armed_span_us") if flight.meta else None
    if span is not None and len(span) == 2 and span[0] is not None and span[1] is not None:
        return int(span[0]), int(span[1])
    return armed_span_us(flight.tables)


def home_altitude(flight: Flight) -> tuple[float, str]:
    """Home altitude AMSL [m] and where it came from.

    Recorded altitudes are relative to home as the EKF defines it, so the EKF's own figure
    comes first: median of ``POS.Alt - POS.RelHomeAlt``. Then the source's stated home (tlm
    meta, SITL sidecar), then the GPS altitude at arming (first healthy fix, Status >= 3, at
    or after the ARMED event, or the first healthy fix)."""
    pos = flight.tables.get("POS")
    if pos is not None and len(pos) and {"Alt", "RelHomeAlt"} <= set(pos.columns):
        return float(np.median(pos["Alt"].to_numpy(float) - pos["RelHomeAlt"].to_numpy(float))), \
            "POS.Alt - POS.RelHomeAlt"
    if flight.home is not None:
        return float(flight.home[2]), "source home"
    gps = _gps(flight.tables, flight.id)
    ok = gps[gps["Status"] >= 3] if "Status" in gps.columns else gps
    armed = flight_armed_span_us(flight)
    if armed is not None:
        after = ok[ok["TimeUS"] >= armed[0]]
        ok = after if len(after) else ok
    if not len(ok):
        raise AnchorError("no healthy GPS fix to take the home altitude from", source=flight.id)
    return float(ok["Alt"].iloc[0]), "GPS at arming"


def _gps_enu(gps: pd.DataFrame, home_alt: float) -> tuple[np.ndarray, float, float]:
    """GPS rows as (north, east, up above home) [m] about the last row; and that origin."""
    lat0, lon0 = float(gps["Lat"].iloc[-1]), float(gps["Lng"].iloc[-1])
    n, e = latlon_to_ne(gps["Lat"].to_numpy(float), gps["Lng"].to_numpy(float), lat0, lon0)
    up = gps["Alt"].to_numpy(float) - home_alt
    return np.stack([n, e, up], axis=1), lat0, lon0


def _point_enu(p: tuple[float, float, float], lat0: float, lon0: float) -> np.ndarray:
    n, e = latlon_to_ne(p[0], p[1], lat0, lon0)
    return np.array([float(n), float(e), p[2]])


# --------------------------------------------------------------------------------------------
# Anchoring
# --------------------------------------------------------------------------------------------

def anchor_by_time(records: Sequence[FaultRecord], tables: Mapping[str, pd.DataFrame],
                   source: str | None = None) -> list[FaultWindow]:
    """Windows from the recorded log times; a time outside the log matches nowhere."""
    t_first, t_last = log_span_us(tables)
    out = []
    for r in records:
        if not r.has_times:
            raise AnchorError(f"{r.name}: the record has no log times (start_time_us/"
                              "end_time_us); anchor by position", source=source)
        assert r.start_time_us is not None
        if not t_first <= r.start_time_us <= t_last:
            raise AnchorError(
                f"{r.name}: start {r.start_time_us * 1e-6:.3f} s matches nowhere: the log "
                f"spans {t_first * 1e-6:.3f}-{t_last * 1e-6:.3f} s", source=source)
        if r.held_to_end:
            end = float("inf")
        else:
            assert r.end_time_us is not None
            if r.end_time_us > t_last + 1:
                raise AnchorError(
                    f"{r.name}: end {r.end_time_us * 1e-6:.3f} s matches nowhere: the log ends "
                    f"at {t_last * 1e-6:.3f} s", source=source)
            end = float(r.end_time_us)
        out.append(FaultWindow(r.index, r.type, r.label, float(r.start_time_us), end, "time"))
    return out


def _ordered_min_cost(cost: np.ndarray) -> np.ndarray:
    """Rows j_0 < j_1 < ... (one per line of ``cost [m, n]``) minimising the summed cost.

    Ties go to the earliest row. Returns the m row indices. Dynamic programming over prefix
    minima, O(m n)."""
    m, n = cost.shape
    if n < m:
        raise AnchorError(f"{m} fault boundaries but only {n} GPS rows to put them on")
    idx = np.arange(n)
    best = cost[0].copy()
    back = np.zeros((m, n), dtype=np.int64)
    for i in range(1, m):
        pm = np.minimum.accumulate(best)
        new = np.r_[True, best[1:] < pm[:-1]]
        arg = np.maximum.accumulate(np.where(new, idx, 0))
        prev_min = np.r_[np.inf, pm[:-1]]  # best over rows < j
        back[i] = np.r_[0, arg[:-1]]
        best = cost[i] + prev_min
    rows = np.zeros(m, dtype=np.int64)
    rows[-1] = int(np.argmin(best))
    for i in range(m - 1, 0, -1):
        rows[i - 1] = back[i, rows[i]]
    return rows


def match_positions(flight: Flight, records: Sequence[FaultRecord] | None = None,
                    home_alt: float | None = None,
                    armed_only: bool = True) -> list[tuple[PositionMatch, PositionMatch | None]]:
    """The paper's method without a distance limit: per record, the GPS rows matched to its
    start and end position (end None for a fault held to the end of the log).

    Boundaries are kept in the records' order and, with ``armed_only`` and an EV table, in the
    armed phase (see the module docstring)."""
    records = flight.records if records is None else records
    gps = _gps(flight.tables, flight.id)
    if home_alt is None:
        home_alt = home_altitude(flight)[0]
    xyz, lat0, lon0 = _gps_enu(gps, home_alt)
    t = gps["TimeUS"].to_numpy(np.int64)
    allowed = np.ones(len(t), dtype=bool)
    span = flight_armed_span_us(flight) if armed_only else None
    if span is not None:
        allowed = (t >= span[0]) & (t <= span[1])
    points = []
    for r in records:
        if not r.has_positions:
            raise AnchorError(f"{r.name}: the record has no positions (start_lat/lon/alt, "
                              "end_lat/lon/alt) to anchor by", source=flight.id)
        assert r.start_pos is not None
        points.append(r.start_pos)
        if not r.held_to_end:
            assert r.end_pos is not None
            points.append(r.end_pos)
    if not points:
        return []
    p = np.stack([_point_enu(q, lat0, lon0) for q in points])
    dist = np.linalg.norm(xyz[None, :, :] - p[:, None, :], axis=2)
    cost = np.where(allowed[None, :], dist, np.inf)
    rows = _ordered_min_cost(cost)
    if not np.isfinite(cost[np.arange(len(rows)), rows]).all():
        raise AnchorError(f"{len(points)} fault boundaries do not fit in order on the "
                          f"{int(allowed.sum())} GPS rows of the armed flight", source=flight.id)
    out: list[tuple[PositionMatch, PositionMatch | None]] = []
    k = 0
    for r in records:
        j0 = int(rows[k])
        start = PositionMatch(j0, int(t[j0]), float(dist[k, j0]))
        k += 1
        end = None
        if not r.held_to_end:
            j1 = int(rows[k])
            end = PositionMatch(j1, int(t[j1]), float(dist[k, j1]))
            k += 1
        out.append((start, end))
    return out


def anchor_by_position(flight: Flight, max_match_m: float = DEFAULT_MAX_MATCH_M,
                       armed_only: bool = True) -> list[FaultWindow]:
    """Windows by the paper's method (nearest GPS row to each recorded position, in order).

    A boundary whose matched GPS row is farther than ``max_match_m`` [m] from the recorded
    position matches nowhere (AnchorError)."""
    matches = match_positions(flight, armed_only=armed_only)
    out = []
    for r, (m0, m1) in zip(flight.records, matches, strict=True):
        for edge, m in (("start", m0), ("end", m1)):
            if m is not None and m.distance_m > max_match_m:
                raise AnchorError(
                    f"{r.name}: the recorded {edge} position matches nowhere: the nearest GPS "
                    f"row is {m.distance_m:.1f} m away (limit {max_match_m:g} m)",
                    source=flight.id)
        end = float("inf") if m1 is None else float(m1.time_us)
        out.append(FaultWindow(r.index, r.type, r.label, float(m0.time_us), end, "position"))
    return out


def compare_methods(flight: Flight, home_alt: float | None = None,
                    armed_only: bool = True) -> list[AnchorComparison]:
    """Per fault, how far the paper's position method lands from the recorded times
    (records with both times and positions only; see :class:`AnchorComparison`)."""
    recs = [r for r in flight.records if r.has_times and r.has_positions]
    if not recs:
        return []
    if home_alt is None:
        home_alt = home_altitude(flight)[0]
    gps = _gps(flight.tables, flight.id)
    xyz, lat0, lon0 = _gps_enu(gps, home_alt)
    t = gps["TimeUS"].to_numpy(np.int64)
    matches = match_positions(flight, recs, home_alt, armed_only)

    def at_time(t_us: int, pos: tuple[float, float, float]) -> tuple[int, float]:
        j = min(int(np.searchsorted(t, t_us, side="left")), len(t) - 1)
        # the GPS position logged at t_us: the latest row at or before it
        k = max(int(np.searchsorted(t, t_us, side="right")) - 1, 0)
        return j, float(np.linalg.norm(xyz[k] - _point_enu(pos, lat0, lon0)))

    out = []
    for r, (m0, m1) in zip(recs, matches, strict=True):
        assert r.start_time_us is not None and r.start_pos is not None
        j0, off0 = at_time(r.start_time_us, r.start_pos)
        dt1 = rows1 = match1 = off1 = None
        if m1 is not None:
            assert r.end_time_us is not None and r.end_pos is not None
            j1, off1 = at_time(r.end_time_us, r.end_pos)
            dt1 = (m1.time_us - r.end_time_us) * 1e-6
            rows1 = m1.row - j1
            match1 = m1.distance_m
        out.append(AnchorComparison(
            r.index, r.type, (m0.time_us - r.start_time_us) * 1e-6, dt1, m0.row - j0, rows1,
            m0.distance_m, match1, off0, off1))
    return out


def check_windows(windows: Sequence[FaultWindow], source: str | None = None) -> None:
    """Raise AnchorError when two windows overlap (or one ends before it starts)."""
    for w in windows:
        if not w.end_us > w.start_us:
            raise AnchorError(f"{w.name}: window ends at or before its start "
                              f"({w.describe()})", source=source)
    ordered = sorted(windows, key=lambda w: w.start_us)
    for a, b in zip(ordered, ordered[1:], strict=False):
        if b.start_us < a.end_us:
            raise AnchorError(f"overlapping fault windows: {a.describe()} and {b.describe()}",
                              source=source)


def anchor_flight(flight: Flight, method: Method = "auto",
                  max_match_m: float = DEFAULT_MAX_MATCH_M,
                  armed_only: bool = True) -> list[FaultWindow]:
    """The flight's fault windows (checked: no overlaps). ``method``: "time", "position", or
    "auto" = time when every record has its log times, else position."""
    if method not in ("auto", "time", "position"):
        raise AnchorError(f"unknown anchoring method {method!r}; use auto, time or position")
    _gps(flight.tables, flight.id)
    if method == "auto":
        method = "time" if all(r.has_times for r in flight.records) else "position"
    if method == "time":
        windows = anchor_by_time(flight.records, flight.tables, flight.id)
    else:
        windows = anchor_by_position(flight, max_match_m, armed_only)
    check_windows(windows, flight.id)
    return windows


# --------------------------------------------------------------------------------------------
# Labels
# --------------------------------------------------------------------------------------------

def _failsafe_end_us(tables: Mapping[str, pd.DataFrame], w: FaultWindow) -> float | None:
    """End of the mode the radio failsafe switched to inside RC window ``w`` [us]: the first
    landing (EV 18) or disarm (EV 11), or change to another mode, after it; ``inf`` when none
    comes before the log ends; None when no failsafe mode change (MODE.Rsn 3) is in the
    window."""
    mode = tables.get("MODE")
    if mode is None or not len(mode) or "Rsn" not in mode.columns:
        return None
    t = mode["TimeUS"].to_numpy(np.float64)
    fs = np.flatnonzero((t >= w.start_us) & (t < w.end_us)
                        & (mode["Rsn"].to_numpy() == AP.RSN_RADIO_FAILSAFE))
    if not len(fs):
        return None
    t_fs = t[fs[0]]
    m_fs = mode["Mode"].to_numpy()[fs[0]]
    ends = [np.inf]
    later = (t > t_fs) & (mode["Mode"].to_numpy() != m_fs)
    if later.any():
        ends.append(float(t[later].min()))
    ev = tables.get("EV")
    if ev is not None and len(ev):
        te = ev["TimeUS"].to_numpy(np.float64)
        done = (te > t_fs) & np.isin(ev["Id"].to_numpy(), (AP.EV_LAND_COMPLETE, AP.EV_DISARMED))
        if done.any():
            ends.append(float(te[done].min()))
    return min(ends)


def extend_rc_failsafe(windows: Sequence[FaultWindow], tables: Mapping[str, pd.DataFrame],
                       source: str | None = None) -> list[FaultWindow]:
    """The windows with every RC window that started a radio failsafe run on to the end of
    the failsafe's mode (:func:`_failsafe_end_us`: landed, disarmed or another mode), cut at
    the next window's start; the others as they are. An RC fault whose failsafe did not
    change the mode (FS_THR_ENABLE 0) keeps its window."""
    from dataclasses import replace

    out = list(windows)
    starts = sorted(w.start_us for w in windows)
    for i, w in enumerate(out):
        if w.type != "rc":
            continue
        end = _failsafe_end_us(tables, w)
        if end is None or end <= w.end_us:
            continue
        nxt = [s for s in starts if s > w.start_us]
        out[i] = replace(w, end_us=min(end, nxt[0]) if nxt else end)
    check_windows(out, source)
    return out


def label_rows(time_us: np.ndarray, windows: Sequence[FaultWindow]) -> np.ndarray:
    """Label (int8) of each TimeUS: the window's label inside a window, 0 elsewhere."""
    t = np.asarray(time_us, dtype=np.float64)
    out = np.zeros(len(t), dtype=np.int8)
    for w in windows:
        out[(t >= w.start_us) & (t < w.end_us)] = w.label
    return out


def label_tables(tables: Mapping[str, pd.DataFrame],
                 windows: Sequence[FaultWindow]) -> dict[str, pd.DataFrame]:
    """Copies of every table with a ``label`` column (Table 6) on every row."""
    check_windows(windows)
    out = {}
    for name, df in tables.items():
        d = df.copy()
        d["label"] = label_rows(d["TimeUS"].to_numpy(), windows) if "TimeUS" in d.columns \
            else np.zeros(len(d), dtype=np.int8)
        out[name] = d
    return out
