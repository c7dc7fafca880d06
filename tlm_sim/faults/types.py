"""The four fault types of the TLM paper and the SITL parameters that inject and clear them.

Labels are the paper's Table 6 class labels (0 is normal flight). The parameter values are
exactly those the reference SITL flights set (``shared/reference/sitl/*.json``,
``faults[].params_start`` / ``params_end``), under ArduPilot's current names; the paper's own
names are accepted as aliases by :mod:`tlm_sim.params` (``SIM_GPS_DISABLE`` 1 is
``SIM_GPS1_ENABLE`` 0).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

__all__ = ["FAULT_TYPES", "NORMAL_LABEL", "FaultType"]

#: Class label of samples outside every fault window (paper Table 6).
NORMAL_LABEL = 0


@dataclass(frozen=True, slots=True)
class FaultType:
    """One kind of fault: its name, paper label and the parameter values that make it.

    ``params_start`` is set when the fault begins and ``params_end`` when it is cleared
    (``name -> value``, ArduPilot names and units).
    """

    name: str
    label: int
    params_start: Mapping[str, float]
    params_end: Mapping[str, float]
    description: str

    def __reduce__(self) -> tuple[Any, ...]:
        # mappingproxy cannot be pickled: rebuild from plain dicts (for process pools)
        return (_type, (self.name, self.label, dict(self.params_start), dict(self.params_end),
                        self.description))


def _type(name: str, label: int, start: dict[str, float], end: dict[str, float],
          description: str) -> FaultType:
    return FaultType(name, label, MappingProxyType(start), MappingProxyType(end), description)


#: The paper's faults by name, in label order.
FAULT_TYPES: Mapping[str, FaultType] = MappingProxyType({
    t.name: t for t in (
        _type("gps", 1, {"SIM_GPS1_ENABLE": 0.0}, {"SIM_GPS1_ENABLE": 1.0},
              "GPS 1 streams 'no fix' with 3 satellites (paper: SIM_GPS_DISABLE 0 -> 1)"),
        _type("accel", 2, {"SIM_ACCEL1_FAIL": 1.0, "SIM_ACCEL2_FAIL": 1.0},
              {"SIM_ACCEL1_FAIL": 0.0, "SIM_ACCEL2_FAIL": 0.0},
              "both accelerometers read a constant (1, 1, 1) m/s/s"),
        _type("engine", 3, {"SIM_ENGINE_MUL": 0.0}, {"SIM_ENGINE_MUL": 1.0},
              "the SIM_ENGINE_FAIL motors (motor 1) lose all thrust"),
        _type("rc", 4, {"SIM_RC_FAIL": 1.0}, {"SIM_RC_FAIL": 0.0},
              "no RC frames arrive: radio failsafe, RTL (the vehicle stays in RTL after)"),
    )
})
