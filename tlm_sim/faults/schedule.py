"""Fault schedules: which faults one flight gets, when they begin and when they are cleared.

A :class:`FaultSchedule` is an ordered tuple of :class:`Fault` s. Each fault has a type (one of
:data:`~tlm_sim.faults.types.FAULT_TYPES`), a start :class:`Trigger` and an optional end
trigger (none: held until the flight ends). A trigger is either a time in seconds since boot
(the log's ``TimeUS / 1e6``) or the moment a mission waypoint (1-based) is reached. The
simulation loop consumes :meth:`FaultSchedule.param_changes`: the SITL parameter changes
(current ArduPilot names) of every fault boundary, applied strictly in list order.

Three ways to write one::

    FaultSchedule.from_file("faults.yaml")     # {"faults": [{"fault": "gps", "start": 60,
                                               #              "end": 110}, ...]}
    FaultSchedule.from_shorthand(["gps:60-110", "engine:wp40-wp48", "rc:200-", "accel:120+30"])
    FaultSchedule.paper(seed=21)               # the paper's GPS, accel, engine, RC sequence

Errors are :class:`FaultScheduleError` (a ``ValueError``) with a one-line message that names
the fault by its 0-based position and type, e.g. ``fault 2 (engine): end 90 s is before
start 120 s``.
"""

from __future__ import annotations

import difflib
import json
import math
import numbers
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import yaml

from tlm_sim.faults.fault import Fault, lookup_type
from tlm_sim.faults.trigger import (
    TIME_RE,
    FaultScheduleError,
    Trigger,
    TriggerKind,
    fmt_number,
    is_real,
    trigger_problem,
)
from tlm_sim.faults.types import FAULT_TYPES
from tlm_sim.textfile import TextFileError, read_text

__all__ = [
    "PAPER_GAP_S",
    "PAPER_HOLD_S",
    "PAPER_ORDER",
    "Fault",
    "FaultSchedule",
    "FaultScheduleError",
    "ParamChange",
    "Trigger",
    "TriggerKind",
]

#: Fault order of the paper's single-flight sequence (A->B GPS, C->D accel, E->F engine,
#: G->H RC; paper §4.3, reference combined flight).
PAPER_ORDER: tuple[str, ...] = ("gps", "accel", "engine", "rc")
#: Range of the gap before each fault of the paper sequence [s]: after the switch to AUTO for
#: the first, after the previous fault's end for the others.
PAPER_GAP_S: tuple[float, float] = (15.0, 25.0)
#: Range of the time each fault of the paper sequence is held [s].
PAPER_HOLD_S: tuple[float, float] = (20.0, 40.0)

_FAULT_KEYS = ("fault", "start", "end", "params_start", "params_end", "absolute")
_FILE_SUFFIXES = (".json", ".yaml", ".yml")
_SHORT_RE = re.compile(
    r"^(?P<type>[A-Za-z_]\w*)\s*:\s*(?P<start>[^-+\s]+)\s*"
    r"(?:(?P<op>[-+])\s*(?P<end>[^-+\s]*))?$")
_SHORT_HELP = ("expected TYPE:START-END, TYPE:START- or TYPE:START+DURATION with times in s or "
               "waypoints wpN (e.g. gps:60-110, engine:wp40-wp48, rc:200-, accel:120+30)")


# --------------------------------------------------------------------------------------------
# Schedule
# --------------------------------------------------------------------------------------------

class ParamChange(NamedTuple):
    """One SITL parameter change of a schedule, for the simulation loop.

    ``kind`` "time": apply at ``at`` seconds since boot; "wp": when waypoint ``at`` (1-based)
    is reached. ``name`` is the current ArduPilot name, ``value`` in its unit. ``fault`` is the
    0-based position of the fault in the schedule, ``edge`` "start" or "end".
    """

    kind: str
    at: float
    name: str
    value: float
    fault: int
    edge: str


class _Boundary(NamedTuple):
    index: int
    edge: str
    trigger: Trigger


def _check_positive_int(x: Any, what: str) -> None:
    if isinstance(x, bool) or not isinstance(x, numbers.Integral) or x < 1:
        raise FaultScheduleError(f"{what} must be a whole number >= 1, got {x!r}")


def _check_time(x: Any, what: str, allow_zero: bool = False) -> float:
    if not is_real(x) or not math.isfinite(float(x)) or float(x) < 0 or (
            float(x) == 0 and not allow_zero):
        lim = ">= 0" if allow_zero else "> 0"
        raise FaultScheduleError(f"{what} must be a finite number of seconds {lim}, got {x!r}")
    return float(x)


@dataclass(frozen=True, slots=True)
class FaultSchedule:
    """The faults of one flight, in the order they happen (may be empty: a normal flight).

    The simulation applies the fault boundaries strictly in list order: fault 0's start, its
    end, fault 1's start, ... Construction checks each fault and that the boundaries are in
    order wherever two can be compared (both times or both waypoints); :meth:`validate` also
    checks them against a mission's waypoint count and a flight's length.
    """

    faults: tuple[Fault, ...] = ()

    def __post_init__(self) -> None:
        faults = self.faults
        if isinstance(faults, str | bytes | Mapping | Fault) or not isinstance(
                faults, Sequence):
            raise FaultScheduleError(
                f"faults must be a sequence of Fault, got {type(faults).__name__}")
        for i, f in enumerate(faults):
            if not isinstance(f, Fault):
                raise FaultScheduleError(f"is a {type(f).__name__}, not a Fault", index=i)
        object.__setattr__(self, "faults", tuple(faults))
        self.validate()

    # -- checks ---------------------------------------------------------------------------
    def validate(self, n_waypoints: int | None = None, max_time_s: float | None = None) -> None:
        """Raise :class:`FaultScheduleError` unless the schedule is usable.

        Always: each fault is valid, a fault without end is the last one, and the boundaries
        are in list order wherever they are comparable (same kind): no fault starts before the
        previous one ends (no overlap), none is listed before an earlier one. With
        ``n_waypoints`` (the mission's waypoint count): every waypoint trigger is in
        ``1..n_waypoints``. With ``max_time_s`` [s]: no time trigger is after it.
        """
        if n_waypoints is not None:
            _check_positive_int(n_waypoints, "n_waypoints")
        if max_time_s is not None:
            max_time_s = _check_time(max_time_s, "max_time_s")
        for i, f in enumerate(self.faults):
            for edge, trig in (("start", f.start), ("end", f.end)):
                if trig is None:
                    continue
                problem = trigger_problem(trig.kind, trig.value)
                if problem is not None:
                    raise FaultScheduleError(f"{edge} {problem}", index=i, fault_type=f.type)
                if (n_waypoints is not None and trig.kind == "wp"
                        and trig.value > n_waypoints):
                    raise FaultScheduleError(
                        f"{edge} {trig} is beyond the mission's last waypoint wp{n_waypoints}",
                        index=i, fault_type=f.type)
                if (max_time_s is not None and trig.kind == "time"
                        and trig.value > max_time_s):
                    raise FaultScheduleError(
                        f"{edge} {trig} is after the end of the flight "
                        f"({fmt_number(max_time_s)} s)",
                        index=i, fault_type=f.type)
            if f.end is None and i + 1 < len(self.faults):
                nxt = self.faults[i + 1]
                raise FaultScheduleError(
                    f"has no end (held until the flight ends) but fault {i + 2} ({nxt.type}) "
                    "comes after it; give it an end or make it the last fault",
                    index=i, fault_type=f.type)
        self._check_order()

    def require_times(self) -> None:
        """Raise :class:`FaultScheduleError` naming the first waypoint trigger: a flight
        without waypoints (flown from sticks) takes its faults by time only."""
        for i, f in enumerate(self.faults):
            for edge, trig in (("start", f.start), ("end", f.end)):
                if trig is not None and trig.kind == "wp":
                    raise FaultScheduleError(
                        f"{edge} {trig}: a pilot-flown flight has no waypoints; give the "
                        "fault's start and end as times", index=i, fault_type=f.type)

    def _boundaries(self) -> list[_Boundary]:
        out = []
        for i, f in enumerate(self.faults):
            out.append(_Boundary(i, "start", f.start))
            if f.end is not None:
                out.append(_Boundary(i, "end", f.end))
        return out

    def _check_order(self) -> None:
        bounds = self._boundaries()
        for k, q in enumerate(bounds):
            for p in bounds[:k]:
                if p.index == q.index or not p.trigger.comparable(q.trigger):
                    continue
                if q.trigger.value >= p.trigger.value:
                    continue
                first = self.faults[p.index]
                overlap = q.edge == "start" and p.edge == "end" and not (
                    first.start.comparable(q.trigger) and q.trigger.value < first.start.value)
                why = ("faults must not overlap" if overlap else
                       "list faults in the order they happen (boundaries apply in list order)")
                raise FaultScheduleError(
                    f"{q.edge} {q.trigger} is before the {p.edge} {p.trigger} of fault "
                    f"{p.index + 1} ({first.type}); {why}",
                    index=q.index, fault_type=self.faults[q.index].type)

    # -- what the simulation consumes -----------------------------------------------------
    def param_changes(self, own: Mapping[str, float] | None = None) -> list[ParamChange]:
        """Every parameter change in the order the loop must apply them: fault 0's start
        changes, fault 0's end changes, fault 1's start changes, ... (current names).
        ``own``: the flight's parameters, against which relative faults are resolved
        (:meth:`Fault.flown`); None: the values as given."""
        out: list[ParamChange] = []
        for i, f in enumerate(self.faults):
            start, end = f.flown(own)
            for name, value in start.items():
                out.append(ParamChange(f.start.kind, f.start.value, name, value, i, "start"))
            if f.end is not None:
                for name, value in end.items():
                    out.append(ParamChange(f.end.kind, f.end.value, name, value, i, "end"))
        return out

    # -- Eq. 5 window stretching ------------------------------------------------------------
    def stretched(self, lam: float, *, shift: bool = True, n_waypoints: int | None = None,
                  max_time_s: float | None = None) -> FaultSchedule:
        """Every fault window scaled by ``lam`` (λ, the paper's Eq. 5 failure time window
        control factor): each fault keeps its start and lasts λ times as long.

        * time start and end [s]: ``end = start + λ·(end − start)`` (rounded to 1 µs);
        * waypoint start and end: the window is counted in waypoints,
          ``end = start + max(1, round(λ·(end − start)))``;
        * start and end of different kinds (``gps:wp10-140``): FaultScheduleError, since how
          long such a window lasts is known only in flight;
        * no end (held until the flight ends): unchanged.

        ``shift=True`` (default) moves every later boundary of the same kind by the length
        added (or removed, λ < 1) so far, so the normal gaps between faults keep their length
        (the paper's sequence starts each fault U(15, 25) s after the previous one ends).
        Time and waypoint boundaries do not shift each other (how they relate is known only in
        flight); the loop applies boundaries in list order, so faults cannot overlap in flight
        either. ``shift=False`` keeps every start: a stretched fault that would reach the next
        one's start is a FaultScheduleError. With ``n_waypoints`` / ``max_time_s`` the result is
        checked as by :meth:`validate`: a window stretched past the mission's last waypoint or
        past the end of the flight is a FaultScheduleError (never cut short silently).
        """
        if not is_real(lam) or not math.isfinite(float(lam)) or float(lam) <= 0:
            raise FaultScheduleError(f"lambda must be a finite number > 0, got {lam!r}")
        lam = float(lam)
        added = {"time": 0.0, "wp": 0.0}
        faults = []
        try:
            for i, f in enumerate(self.faults):
                assert f.params_start is not None and f.params_end is not None
                kind = f.start.kind
                start = f.start
                if shift and added[kind]:
                    start = Trigger(kind, round(start.value + added[kind], 6))
                end = f.end
                if end is not None:
                    if end.kind != kind:
                        raise FaultScheduleError(
                            f"cannot stretch a window from {f.start} to {f.end}: its start and "
                            "end must both be times or both waypoints", index=i,
                            fault_type=f.type)
                    span = end.value - f.start.value
                    new_span = (round(lam * span, 6) if kind == "time"
                                else float(max(1, round(lam * span))))
                    end = Trigger(kind, round(start.value + new_span, 6))
                    added[kind] += new_span - span
                faults.append(Fault(f.type, start, end, dict(f.params_start),
                                    dict(f.params_end) if end is not None else None))
            out = FaultSchedule(tuple(faults))
            if n_waypoints is not None or max_time_s is not None:
                out.validate(n_waypoints, max_time_s)
        except FaultScheduleError as exc:
            raise FaultScheduleError(f"stretched by lambda {fmt_number(lam)}: {exc.reason}",
                                     index=exc.index, fault_type=exc.fault_type) from None
        return out

    # -- container ------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.faults)

    def __iter__(self) -> Iterator[Fault]:
        return iter(self.faults)

    def __getitem__(self, index: int) -> Fault:
        return self.faults[index]

    def __str__(self) -> str:
        if not self.faults:
            return "no faults"
        return "\n".join(f"{i} {f}" for i, f in enumerate(self.faults))

    # -- dict and file form ---------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: Mapping[str, Any] | Sequence[Mapping[str, Any]], *,
                  n_waypoints: int | None = None,
                  max_time_s: float | None = None) -> FaultSchedule:
        """A schedule from its file form ``{"faults": [{"fault": "gps", "start": 60,
        "end": 110}, ...]}`` or the bare list. ``start`` / ``end``: seconds since boot or
        ``"wpN"``; ``end`` may be left out (held to the end); optional ``params_start`` /
        ``params_end`` mappings. ``n_waypoints`` / ``max_time_s``: see :meth:`validate`."""
        if isinstance(d, Mapping):
            unknown = [k for k in d if k != "faults"]
            if unknown:
                raise FaultScheduleError(
                    f"unknown key {unknown[0]!r} in a fault schedule (only 'faults')")
            if "faults" not in d:
                raise FaultScheduleError("a fault schedule needs a 'faults' list")
            items = d["faults"] if d["faults"] is not None else []
        else:
            items = d
        if isinstance(items, str | bytes | Mapping) or not isinstance(items, Sequence):
            raise FaultScheduleError(
                f"the faults must be a list of fault mappings, got {type(items).__name__}")
        return cls._parse_each(items, _fault_from_dict, n_waypoints, max_time_s)

    @classmethod
    def _parse_each(cls, items: Sequence[Any], parse: Callable[[Any], Fault],
                    n_waypoints: int | None, max_time_s: float | None) -> FaultSchedule:
        """A schedule of ``parse(item)`` per item (errors name the item's position), checked
        against the mission and flight bounds when they are given."""
        faults = []
        for i, item in enumerate(items):
            try:
                faults.append(parse(item))
            except FaultScheduleError as exc:
                raise exc.at(i) from None
        schedule = cls(tuple(faults))
        if n_waypoints is not None or max_time_s is not None:
            schedule.validate(n_waypoints, max_time_s)
        return schedule

    def to_dict(self) -> dict[str, Any]:
        """File form (JSON/YAML-ready); :meth:`from_dict` reads it back to an equal schedule."""
        return {"faults": [f.to_dict() for f in self.faults]}

    @classmethod
    def from_file(cls, path: str | Path, *, n_waypoints: int | None = None,
                  max_time_s: float | None = None) -> FaultSchedule:
        """Read a ``.json``, ``.yaml`` or ``.yml`` schedule file (see :meth:`from_dict`)."""
        path = Path(path)
        suffix = _suffix(path)
        try:
            text = read_text(path)
        except TextFileError as exc:
            raise FaultScheduleError(f"cannot read fault schedule {path}: {exc}") from None
        try:
            data = json.loads(text) if suffix == ".json" else yaml.safe_load(text)
        except json.JSONDecodeError as exc:
            raise FaultScheduleError(f"invalid JSON: {exc}", source=str(path)) from None
        except yaml.YAMLError as exc:
            raise FaultScheduleError(f"invalid YAML: {exc}", source=str(path)) from None
        except RecursionError:
            raise FaultScheduleError("nested too deeply to be a fault schedule",
                                     source=str(path)) from None
        try:
            return cls.from_dict(data, n_waypoints=n_waypoints, max_time_s=max_time_s)
        except FaultScheduleError as exc:
            raise exc.in_file(str(path)) from None

    def to_file(self, path: str | Path) -> Path:
        """Write the file form to ``path`` (``.json``, ``.yaml`` or ``.yml``); returns it."""
        path = Path(path)
        if _suffix(path) == ".json":
            text = json.dumps(self.to_dict(), indent=2) + "\n"
        else:
            text = yaml.safe_dump(self.to_dict(), sort_keys=False)
        path.write_text(text)
        return path

    # -- shorthand and the paper's sequence -----------------------------------------------
    @classmethod
    def from_shorthand(cls, specs: Sequence[str] | str, *, n_waypoints: int | None = None,
                       max_time_s: float | None = None) -> FaultSchedule:
        """A schedule from command-line shorthand, one spec per fault, in order:

        ``gps:60-110`` (from 60 s to 110 s since boot), ``engine:wp40-wp48`` (from reaching
        waypoint 40 to reaching waypoint 48), ``gps:wp10-140`` (mixed), ``rc:200-`` or
        ``rc:200`` (held until the flight ends), ``accel:120+30`` (start 120 s, held 30 s).
        A single string may hold several specs separated by commas or spaces.
        """
        if isinstance(specs, str):
            specs = [s for s in re.split(r"[,\s]+", specs.strip()) if s]
        return cls._parse_each(specs, _fault_from_shorthand, n_waypoints, max_time_s)

    @classmethod
    def paper(cls, seed: int, auto_start_s: float = 20.0) -> FaultSchedule:
        """The paper's single-flight sequence A->H (§4.3; the reference combined flight).

        GPS, accel, engine and RC faults in that order, each held U(20, 40) s; the GPS fault
        starts U(15, 25) s after the switch to AUTO at ``auto_start_s`` [s since boot], each
        later one U(15, 25) s after the previous one ends. The RC fault ends too (the RC link
        returns; the vehicle stays in RTL). Gaps and holds are drawn in that order (gap, hold
        per fault) from ``numpy.random.default_rng(seed)`` and rounded to 0.1 s, as are the
        boundary times, so a schedule is a pure function of ``(seed, auto_start_s)``.
        """
        if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
            raise FaultScheduleError(f"seed must be a whole number >= 0, got {seed!r}")
        t = _check_time(auto_start_s, "auto_start_s", allow_zero=True)
        rng = np.random.default_rng(int(seed))
        faults = []
        for name in PAPER_ORDER:
            gap = round(float(rng.uniform(*PAPER_GAP_S)), 1)
            hold = round(float(rng.uniform(*PAPER_HOLD_S)), 1)
            start = round(t + gap, 1)
            t = round(start + hold, 1)
            faults.append(Fault(name, Trigger("time", start), Trigger("time", t)))
        return cls(tuple(faults))


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in _FILE_SUFFIXES:
        raise FaultScheduleError(
            f"{path}: unsupported fault schedule file type {suffix or '(none)'!r}; "
            f"use {', '.join(_FILE_SUFFIXES)}")
    return suffix


def _fault_from_dict(item: Any) -> Fault:
    if not isinstance(item, Mapping):
        raise FaultScheduleError(
            f"expected a mapping like {{'fault': 'gps', 'start': 60, 'end': 110}}, "
            f"got {item!r}")
    name = item.get("fault")
    fault_type = name.strip().lower() if isinstance(name, str) else None
    if fault_type not in FAULT_TYPES:
        fault_type = None
    for key in item:
        if key not in _FAULT_KEYS:
            close = difflib.get_close_matches(str(key), _FAULT_KEYS, n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise FaultScheduleError(
                f"unknown key {key!r}{hint}; keys: {', '.join(_FAULT_KEYS)}",
                fault_type=fault_type)
    for key in ("fault", "start"):
        if key not in item:
            raise FaultScheduleError(f"missing {key!r}", fault_type=fault_type)
    return Fault(item["fault"], item["start"], item.get("end"), item.get("params_start"),
                 item.get("params_end"), item.get("absolute", False))


def _fault_from_shorthand(spec: Any) -> Fault:
    if not isinstance(spec, str):
        raise FaultScheduleError(f"shorthand {spec!r} is not a string; {_SHORT_HELP}")
    m = _SHORT_RE.match(spec.strip())
    if m is None:
        raise FaultScheduleError(f"cannot read {spec!r}; {_SHORT_HELP}")
    name = lookup_type(m.group("type")).name
    try:
        start, end = _shorthand_triggers(spec, m.group("start"), m.group("op"), m.group("end"))
    except FaultScheduleError as exc:
        raise FaultScheduleError(exc.reason, fault_type=name) from None
    return Fault(name, start, end)


def _shorthand_triggers(spec: str, start_text: str, op: str | None,
                        end_text: str | None) -> tuple[Trigger, Trigger | None]:
    """Start and end of one shorthand spec (``op``: "-" end or "+" duration, or none)."""
    start = Trigger.parse(start_text, "start")
    if op == "-" and end_text:
        return start, Trigger.parse(end_text, "end")
    if op != "+":
        return start, None
    if start.kind != "time":
        raise FaultScheduleError(f"{spec!r}: a duration (+) needs a start time in s, not {start}")
    if not end_text or not TIME_RE.match(end_text):
        raise FaultScheduleError(f"{spec!r}: duration {end_text!r} is not a number of seconds")
    duration = float(end_text.rstrip("sS"))
    if not math.isfinite(duration) or duration <= 0:
        raise FaultScheduleError(f"{spec!r}: duration must be > 0 s")
    return start, Trigger("time", round(start.value + duration, 6))
