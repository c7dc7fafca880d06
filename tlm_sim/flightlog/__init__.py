"""Flight logs: ArduPilot message schemas, FlightLog tables, CSV/Parquet files, .bin reading.

See ``schema`` for the value convention (DataFrame units = what pymavlink shows) and
``flightlog`` for the simulator's log-buffer contract.
"""

from .binreader import read_bin, read_events, read_params, read_schemas
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
