"""The fault-type registry of ``tlm_process``: one record per fault type.

A :class:`FaultTypeRecord` is everything tlm knows about a fault type: the simulator's part
(:class:`tlm_sim.faults.FaultType`: name, label, the SITL parameters that start and clear it,
description, display name, colour) and the processing part (how ``tlm generate`` draws its
magnitude: :attr:`~FaultTypeRecord.knobs` and the :attr:`~FaultTypeRecord.params` function
that turns a draw into SITL parameters; and its :attr:`~FaultTypeRecord.signature`, the
metric function :func:`tlm_process.fault_signatures.fault_signature` calls).
:func:`register_fault_type` registers both parts at once (the simulator's into
:data:`tlm_sim.faults.FAULT_TYPES`, which ``tlm_sim`` reads on its own), so a new fault type is
one module that calls it (``docs/extending.md``, "A fault type"); the built-in catalogue is
registered by :mod:`tlm_process.fault_types.catalogue`.

Consumers read the registry when they run, never a list of their own: the scenario draws of
``tlm generate``, the presets ``all`` / ``new``, fault-record ingest and labels, class names
(``tlm evaluate``, ``tlm detect``), plot colours, the signature dispatch and
``tools/fidelity_faults.py``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, NamedTuple

from tlm_sim.faults import types as sim_types
from tlm_sim.faults.types import FaultType

__all__ = ["FaultTypeRecord", "Knob", "ParamsFn", "SignatureFn", "fault_type_record",
           "fault_type_records", "register_fault_type", "unregister_fault_type"]

#: ``(knob values, home latitude [deg]) -> params_start`` of one drawn fault (ArduPilot names
#: and units); the clearing values come from the type's ``params_end`` (tlm's defaults for a
#: parameter it does not list).
ParamsFn = Callable[[Mapping[str, Any], float], Mapping[str, float]]
#: ``(flight, start_time_us, end_time_us, fault, route) -> metric name -> value``: ``flight`` a
#: :class:`tlm_process.fault_metrics.Flight` of the log, the window in log TimeUS [us],
#: ``fault`` the fault record (``type``, ``params_start`` ...), ``route`` the mission's
#: waypoints as (lat, lon) rows or None.
SignatureFn = Callable[..., Mapping[str, float]]


class Knob(NamedTuple):
    """One magnitude knob of a fault type (``tlm generate``, ``magnitudes:``).

    Attributes:
        how: ``"range"`` (drawn uniformly in the configured (low, high)) or ``"choice"``
            (one of the configured values, equal chances).
        limits: ``"range"``: the (low, high) a configuration may ask for; ``"choice"``: the
            allowed values.
        default: the setting when the configuration gives none: (low, high) or a list.
        decimals: a range draw is rounded to this many decimals.
        configurable: False for a draw no configuration sets (always ``default``), e.g. the
            GPS glitch's bearing.
    """

    how: str
    limits: Any
    default: Any
    decimals: int = 3
    configurable: bool = True


@dataclass(frozen=True)
class FaultTypeRecord:
    """A registered fault type: the simulator's record and the processing functions.

    Attributes:
        sim: the :class:`~tlm_sim.faults.FaultType` (name, label, parameters, description,
            title, colour).
        signature: the metric function (:data:`SignatureFn`).
        knobs: magnitude knobs by name, in drawing order (empty: every fault of the type flies
            its ``params_start``).
        params: turns one draw of the knobs into ``params_start`` (:data:`ParamsFn`); given
            exactly when ``knobs`` is.
    """

    sim: FaultType
    signature: SignatureFn
    knobs: Mapping[str, Knob] = field(default_factory=dict)
    params: ParamsFn | None = None

    @property
    def name(self) -> str:
        """The type name."""
        return self.sim.name

    @property
    def label(self) -> int:
        """The class label."""
        return self.sim.label


_RECORDS: dict[str, FaultTypeRecord] = {}


def _checked_knobs(name: str, knobs: Mapping[str, Any] | None) -> dict[str, Knob]:
    """``knobs`` as :class:`Knob` records, ValueError for a malformed one."""
    out: dict[str, Knob] = {}
    for k, v in (knobs or {}).items():
        knob = v if isinstance(v, Knob) else Knob(*v)
        if knob.how not in ("range", "choice"):
            raise ValueError(f"fault type {name!r}, knob {k!r}: how must be 'range' or "
                             f"'choice', got {knob.how!r}")
        if knob.how == "range":
            lo, hi = (float(x) for x in knob.limits)
            dlo, dhi = (float(x) for x in knob.default)
            if not lo <= dlo <= dhi <= hi:
                raise ValueError(f"fault type {name!r}, knob {k!r}: default {knob.default} "
                                 f"outside the limits {knob.limits}")
        elif not knob.default or any(x not in knob.limits for x in knob.default):
            raise ValueError(f"fault type {name!r}, knob {k!r}: default {knob.default} must "
                             f"be a non-empty list of {knob.limits}")
        out[str(k)] = knob
    return out


def register_fault_type(ftype: FaultType, *, signature: SignatureFn,
                        knobs: Mapping[str, Any] | None = None, params: ParamsFn | None = None,
                        replace: bool = False) -> FaultTypeRecord:
    """Register a fault type everywhere: ``ftype`` into :data:`tlm_sim.faults.FAULT_TYPES`
    (:func:`tlm_sim.faults.types.register_fault_type`) and its record here.

    Args:
        ftype: the simulator's record (a new name and the next free label).
        signature: its metric function (:data:`SignatureFn`).
        knobs: its magnitude knobs, name -> :class:`Knob` (or a tuple of its fields), in
            drawing order; None or empty for none.
        params: the draw -> ``params_start`` function; required with knobs, refused without.
        replace: replace a registered (not built-in) type of the same name.

    Returns:
        The record. Raises ValueError for a malformed record, a taken name or label.
    """
    if not callable(signature):
        raise ValueError(f"fault type {ftype.name!r}: signature must be callable")
    checked = _checked_knobs(ftype.name, knobs)
    if bool(checked) != (params is not None):
        raise ValueError(f"fault type {ftype.name!r}: give params (draw -> SITL parameters) "
                         "exactly when it has knobs")
    if params is not None and not callable(params):
        raise ValueError(f"fault type {ftype.name!r}: params must be callable")
    old = _RECORDS.get(ftype.name)
    if old is not None and not replace:
        raise ValueError(f"fault type {ftype.name!r} is already registered (label "
                         f"{old.label}); choose another name")
    sim_types.register_fault_type(ftype, replace=replace)
    record = FaultTypeRecord(ftype, signature, MappingProxyType(checked), params)
    _RECORDS[ftype.name] = record
    return record


def unregister_fault_type(name: str) -> FaultTypeRecord:
    """Remove a registered (not built-in) type from both registries and return its record;
    KeyError if it is not registered."""
    record = _RECORDS[name]
    sim_types.unregister_fault_type(name)
    del _RECORDS[name]
    return record


def fault_type_record(name: str) -> FaultTypeRecord | None:
    """The record of the registered type ``name``; None for a name only ``tlm_sim`` knows
    (registered with :func:`tlm_sim.faults.types.register_fault_type` alone: it flies, but has
    no draw and no signature) or none at all."""
    return _RECORDS.get(name)


def fault_type_records() -> list[FaultTypeRecord]:
    """Every registered record, in label order."""
    return [_RECORDS[n] for n in sim_types.FAULT_TYPES if n in _RECORDS]
