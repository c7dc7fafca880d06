"""Fault signatures: what a fault does to a flight, as numbers, for every registered type.

:func:`fault_signature` measures one fault window with its type's ``signature`` function (the
record of :mod:`tlm_process.fault_types`), the same way in a tlm ``FlightLog.tables`` and in the
tables ``read_bin`` gives for a genuine SITL ``.bin``. The built-in types' metrics, their
conventions and :class:`~tlm_process.fault_metrics.Flight` (the shared time lines a metric
function gets) are in :mod:`tlm_process.fault_metrics`, whose docstring defines each metric.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.fault_metrics import SIGNATURE_MESSAGES, Flight, route_from_tables, truth_timeline
from tlm_process.fault_types import fault_type_record, fault_type_records

__all__ = ["SIGNATURE_MESSAGES", "fault_signature", "route_from_tables", "signature_types",
           "truth_timeline"]


def signature_types() -> tuple[str, ...]:
    """The fault types :func:`fault_signature` measures (every registered record), in label
    order."""
    return tuple(r.name for r in fault_type_records())


def fault_signature(tables: Mapping[str, pd.DataFrame], fault: Mapping[str, Any],
                    route: Any = None) -> dict[str, float]:
    """Measure one fault's signature in a flight log.

    Args:
        tables: log tables by message name (tlm ``FlightLog.tables`` or ``read_bin`` output).
        fault: at least ``type`` (one of :func:`signature_types`), ``start_time_us`` and
            ``end_time_us`` (log TimeUS); ``params_start`` (e.g. ``{"SIM_ACCEL1_FAIL": 1}``)
            selects the failed instances where a type has several (accel: IMU stuck values,
            default IMU 0 and 1 reading 1 m/s^2; gyro / accel_samples: the mask's bits,
            default IMU 0; baro: SIM_BARO_DISABLE / SIM_BAR2_DISABLE, default both; compass:
            SIM_MAGn_FAIL, default compass 0; motor_partial: SIM_ENGINE_FAIL, default motor 1).
        route: the mission's waypoints as (lat, lon) rows (the route deviation of baro and
            gps_glitch); None takes them from the log's CMD messages (None without).

    Returns:
        Metric name -> value (the type's signature function; the built-in types' metrics are
        listed in :mod:`tlm_process.fault_metrics`); ``*_s`` are seconds after the start,
        ``*_after_end_s`` after the end.
    """
    kind = fault["type"]
    record = fault_type_record(kind) if isinstance(kind, str) else None
    if record is None:
        raise ValueError(f"unknown fault type {kind!r}; expected one of "
                         f"{', '.join(signature_types())}")
    t0, t1 = float(fault["start_time_us"]), float(fault["end_time_us"])
    if not t1 > t0:
        raise ValueError(f"fault window must have end_time_us > start_time_us, got {t0}..{t1}")
    f = Flight(tables)
    if route is None:
        route = route_from_tables(tables)
    route = None if route is None else np.asarray(route, dtype=float)[:, :2]
    return dict(record.signature(f, t0, t1, fault, route))
