"""Read flights for the TLM pipeline: tables (ArduPilot names) plus Eq. 4 fault records.

Kinds of input (:func:`detect_kind` decides from the path):

* ``"tlm"`` — a ``tlm fly`` output folder: ``DIR/meta.json`` (``"format": "tlm.flightlog"``)
  and ``DIR/<NAME>.parquet`` / ``.csv``; records from ``meta.json`` (``DIR/faults.json`` holds
  the same).
* ``"bin"`` — an ArduPilot DataFlash ``X.bin`` with its sidecar ``X.json`` beside it (the
  reference SITL layout: ``{"faults": [...], "sitl": {"home": [lat, lon, alt, hdg]}}``), of
  any firmware: read through :mod:`tlm_process.logread` (Copter 3.x's ``TimeMS`` as
  ``TimeUS``, ``IMU2``/``IMU3`` as ``IMU`` rows with ``I`` 1/2). ``"log"`` — the same as a
  DataFlash text log ``X.log``.
* ``"csv"`` — a folder of per-message CSVs with ArduPilot column names (``DIR/GPS.csv``,
  ``DIR/IMU.csv``, ...; a leading ``timestamp`` column as ``mavlogdump.py --format csv``
  writes is allowed) and ``DIR/faults.json`` (``{"faults": [...]}`` or a bare list; ``[]`` for
  a normal flight).
* ``"dataset"`` — a multi-flight dataset: ``DS/<NAME>.parquet`` with a ``flight`` column and
  ``DS/faults.parquet`` with one row per fault record (``flight`` plus the record keys
  below). Each flight becomes one :class:`Flight`. A ``tlm generate`` data set (it has
  ``DS/manifest.json``) is read through :mod:`tlm_process.generate.reader`: only the flights
  its journal lists as finished, and only when it is complete unless ``partial``.
* a plain folder holding any of the above (``*.bin`` with sidecars, flight folders,
  datasets) is expanded one level.

A fault record (:class:`FaultRecord`) needs ``type`` (``gps``/``accel``/``engine``/``rc`` or
any other ``tlm_sim.faults.FAULT_TYPES`` name) or its ``label`` (1-14, or a registered
type's), and a start and an end given as log times (``start_time_us`` / ``end_time_us``,
microseconds since boot, as tlm and the SITL sidecars write) and/or as positions
(``start_lat``, ``start_lon``, ``start_alt`` ... with the altitude in metres above home, as the
paper recorded them). A record without any end (or ``"end_by": "flight end"``) is held until
the log ends.

Adding an input kind: write ``_read_<kind>(path) -> list[Flight]``, teach
:func:`detect_kind` to recognise it and add it to ``_READERS``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from tlm_process.pipeline.errors import IngestError
from tlm_sim import ardupilot as AP
from tlm_sim.faults.types import FAULT_TYPES, type_of_label
from tlm_sim.textfile import TextFileError, read_text

__all__ = [
    "AUX_TABLES",
    "DATA_TABLES",
    "FaultRecord",
    "Flight",
    "detect_kind",
    "expand_inputs",
    "parse_records",
    "read_dataset",
    "read_flight",
    "read_flights",
    "unique_ids",
]

#: The tables the pipeline turns into data sets (paper Table 5).
DATA_TABLES: tuple[str, ...] = ("GPS", "IMU", "RATE", "VIBE")
#: Tables read as well when present: POS (EKF position: home altitude), EV (arm/disarm: the
#: flight phase), ATT (attitude, for the per-fault plots), MODE (flight modes, for reports).
AUX_TABLES: tuple[str, ...] = ("POS", "EV", "ATT", "MODE")

_POS_KEYS = ("lat", "lon", "alt")


@dataclass(frozen=True, slots=True)
class FaultRecord:
    """One Eq. 4 record: a fault's type and when/where it started and ended.

    ``start_time_us`` / ``end_time_us``: log time (µs since boot) or None when not recorded.
    ``start_pos`` / ``end_pos``: (lat [deg], lon [deg], alt [m above home]) as a ground
    station records it (the vehicle's estimate), or None. ``held_to_end``: the fault was never
    cleared (it lasts until the log ends; ``end_*`` then say where the log ended, if given).
    ``index``: position of the record in the flight's list (0-based).
    """

    index: int
    type: str
    label: int
    start_time_us: int | None
    end_time_us: int | None
    start_pos: tuple[float, float, float] | None
    end_pos: tuple[float, float, float] | None
    held_to_end: bool = False

    @property
    def name(self) -> str:
        """``fault N (TYPE)``, as messages name it (N = index + 1: faults count from 1)."""
        return f"fault {self.index + 1} ({self.type})"

    @property
    def has_times(self) -> bool:
        """Whether the log times of both boundaries are recorded (a held fault needs only
        its start)."""
        return self.start_time_us is not None and (
            self.end_time_us is not None or self.held_to_end)

    @property
    def has_positions(self) -> bool:
        """Whether the positions of both boundaries are recorded (a held fault needs only its
        start)."""
        return self.start_pos is not None and (self.end_pos is not None or self.held_to_end)


@dataclass(slots=True)
class Flight:
    """One flight as the pipeline sees it.

    ``id``: unique name in a data set, containing the source's file or folder name
    (``combined_s21``). ``tables``: message name -> DataFrame (ArduPilot columns, TimeUS in
    µs since boot; instances as rows). ``records``: the Eq. 4 fault records in the order the
    faults happened. ``home``: (lat, lon, alt AMSL [m]) when the source says it, else None.
    """

    id: str
    source: str
    kind: str
    tables: dict[str, pd.DataFrame]
    records: list[FaultRecord]
    home: tuple[float, float, float] | None = None
    meta: dict[str, Any] = field(default_factory=dict)

    @property
    def unlabelled(self) -> bool:
        """Whether nothing labels the flight's faults: a log with no sidecar, no
        ``faults.json`` and no fault records of its own (``meta["labels_source"]`` None), so
        it would be taken as a normal flight by default. Other sources always carry labels."""
        return "labels_source" in self.meta and self.meta["labels_source"] is None


# --------------------------------------------------------------------------------------------
# Fault records
# --------------------------------------------------------------------------------------------

def _number(x: Any) -> float | None:
    if x is None or isinstance(x, bool):
        return None
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def _position(d: Mapping[str, Any], edge: str, where: str) -> tuple[float, float, float] | None:
    vals = [_number(d.get(f"{edge}_{k}")) for k in _POS_KEYS]
    if all(v is None for v in vals):
        return None
    if any(v is None for v in vals):
        raise IngestError(f"{where}: {edge} position needs {edge}_lat, {edge}_lon and "
                          f"{edge}_alt (numbers)")
    lat, lon, alt = vals
    assert lat is not None and lon is not None and alt is not None
    if not (-90 <= lat <= 90 and -180 <= lon <= 180):
        raise IngestError(f"{where}: {edge} position ({lat}, {lon}) is not a lat/lon in degrees")
    return lat, lon, alt


def _time_us(d: Mapping[str, Any], key: str, where: str) -> int | None:
    raw = d.get(key)
    if raw is None:
        return None
    v = _number(raw)
    if v is None or v < 0:
        raise IngestError(f"{where}: {key} must be microseconds since boot >= 0, got {raw!r}")
    return int(round(v))


def _label_range() -> str:
    """The registered fault labels as ``lowest-highest``."""
    labels = [t.label for t in FAULT_TYPES.values()]
    return f"{min(labels)}-{max(labels)}"


def _record(d: Any, index: int, source: str) -> FaultRecord:
    where = f"fault {index + 1}"
    if not isinstance(d, Mapping):
        raise IngestError(f"{where}: expected a mapping, got {type(d).__name__}", source=source)
    try:
        name = d.get("type", d.get("fault"))
        label = d.get("label")
        if name is None and label is None:
            raise IngestError(f"{where}: needs 'type' (gps, accel, engine, rc, ...: "
                              f"tlm_sim.faults.FAULT_TYPES) or 'label' ({_label_range()})")
        if name is not None:
            ftype = FAULT_TYPES.get(str(name).strip().lower())
            if ftype is None:
                raise IngestError(f"{where}: unknown fault type {name!r}; known: "
                                  f"{', '.join(FAULT_TYPES)}")
            if label is not None and _number(label) != ftype.label:
                raise IngestError(f"{where} ({ftype.name}): label {label!r} does not match the "
                                  f"type (Table 6: {ftype.name} is {ftype.label})")
        else:
            lab = _number(label)
            found = type_of_label(int(lab)) if lab is not None and lab == int(lab) else None
            if found is None:
                raise IngestError(f"{where}: label {label!r} is not a fault label "
                                  f"({_label_range()})")
            ftype = found
        where = f"fault {index + 1} ({ftype.name})"
        t0 = _time_us(d, "start_time_us", where)
        t1 = _time_us(d, "end_time_us", where)
        p0 = _position(d, "start", where)
        p1 = _position(d, "end", where)
        held = str(d.get("end_by", "")).strip().lower() == "flight end" or (
            t1 is None and p1 is None and d.get("end") is None)
        if t0 is None and p0 is None:
            raise IngestError(f"{where}: no start: give start_time_us (µs since boot) or "
                              "start_lat/start_lon/start_alt")
        if t0 is not None and t1 is not None and t1 <= t0 and not held:
            raise IngestError(f"{where}: end_time_us {t1} is not after start_time_us {t0}")
    except IngestError as exc:
        raise IngestError(exc.reason, source=source) from None
    return FaultRecord(index, ftype.name, ftype.label, t0, t1, p0, p1, held)


def parse_records(records: Any, source: str = "") -> list[FaultRecord]:
    """Fault records from a list of dicts (or ``{"faults": [...]}``) as tlm, the SITL
    sidecars or a user's faults.json write them; see the module docstring for the keys."""
    if isinstance(records, Mapping):
        if "faults" not in records:
            raise IngestError("no 'faults' list in the fault records", source=source or None)
        records = records["faults"]
    if records is None:
        records = []
    if isinstance(records, str | bytes) or not isinstance(records, Sequence):
        raise IngestError(f"the fault records must be a list, got {type(records).__name__}",
                          source=source or None)
    return [_record(r, i, source or "faults") for i, r in enumerate(records)]


def _read_json(path: Path) -> Any:
    try:
        return json.loads(read_text(path))
    except TextFileError as exc:
        raise IngestError(f"cannot read: {exc}", source=str(path)) from None
    except json.JSONDecodeError as exc:
        raise IngestError(f"invalid JSON: {exc}", source=str(path)) from None
    except RecursionError:
        raise IngestError("invalid JSON: nested too deeply", source=str(path)) from None


# --------------------------------------------------------------------------------------------
# Readers, one per kind
# --------------------------------------------------------------------------------------------

def _require_gps(tables: Mapping[str, pd.DataFrame], source: str) -> None:
    gps = tables.get("GPS")
    if gps is None or not len(gps):
        raise IngestError("the log has no GPS rows (the GPS table anchors the fault windows "
                          "and is one of the data tables)", source=source)


def _read_tlm(path: Path) -> list[Flight]:
    from tlm_sim.flightlog import FlightLog

    try:
        log = FlightLog.read(path)
    except (OSError, ValueError, KeyError) as exc:
        raise IngestError(f"cannot read the tlm flight folder: {exc}", source=str(path)) from None
    want = DATA_TABLES + AUX_TABLES
    tables = {n: df for n, df in log.tables.items() if n in want}
    _require_gps(tables, str(path))
    faults: Any = log.faults
    if not faults and (path / "faults.json").exists():
        faults = _read_json(path / "faults.json")
    home = log.meta.get("home")
    return [Flight(path.name, str(path), "tlm", tables, parse_records(faults, str(path)),
                   _home(home), {"seed": log.meta.get("seed"),
                                 "mission": log.meta.get("mission")})]


def _home(home: Any) -> tuple[float, float, float] | None:
    if not isinstance(home, Sequence) or len(home) < 3:
        return None
    vals = [_number(v) for v in home[:3]]
    if any(v is None for v in vals):
        return None
    return vals[0], vals[1], vals[2]  # type: ignore[return-value]


def _records_in_log(raw: Mapping[str, pd.DataFrame]) -> dict[str, Any]:
    """The fault records a log holds itself (``tlm_sim.faults.detect.faults_in_log``): tlm's
    own "tlm: fault TYPE (label N) start/end" MSG lines, else the SIM_* parameter changes of
    its PARM messages (a SITL log)."""
    from tlm_sim.faults.detect import faults_in_log
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    parm = raw.get("PARM")
    changes = (param_changes_from_parm(parm, exclude=())
               if parm is not None and len(parm) else None)
    return {"faults": [{k: f[k] for k in ("type", "label", "start_time_us", "end_time_us")}
                       for f in faults_in_log(raw.get("MSG"), changes)]}


#: tables read for the armed phase of a log without an arming event (EV 10), besides EV
_ARMING_TABLES: tuple[str, ...] = ("ARM", "RCOU")


def _read_bin(path: Path) -> list[Flight]:
    """A DataFlash log: a ``.bin`` of any firmware or a DataFlash text ``.log``, read through
    :func:`tlm_process.logread.read_log_tables` (Copter 3.x's TimeMS as TimeUS, IMU2/IMU3 as
    IMU rows with I 1/2; a 4.x log's tables exactly as logged). Its fault records: the sidecar
    ``LOG.json`` beside it, else tlm fly's ``faults.json`` in the same folder, else what the
    log holds itself (tlm's fault MSG lines, or a SITL log's SIM_* parameter changes); none
    found: a normal flight.

    A log without an EV 10 (ARMED) event, e.g. one that starts at arming (``LOG_DISARMED
    0``), takes its armed phase from :func:`tlm_process.logread.arming_time_us` (ARM, or the
    motor outputs) and :func:`~tlm_process.logread.disarm_time_us`: ``meta["armed_span_us"]``
    and ``meta["armed_source"]`` (:func:`tlm_process.pipeline.anchoring.flight_armed_span_us`
    reads them)."""
    from tlm_process.logread import (
        LogReadError,
        arming_time_us,
        disarm_time_us,
        read_log_tables,
        warn_damage,
    )
    from tlm_sim.flightlog.sidecar import fault_sidecar

    sidecar = fault_sidecar(path)
    try:
        lt = read_log_tables(path, DATA_TABLES + AUX_TABLES + ("MSG", "PARM") + _ARMING_TABLES)
    except (OSError, ValueError, KeyError, IndexError) as exc:
        reason = str(exc).removeprefix(f"{path}: ") if isinstance(exc, LogReadError) else exc
        raise IngestError(f"cannot read the DataFlash log: {reason}",
                          source=str(path)) from None
    warn_damage(lt)  # a cut-off or corrupt log: one "tlm: warning:" line, as read_bin gave
    raw = lt.tables
    if sidecar is not None:
        doc, source = _read_json(sidecar), str(sidecar)
    else:
        doc, source = _records_in_log(raw), f"{path} (its own MSG/PARM)"
    tables = {n: df for n, df in raw.items() if len(df) and n in DATA_TABLES + AUX_TABLES}
    _require_gps(tables, str(path))
    home = _home((doc.get("sitl") or {}).get("home")) if isinstance(doc, Mapping) else None
    meta = {k: doc.get(k) for k in ("scenario", "seed")} if isinstance(doc, Mapping) else {}
    # where the fault labels came from: the sidecar, the log's own fault records, or None
    # when neither holds any (taken as a normal flight; tlm evaluate --test-on asks first)
    meta["labels_source"] = str(sidecar) if sidecar is not None else (
        "log" if doc["faults"] else None)
    ev = raw.get("EV")
    if ev is None or "Id" not in ev.columns or not (ev["Id"] == AP.EV_ARMED).any():
        t0, src = arming_time_us(raw, lt.params)
        meta["armed_source"] = src
        if t0 is not None:
            t1, end_src = disarm_time_us(raw, lt.params, t0)
            meta["armed_span_us"] = [t0, t1]
            meta["disarm_source"] = end_src
    notes = [n for n in lt.notes if not n.startswith("damage: ")]
    if notes:  # what logread normalised (Copter 3.x, text logs)
        meta["normalised"] = notes
    return [Flight(path.stem, str(path), "log" if lt.kind == "text" else "bin", tables,
                   parse_records(doc, source), home, meta)]


def _read_table_file(path: Path) -> pd.DataFrame:
    try:
        if path.suffix == ".parquet":
            return pd.read_parquet(path)
        return pd.read_csv(path, skipinitialspace=True)
    except (OSError, ValueError) as exc:
        raise IngestError(f"cannot read table: {exc}", source=str(path)) from None


def _read_csv_folder(path: Path) -> list[Flight]:
    faults_path = path / "faults.json"
    if not faults_path.exists():
        raise IngestError("no faults.json in the folder (the fault records; "
                          "'{\"faults\": []}' for a normal flight)", source=str(path))
    records = parse_records(_read_json(faults_path), str(faults_path))
    tables = {}
    for name in DATA_TABLES + AUX_TABLES:
        for suffix in (".csv", ".parquet"):
            p = path / f"{name}{suffix}"
            if p.exists():
                df = _read_table_file(p)
                if "TimeUS" not in df.columns:
                    raise IngestError("no TimeUS column (ArduPilot column names expected)",
                                      source=str(p))
                tables[name] = df.sort_values("TimeUS", kind="stable").reset_index(drop=True)
                break
    _require_gps(tables, str(path))
    return [Flight(path.name, str(path), "csv", tables, records)]


def _generated_tables(path: Path, partial: bool, names: Sequence[str]
                      ) -> tuple[pd.DataFrame, dict[str, pd.DataFrame], dict]:
    """Fault records and tables ``names`` (those it has) of a ``tlm generate`` data set,
    through its loader (the committed flights only; a data set that is not complete only
    with ``partial``), and the loader's summary (state, flights read, files ignored)."""
    from tlm_process.generate.errors import GenerateError
    from tlm_process.generate.reader import index_dataset, read_dataset_table

    try:
        idx = index_dataset(path, partial=partial)
        if "faults" not in idx.tables:
            raise IngestError("no faults.parquet in the dataset", source=str(path))
        faults = read_dataset_table(idx, "faults")
        frames = {name: read_dataset_table(idx, name) for name in names if name in idx.tables}
    except GenerateError as exc:
        raise IngestError(str(exc), source=str(path)) from None
    return faults, frames, idx.summary()


def _plain_tables(path: Path, names: Sequence[str]
                  ) -> tuple[pd.DataFrame, dict[str, pd.DataFrame]]:
    """Fault records and tables ``names`` (those it has) of a data set without a tlm
    manifest (single files or folders with a ``flight`` column), read whole."""
    faults = _read_table_file(path / "faults.parquet")
    frames = {}
    for name in names:
        p = path / f"{name}.parquet"
        if p.exists():
            frames[name] = _read_table_file(p)
    return faults, frames


def read_dataset(path: str | Path, *, partial: bool = False,
                 tables: Sequence[str] = DATA_TABLES + AUX_TABLES
                 ) -> tuple[list[Flight], dict | None]:
    """The flights of a multi-flight data set, with the tables ``tables`` it has (default:
    the pipeline's; ``tlm train`` asks for every table its detector reads), and for a ``tlm
    generate`` data set (one with ``manifest.json``) the loader's summary (:meth:`~tlm_process.
    generate.reader.DatasetIndex.summary`; None otherwise). A generated data set is read
    through :mod:`tlm_process.generate.reader`: committed flights only, and one that is not
    complete is refused unless ``partial``."""
    path = Path(path)
    info = None
    if (path / "manifest.json").exists():
        faults, frames, info = _generated_tables(path, partial, tables)
    else:
        faults, frames = _plain_tables(path, tables)
    if len(faults) and "flight" not in faults.columns:
        raise IngestError("faults.parquet has no 'flight' column", source=str(path))
    for name, df in frames.items():
        if "flight" not in df.columns:
            raise IngestError("no 'flight' column (a dataset table holds many flights)",
                              source=str(path / f"{name}.parquet"))
    if "GPS" not in frames:
        raise IngestError("no GPS.parquet in the dataset", source=str(path))
    return _dataset_flights(path, faults, frames), info


def _read_dataset(path: Path) -> list[Flight]:
    return read_dataset(path)[0]


def _dataset_flights(path: Path, faults: pd.DataFrame,
                     frames: dict[str, pd.DataFrame]) -> list[Flight]:
    """One Flight per flight of the GPS table (tables and fault records by ``flight``)."""
    # one pass over each table (a filter per flight would read every table once per flight)
    by_flight = {name: dict(iter(df.groupby("flight", sort=False)))
                 for name, df in frames.items()}
    fault_groups = dict(iter(faults.groupby("flight", sort=False))) if len(faults) else {}
    flights = []
    for fid in sorted(by_flight["GPS"]):
        tables = {}
        for name in frames:
            sub = by_flight[name].get(fid)
            if sub is not None and len(sub):
                tables[name] = sub.drop(columns="flight").reset_index(drop=True)
        recs = fault_groups.get(fid)
        rows = [] if recs is None else recs.drop(columns="flight").to_dict(orient="records")
        dicts = [{k: (None if _is_missing(v) else v) for k, v in r.items()} for r in rows]
        flights.append(Flight(f"{path.name}:{fid}", f"{path}:{fid}", "dataset", tables,
                              parse_records(dicts, f"{path}:{fid}")))
    return flights


def _is_missing(v: Any) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


_READERS = {"tlm": _read_tlm, "bin": _read_bin, "log": _read_bin, "csv": _read_csv_folder,
            "dataset": _read_dataset}


# --------------------------------------------------------------------------------------------
# Detection and expansion
# --------------------------------------------------------------------------------------------

def detect_kind(path: str | Path) -> str | None:
    """The input kind of ``path`` ("tlm", "bin", "log", "csv", "dataset"), "folder" for a
    folder of inputs, or None when it is none of these (see the module docstring)."""
    p = Path(path)
    if p.is_file():
        if p.suffix.lower() == ".bin":
            return "bin"
        if p.suffix.lower() == ".log":
            from tlm_process.logread import is_text_log

            return "log" if is_text_log(p) else None
        return None
    if not p.is_dir():
        return None
    meta = p / "meta.json"
    if meta.exists():
        try:
            if json.loads(meta.read_text()).get("format") == "tlm.flightlog":
                return "tlm"
        except (OSError, ValueError, AttributeError):
            return None
    if ((p / "faults.parquet").exists() and (p / "GPS.parquet").exists()) or (
            (p / "manifest.json").exists() and (p / "flights.jsonl").exists()):
        return "dataset"
    if (p / "GPS.csv").exists() or (p / "GPS.parquet").exists():
        return "csv"
    return "folder"


def _is_processed(p: Path) -> bool:
    rep = p / "report.json"
    if not rep.exists():
        return False
    try:
        return json.loads(rep.read_text()).get("format") == "tlm.process"
    except (OSError, ValueError, AttributeError):
        return False


def expand_inputs(paths: Iterable[str | Path]) -> list[tuple[str, Path]]:
    """``(kind, path)`` of every flight source named by ``paths``; plain folders are expanded
    one level (their ``*.bin`` files and flight folders/datasets, sorted by name)."""
    out: list[tuple[str, Path]] = []
    for raw in paths:
        p = Path(raw)
        if not p.exists():
            raise IngestError("no such file or folder", source=str(p))
        if p.is_dir() and _is_processed(p):
            raise IngestError("is a 'tlm process' output (features only), not raw flights",
                              source=str(p))
        kind = detect_kind(p)
        if kind is None:
            raise IngestError("not a .bin log, a flight folder or a dataset (nor a DataFlash "
                              "text .log)", source=str(p))
        if kind != "folder":
            out.append((kind, p))
            continue
        found = []
        for child in sorted(p.iterdir()):
            k = detect_kind(child)
            if k in _READERS and not (child.is_dir() and _is_processed(child)):
                found.append((k, child))
        if not found:
            raise IngestError("no flights found: expected *.bin (or DataFlash text *.log) logs "
                              "with sidecars, tlm fly folders, CSV folders with faults.json, "
                              "or datasets",
                              source=str(p))
        out.extend(found)
    return out


def read_flights(paths: Iterable[str | Path], *, partial: bool = False) -> list[Flight]:
    """Every flight named by ``paths`` (see :func:`expand_inputs`), with unique ids.
    ``partial``: read the finished flights of a generated data set that is not complete
    (see :func:`read_dataset`)."""
    flights: list[Flight] = []
    for kind, p in expand_inputs(paths):
        flights.extend(read_flight(kind, p, partial=partial))
    return unique_ids(flights)


def unique_ids(flights: list[Flight], seen: dict[str, int] | None = None) -> list[Flight]:
    """Make flight ids unique in place: repeats get ``-2``, ``-3``, ... appended. ``seen``
    (id -> times used) carries over between calls when flights are read one source at a
    time."""
    seen = {} if seen is None else seen
    for f in flights:
        n = seen.get(f.id, 0) + 1
        seen[f.id] = n
        if n > 1:
            f.id = f"{f.id}-{n}"
    return flights


def read_flight(kind: str, path: str | Path, *, partial: bool = False) -> list[Flight]:
    """The flights of one source of a known kind (see :func:`detect_kind`); ``partial``:
    see :func:`read_dataset`."""
    if kind not in _READERS:
        raise IngestError(f"unknown input kind {kind!r}", source=str(path))
    if kind == "dataset":
        return read_dataset(path, partial=partial)[0]
    return _READERS[kind](Path(path))
