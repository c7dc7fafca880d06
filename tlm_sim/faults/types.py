"""The fault types tlm injects and the SITL parameters that inject and clear them.

Labels 1-4 are the TLM paper's Table 6 class labels (0 is normal flight); labels 5-12 are the
rest of SITL's fault catalogue under the type names of the second reference set (``gyro`` 5,
``baro`` 6, ``compass`` 7, ``gps_glitch`` 8, ``motor_partial`` 9, ``vibration`` 10,
``battery`` 11, ``gps_jam`` 12); 13 is the accelerometer-sample loss (``SIM_ACC_FAIL_MSK``,
"5b" of issue 19: its own label so that detectors can tell it from the gyro loss). Labels are
stable: a new type gets the next free number.

The parameter values are exactly those the reference SITL flights set
(``shared/reference/sitl/*.json``, ``faults[].params_start`` / ``params_end``), under
ArduPilot's current names; the paper's own names are accepted as aliases by
:mod:`tlm_sim.params` (``SIM_GPS_DISABLE`` 1 is ``SIM_GPS1_ENABLE`` 0). A fault of any type
may set other values (``params_start`` / ``params_end`` of :class:`~tlm_sim.faults.Fault`,
e.g. ``SIM_MAG1_FAIL`` 2 for a frozen compass or ``SIM_RC_FAIL`` 2 for neutral sticks).
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


#: Every fault type by name, in label order (the paper's four first).
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
        _type("gyro", 5, {"SIM_GYR_FAIL_MSK": 1.0}, {"SIM_GYR_FAIL_MSK": 0.0},
              "IMU 1's gyro stops producing samples (IMU.GH 0, its logged gyro frozen; the EKF "
              "and controllers use IMU 2's); masking every gyro is refused (SITL freezes)"),
        _type("baro", 6, {"SIM_BARO_DISABLE": 1.0, "SIM_BAR2_DISABLE": 1.0},
              {"SIM_BARO_DISABLE": 0.0, "SIM_BAR2_DISABLE": 0.0},
              "both barometers stop (BARO.H 0); ~10 s later the height estimate is lost"),
        _type("compass", 7, {"SIM_MAG1_FAIL": 1.0}, {"SIM_MAG1_FAIL": 0.0},
              "compass 1 delivers no data (MAG.Health 0, ERR 3/4); the EKF switches compass"),
        _type("gps_glitch", 8, {"SIM_GPS1_GLTCH_X": 0.0003, "SIM_GPS1_GLTCH_Y": 0.0003},
              {"SIM_GPS1_GLTCH_X": 0.0, "SIM_GPS1_GLTCH_Y": 0.0},
              "GPS 1 position offset by 0.0003 deg in latitude and longitude (~43 m)"),
        _type("motor_partial", 9, {"SIM_ENGINE_MUL": 0.5}, {"SIM_ENGINE_MUL": 1.0},
              "the SIM_ENGINE_FAIL motors (motor 1) deliver half their PWM above 1000 us"),
        _type("vibration", 10,
              {"SIM_ACC1_RND": 4.8, "SIM_ACC2_RND": 4.8, "SIM_VIB_MOT_MAX": 350.0},
              {"SIM_VIB_MOT_MAX": 0.0, "SIM_ACC1_RND": 0.0, "SIM_ACC2_RND": 0.0},
              "motor-rpm sinusoids of 4.8 m/s/s on both accelerometers (VIBE ~6 m/s/s)"),
        _type("battery", 11, {"SIM_BATT_VOLTAGE": 10.2}, {"SIM_BATT_VOLTAGE": 12.6},
              "battery at 10.2 V: less thrust per PWM, the low-battery failsafe after "
              "BATT_LOW_TIMER"),
        _type("gps_jam", 12, {"SIM_GPS1_JAM": 1.0}, {"SIM_GPS1_JAM": 0.0},
              "GPS 1 jammed: fix lost and regained at random, satellites, position, velocity "
              "and accuracy jump"),
        _type("accel_samples", 13, {"SIM_ACC_FAIL_MSK": 1.0}, {"SIM_ACC_FAIL_MSK": 0.0},
              "IMU 1's accelerometer stops producing samples (IMU.AH 0, its logged accel "
              "frozen)"),
    )
})
