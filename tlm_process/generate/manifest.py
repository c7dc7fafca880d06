"""The manifest of a generated data set: its settings, and what happened to every flight.

``DS/manifest.json`` (the header): format, tlm version, a hash of the simulator's source, the
run seed, the settings every flight was drawn and written with, λ, the state of the data set
(``running`` while a run writes, ``complete`` or ``incomplete`` after), flight counts and one
entry per run (executor, workers, wall time).

``DS/flights.jsonl`` (the journal): one JSON line per finished flight, appended once its files
are in place: ``flight``, ``status`` (``ok`` / ``failed``), ``scenario`` (everything needed to
fly it again, :class:`~tlm_process.generate.scenario.Scenario`), ``summary``, ``timing``,
``worker``, ``error`` and ``traceback`` for a failed flight. The last line of a flight counts.

``DS/manifest.parquet``: the journal as a table, one row per flight, with each flight's frame
and wind as columns (:data:`CONDITION_COLUMNS`; written at the end of a run, also after
Ctrl-C).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from tlm_process.generate.errors import GenerateError
from tlm_process.generate.scenario import FlightSpec, Scenario, flight_conditions

__all__ = [
    "CONDITION_COLUMNS",
    "FORMAT",
    "FORMAT_VERSION",
    "HEADER",
    "JOURNAL",
    "MANIFEST_TABLE",
    "check_compatible",
    "manifest_frame",
    "read_header",
    "read_journal",
    "scenario_from_manifest",
    "sim_fingerprint",
    "write_json_atomic",
]

FORMAT = "tlm.dataset"
FORMAT_VERSION = 1
HEADER = "manifest.json"
JOURNAL = "flights.jsonl"
MANIFEST_TABLE = "manifest.parquet"


def sim_fingerprint() -> dict[str, str]:
    """tlm's version and a hash of tlm_sim's source (flights differ when either does)."""
    import tlm_sim
    from tlm_sim._cache import source_hash

    return {"tlm_version": tlm_sim.__version__,
            "sim_source": source_hash(Path(tlm_sim.__file__).resolve().parent)}


def write_json_atomic(path: Path, doc: Any) -> None:
    """Write JSON to ``path`` through a temporary file and a rename."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(json.dumps(doc, indent=1, sort_keys=False) + "\n")
    os.replace(tmp, path)


def read_header(ds: Path) -> dict[str, Any] | None:
    """The header of data set ``ds``; None when the folder holds none.

    Raises GenerateError when the file is unreadable or not a tlm data set header."""
    path = ds / HEADER
    if not path.exists():
        return None
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:  # ValueError: JSON or UTF-8 decoding
        raise GenerateError(f"{path}: cannot read the data set manifest: {exc}") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise GenerateError(f"{path} is not a tlm data set manifest")
    for key, (kinds, what) in _HEADER_FIELDS.items():
        if key in doc and not _is(doc[key], kinds):
            raise GenerateError(f"{path}: {key!r} must be {what}, got {json.dumps(doc[key])}; "
                                "restore the file or use another --out")
    if doc.get("format_version", FORMAT_VERSION) > FORMAT_VERSION:
        raise GenerateError(f"{path}: data set format version {doc['format_version']}; this tlm "
                            f"reads versions up to {FORMAT_VERSION} (a newer tlm wrote it: "
                            f"update tlm)")
    return doc


def _is(value: Any, kinds: tuple[type, ...]) -> bool:
    """isinstance, with bool not an int and whole numbers >= 0 where int is asked for."""
    if isinstance(value, bool) and bool not in kinds:
        return False
    if int in kinds and isinstance(value, int) and not isinstance(value, bool):
        return value >= 0
    return isinstance(value, kinds)


_NONE = type(None)
#: header field -> (allowed types, in words) (int: a whole number >= 0)
_HEADER_FIELDS: dict[str, tuple[tuple[type, ...], str]] = {
    "format_version": ((int,), "a whole number"),
    "flights": ((int,), "a whole number >= 0"),
    "seed": ((int,), "a whole number >= 0"),
    "state": ((str,), "a text"),
    "runs": ((list,), "a list"),
    "settings": ((dict,), "an object"),
    "counts": ((dict,), "an object"),
    "pilot": ((dict, _NONE), "an object"),
    "lambda": ((int, float, _NONE), "a number"),
    "tlm_version": ((str, _NONE), "a text"),
    "sim_source": ((str, _NONE), "a text"),
}
#: journal field -> (allowed types, in words)
_ENTRY_FIELDS: dict[str, tuple[tuple[type, ...], str]] = {
    "scenario": ((dict, _NONE), "an object or null"),
    "summary": ((dict,), "an object"),
    "timing": ((dict,), "an object"),
    "worker": ((str, _NONE), "a text or null"),
    "parts": ((list,), "a list of table names"),
    "bytes": ((int,), "a whole number >= 0"),
    "error": ((str, _NONE), "a text or null"),
    "traceback": ((str, _NONE), "a text or null"),
}


def check_compatible(header: Mapping[str, Any], wanted: Mapping[str, Any], ds: Path) -> None:
    """Raise GenerateError unless data set ``ds`` (its ``header``) was made like ``wanted``:
    same format version, tlm version, simulator source, seed and settings."""
    if header.get("format_version") != FORMAT_VERSION:
        raise GenerateError(f"{ds} has data set format version {header.get('format_version')}; "
                            f"this tlm writes version {FORMAT_VERSION}; use another --out")
    for key, what in (("tlm_version", "tlm version"), ("sim_source", "simulator source")):
        if header.get(key) != wanted.get(key):
            raise GenerateError(f"{ds} was made with {what} {header.get(key)} (this tlm: "
                                f"{wanted.get(key)}), whose flights differ; use another --out")
    if header.get("seed") != wanted.get("seed"):
        raise GenerateError(f"{ds} was made with --seed {header.get('seed')} (this run: "
                            f"{wanted.get('seed')}); use another --out, or the same settings "
                            "to continue it")
    old, new = header.get("settings", {}), wanted.get("settings", {})
    for key in sorted(set(old) | set(new)):
        if old.get(key) != new.get(key):
            detail = _first_difference(old.get(key), new.get(key), key)
            raise GenerateError(f"{ds} was made with other settings ({detail}); use another "
                                "--out, or the same settings to continue it")


def _first_difference(a: Any, b: Any, where: str) -> str:
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        for k in sorted(set(a) | set(b), key=str):
            if a.get(k) != b.get(k):
                return _first_difference(a.get(k), b.get(k), f"{where}.{k}")
    return f"{where}: {json.dumps(a)} there, {json.dumps(b)} now"


def read_journal(ds: Path) -> tuple[dict[int, dict[str, Any]], int]:
    """The last journal entry of every flight, and how many lines could not be read (a line
    cut short by a hard kill: skipped).

    Raises GenerateError for a line that is JSON but not a journal entry (a hand-edited line
    with a value of the wrong type): it names the line."""
    path = ds / JOURNAL
    entries: dict[int, dict[str, Any]] = {}
    bad = 0
    if not path.exists():
        return entries, 0
    with path.open("rb") as fh:  # bytes: a line that is not UTF-8 is one bad line
        for number, line in enumerate(fh, 1):
            line = line.strip()
            if not line:
                continue
            try:
                rec = json.loads(line)
            except ValueError:  # JSONDecodeError or UnicodeDecodeError
                bad += 1  # cut short by a hard kill
                continue
            _check_entry(rec, f"{path} line {number}")
            entries[rec["flight"]] = rec
    return entries, bad


def _check_entry(rec: Any, where: str) -> None:
    """Raise GenerateError unless ``rec`` is a journal entry (a hand-edited line)."""
    fix = ("fix or delete the line (tlm generate then flies that flight again)")
    if not isinstance(rec, dict):
        raise GenerateError(f"{where}: a journal entry must be an object, got "
                            f"{type(rec).__name__}; {fix}")
    if not _is(rec.get("flight"), (int,)):
        raise GenerateError(f"{where}: 'flight' must be a whole number >= 0, got "
                            f"{json.dumps(rec.get('flight'))}; {fix}")
    if rec.get("status") not in ("ok", "failed"):
        raise GenerateError(f"{where}: 'status' must be \"ok\" or \"failed\", got "
                            f"{json.dumps(rec.get('status'))}; {fix}")
    for key, (kinds, what) in _ENTRY_FIELDS.items():
        if key in rec and not _is(rec[key], kinds):
            raise GenerateError(f"{where}: {key!r} must be {what}, got "
                                f"{json.dumps(rec[key])[:60]}; {fix}")
    if not all(isinstance(p, str) for p in rec.get("parts") or []):
        raise GenerateError(f"{where}: 'parts' must be a list of table names; {fix}")
    if rec["status"] == "ok" and not isinstance(rec.get("scenario"), dict):
        raise GenerateError(f"{where}: a finished flight needs its 'scenario' object; {fix}")


#: The frame and wind columns of manifest.parquet (:func:`manifest_frame`), as
#: :func:`~tlm_process.generate.scenario.flight_conditions` gives them.
CONDITION_COLUMNS: tuple[str, ...] = ("frame", "frame_class", "frame_type", "calm", "wind_spd",
                                      "wind_dir", "wind_turb", "vibration")


def manifest_frame(entries: Mapping[int, Mapping[str, Any]]) -> pd.DataFrame:
    """One row per flight: status, kind, seeds, mission, frame (``frame`` name,
    ``frame_class``, ``frame_type``), wind (``calm``; ``wind_spd`` m/s, ``wind_dir`` deg
    (empty when calm), ``wind_turb`` m/s: the SIM_WIND_* values flown), ``vibration``
    (``real`` or ``quiet`` airframe), faults, λ, duration,
    landing, why the flight ended (``end_reason``: ``landed``, ``crash``, ``time_cap`` or
    ``not_armed``, see
    :data:`tlm_sim.flight.END_REASONS`), timings, error, scenario (JSON)."""
    rows = []
    for flight in sorted(entries):
        e = entries[flight]
        sc, sm, tm = (_obj(e.get(k)) for k in ("scenario", "summary", "timing"))
        m = _obj(sc.get("mission"))
        mission = _mission_name(m)
        cond = (flight_conditions(_obj(sc.get("params"))) if sc
                else dict.fromkeys(CONDITION_COLUMNS))
        rows.append({
            "flight": flight,
            "status": e.get("status"),
            "kind": sc.get("kind"),
            "seed": sc.get("seed"),
            "mission": mission,
            **{c: cond[c] for c in CONDITION_COLUMNS},
            "faults": ",".join(str(_obj(f).get("fault"))
                               for f in _list(_obj(sc.get("faults")).get("faults"))),
            "faults_recorded": ",".join(str(f) for f in _list(sm.get("faults"))),
            "lam": sc.get("lam", math.nan),
            "duration_s": sm.get("duration_s", math.nan),
            "waypoints_reached": sm.get("waypoints_reached"),
            "landed": sm.get("landed"),
            "end_reason": sm.get("end_reason"),
            "gps_rows": sm.get("gps_rows"),
            "gps_fault_rows": sm.get("gps_fault_rows"),
            "wall_s": tm.get("total_s", math.nan),
            "fly_s": tm.get("fly_s", math.nan),
            "worker": e.get("worker"),
            "error": e.get("error"),
            "scenario": json.dumps(sc, sort_keys=True),
        })
    cols = ["flight", "status", "kind", "seed", "mission", *CONDITION_COLUMNS, "faults",
            "faults_recorded", "lam", "duration_s", "waypoints_reached", "landed", "end_reason",
            "gps_rows", "gps_fault_rows", "wall_s", "fly_s", "worker", "error", "scenario"]
    df = pd.DataFrame(rows, columns=cols)
    for c in ("flight", "seed", "waypoints_reached", "gps_rows", "gps_fault_rows",
              "frame_class", "frame_type"):
        df[c] = pd.to_numeric(df[c], errors="coerce").round().astype("Int64")
    for c in ("lam", "duration_s", "wall_s", "fly_s", "wind_spd", "wind_dir", "wind_turb"):
        df[c] = pd.to_numeric(df[c], errors="coerce").astype("float64")
    for c in ("kind", "mission", "frame", "vibration", "worker", "error"):  # None, not NaN
        df[c] = df[c].map(lambda v: None if v is None or v != v else str(v))
    for c in ("landed", "calm"):
        df[c] = df[c].map(lambda v: v if isinstance(v, bool) else pd.NA).astype("boolean")
    return df


def _mission_name(m: Mapping[str, Any]) -> str | None:
    """The manifest's ``mission`` of a recipe: ``builtin-K``, ``random-SEED`` or, for a
    pilot-flown flight, ``pilot-MODE-PATTERN``."""
    if not m:
        return None
    if m.get("source") == "builtin":
        return f"builtin-{m.get('id')}"
    if m.get("source") == "pilot":
        p = _obj(m.get("pilot"))
        return f"pilot-{p.get('mode')}-{p.get('pattern')}"
    return f"random-{m.get('seed')}"


def _obj(v: Any) -> dict[str, Any]:
    """``v`` when it is a JSON object, else an empty one (a hand-edited journal value)."""
    return v if isinstance(v, dict) else {}


def _list(v: Any) -> list[Any]:
    return v if isinstance(v, list) else []


def scenario_from_manifest(ds: str | os.PathLike, flight: int, *,
                           strict: bool = True) -> FlightSpec:
    """``(mission, schedule, params, seed, profile, sticks)`` of flight ``flight`` of data set
    ``ds``, to fly it again alone (``tlm_sim.fly(*spec[:5], sticks=spec.sticks)`` gives the
    tables the data set holds).

    Raises GenerateError: not a data set, no such flight, or (``strict``) a data set made by
    another simulator source, whose flights would not come out the same."""
    root = Path(ds)
    header = read_header(root)
    if header is None:
        raise GenerateError(f"{root} is not a tlm data set (no {HEADER})")
    if isinstance(flight, bool) or not isinstance(flight, int) or flight < 0:
        raise GenerateError(f"--flight must be a whole number >= 0, got {flight!r}")
    entries, _ = read_journal(root)
    entry = entries.get(flight)
    if entry is None or not entry.get("scenario"):
        n = int(header.get("flights") or 0)
        raise GenerateError(f"{root} has no flight {flight} (flights 0..{max(n - 1, 0)}, "
                            f"{len(entries)} of them finished)")
    fp = sim_fingerprint()
    if strict and header.get("sim_source") != fp["sim_source"]:
        raise GenerateError(f"{root} was made by another simulator source "
                            f"({header.get('sim_source')}; this tlm: {fp['sim_source']}): "
                            "its flights would not come out the same")
    try:
        return Scenario.from_dict(entry["scenario"]).realise()
    except Exception as exc:  # noqa: BLE001 - a hand-edited scenario: any error, one line
        why = (str(exc) if isinstance(exc, GenerateError)
               else f"{type(exc).__name__}: {exc}".splitlines()[0][:200])
        raise GenerateError(f"{root} flight {flight}: its scenario in the journal cannot be "
                            f"flown ({why})") from None
