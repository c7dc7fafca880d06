"""The built-in fault types' records: labels 1-14, one :func:`register_fault_type` call each.

The simulator's part of each record (name, label, SITL parameters, description, display name,
colour) is declared in :mod:`tlm_sim.faults.types` (``tlm_sim`` flies without
``tlm_process``); here each type gets its magnitude knobs (what ``tlm generate`` may draw:
``magnitudes:`` of a scenario configuration), the function that turns one draw into SITL
parameters, and its signature metrics (:mod:`tlm_process.fault_metrics`). The paper's four
types have no knobs: every such fault flies its type's parameters, so the default data set
draws nothing for them.

Knob units: ``offset_m`` metres (horizontal, the bearing drawn uniformly), ``mul`` the
``SIM_ENGINE_MUL`` multiplier, ``volt`` volts, ``amplitude`` m/s/s (``SIM_ACCn_RND``),
``imbalance`` m/s/s (``TLM_VIB_IMB``, at full command), ``instance`` the 1-based sensor
number (``"both"`` for both baros / IMUs), ``mode`` ``SIM_MAGn_FAIL`` (1 no data, 2 frozen).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from tlm_process import fault_metrics as M
from tlm_process.fault_types.registry import Knob, ParamsFn, register_fault_type
from tlm_sim.ardupilot import M_PER_DEG_LAT
from tlm_sim.faults.types import FAULT_TYPES

__all__: list[str] = []


def _mask(name: str) -> ParamsFn:
    """Params of an IMU sample loss: bit ``instance - 1`` of mask ``name`` (both: 3)."""
    def params(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
        inst = knobs["instance"]
        return {name: float(3 if inst == "both" else 1 << (int(inst) - 1))}
    return params


def _baro(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    names = {1: ["SIM_BARO_DISABLE"], 2: ["SIM_BAR2_DISABLE"],
             "both": ["SIM_BARO_DISABLE", "SIM_BAR2_DISABLE"]}[knobs["instance"]]
    return {n: 1.0 for n in names}


def _compass(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    return {f"SIM_MAG{int(knobs['instance'])}_FAIL": float(knobs["mode"])}


def _gps_glitch(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    """GPS 1 offset ``offset_m`` towards ``bearing_deg`` (deg from north), in degrees of
    latitude / longitude at ``lat_deg`` (rounded to 1e-7 deg, ~1 cm)."""
    dn = knobs["offset_m"] * math.cos(math.radians(knobs["bearing_deg"]))
    de = knobs["offset_m"] * math.sin(math.radians(knobs["bearing_deg"]))
    return {"SIM_GPS1_GLTCH_X": round(dn / M_PER_DEG_LAT, 7),
            "SIM_GPS1_GLTCH_Y": round(de / (M_PER_DEG_LAT * math.cos(math.radians(lat_deg))), 7)}


def _motor_partial(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    """``SIM_ENGINE_MUL`` ``mul`` on motor ``motor``: its SIM_ENGINE_FAIL bit (motor 1, SITL's
    default and the reference flight's, gives the type's own parameters; a draw made before the
    knob existed has none: motor 1)."""
    motor = int(knobs.get("motor", 1))
    if motor == 1:
        return {"SIM_ENGINE_MUL": knobs["mul"]}
    return {"SIM_ENGINE_FAIL": float(1 << (motor - 1)), "SIM_ENGINE_MUL": knobs["mul"]}


def _vibration(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    return {"SIM_ACC1_RND": knobs["amplitude"], "SIM_ACC2_RND": knobs["amplitude"],
            "SIM_VIB_MOT_MAX": 350.0}


def _prop_damage(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    """The type's own parameters (its rotor frequency on an airframe without one of its own)
    on motor ``motor`` (its imbalance and its SIM_ENGINE_FAIL bit), with the imbalance
    ``imbalance`` m/s/s at full command and the PWM above 1000 us times ``mul``."""
    motor = int(knobs["motor"])
    return {**FAULT_TYPES["prop_damage"].params_start,
            "TLM_VIB_IMB_MOT": float(motor), "SIM_ENGINE_FAIL": float(1 << (motor - 1)),
            "TLM_VIB_IMB": knobs["imbalance"], "SIM_ENGINE_MUL": knobs["mul"]}


def _battery(knobs: Mapping[str, Any], lat_deg: float) -> dict[str, float]:
    return {"SIM_BATT_VOLTAGE": knobs["volt"]}


def _register() -> None:
    T = FAULT_TYPES
    register_fault_type(T["gps"], signature=M.gps_metrics)
    register_fault_type(T["accel"], signature=M.accel_metrics)
    register_fault_type(T["engine"], signature=M.engine_metrics)
    register_fault_type(T["rc"], signature=M.rc_metrics)
    # both gyros masked is refused (SITL freezes): no "both"
    register_fault_type(T["gyro"], signature=M.gyro_metrics,
                        knobs={"instance": Knob("choice", (1, 2), [1])},
                        params=_mask("SIM_GYR_FAIL_MSK"))
    register_fault_type(T["baro"], signature=M.baro_metrics,
                        knobs={"instance": Knob("choice", (1, 2, "both"), ["both"])},
                        params=_baro)
    register_fault_type(T["compass"], signature=M.compass_metrics,
                        knobs={"instance": Knob("choice", (1, 2, 3), [1]),
                               "mode": Knob("choice", (1, 2), [1])},
                        params=_compass)
    register_fault_type(T["gps_glitch"], signature=M.gps_glitch_metrics,
                        knobs={"offset_m": Knob("range", (0.0, 1000.0), (20.0, 60.0)),
                               "bearing_deg": Knob("range", (0.0, 360.0), (0.0, 360.0),
                                                   decimals=1, configurable=False)},
                        params=_gps_glitch)
    register_fault_type(T["motor_partial"], signature=M.motor_partial_metrics,
                        knobs={"mul": Knob("range", (0.0, 1.0), (0.4, 0.8)),
                               "motor": Knob("choice", tuple(range(1, 9)), [1])},
                        params=_motor_partial)
    register_fault_type(T["vibration"], signature=M.vibration_metrics,
                        knobs={"amplitude": Knob("range", (0.0, 50.0), (2.0, 6.0))},
                        params=_vibration)
    register_fault_type(T["battery"], signature=M.battery_metrics,
                        knobs={"volt": Knob("range", (0.0, 30.0), (9.9, 10.4))},
                        params=_battery)
    register_fault_type(T["gps_jam"], signature=M.gps_jam_metrics)
    register_fault_type(T["accel_samples"], signature=M.accel_samples_metrics,
                        knobs={"instance": Knob("choice", (1, 2, "both"), [1])},
                        params=_mask("SIM_ACC_FAIL_MSK"))
    register_fault_type(T["prop_damage"], signature=M.prop_damage_metrics,
                        knobs={"imbalance": Knob("range", (0.0, 500.0), (15.0, 45.0)),
                               "mul": Knob("range", (0.0, 1.0), (0.8, 0.95)),
                               # any motor of a quad (and of the larger frames' first four):
                               # a detector meets a damaged propeller on any arm
                               "motor": Knob("choice", tuple(range(1, 9)), [1, 2, 3, 4])},
                        params=_prop_damage)


_register()
