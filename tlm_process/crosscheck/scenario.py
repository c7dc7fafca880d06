"""Rebuild the scenario of a real ArduPilot SITL log so that tlm can fly the same flight.

From the log alone: the mission from its CMD messages (the last upload), home from ORGN (type
1, the AHRS home set at arming) or the first 3D GPS fix, the parameters from PARM (the values
at log start of the parameters tlm knows, loaded as a whole set: those tlm does not model are
carried, reported in one warning and in the flight's meta, and change nothing), the arming
time from :func:`tlm_process.logread.arming_time_us` (EV 10, else the ARM message, else the
motor outputs of a log that starts at arming), and the faults from the SIM_* parameter changes
(``tlm_sim.faults.detect``). The log is read through :func:`tlm_process.logread.read_log_tables`
(a 4.x log's tables as logged; older logs normalised).
A sidecar JSON (the reference logs' ``.json``) is preferred where it is given: its mission
(with Algorithm 1's raw points), SITL home, seed and fault records (Eq. 4, with the parameters
set).

A fault still active when the log ends (a log cut off during it: no end in its parameter
changes) runs to the log's end: tlm holds it to the end of its flight (no ``params_end``) and
the scenario's notes say so in one line.

Time lines differ: SITL arms ~40 s after boot (GPS lock, EKF start-up), tlm at TLM_ARM_TIME.
Faults are moved to tlm's time line by keeping their offset from arming.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.fault_signatures import SIGNATURE_MESSAGES

__all__ = ["SitlScenario", "reconstruct", "mission_from_cmd", "ARMED", "DISARMED"]

ARMED, DISARMED = 10, 11
#: Message types the cross-check reads from a SITL log.
TYPES = tuple(dict.fromkeys((
    "GPS", "IMU", "RATE", "VIBE", "CTUN", "ATT", "EV", "MODE", "ERR", "SIM", "XKF1", "POS",
    "CMD", "PARM", "ORGN", "MSG", *SIGNATURE_MESSAGES)))  # + what the fault signatures read


#: what the arming time needs besides EV (:func:`tlm_process.logread.arming_time_us`)
_ARMING_TYPES = ("ARM", "RCOU")


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
        schedule: the same faults as a ``FaultSchedule`` on tlm's time line, or None (no
            faults, or flown as raw ``changes``).
        changes: the faults as raw ``(time_s, name, value)`` parameter changes on tlm's time
            line when a fault's type is not in ``FAULT_TYPES`` (else None).
        sitl_arm_us: SITL's arming time (EV 10; ``logread.arming_time_us``) [us].
        tlm_arm_s: tlm's arming time [s].
        seed: seed for tlm's flight (the sidecar's, else 0).
        source: where mission and faults came from ("sidecar" or "log").
        notes: what could not be flown as SITL did (unknown types, unmodelled parameters).
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
    changes: list[tuple[float, str, float]] | None = None

    def to_tlm_us(self, sitl_us: float) -> float:
        """A SITL log time [us] on tlm's time line (same offset from arming)."""
        return sitl_us - self.sitl_arm_us + self.tlm_arm_s * 1e6

    @property
    def fly_faults(self) -> Any:
        """What ``tlm_sim.fly(faults=...)`` takes: the schedule, the raw changes, or None."""
        return self.schedule if self.schedule is not None else self.changes

    def tlm_fault_records(self, flown_records: list[dict[str, Any]] | None = None
                          ) -> list[dict[str, Any]]:
        """The faults on tlm's time line: the flight's own Eq. 4 records when it flew the
        schedule, else the SITL records with their windows moved (``to_tlm_us``)."""
        if self.schedule is not None and flown_records is not None:
            return list(flown_records)
        out = []
        for f in self.faults:
            end = f.get("end_time_us")
            out.append(dict(f, start_time_us=self.to_tlm_us(float(f["start_time_us"])),
                            end_time_us=None if end is None else self.to_tlm_us(float(end))))
        return out


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

    Item 0 is home; the items after it are read with the mission-file rules
    (:func:`tlm_sim.mission.wpl.mission_from_items`): NAV_TAKEOFF gives the takeoff altitude,
    NAV_WAYPOINT / NAV_LOITER_TIME items are the waypoints with their hold times, DO_CHANGE_SPEED
    and a final NAV_LAND are flown, RTL ends the mission; an item or parameter tlm does not fly
    is a ScenarioError naming it, never dropped.
    """
    from tlm_sim.flightlog.binreader import MISSION_FIELDS
    from tlm_sim.flightlog.binreader import mission_from_cmd as cmd_items
    from tlm_sim.mission import MissionError
    from tlm_sim.mission.wpl import mission_from_items

    missing = [c for c in ("CTot", *MISSION_FIELDS) if c not in cmd.columns]
    if missing:  # an older firmware's CMD (Copter 3.x: no Frame, Prm2-4)
        raise ScenarioError(f"the log has no mission (no CMD messages with "
                            f"{', '.join(missing)}: an older firmware's layout)")
    items = cmd_items(cmd)
    if not items:
        raise ScenarioError("the log has no mission (no CMD messages)")
    try:
        return mission_from_items([i for i in items if i["CNum"] > 0], home, name,
                                  source=f"{name or 'log'} CMD item")
    except MissionError as exc:
        raise ScenarioError(str(exc)) from None


def _initial_params(parm: pd.DataFrame) -> dict[str, float]:
    """PARM values at log start, limited to parameters tlm knows, where they differ from its
    defaults. A parameter tlm does not model (and ignores) is left out when its value is not a
    number (ArduPilot's LogAnalyzer example ``nan.log`` logs NaN for ``COMPASS_MOT_*``)."""
    from tlm_sim.params import Params, is_modelled

    defaults = Params.defaults()
    first = parm.drop_duplicates("Name", keep="first")
    out = {}
    for n, v in zip(first.Name.astype(str), first.Value.astype(float), strict=True):
        if n not in defaults or (not np.isfinite(v) and not is_modelled(n)):
            continue
        if not np.isclose(defaults[n], v, rtol=1e-6, atol=1e-9):
            out[n] = float(v)
    return out


def _frame_params(t: Mapping[str, pd.DataFrame], doc: Mapping[str, Any] | None,
                  name: str) -> dict[str, float]:
    """FRAME_CLASS / FRAME_TYPE of the flight: the log's PARM where it has them, else the frame
    the SITL model name (sidecar ``sitl.model`` or ``frame``) or the firmware's ``Frame:``
    MSG names. SITL flies its model's motors with the autopilot's mixer of FRAME_CLASS /
    FRAME_TYPE; tlm flies one frame for both, so a log whose model and parameters name
    different frames is refused (ScenarioError)."""
    from tlm_sim.frames import FRAMES, FrameError, frame_for, frame_for_model

    parm = t["PARM"]
    logged = {n: float(parm[parm.Name == n].Value.iloc[0])
              for n in ("FRAME_CLASS", "FRAME_TYPE") if (parm.Name == n).any()}
    model = None
    sitl = (doc or {}).get("sitl") or {}
    label = sitl.get("model") or (doc or {}).get("frame")
    if label:
        try:
            model = frame_for_model(str(label))
        except FrameError as exc:
            raise ScenarioError(f"{name}: {exc}") from None
    else:
        msg = t.get("MSG")
        texts = [] if msg is None else [str(m) for m in msg.Message if str(m).startswith("Frame: ")]
        labels = {f.label: f for f in FRAMES.values()}
        if texts and texts[0][len("Frame: "):] in labels:
            model = labels[texts[0][len("Frame: "):]]
    if model is None:
        return {}
    if len(logged) == 2:
        try:
            autopilot = frame_for(logged["FRAME_CLASS"], logged["FRAME_TYPE"])
        except FrameError:
            return {}  # Params refuses it with its own message
        if autopilot != model:
            raise ScenarioError(
                f"{name}: SITL flew model {model.name!r} with the autopilot's {autopilot.label} "
                f"mixer (FRAME_CLASS {logged['FRAME_CLASS']:g}, FRAME_TYPE "
                f"{logged['FRAME_TYPE']:g}); tlm flies one frame for both, so it cannot fly "
                f"a mismatched mixer")
        return {}
    return {"FRAME_CLASS": float(model.frame_class), "FRAME_TYPE": float(model.frame_type)}


def _faults_from_log(parm: pd.DataFrame) -> list[dict[str, Any]]:
    """Detected faults (``FAULT_TYPES``) and, from the SIM_* changes none of them explains,
    faults of type ``unknown`` (see the module docstring), in start order."""
    from tlm_sim.faults import FAULT_TYPES
    from tlm_sim.faults.detect import faults_from_param_changes
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    changes = param_changes_from_parm(parm, exclude=())
    out = []
    for f in faults_from_param_changes(changes):
        ft = FAULT_TYPES[f["type"]]
        out.append(dict(f, params_start=dict(ft.params_start), params_end=dict(ft.params_end)))
    out += unknown_faults(changes, out)
    return sorted(out, key=lambda f: f["start_time_us"])


def _explained(t: float, name: str, faults: list[dict[str, Any]]) -> bool:
    for f in faults:
        names = set(f.get("params_start") or {}) | set(f.get("params_end") or {})
        end = f["end_time_us"] if f.get("end_time_us") is not None else np.inf
        if name in names and f["start_time_us"] <= t <= end:
            return True
    return False


def unknown_faults(changes: pd.DataFrame, known: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Faults of type ``unknown`` from the SIM_* parameter changes that no ``known`` fault
    explains (a change of one of its parameters inside its window).

    A group starts when such a parameter leaves its log-start value (``Old`` of its first
    change) and ends when every parameter of the group is back at its log-start value; each
    group is one record with ``params_start`` (the first value of each parameter),
    ``params_end`` (the last) and ``changes`` (every ``(TimeUS, name, value)``, to replay).
    """
    out: list[dict[str, Any]] = []
    base: dict[str, float] = {}
    away: set[str] = set()
    rec: dict[str, Any] | None = None
    for t, name, value, old in zip(changes["TimeUS"], changes["Name"], changes["Value"],
                                   changes["Old"], strict=True):
        name, value = str(name), float(value)
        if not name.startswith("SIM_") or _explained(float(t), name, known):
            continue
        base.setdefault(name, float(old))
        if rec is None:
            rec = {"type": "unknown", "label": None, "start_time_us": int(t),
                   "end_time_us": None, "params_start": {}, "params_end": {},
                   "changes": [], "source": "PARM"}
            out.append(rec)
        rec["params_start"].setdefault(name, value)
        rec["params_end"][name] = value
        rec["changes"].append((int(t), name, value))
        if np.isclose(value, base[name], rtol=1e-6, atol=1e-9):
            away.discard(name)
        else:
            away.add(name)
        if not away:
            rec["end_time_us"] = int(t)
            rec = None
    for r in out:  # a parameter that never left its value does not start a fault
        r["params_start"] = {k: v for k, v in r["params_start"].items()
                             if k in r["params_end"]}
    return out


def _raw_changes(f: dict[str, Any]) -> list[tuple[float, str, float]]:
    """(SITL TimeUS, name, value) of one fault: its recorded ``changes``, else params_start at
    its start and params_end at its end."""
    if f.get("changes"):
        return [(float(t), str(n), float(v)) for t, n, v in f["changes"]]
    out = [(float(f["start_time_us"]), k, float(v))
           for k, v in (f.get("params_start") or {}).items()]
    if f.get("end_time_us") is not None:
        out += [(float(f["end_time_us"]), k, float(v))
                for k, v in (f.get("params_end") or {}).items()]
    return out


def _flyable(name: str) -> str | None:
    """Why tlm cannot fly parameter ``name`` (None if it can)."""
    from tlm_sim.params import ALIASES, Params, is_modelled

    canonical = ALIASES[name].target if name in ALIASES else name
    if canonical not in Params.defaults():
        return "unknown to tlm"
    return None if is_modelled(canonical) else "not modelled by tlm"


def _plan(faults: list[dict[str, Any]], to_tlm_s) -> tuple[Any, Any, list[str]]:
    """(schedule, raw changes, notes) that fly ``faults`` on tlm's time line (module
    docstring): the schedule when every type is known, else the raw changes; parameters tlm
    cannot fly are left out of both and named in the notes."""
    from tlm_sim.faults import FAULT_TYPES, FaultScheduleError

    notes: list[str] = []
    skip: set[str] = set()
    for f in faults:
        for _, name, _ in _raw_changes(f):
            why = _flyable(name)
            if why is not None and name not in skip:
                skip.add(name)
                notes.append(f"{f.get('type')} fault: {name} is {why}; flown without it")
    if all(f.get("type") in FAULT_TYPES for f in faults):
        try:
            return _schedule(faults, to_tlm_s, skip), None, notes
        except FaultScheduleError as exc:
            notes.append(f"flown as raw parameter changes: {exc}")
    else:
        odd = sorted({str(f.get("type")) for f in faults if f.get("type") not in FAULT_TYPES})
        notes.append(f"fault type {', '.join(odd)} unknown to tlm: flown as raw parameter "
                     "changes")
    changes = sorted(((round(to_tlm_s(t), 3), n, v) for f in faults
                      for t, n, v in _raw_changes(f) if n not in skip), key=lambda c: c[0])
    return None, changes or None, notes


def _schedule(faults: list[dict[str, Any]], to_tlm_s, skip: set[str] = frozenset()) -> Any:
    """The faults as a FaultSchedule, without the parameters in ``skip``
    (FaultScheduleError when a fault is left with none: it is then flown as raw changes)."""
    from tlm_sim.faults import FaultSchedule

    if not faults:
        return None
    if skip:
        faults = [dict(f, params_start={k: v for k, v in (f.get("params_start") or {}).items()
                                        if k not in skip},
                       params_end={k: v for k, v in (f.get("params_end") or {}).items()
                                   if k not in skip}) for f in faults]
        if any(not f["params_start"] for f in faults):
            from tlm_sim.faults import FaultScheduleError

            raise FaultScheduleError("a fault has no parameter tlm can fly")
    items = []
    for f in faults:
        # SITL set these values, whatever the vehicle's own: absolute
        item: dict[str, Any] = {"fault": f["type"], "start": round(to_tlm_s(f["start_time_us"]), 3),
                                "absolute": True}
        if f.get("end_time_us") is not None:
            item["end"] = round(to_tlm_s(f["end_time_us"]), 3)
        if f.get("params_start"):
            item["params_start"] = {k: float(v) for k, v in f["params_start"].items()}
        if f.get("params_end") and "end" in item:  # a fault without end is held: no end values
            item["params_end"] = {k: float(v) for k, v in f["params_end"].items()}
        items.append(item)
    return FaultSchedule.from_dict({"faults": items})


def _held_notes(faults: list[dict[str, Any]], t: Mapping[str, pd.DataFrame]) -> list[str]:
    """One note per fault still active when the log ends (no end: a log cut off during it)."""
    held = [f for f in faults if f.get("start_time_us") is not None
            and f.get("end_time_us") is None]
    if not held:
        return []
    last = [float(df.TimeUS.max()) for df in t.values() if "TimeUS" in df and len(df)]
    end = f" at {max(last) * 1e-6:.1f} s" if last else ""
    return [f"{f.get('type')} fault (from {float(f['start_time_us']) * 1e-6:.1f} s) is still "
            f"active when the log ends{end}: it runs to the log's end (held to the end of "
            "tlm's flight)" for f in held]


def _read_sidecar(path: Path, explicit: bool) -> dict[str, Any] | None:
    """The sidecar JSON object at ``path``; ``None`` when there is none beside the log.

    Raises:
        ScenarioError: an ``explicit`` sidecar (``--sidecar``) that is missing or names no
            mission; any sidecar that is not a JSON object.
    """
    if not path.is_file():
        if explicit:
            raise ScenarioError(f"--sidecar {path}: no such file")
        return None
    from tlm_sim.flightlog.sidecar import load_sidecar_json

    try:
        doc = load_sidecar_json(path)
    except ValueError as exc:
        raise ScenarioError(str(exc)) from None
    if not isinstance(doc, dict):
        raise ScenarioError(f"{path} is not a sidecar JSON (not an object)")
    if explicit and "mission" not in doc:
        raise ScenarioError(f"--sidecar {path} names no mission (a SITL sidecar has "
                            f"'mission'); leave --sidecar out to take the scenario from the log")
    return doc


def _read_tables(path: Path) -> tuple[dict[str, pd.DataFrame], dict[str, float]]:
    """The ``TYPES`` tables (and ARM, RCOU for the arming time) of a log, normalised by
    :func:`tlm_process.logread.read_log_tables` (a 4.x log's exactly as logged), each type
    tlm knows present (empty when the log has none, as ``read_bin`` gives them), and the
    log's parameters."""
    from tlm_process.logread import LogReadError, read_log_tables, warn_damage
    from tlm_sim.flightlog import SCHEMAS
    from tlm_sim.flightlog.binreader import empty_table

    names = (*TYPES, *_ARMING_TYPES)
    try:
        lt = read_log_tables(path, names)
    except LogReadError as exc:
        raise ScenarioError(str(exc)) from None
    warn_damage(lt)
    tables = {n: lt.tables[n] if n in lt.tables else empty_table(SCHEMAS[n])
              for n in names if n in lt.tables or n in SCHEMAS}
    return tables, lt.params


def reconstruct(bin_path: str | Path, sidecar: str | Path | None = None,
                seed: int | None = None) -> SitlScenario:
    """The scenario of a SITL ``.bin`` (and its sidecar, when given or found beside it).

    Args:
        bin_path: the SITL log.
        sidecar: its JSON sidecar; None looks for ``<log>.json`` beside the log.
        seed: tlm's seed (default: the sidecar's, else 0).
    Raises:
        ScenarioError: the log never armed, has no mission or no home, or sets a parameter to
            a value tlm does not simulate (e.g. FRAME_CLASS 4), or its SITL model and its
            FRAME_CLASS / FRAME_TYPE name different frames.
    """
    from tlm_process.logread import arming_time_us
    from tlm_sim import Mission
    from tlm_sim.params import Params

    bin_path = Path(bin_path)
    t, log_params = _read_tables(bin_path)
    arm_us, _ = arming_time_us(t, log_params)
    if arm_us is None:
        raise ScenarioError(f"{bin_path.name}: the vehicle never armed (no EV 10, no ARM "
                            "message, no motor output rise)")
    side_path = Path(sidecar) if sidecar else bin_path.with_suffix(".json")
    doc = _read_sidecar(side_path, explicit=bool(sidecar))
    from tlm_sim.params import ParamError

    initial = _initial_params(t["PARM"])
    initial.update(_frame_params(t, doc, bin_path.name))
    try:
        params = Params.from_values(initial, source=f"{bin_path.name} (PARM)")
    except ParamError as exc:
        raise ScenarioError(f"tlm cannot fly this log's parameters: {exc}") from None
    tlm_arm_s = float(params["TLM_ARM_TIME"])
    sitl_arm_us = float(arm_us)

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
    schedule, changes, notes = _plan(faults, to_tlm_s)
    notes[:0] = _held_notes(faults, t)
    return SitlScenario(
        name=bin_path.stem, tables=t, mission=mission, params=params, faults=faults,
        schedule=schedule, sitl_arm_us=sitl_arm_us, tlm_arm_s=tlm_arm_s,
        seed=0 if seed is None else int(seed), source=source, notes=notes, changes=changes,
    )
