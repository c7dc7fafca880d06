"""Fault records of the paper's Eq. 4, as a ground station would have written them.

For each fault of a schedule: the log times (TimeUS) at which its start and end parameter
changes took effect, and the vehicle's position at those moments as DroneKit's
``global_relative_frame`` reports it (the EKF estimate: ``POS`` Lat/Lng and RelHomeAlt, metres
above home), plus the true position (``SIM``). The keys are those of the genuine SITL sidecars
in ``shared/reference/sitl/*.json`` (``type``, ``label``, ``start_time_us``, ``end_time_us``,
``start_lat`` ... ``end_alt``, ``params_start``, ``params_end``), so the same anchoring code
reads both.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from tlm_sim.faults.schedule import FaultSchedule, ParamChange, Trigger


def _sample_at(df: pd.DataFrame | None, t_us: float) -> pd.Series | None:
    """The latest row of df at or before t_us (the first row if none is earlier)."""
    if df is None or not len(df):
        return None
    i = int(np.searchsorted(df.TimeUS.to_numpy(), t_us, side="right")) - 1
    return df.iloc[max(i, 0)]


def _trigger_text(tr: Trigger | None) -> float | str | None:
    """A trigger as the schedule file writes it (seconds, or "wpN"); None for no end."""
    return None if tr is None else tr.to_value()


def _position(tables: Mapping[str, pd.DataFrame], t_us: float | None,
              home_alt: float) -> dict[str, float | None]:
    """Estimated (POS) and true (SIM) position at t_us; alt in metres above home."""
    keys = ("lat", "lon", "alt", "true_lat", "true_lon", "true_alt")
    out: dict[str, float | None] = dict.fromkeys(keys)
    if t_us is None:
        return out
    pos = _sample_at(tables.get("POS"), t_us)
    if pos is not None:
        out["lat"], out["lon"] = float(pos.Lat), float(pos.Lng)
        out["alt"] = round(float(pos.RelHomeAlt), 3)
    sim = _sample_at(tables.get("SIM"), t_us)
    if sim is not None:
        out["true_lat"], out["true_lon"] = float(sim.Lat), float(sim.Lng)
        out["true_alt"] = round(float(sim.Alt) - home_alt, 3)
    return out


def fault_records(
    schedule: FaultSchedule,
    changes: Sequence[ParamChange],
    applied_us: np.ndarray,
    tables: Mapping[str, pd.DataFrame],
    home_alt: float,
    t_last_us: float,
) -> list[dict[str, Any]]:
    """Eq. 4 records of a flown schedule.

    changes: ``schedule.param_changes(own)`` as flown (the records give the values flown);
    applied_us[i]: TimeUS at which change i took
    effect (< 0 if the flight ended first: the fault then ends with the log, ``end_by`` says
    so). tables: the flight's tables (``POS`` and ``SIM`` are read). home_alt: home altitude
    AMSL [m]. t_last_us: TimeUS of the log's last row (the end of a fault the flight outlived).
    """
    records: list[dict[str, Any]] = []
    t_last = float(t_last_us)
    for i, fault in enumerate(schedule):
        starts = [applied_us[k] for k, ch in enumerate(changes)
                  if ch.fault == i and ch.edge == "start" and applied_us[k] >= 0]
        ends = [applied_us[k] for k, ch in enumerate(changes)
                if ch.fault == i and ch.edge == "end" and applied_us[k] >= 0]
        if not starts:
            continue  # never started: the flight ended first
        t0 = float(min(starts))
        if fault.end is not None and ends:
            t1, end_by = float(max(ends)), "schedule"
        else:
            t1, end_by = t_last, "flight end"
        p0 = _position(tables, t0, home_alt)
        p1 = _position(tables, t1, home_alt)
        rec: dict[str, Any] = {
            "type": fault.type,
            "label": int(fault.label),
            "start": _trigger_text(fault.start),
            "end": _trigger_text(fault.end),
            "params_start": {ch.name: ch.value for ch in changes
                             if ch.fault == i and ch.edge == "start"},
            "params_end": ({ch.name: ch.value for ch in changes
                            if ch.fault == i and ch.edge == "end"}
                           if fault.end is not None else dict(fault.params_end or {})),
            "start_time_us": int(round(t0)),
            "end_time_us": int(round(t1)),
            "time_source": "tlm schedule",
            "end_by": end_by,
            "duration_s": round((t1 - t0) * 1e-6, 6),
        }
        for edge, pos in (("start", p0), ("end", p1)):
            for k in ("lat", "lon", "alt"):
                rec[f"{edge}_{k}"] = pos[k]
            for k in ("lat", "lon", "alt"):
                rec[f"{edge}_true_{k}"] = pos[f"true_{k}"]
        records.append(rec)
    return records
