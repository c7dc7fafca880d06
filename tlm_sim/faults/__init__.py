"""Fault injection: the paper's fault types, fault schedules and satellite-count jitter.

``FaultSchedule`` says which faults a flight gets and when (seconds since boot or mission
waypoints); the simulation loop applies its :meth:`FaultSchedule.param_changes`.
``jitter_nsats`` is the paper's Eq. 3 jitter of ``GPS.NSats``.
"""

from tlm_sim.faults.satellites import jitter_nsats
from tlm_sim.faults.schedule import (
    Fault,
    FaultSchedule,
    FaultScheduleError,
    ParamChange,
    Trigger,
)
from tlm_sim.faults.types import FAULT_TYPES, FaultType

__all__ = [
    "FAULT_TYPES",
    "Fault",
    "FaultSchedule",
    "FaultScheduleError",
    "FaultType",
    "ParamChange",
    "Trigger",
    "jitter_nsats",
]
