"""The in-loop log: preallocated float64 buffers, one row appender, column indices by name.

Buffers come as a tuple in ``tlm_sim.flightlog.LOGGED_MESSAGES`` order (``LOG_ORDER``; the
``K_NAME`` constants, made from the schema at import, index it); columns follow each
message's ArduPilot field order (``tlm_sim.flightlog.schema``), values in the units pymavlink
shows (degrees, metres, m/s, deg/s, cm/s^2 where ArduPilot logs them). :func:`new_row` is
the only way a row is appended; rows beyond a buffer's capacity are dropped (the counts never
exceed the buffer size). Each subsystem writes its own messages (``sensors.log``,
``ekf.log``, ``control.log``, ``control.events``, ``dynamics.log``), addressing columns by
name through the ``*_COLS`` constants here, made from the schema at import::

    r = new_row(log, K_GPS, t_us)  # log: (buffers, row counts)
    if r >= 0:
        log[0][K_GPS][r, GPS_COLS.Lat] = lat

(a NamedTuple of ints is a compile-time constant to numba: ``GPS_COLS.Lat`` compiles to 7).
"""

import math
from collections import namedtuple
from typing import Any

import numpy as np

from tlm_sim._jit import tick_jit
from tlm_sim.flightlog.flightlog import allocate_buffers
from tlm_sim.flightlog.schema import LOGGED_MESSAGES, SCHEMAS
from tlm_sim.rotation import quat_to_euler

#: the order of the flight loop's log buffers and of their row counts: the schema's
#: LOGGED_MESSAGES, so a new message is its schema entry and its writer only
LOG_ORDER: tuple[str, ...] = LOGGED_MESSAGES

#: The event messages (MODE, EV, ERR: consecutive in LOG_ORDER) as a tuple of their own,
#: indexed by E_*, with their row counts ``counts[K_MODE:K_ERR + 1]`` (a view): what the
#: vehicle logic writes into. A short tuple, because numba passes each array of a tuple as
#: seven arguments to every function that takes it (the whole log is 39 arrays).
E_MODE, E_EV, E_ERR = 0, 1, 2
_K_EVENTS = LOG_ORDER.index("MODE")
assert LOG_ORDER[_K_EVENTS:_K_EVENTS + 3] == ("MODE", "EV", "ERR")

RAD2DEG = 180.0 / math.pi
TIME_US = 0  # every message's first column: TimeUS (checked against the schema by the tests)


def schema_columns(name: str) -> Any:
    """Column indices of message ``name``'s log buffer by column name (a NamedTuple of ints,
    ``schema_columns("GPS").Lat == 7``), from ``tlm_sim.flightlog.schema``."""
    cols = SCHEMAS[name].columns
    return namedtuple(f"{name}_COLS", cols)(*range(len(cols)))


def _message_constants() -> dict[str, Any]:
    """For each message of LOG_ORDER: ``K_NAME``, its buffer's index, and ``NAME_COLS``, its
    column indices by name (:func:`schema_columns`)."""
    out: dict[str, Any] = {}
    for k, name in enumerate(LOG_ORDER):
        out[f"K_{name}"] = k
        out[f"{name}_COLS"] = schema_columns(name)
    return out


#: ``K_NAME`` (an int) and ``NAME_COLS`` (a NamedTuple of ints) of every logged message, made
#: from the schema and set as this module's globals (``L.K_GPS``, ``L.GPS_COLS.Lat``), which
#: numba compiles in as constants like any other module constant
MESSAGE_CONSTANTS: dict[str, Any] = _message_constants()
globals().update(MESSAGE_CONSTANTS)

__all__ = [
    "LOG_ORDER", "MESSAGE_CONSTANTS", "E_MODE", "E_EV", "E_ERR", "RAD2DEG", "TIME_US",
    "schema_columns", "event_buffers", "new_buffers", "new_row", "euler_deg",
    *MESSAGE_CONSTANTS,
]


@tick_jit
def event_buffers(bufs: tuple[np.ndarray, ...], counts: np.ndarray
                  ) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """The event buffers (E_* order) of a log-buffer tuple and a view of their row counts: the
    ``ev`` pair the vehicle logic writes MODE, EV and ERR rows through (the flight loop's, and
    tests')."""
    k = _K_EVENTS
    return (bufs[k + E_MODE], bufs[k + E_EV], bufs[k + E_ERR]), counts[k:k + 3]


def new_buffers(duration_s: float) -> tuple[tuple[np.ndarray, ...], np.ndarray]:
    """Zeroed log buffers for a flight of ``duration_s`` [s] as the tuple the flight loop takes
    (LOG_ORDER), and their row counts."""
    bufs = allocate_buffers(duration_s, LOG_ORDER)
    return tuple(bufs[n] for n in LOG_ORDER), np.zeros(len(LOG_ORDER), dtype=np.int64)


@tick_jit
def new_row(log, k, t_us):
    """Reserve the next row of buffer k of log (the buffers and their row counts: the flight's
    :class:`tlm_sim.bundles.FlightLogs`, :func:`new_buffers`' pair or the event buffers of
    :func:`event_buffers`), write TimeUS; returns the row index or -1 when full."""
    bufs, counts = log[0], log[1]
    n = counts[k]
    buf = bufs[k]
    if n >= buf.shape[0]:
        return -1
    buf[n, TIME_US] = t_us
    counts[k] = n + 1
    return n


@tick_jit
def euler_deg(qw, qx, qy, qz):
    """(roll, pitch, yaw 0..360) [deg] of a body->NED quaternion."""
    roll, pitch, yaw = quat_to_euler(qw, qx, qy, qz)
    yd = yaw * RAD2DEG
    if yd < 0.0:
        yd += 360.0
    return roll * RAD2DEG, pitch * RAD2DEG, yd
