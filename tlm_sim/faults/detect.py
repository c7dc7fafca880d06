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
"""

from __future__ import annotations

import math
from typing import Any

import pandas as pd

from tlm_sim.faults.types import FAULT_TYPES

__all__ = ["faults_from_param_changes", "same_value"]

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
