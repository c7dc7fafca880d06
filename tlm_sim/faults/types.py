"""The fault types tlm injects and the SITL parameters that inject and clear them.

Each fault type is one :class:`FaultType` record, kept in one registry
(:data:`FAULT_TYPES`, in label order). This module registers the built-in catalogue;
:func:`register_fault_type` adds a new type (``tlm_process.fault_types.register_fault_type``
adds it together with its ``tlm generate`` draw and its signature metrics: see
``docs/extending.md``, "A fault type"). Every consumer (schedules and the ``--fault``
shorthand, Eq. 4 records, fault detection in SITL logs, ``tlm process`` labels, plot colours,
``tlm evaluate`` / ``tlm detect`` class names) reads the registry, so a registered type is
known everywhere at once.

Labels 1-4 are the TLM paper's Table 6 class labels (0 is normal flight); labels 5-12 are the
rest of SITL's fault catalogue under the type names of the second reference set (``gyro`` 5,
``baro`` 6, ``compass`` 7, ``gps_glitch`` 8, ``motor_partial`` 9, ``vibration`` 10,
``battery`` 11, ``gps_jam`` 12); 13 is the accelerometer-sample loss (``SIM_ACC_FAIL_MSK``,
"5b" of issue 19: its own label so that detectors can tell it from the gyro loss); 14 is a
damaged propeller (``prop_damage``, issue 40), tlm's own: SITL has no such fault, so it is made
of tlm's imbalance parameters (``TLM_VIB_IMB``) and SITL's motor multiplier. Labels are
stable: a new type gets the next free number.

The parameter values are exactly those the reference SITL flights set
(``shared/reference/sitl/*.json``, ``faults[].params_start`` / ``params_end``), under
ArduPilot's current names; the paper's own names are accepted as aliases by
:mod:`tlm_sim.params` (``SIM_GPS_DISABLE`` 1 is ``SIM_GPS1_ENABLE`` 0). A fault of any type
may set other values (``params_start`` / ``params_end`` of :class:`~tlm_sim.faults.Fault`,
e.g. ``SIM_MAG1_FAIL`` 2 for a frozen compass or ``SIM_RC_FAIL`` 2 for neutral sticks).
"""

from __future__ import annotations

import colorsys
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

__all__ = ["BUILTIN_TYPES", "FAULT_TYPES", "NORMAL_COLOUR", "NORMAL_LABEL", "FaultType",
           "RELATIVE_RULES",
           "label_colour", "register_fault_type", "type_of_label", "unregister_fault_type"]

#: Class label of samples outside every fault window (paper Table 6).
NORMAL_LABEL = 0
#: Plot colour of normal flight (label 0), a matplotlib grey.
NORMAL_COLOUR = "0.6"
#: A fault type's name: lower case letters, digits and underscores, starting with a letter.
_NAME = re.compile(r"[a-z][a-z0-9_]*")


@dataclass(frozen=True, slots=True)
class FaultType:
    """One kind of fault: its name, label, the parameter values that make it and how it is
    shown.

    Attributes:
        name: the type name (schedules, shorthand ``name:60-110``, sidecars, class names of
            labels 5 and up).
        label: class label, >= 1, unique and stable (0 is normal flight).
        params_start: set when the fault begins (``name -> value``, ArduPilot names and
            units; any mapping, kept read-only).
        params_end: set when the fault is cleared (the healthy values).
        description: what happens, one sentence (data set cards, docs).
        title: display name (section titles and figure captions, e.g. ``"GPS glitch"``);
            empty: the name with spaces for underscores.
        colour: matplotlib colour of the label in plots; None: a colour generated from the
            label (:func:`label_colour`).
        relative: how a fault of this type sets a parameter a vehicle may have a value of its
            own (name -> rule; other parameters are set to the value given). ``"add"``: the
            vehicle's own value plus the value given (so a fault's ``params_end`` 0 restores
            the vehicle's own); ``"own"``: the vehicle's own value where it is not 0, else the
            value given. For a vehicle at SITL's defaults (0) both give the value itself. The
            ``vibration`` type is relative, so it stays a fault on an airframe that vibrates
            of its own (issue 40). A :class:`~tlm_sim.faults.Fault` with ``absolute`` sets
            the values as given (``tlm crosscheck`` re-flying a SITL log).
    """

    name: str
    label: int
    params_start: Mapping[str, float]
    params_end: Mapping[str, float]
    description: str
    title: str = ""
    colour: str | None = None
    relative: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for attr in ("params_start", "params_end"):
            v = getattr(self, attr)
            if not isinstance(v, Mapping):
                raise TypeError(f"fault type {self.name!r}: {attr} must be a mapping NAME -> "
                                f"value, got {type(v).__name__}")
            set_(self, attr, MappingProxyType({str(k): float(x) for k, x in v.items()}))
        if not isinstance(self.relative, Mapping):
            raise TypeError(f"fault type {self.name!r}: relative must be a mapping NAME -> "
                            f"rule, got {type(self.relative).__name__}")
        set_(self, "relative", MappingProxyType({str(k): str(r)
                                                 for k, r in self.relative.items()}))
        if not self.title:
            set_(self, "title", str(self.name).replace("_", " "))

    def __reduce__(self) -> tuple[Any, ...]:
        # mappingproxy cannot be pickled: rebuild from plain dicts (for process pools)
        return (FaultType, (self.name, self.label, dict(self.params_start),
                            dict(self.params_end), self.description, self.title, self.colour,
                            dict(self.relative)))

    def flown_value(self, name: str, value: float, own: float) -> float:
        """The value a fault of this type sets for ``name`` given as ``value`` on a vehicle
        whose own value of it is ``own`` (the ``relative`` rule; ``value`` itself for a
        parameter without one)."""
        rule = self.relative.get(name)
        if rule == "add":
            return own + value
        if rule == "own" and own != 0.0:
            return own
        return value


#: The rules of :attr:`FaultType.relative`.
RELATIVE_RULES: tuple[str, ...] = ("add", "own")


#: The registry: name -> type, kept in label order (only this module writes it).
_REGISTRY: dict[str, FaultType] = {}
#: Every fault type by name, in label order (the paper's four first): a read-only, live view
#: of the registry (a type registered later appears in it).
FAULT_TYPES: Mapping[str, FaultType] = MappingProxyType(_REGISTRY)


def _check(ftype: FaultType) -> None:
    """ValueError unless ``ftype`` is a well-formed type whose parameters tlm knows."""
    from tlm_sim.params import ParamError, Params

    if not isinstance(ftype, FaultType):
        raise TypeError(f"expected a FaultType, got {type(ftype).__name__}")
    if not isinstance(ftype.name, str) or not _NAME.fullmatch(ftype.name):
        raise ValueError(f"fault type name {ftype.name!r}: lower-case letters, digits and _, "
                         "starting with a letter")
    if isinstance(ftype.label, bool) or not isinstance(ftype.label, int) or ftype.label < 1:
        raise ValueError(f"fault type {ftype.name!r}: label must be a whole number >= 1 "
                         f"({NORMAL_LABEL} is normal flight), got {ftype.label!r}")
    if not ftype.params_start or not ftype.params_end:
        raise ValueError(f"fault type {ftype.name!r}: params_start and params_end must set "
                         "at least one parameter each")
    for what in ("params_start", "params_end"):
        try:
            Params(getattr(ftype, what))
        except ParamError as exc:
            raise ValueError(f"fault type {ftype.name!r}, {what}: {exc}") from None
    for name, rule in ftype.relative.items():
        if rule not in RELATIVE_RULES:
            raise ValueError(f"fault type {ftype.name!r}: relative rule {rule!r} of {name}: "
                             f"one of {', '.join(RELATIVE_RULES)}")
        if name not in Params.defaults():
            raise ValueError(f"fault type {ftype.name!r}: relative names {name!r}, not a "
                             "parameter tlm knows")


def register_fault_type(ftype: FaultType, *, replace: bool = False) -> FaultType:
    """Add ``ftype`` to :data:`FAULT_TYPES` (kept in label order) and return it.

    Registering a record equal to the registered one of its name does nothing. Raises
    ValueError for a malformed type (name, label >= 1, parameters :class:`~tlm_sim.params.Params`
    accepts), a name already registered with other values (unless ``replace``; a built-in
    type cannot be replaced) or a label another type has."""
    _check(ftype)
    old = _REGISTRY.get(ftype.name)
    if old == ftype:
        return old
    if old is not None and (not replace or ftype.name in BUILTIN_TYPES):
        raise ValueError(f"fault type {ftype.name!r} is already registered (label "
                         f"{old.label}); choose another name")
    taken = type_of_label(ftype.label)
    if taken is not None and taken.name != ftype.name:
        free = max(t.label for t in _REGISTRY.values()) + 1
        raise ValueError(f"fault type {ftype.name!r}: label {ftype.label} is {taken.name!r}'s; "
                         f"the next free label is {free}")
    items = {**_REGISTRY, ftype.name: ftype}
    _REGISTRY.clear()
    _REGISTRY.update(sorted(items.items(), key=lambda kv: kv[1].label))
    return ftype


def unregister_fault_type(name: str) -> FaultType:
    """Remove a registered type (not a built-in one) and return it; KeyError if none."""
    if name in BUILTIN_TYPES:
        raise ValueError(f"{name!r} is a built-in fault type; it cannot be removed")
    return _REGISTRY.pop(name)


def type_of_label(label: int) -> FaultType | None:
    """The registered type with class label ``label``, None if none has it."""
    return next((t for t in _REGISTRY.values() if t.label == int(label)), None)


def label_colour(label: int) -> str:
    """Matplotlib colour of a class label: grey for normal flight, the type's ``colour``,
    else one generated from the label (hues spaced by the golden angle, so no two labels
    share a colour and none wraps round to an earlier one)."""
    k = int(label)
    if k == NORMAL_LABEL:
        return NORMAL_COLOUR
    ftype = type_of_label(k)
    if ftype is not None and ftype.colour:
        return ftype.colour
    hue = (k * 0.6180339887498949) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.75 if k % 2 else 0.55, 0.8 if k % 3 else 0.6)
    return f"#{round(r * 255):02x}{round(g * 255):02x}{round(b * 255):02x}"


_BUILTIN = (
    FaultType("gps", 1, {"SIM_GPS1_ENABLE": 0.0}, {"SIM_GPS1_ENABLE": 1.0},
              "GPS 1 streams 'no fix' with 3 satellites (paper: SIM_GPS_DISABLE 0 -> 1)",
              "GPS", "tab:blue"),
    FaultType("accel", 2, {"SIM_ACCEL1_FAIL": 1.0, "SIM_ACCEL2_FAIL": 1.0},
              {"SIM_ACCEL1_FAIL": 0.0, "SIM_ACCEL2_FAIL": 0.0},
              "both accelerometers read a constant (1, 1, 1) m/s/s", "Accelerometer",
              "tab:orange"),
    FaultType("engine", 3, {"SIM_ENGINE_MUL": 0.0}, {"SIM_ENGINE_MUL": 1.0},
              "the SIM_ENGINE_FAIL motors (motor 1) lose all thrust", "Engine", "tab:red"),
    FaultType("rc", 4, {"SIM_RC_FAIL": 1.0}, {"SIM_RC_FAIL": 0.0},
              "no RC frames arrive: radio failsafe, RTL (the vehicle stays in RTL after)",
              "RC", "tab:purple"),
    FaultType("gyro", 5, {"SIM_GYR_FAIL_MSK": 1.0}, {"SIM_GYR_FAIL_MSK": 0.0},
              "IMU 1's gyro stops producing samples (IMU.GH 0, its logged gyro frozen; the EKF "
              "and controllers use IMU 2's); masking every gyro is refused (SITL freezes)",
              "Gyro", "tab:green"),
    FaultType("baro", 6, {"SIM_BARO_DISABLE": 1.0, "SIM_BAR2_DISABLE": 1.0},
              {"SIM_BARO_DISABLE": 0.0, "SIM_BAR2_DISABLE": 0.0},
              "both barometers stop (BARO.H 0); ~10 s later the height estimate is lost",
              "Barometer", "tab:brown"),
    FaultType("compass", 7, {"SIM_MAG1_FAIL": 1.0}, {"SIM_MAG1_FAIL": 0.0},
              "compass 1 delivers no data (MAG.Health 0, ERR 3/4); the EKF switches compass",
              "Compass", "tab:pink"),
    FaultType("gps_glitch", 8, {"SIM_GPS1_GLTCH_X": 0.0003, "SIM_GPS1_GLTCH_Y": 0.0003},
              {"SIM_GPS1_GLTCH_X": 0.0, "SIM_GPS1_GLTCH_Y": 0.0},
              "GPS 1 position offset by 0.0003 deg in latitude and longitude (~43 m)",
              "GPS glitch", "tab:olive"),
    FaultType("motor_partial", 9, {"SIM_ENGINE_MUL": 0.5}, {"SIM_ENGINE_MUL": 1.0},
              "the SIM_ENGINE_FAIL motors (motor 1) deliver half their PWM above 1000 us",
              "Partial motor", "tab:cyan"),
    FaultType("vibration", 10,
              {"SIM_ACC1_RND": 4.8, "SIM_ACC2_RND": 4.8, "SIM_VIB_MOT_MAX": 350.0},
              {"SIM_VIB_MOT_MAX": 0.0, "SIM_ACC1_RND": 0.0, "SIM_ACC2_RND": 0.0},
              "motor-rpm sinusoids of 4.8 m/s/s more on both accelerometers (VIBE ~6 m/s/s "
              "on a quiet airframe), at the airframe's own rotor frequency where it has one",
              "Vibration", "gold",
              relative={**{f"SIM_{s}{i}_RND": "add" for s in ("ACC", "GYR") for i in (1, 2)},
                        "SIM_VIB_MOT_MAX": "own"}),
    FaultType("battery", 11, {"SIM_BATT_VOLTAGE": 10.2}, {"SIM_BATT_VOLTAGE": 12.6},
              "battery at 10.2 V: less thrust per PWM, the low-battery failsafe after "
              "BATT_LOW_TIMER", "Battery", "navy"),
    FaultType("gps_jam", 12, {"SIM_GPS1_JAM": 1.0}, {"SIM_GPS1_JAM": 0.0},
              "GPS 1 jammed: fix lost and regained at random, satellites, position, velocity "
              "and accuracy jump", "GPS jamming", "lime"),
    FaultType("accel_samples", 13, {"SIM_ACC_FAIL_MSK": 1.0}, {"SIM_ACC_FAIL_MSK": 0.0},
              "IMU 1's accelerometer stops producing samples (IMU.AH 0, its logged accel "
              "frozen)", "Accelerometer samples", "teal"),
    FaultType("prop_damage", 14,
              {"SIM_VIB_MOT_MAX": 150.0, "TLM_VIB_IMB_MOT": 1.0, "TLM_VIB_IMB": 20.0,
               "SIM_ENGINE_MUL": 0.9},
              {"TLM_VIB_IMB": 0.0, "TLM_VIB_IMB_MOT": 0.0, "SIM_VIB_MOT_MAX": 0.0,
               "SIM_ENGINE_MUL": 1.0},
              "a propeller damaged (tlm's, SITL has none; motor 1, SIM_ENGINE_FAIL's default; "
              "another with its TLM_VIB_IMB_MOT and SIM_ENGINE_FAIL bit): its rotor out of "
              "balance, a force turning once per revolution (20 m/s/s at full command, with "
              "rpm squared), and 10 % of its PWM above 1000 us lost", "Damaged propeller",
              "crimson",
              relative={"TLM_VIB_IMB": "add", "TLM_VIB_IMB_MOT": "own",
                        "SIM_VIB_MOT_MAX": "own"}),
)
#: Names of the built-in catalogue (labels 1-14), which cannot be replaced or removed.
BUILTIN_TYPES: tuple[str, ...] = tuple(t.name for t in _BUILTIN)
for _t in _BUILTIN:
    register_fault_type(_t)
del _t
