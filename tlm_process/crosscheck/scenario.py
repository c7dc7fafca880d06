"""Rebuild the scenario of a real ArduPilot SITL log so that tlm can fly the same flight.

From the log alone: the mission from its CMD messages (the last upload), home from ORGN (type
1, the AHRS home set at arming) or the first 3D GPS fix, the parameters from PARM (the values
at log start of the parameters tlm knows, loaded as a whole set: those tlm does not model are
carried, reported in one warning and in the flight's meta, and change nothing), the arming
time from EV 10, and the faults from the SIM_* parameter changes (``tlm_sim.faults.detect``).
A sidecar JSON (the reference logs' ``.json``) is preferred where it is given: its mission
(with Algorithm 1's raw points), SITL home, seed and fault records (Eq. 4, with the parameters
set).

Time lines differ: SITL arms ~40 s after boot (GPS lock, EKF start-up), tlm at TLM_ARM_TIME.
Faults are moved to tlm's time line by keeping their offset from arming.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

__all__ = ["SitlScenario", "reconstruct", "mission_from_cmd", "ARMED", "DISARMED"]

ARMED, DISARMED = 10, 11
#: Message types the cross-check reads from a SITL log.
TYPES = ("GPS", "IMU", "RATE", "VIBE", "CTUN", "ATT", "EV", "MODE", "ERR", "SIM", "XKF1",
         "POS", "BARO", "RCOU", "CMD", "PARM", "ORGN", "MSG", "MAG", "XKF4", "XKFS")
_NAV_WAYPOINT, _NAV_TAKEOFF = 16, 22


class ScenarioError(ValueError):
    """The log lacks what a scenario needs (no mission, never armed, ...)."""


@dataclass
class SitlScenario:
    """What tlm needs to fly a SITL log's flight, and the SITL log itself.

    Attributes:
        name: the log's file stem.
        tables: the SITL log's tables (``TYPES``).
        mission: a ``tlm_sim.Mission``.
        params: the ``Params`` to fly: tlm's defaults with the PARM values at log start
            (``Params.from_values``; ``params.changed()`` is what differs from tlm's defaults,
            ``params.unmodelled()`` what of that tlm does not model).
        faults: fault records on SITL's time line (type, label, start/end_time_us,
            params_start/params_end).
        schedule: the same faults as a ``FaultSchedule`` on tlm's time line, or None.
        sitl_arm_us: SITL's arming time (EV 10) [us].
        tlm_arm_s: tlm's arming time [s].
        seed: seed for tlm's flight (the sidecar's, else 0).
        source: where mission and faults came from ("sidecar" or "log").
    """

    name: str
    tables: dict[str, pd.DataFrame]
    mission: Any
    params: Any
    faults: list[dict[str, Any]]
    schedule: Any
    sitl_arm_us: float
    tlm_arm_s: float
    seed: int = 0
    source: str = "log"
    notes: list[str] = field(default_factory=list)

    def to_tlm_us(self, sitl_us: float) -> float:
        """A SITL log time [us] on tlm's time line (same offset from arming)."""
        return sitl_us - self.sitl_arm_us + self.tlm_arm_s * 1e6


def _home_from_log(t: dict[str, pd.DataFrame]) -> tuple[float, float, float]:
    orgn = t.get("ORGN")
    if orgn is not None and len(orgn[orgn.Type == 1]):
        r = orgn[orgn.Type == 1].iloc[-1]
        return float(r.Lat), float(r.Lng), float(r.Alt)
    gps = t["GPS"]
    fix = gps[gps.Status >= 3]
    if not len(fix):
        raise ScenarioError("no home: no ORGN message and no 3D GPS fix in the log")
    r = fix.iloc[0]
    return float(r.Lat), float(r.Lng), float(r.Alt)


def mission_from_cmd(cmd: pd.DataFrame, home: tuple[float, float, float], name: str = ""):
    """A ``Mission`` from a log's CMD messages (the last upload, ``binreader.mission_from_cmd``).

    Item 0 is home; NAV_TAKEOFF gives the takeoff altitude; NAV_WAYPOINT items after it are the
    waypoints (relative altitudes, frame 3); RTL and other commands are not waypoints.
    """
    from tlm_sim.flightlog.binreader import mission_from_cmd as cmd_items
    from tlm_sim.mission import Mission

    items = cmd_items(cmd)
    if not items:
        raise ScenarioError("the log has no mission (no CMD messages)")
    wps = [(i["Lat"], i["Lng"], i["Alt"]) for i in items
           if i["CId"] == _NAV_WAYPOINT and i["CNum"] > 0]
    if not wps:
        raise ScenarioError("the log's mission has no waypoints")
    takeoff = [i["Alt"] for i in items if i["CId"] == _NAV_TAKEOFF]
    return Mission(waypoints=np.asarray(wps, dtype=np.float64), home=home, name=name,
                   takeoff_alt=takeoff[0] if takeoff else None)


def _initial_params(parm: pd.DataFrame) -> dict[str, float]:
    """PARM values at log start, limited to parameters tlm knows, where they differ from its
    defaults."""
    from tlm_sim.params import Params

    defaults = Params.defaults()
    first = parm.drop_duplicates("Name", keep="first")
    out = {}
    for n, v in zip(first.Name.astype(str), first.Value.astype(float), strict=True):
        if n in defaults and not np.isclose(defaults[n], v, rtol=1e-6, atol=1e-9):
            out[n] = float(v)
    return out


def _faults_from_log(parm: pd.DataFrame) -> list[dict[str, Any]]:
    from tlm_sim.faults import FAULT_TYPES
    from tlm_sim.faults.detect import faults_from_param_changes
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    out = []
    for f in faults_from_param_changes(param_changes_from_parm(parm, exclude=())):
        ft = FAULT_TYPES[f["type"]]
        out.append(dict(f, params_start=dict(ft.params_start), params_end=dict(ft.params_end)))
    return out


def _schedule(faults: list[dict[str, Any]], to_tlm_s) -> Any:
    from tlm_sim.faults import FaultSchedule

    if not faults:
        return None
    items = []
    for f in faults:
        item: dict[str, Any] = {"fault": f["type"], "start": round(to_tlm_s(f["start_time_us"]), 3)}
        if f.get("end_time_us") is not None:
            item["end"] = round(to_tlm_s(f["end_time_us"]), 3)
        if f.get("params_start"):
            item["params_start"] = {k: float(v) for k, v in f["params_start"].items()}
        if f.get("params_end"):
            item["params_end"] = {k: float(v) for k, v in f["params_end"].items()}
        items.append(item)
    return FaultSchedule.from_dict({"faults": items})


def reconstruct(bin_path: str | Path, sidecar: str | Path | None = None,
                seed: int | None = None) -> SitlScenario:
    """The scenario of a SITL ``.bin`` (and its sidecar, when given or found beside it).

    Args:
        bin_path: the SITL log.
        sidecar: its JSON sidecar; None looks for ``<log>.json`` beside the log.
        seed: tlm's seed (default: the sidecar's, else 0).
    Raises:
        ScenarioError: the log never armed, has no mission or no home.
    """
    from tlm_sim import Mission
    from tlm_sim.flightlog import read_bin
    from tlm_sim.params import Params

    bin_path = Path(bin_path)
    t = read_bin(bin_path, TYPES)
    ev = t["EV"]
    armed = ev[ev.Id == ARMED].TimeUS
    if not len(armed):
        raise ScenarioError(f"{bin_path.name}: the vehicle never armed (no EV 10)")
    side_path = Path(sidecar) if sidecar else bin_path.with_suffix(".json")
    doc = json.loads(side_path.read_text()) if side_path.is_file() else None
    params = Params.from_values(_initial_params(t["PARM"]), source=f"{bin_path.name} (PARM)")
    tlm_arm_s = float(params["TLM_ARM_TIME"])
    sitl_arm_us = float(armed.iloc[0])

    def to_tlm_s(us: float) -> float:
        return (us - sitl_arm_us) * 1e-6 + tlm_arm_s

    if doc is not None and "mission" in doc:
        mission = Mission.from_sidecar(side_path)
        faults = [dict(f) for f in doc.get("faults") or ()]
        source = "sidecar"
        seed = int(doc.get("seed", 0)) if seed is None else seed
    else:
        mission = mission_from_cmd(t["CMD"], _home_from_log(t), bin_path.stem)
        faults = _faults_from_log(t["PARM"])
        source = "log"
    return SitlScenario(
        name=bin_path.stem, tables=t, mission=mission, params=params, faults=faults,
        schedule=_schedule(faults, to_tlm_s), sitl_arm_us=sitl_arm_us, tlm_arm_s=tlm_arm_s,
        seed=0 if seed is None else int(seed), source=source,
    )
