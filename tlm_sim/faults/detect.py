"""Find the paper's faults in a log from its in-flight parameter changes (PARM messages).

SITL injects a fault by setting parameters (``FAULT_TYPES``: SIM_GPS1_ENABLE 0, both
SIM_ACCELn_FAIL 1, SIM_ENGINE_MUL 0, SIM_RC_FAIL 1) and clears it by setting them back, and the
autopilot logs each change as a PARM message at the time it took effect (the reference logs
record every change twice, ~1 ms apart). A fault starts at the first change of one of its
start parameters to its start value while it is not active, and ends when every one of its
parameters has been set back to its end value (the double accelerometer fault lasts while either
accelerometer is failed), as the reference sidecars record it. tlm's ``.bin`` files log their
changes the same way, so this reads both. PARM logs values as float32, so a value matches a
type's when it is the same number to float32 precision (SIM_GPS1_GLTCH_X 0.0003 is logged as
0.00030000001, SIM_BATT_VOLTAGE 10.2 as 10.1999998).

``faults_from_messages`` reads tlm's own fault MSG lines ("tlm: fault gps (label 1) start" /
"... end", written by ``tlm_sim.flightlog.binwriter.fault_messages``), and ``faults_in_log``
gives a log's own records: those lines, else its parameter changes. ``tlm process``,
``tlm info`` and ``FlightLog.from_bin`` read a log's faults through these.
"""

from __future__ import annotations

import math
import re
from typing import Any

import pandas as pd

from tlm_sim.faults.types import FAULT_TYPES

__all__ = ["TLM_FAULT_MSG", "faults_from_messages", "faults_from_param_changes", "faults_in_log",
           "same_value"]

#: tlm's fault MSG line (``binwriter.fault_messages``): type, label, "start" or "end".
TLM_FAULT_MSG = re.compile(r"^tlm: fault (\w+) \(label (\d+)\) (start|end)$")

#: relative tolerance of a logged (float32) value against a type's value
_REL = 1e-6


def same_value(logged: float, value: float | None) -> bool:
    """Whether a PARM value is ``value`` (float32 rounding allowed; None never matches)."""
    return value is not None and math.isclose(logged, value, rel_tol=_REL, abs_tol=1e-12)


def faults_from_param_changes(changes: pd.DataFrame) -> list[dict[str, Any]]:
    """Fault windows from in-flight parameter changes.

    Args:
        changes: rows with TimeUS, Name, Value in time order (the parameter changes after
            the log-start block: ``tlm_sim.flightlog.binreader.param_changes_from_parm``).
    Returns:
        one dict per fault in start order: ``type``, ``label``, ``start_time_us``,
        ``end_time_us`` (None when the log ends with the fault active), ``source`` "PARM".
    """
    active: dict[str, dict[str, Any]] = {}
    pending: dict[str, set[str]] = {}  # end parameters not yet set back, per active fault
    out: list[dict[str, Any]] = []
    for t, name, value in zip(changes["TimeUS"], changes["Name"], changes["Value"], strict=True):
        name, value = str(name), float(value)
        for ft in FAULT_TYPES.values():
            rec = active.get(ft.name)
            if rec is None and same_value(value, ft.params_start.get(name)):
                rec = {"type": ft.name, "label": ft.label, "start_time_us": int(t),
                       "end_time_us": None, "source": "PARM"}
                active[ft.name] = rec
                pending[ft.name] = set(ft.params_end)
                out.append(rec)
            elif rec is not None and same_value(value, ft.params_end.get(name)):
                pending[ft.name].discard(name)
                if not pending[ft.name]:
                    rec["end_time_us"] = int(t)
                    del active[ft.name]
    return out


def faults_from_messages(msg: pd.DataFrame | None) -> list[dict[str, Any]]:
    """Fault windows from tlm's fault MSG lines (``TLM_FAULT_MSG``) of a MSG table (TimeUS,
    Message); [] for None or a log without them (a SITL log).

    Returns:
        one dict per fault in start order: ``type``, ``label``, ``start_time_us``,
        ``end_time_us`` (None when the log has no end line for it), ``source`` "MSG".
    """
    out: list[dict[str, Any]] = []
    if msg is None or not len(msg):
        return out
    for t, text in zip(msg["TimeUS"], msg["Message"], strict=True):
        m = TLM_FAULT_MSG.match(str(text))
        if m is None:
            continue
        if m.group(3) == "start":
            out.append({"type": m.group(1), "label": int(m.group(2)),
                        "start_time_us": int(t), "end_time_us": None, "source": "MSG"})
        elif out and out[-1]["type"] == m.group(1) and out[-1]["end_time_us"] is None:
            out[-1]["end_time_us"] = int(t)
    return out


def faults_in_log(msg: pd.DataFrame | None, changes: pd.DataFrame | None
                  ) -> list[dict[str, Any]]:
    """The fault records a log holds itself: tlm's fault MSG lines (``faults_from_messages``),
    else the faults of its parameter changes (``faults_from_param_changes``; a SITL log).

    Args:
        msg: the log's MSG table, or None.
        changes: its in-flight parameter changes (``binreader.param_changes_from_parm``), or
            None.
    Returns:
        records as those functions give them (``source`` "MSG" or "PARM"); [] when none.
    """
    out = faults_from_messages(msg)
    if not out and changes is not None and len(changes):
        out = faults_from_param_changes(changes)
    return out
