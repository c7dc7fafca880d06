"""Fault types as records: the registry (:mod:`.registry`) with the built-in catalogue
(:mod:`.catalogue`) registered.

Import from here (``from tlm_process.fault_types import register_fault_type``): importing the
package registers the built-in types, so every lookup sees them.
"""

from tlm_process.fault_types import catalogue as _catalogue  # noqa: F401  (registers labels 1-14)
from tlm_process.fault_types.registry import (
    FaultTypeRecord,
    Knob,
    ParamsFn,
    SignatureFn,
    fault_type_record,
    fault_type_records,
    register_fault_type,
    unregister_fault_type,
)

__all__ = ["FaultTypeRecord", "Knob", "ParamsFn", "SignatureFn", "fault_type_record",
           "fault_type_records", "register_fault_type", "unregister_fault_type"]
