"""Fault boundaries (:class:`Trigger`) and the error type of the fault package.

A trigger is a time in seconds since boot (the log's ``TimeUS / 1e6``) or the moment a mission
waypoint (1-based) is reached.
"""

from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass
from typing import Any, Literal

__all__ = ["FaultScheduleError", "Trigger", "TriggerKind"]

TriggerKind = Literal["time", "wp"]

_WP_RE = re.compile(r"^wp\s*(\d+)$", re.IGNORECASE)
#: A non-negative number of seconds, optionally followed by "s" (``60``, ``60.5s``, ``.5``).
TIME_RE = re.compile(r"^(\d+(?:\.\d*)?|\.\d+)(?:e[-+]?\d+)?\s*s?$", re.IGNORECASE)


class FaultScheduleError(ValueError):
    """A bad fault, fault schedule or schedule file.

    The message is one line: ``[source: ]fault N (TYPE): reason``, where ``N`` is the fault's
    number counted from 1 (fault 1 is the first of the schedule, as ``tlm fly``'s summary,
    warnings and every other message and file name number them); parts that are unknown are
    left out. The parts are also attributes: ``reason``, ``index`` (the 0-based position in
    the schedule, ``N - 1``: the same number as :attr:`ParamChange.fault`), ``fault_type``,
    ``source`` (a file name).
    """

    def __init__(self, reason: str, *, index: int | None = None, fault_type: str | None = None,
                 source: str | None = None) -> None:
        self.reason = re.sub(r"\s*\n\s*", " ", str(reason)).strip()
        self.index = index
        self.fault_type = fault_type
        self.source = source
        where = ""
        if index is not None or fault_type is not None:
            where = "fault" + (f" {index + 1}" if index is not None else "")
            where += f" ({fault_type})" if fault_type is not None else ""
            where += ": "
        prefix = f"{source}: " if source is not None else ""
        super().__init__(f"{prefix}{where}{self.reason}")

    def at(self, index: int) -> FaultScheduleError:
        """The same error for the fault at position ``index`` of a schedule."""
        return FaultScheduleError(self.reason, index=index, fault_type=self.fault_type,
                                  source=self.source)

    def in_file(self, source: str) -> FaultScheduleError:
        """The same error, read from the file ``source``."""
        return FaultScheduleError(self.reason, index=self.index, fault_type=self.fault_type,
                                  source=source)


def fmt_number(x: float) -> str:
    """Short text of a number: integers without a decimal point."""
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else repr(float(x))


def plain_number(x: float) -> int | float:
    """A number for a file: an ``int`` when it is whole (reads back to the same float)."""
    return int(x) if float(x).is_integer() and abs(x) < 2**53 else float(x)


def is_real(x: Any) -> bool:
    """Whether ``x`` is a real number (numpy scalars included, ``bool`` excluded)."""
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


# --------------------------------------------------------------------------------------------
# Trigger
# --------------------------------------------------------------------------------------------

def trigger_problem(kind: Any, value: Any) -> str | None:
    """Why ``(kind, value)`` is not a valid trigger (text starting with the value), or None."""
    if kind not in ("time", "wp"):
        return f"kind {kind!r} is not 'time' or 'wp'"
    if not is_real(value):
        return f"value {value!r} ({type(value).__name__}) is not a number"
    v = float(value)
    if kind == "time":
        if not math.isfinite(v):
            return f"time {v} s is not finite"
        if v < 0:
            return f"{fmt_number(v)} s is negative (times are seconds since boot)"
        return None
    if not math.isfinite(v) or not v.is_integer() or v < 1:
        shown = fmt_number(v) if math.isfinite(v) else v
        return f"waypoint {shown} is not a waypoint number 1, 2, ..."
    return None


@dataclass(frozen=True, slots=True)
class Trigger:
    """When a fault boundary happens.

    ``kind`` "time": ``value`` is seconds since boot (the log's ``TimeUS / 1e6``);
    ``kind`` "wp": the moment mission waypoint number ``value`` (1-based, whole) is reached.
    """

    kind: TriggerKind
    value: float

    def __post_init__(self) -> None:
        problem = trigger_problem(self.kind, self.value)
        if problem is not None:
            raise FaultScheduleError(f"trigger {problem}")
        object.__setattr__(self, "value", float(self.value))

    @classmethod
    def parse(cls, x: Any, name: str = "trigger") -> Trigger:
        """A trigger from a :class:`Trigger`, a number of seconds, or a string: ``"60"``,
        ``"60.5s"`` (seconds) or ``"wp40"`` (waypoint). ``name`` starts error messages."""
        if isinstance(x, Trigger):
            return x
        if is_real(x):
            kind, value = "time", float(x)
        elif isinstance(x, str):
            text = x.strip()
            if m := _WP_RE.match(text):
                kind, value = "wp", float(m.group(1))
            elif TIME_RE.match(text):
                kind, value = "time", float(text.rstrip("sS"))
            else:
                raise FaultScheduleError(
                    f"{name} {x!r} is not a time in s or a waypoint 'wpN'")
        else:
            raise FaultScheduleError(
                f"{name} {x!r} ({type(x).__name__}) is not a time in s or a waypoint 'wpN'")
        problem = trigger_problem(kind, value)
        if problem is not None:
            raise FaultScheduleError(f"{name} {problem}")
        return cls(kind, value)  # type: ignore[arg-type]

    def to_value(self) -> int | float | str:
        """File form: seconds as a number, a waypoint as ``"wpN"``."""
        return f"wp{int(self.value)}" if self.kind == "wp" else plain_number(self.value)

    def comparable(self, other: Trigger) -> bool:
        """Whether the two can be ordered (both times or both waypoints)."""
        return self.kind == other.kind

    def __str__(self) -> str:
        return f"wp{int(self.value)}" if self.kind == "wp" else f"{fmt_number(self.value)} s"
