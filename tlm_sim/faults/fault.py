"""One fault of a schedule: its type, start and end triggers and the parameters it sets."""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from tlm_sim.faults.trigger import FaultScheduleError, Trigger, fmt_number, plain_number
from tlm_sim.faults.types import FAULT_TYPES, FaultType
from tlm_sim.params import ParamError, check_value

__all__ = ["Fault"]


# --------------------------------------------------------------------------------------------
# Fault
# --------------------------------------------------------------------------------------------

def lookup_type(name: Any) -> FaultType:
    """The :class:`FaultType` called ``name`` (case-insensitive), with a suggestion if none."""
    if not isinstance(name, str):
        raise FaultScheduleError(f"fault type {name!r} is not a string")
    ftype = FAULT_TYPES.get(name.strip().lower())
    if ftype is None:
        close = difflib.get_close_matches(name.strip().lower(), list(FAULT_TYPES), n=1,
                                          cutoff=0.5)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise FaultScheduleError(
            f"unknown fault type {name!r}{hint}; known: {', '.join(FAULT_TYPES)}")
    return ftype


def _canonical_params(given: Any, where: str) -> dict[str, float]:
    """``given`` validated one by one (:func:`~tlm_sim.params.check_value`: names, finite
    values, ranges), with paper-era names resolved to the current ones."""
    if not isinstance(given, Mapping):
        raise FaultScheduleError(
            f"{where} must be a mapping NAME -> value, got {type(given).__name__}")
    if not given:
        raise FaultScheduleError(f"{where} is empty")
    out: dict[str, float] = {}
    for name, value in given.items():
        try:  # alone: a rule between parameters is checked with the flight's (build_schedule)
            canonical, x = check_value(name, value)
        except ParamError as exc:
            raise FaultScheduleError(f"{where}: {exc}") from None
        if canonical in out:
            raise FaultScheduleError(f"{where} sets {canonical} twice (via {name})")
        out[canonical] = x
    return out


def _default_params_end(ftype: FaultType, params_start: Mapping[str, float],
                        start_overridden: bool) -> dict[str, float]:
    """The type's clearing values, limited to the parameters ``params_start`` sets when that
    was given explicitly (a fault of ``SIM_ACCEL1_FAIL`` alone clears only that one)."""
    if not start_overridden:
        return dict(ftype.params_end)
    return {n: ftype.params_end[n] for n in params_start if n in ftype.params_end}


@dataclass(frozen=True, slots=True)
class Fault:
    """One fault of a schedule.

    ``type``: a :data:`FAULT_TYPES` name (case-insensitive). ``start`` / ``end``: a
    :class:`Trigger`, a number of seconds since boot or ``"wpN"``; ``end=None`` holds the fault
    until the flight ends. ``params_start`` / ``params_end``: parameter values set at the
    boundaries (ArduPilot names and units; paper-era names are accepted and stored under the
    current names). They default to the type's; when only ``params_start`` is given,
    ``params_end`` defaults to the type's clearing values of those parameters. A type with
    :attr:`~tlm_sim.faults.types.FaultType.relative` rules (``vibration``) sets those
    parameters relative to the vehicle's own values when flown (:meth:`flown`);
    ``absolute=True`` sets every value as given (re-flying a SITL log, whose values are what
    SITL set).
    """

    type: str
    start: Trigger
    end: Trigger | None = None
    params_start: Mapping[str, float] | None = None
    params_end: Mapping[str, float] | None = None
    absolute: bool = False

    def __post_init__(self) -> None:
        ftype = lookup_type(self.type)
        try:
            self._normalise(ftype)
        except FaultScheduleError as exc:
            raise FaultScheduleError(exc.reason, fault_type=ftype.name) from None

    def _normalise(self, ftype: FaultType) -> None:
        start = Trigger.parse(self.start, "start")
        end = None if self.end is None else Trigger.parse(self.end, "end")
        if end is not None and end.comparable(start) and end.value <= start.value:
            how = "at" if end.value == start.value else "before"
            raise FaultScheduleError(f"end {end} is {how} start {start}")
        if self.params_start is None:
            ps = dict(ftype.params_start)
        else:
            ps = _canonical_params(self.params_start, "params_start")
        if self.params_end is not None:
            if end is None:
                raise FaultScheduleError(
                    "params_end is given but the fault has no end (held until the flight ends)")
            pe = _canonical_params(self.params_end, "params_end")
        else:
            pe = _default_params_end(ftype, ps, self.params_start is not None)
            missing = [n for n in ps if n not in pe]
            if end is not None and missing:
                raise FaultScheduleError(
                    f"give params_end: a {ftype.name} fault does not know how to clear "
                    f"{', '.join(missing)}")
        if not isinstance(self.absolute, bool):
            raise FaultScheduleError(f"absolute must be true or false, got {self.absolute!r}")
        set_ = object.__setattr__
        set_(self, "type", ftype.name)
        set_(self, "start", start)
        set_(self, "end", end)
        set_(self, "params_start", MappingProxyType(ps))
        set_(self, "params_end", MappingProxyType(pe))

    def __hash__(self) -> int:
        assert self.params_start is not None and self.params_end is not None
        return hash((self.type, self.start, self.end, tuple(self.params_start.items()),
                     tuple(self.params_end.items()), self.absolute))

    def __reduce__(self) -> tuple[Any, ...]:
        # mappingproxy cannot be pickled: rebuild from plain dicts (for process pools)
        assert self.params_start is not None and self.params_end is not None
        return (Fault, (self.type, self.start, self.end, dict(self.params_start),
                        dict(self.params_end) if self.end is not None else None,
                        self.absolute))

    def flown(self, own: Mapping[str, float] | None) -> tuple[dict[str, float],
                                                               dict[str, float]]:
        """(start, end) values this fault sets on a vehicle whose parameters are ``own``
        (its type's ``relative`` rules applied; as given with ``absolute`` or ``own``
        None). A vehicle at SITL's defaults gets the values as given."""
        assert self.params_start is not None and self.params_end is not None
        if own is None or self.absolute:
            return dict(self.params_start), dict(self.params_end)
        ftype = self.fault_type
        return ({n: ftype.flown_value(n, v, float(own[n])) for n, v in self.params_start.items()},
                {n: ftype.flown_value(n, v, float(own[n])) for n, v in self.params_end.items()})

    @property
    def fault_type(self) -> FaultType:
        """The :class:`FaultType` of this fault."""
        return FAULT_TYPES[self.type]

    @property
    def label(self) -> int:
        """The paper's class label (Table 6: 1 GPS, 2 accel, 3 engine, 4 RC)."""
        return FAULT_TYPES[self.type].label

    def to_dict(self) -> dict[str, Any]:
        """File form; ``end`` and ``params_*`` only where they are not the defaults."""
        assert self.params_start is not None and self.params_end is not None
        d: dict[str, Any] = {"fault": self.type, "start": self.start.to_value()}
        if self.end is not None:
            d["end"] = self.end.to_value()
        ftype = self.fault_type
        overridden = dict(self.params_start) != dict(ftype.params_start)
        if overridden:
            d["params_start"] = {n: plain_number(v) for n, v in self.params_start.items()}
        if self.end is not None and (
                dict(self.params_end)
                != _default_params_end(ftype, self.params_start, overridden)):
            d["params_end"] = {n: plain_number(v) for n, v in self.params_end.items()}
        if self.absolute:
            d["absolute"] = True
        return d

    def __str__(self) -> str:
        assert self.params_start is not None and self.params_end is not None
        end = str(self.end) if self.end is not None else "end of flight"

        def sets(p: Mapping[str, float]) -> str:
            return ", ".join(f"{n}={fmt_number(v)}" for n, v in p.items())

        text = f"{self.type} (label {self.label}): {self.start} -> {end}; "
        text += f"start {sets(self.params_start)}"
        if self.end is not None and self.params_end:
            text += f"; end {sets(self.params_end)}"
        if self.absolute:
            text += " (absolute)"
        elif any(n in self.fault_type.relative for n in self.params_start):
            text += " (relative to the vehicle's own values)"
        return text
