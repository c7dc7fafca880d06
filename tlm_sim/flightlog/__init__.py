"""Flight logs: ArduPilot message schemas, FlightLog tables, CSV/Parquet files, .bin reading.

See ``schema`` for the value convention (DataFrame units = what pymavlink shows) and
``flightlog`` for the simulator's log-buffer contract.
"""

from .binreader import (
    BinLog,
    read_bin,
    read_events,
    read_log,
    read_messages,
    read_mission,
    read_modes,
    read_param_changes,
    read_params,
    read_schemas,
    split_instances,
)
from .binscan import BinLogError, BinLogWarning
from .flightlog import FlightLog, allocate_buffers
from .quantise import quantise_column, quantise_frame
from .schema import (
    EVENT_MESSAGES,
    FORMAT_CHARS,
    LOGGED_MESSAGES,
    MULTS,
    SCHEMAS,
    UNITS,
    MessageSchema,
)

__all__ = [
    "BinLog",
    "BinLogError",
    "BinLogWarning",
    "read_log",
    "read_messages",
    "read_mission",
    "read_modes",
    "read_param_changes",
    "split_instances",
    "EVENT_MESSAGES",
    "FORMAT_CHARS",
    "LOGGED_MESSAGES",
    "MULTS",
    "SCHEMAS",
    "UNITS",
    "FlightLog",
    "MessageSchema",
    "allocate_buffers",
    "quantise_column",
    "quantise_frame",
    "read_bin",
    "read_events",
    "read_params",
    "read_schemas",
]
