"""Logs for the whole-log detector: every table it reads, the log's parameters, its armed span
and (for training, or a log with a sidecar) its fault windows.

Training reads any input ``tlm process`` reads (a ``tlm generate`` data set, ``.bin`` logs
with their sidecars, ``tlm fly`` folders, folders of these); fault windows are anchored by
the pipeline's own rules (:func:`tlm_process.pipeline.anchoring.anchor_flight`), so a
detector's labels are the data set's. ``tlm detect`` reads any ArduPilot log
(:func:`read_log`), with or without a sidecar.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from tlm_process.detect.channels import align, source_tables
from tlm_process.pipeline.anchoring import FaultWindow, anchor_flight, log_span_us
from tlm_process.pipeline.errors import PipelineError

__all__ = ["DetectError", "LogData", "armed_span", "check_log_path", "read_log",
           "read_training"]


class DetectError(PipelineError):
    """A bad model, log or request for ``tlm train`` / ``tlm detect``: one line, exit 2."""


@dataclass
class LogData:
    """One log as the detector sees it: ``tables`` (ArduPilot names, TimeUS µs since boot,
    instances as rows), ``params`` (the log's PARM, or the flight's drawn parameters),
    ``span_us`` (armed: arming to disarming or the log's end) with where the arming time came
    from, and ``windows``: the fault windows (None when nothing labels the log)."""

    id: str
    source: str
    tables: dict[str, pd.DataFrame]
    params: dict[str, float]
    span_us: tuple[int, int]
    arming: str
    windows: list[FaultWindow] | None = None
    notes: list[str] = field(default_factory=list)


def armed_span(tables: Mapping[str, pd.DataFrame], params: Mapping[str, float]
               ) -> tuple[tuple[int, int], str]:
    """((arming, disarming or the log's end) [µs], where the arming time came from). The
    arming rule is :func:`tlm_process.logread.arming_time_us` (EV 10, ARM, motors above idle);
    a log that never armed spans the whole log ("never armed: whole log")."""
    from tlm_process.logread import arming_time_us, disarm_time_us

    t0, how = arming_time_us(tables, params)
    lo, hi = log_span_us(tables)
    if t0 is None:
        return (lo, hi), "never armed: whole log"
    t1, _ = disarm_time_us(tables, params, t0)
    return (int(t0), int(t1 if t1 is not None else hi)), how


def _generated(path: Path, partial: bool) -> Iterator[LogData]:
    """Flights of a ``tlm generate`` data set (or a plain multi-flight data set), read by the
    pipeline's reader (:func:`tlm_process.pipeline.ingest.read_dataset`) with every table
    the detector reads; parameters from each flight's scenario in ``flights.jsonl``."""
    from tlm_process.pipeline.ingest import read_dataset

    flights, _ = read_dataset(path, partial=partial, tables=source_tables())
    params = _scenario_params(path / "flights.jsonl")
    for fl in flights:
        fid = fl.id.rsplit(":", 1)[1]
        p = params.get(int(fid), {}) if fid.isdigit() else {}
        tables = align(fl.tables)
        span, how = armed_span(tables, p)
        yield LogData(fl.id, fl.source, tables, p, span, how, anchor_flight(fl, "auto"))


def _scenario_params(jsonl: Path) -> dict[int, dict[str, float]]:
    """Flight -> the parameters its scenario drew (FRAME_CLASS, wind, noise), from a ``tlm
    generate`` data set's ``flights.jsonl``; lines that hold none are skipped."""
    params: dict[int, dict[str, float]] = {}
    try:
        lines = jsonl.read_text().splitlines() if jsonl.exists() else []
    except OSError as exc:
        raise DetectError(f"cannot read: {exc.strerror or exc}", source=str(jsonl)) from None
    for line in lines:
        try:
            rec = json.loads(line)
            params[int(rec["flight"])] = {
                k: float(v) for k, v in (rec["scenario"].get("params") or {}).items()}
        except (ValueError, KeyError, TypeError, AttributeError):
            continue
    return params


def _single(kind: str, path: Path) -> Iterator[LogData]:
    """A ``.bin`` or text ``.log`` log or a ``tlm fly`` folder, its fault records as ``tlm
    process`` finds them (sidecar, faults.json, the log's own). A log with no fault labels
    at all is refused: taken as a normal flight it would teach a faulty one as normal."""
    from tlm_process.pipeline.ingest import read_flight

    for fl in read_flight(kind, path):
        if fl.unlabelled:
            raise DetectError("no fault labels (no sidecar LOG.json, no faults.json, no fault "
                              "records in the log): give a normal flight a sidecar with "
                              '{"faults": []}', source=str(path))
        if kind in ("bin", "log"):
            data = read_log(path, labels=False)
            tables, params = data.tables, data.params
        else:
            from tlm_sim.flightlog import FlightLog

            log = FlightLog.read(path)
            tables = align({n: df for n, df in log.tables.items() if len(df)})
            params = {k: float(v) for k, v in (log.params or {}).items()
                      if isinstance(v, int | float)}
        fl.tables = {**tables, **fl.tables}
        span, how = armed_span(tables, params)
        yield LogData(fl.id, fl.source, tables, params, span, how, anchor_flight(fl, "auto"))


def read_training(paths: Sequence[str | Path], *, partial: bool = False) -> Iterator[LogData]:
    """Every labelled flight named by ``paths`` (any ``tlm process`` input), one at a time."""
    from tlm_process.pipeline.ingest import expand_inputs, unique_ids

    seen: dict[str, int] = {}
    for kind, p in expand_inputs(paths):
        if kind == "csv":
            raise DetectError("a CSV folder lacks most tables the detector reads: train on "
                              "tlm generate data sets, .bin logs or tlm fly folders",
                              source=str(p))
        it = _generated(p, partial) if kind == "dataset" else _single(kind, p)
        for log in it:
            unique_ids([log], seen)  # type: ignore[list-item]  # only .id is used
            yield log


def check_log_path(path: str | Path) -> Path:
    """``path`` as a Path; raises :class:`DetectError` when it does not exist or is not a
    file (``tlm detect`` reads log files, never folders)."""
    p = Path(path)
    if not p.exists():
        raise DetectError("no such log", source=str(p))
    if not p.is_file():
        raise DetectError("not a file (expected an ArduPilot .bin or .log)", source=str(p))
    return p


def read_log(path: str | Path, *, labels: bool = True) -> LogData:
    """Any ArduPilot log (``.bin``, or a text ``.log``) for detection: every table the
    detector reads, normalised (:mod:`tlm_process.logread`: TimeMS, IMU2/IMU3, ...), its
    armed span, and with ``labels`` its fault windows when a sidecar ``LOG.json`` (or tlm's
    ``faults.json``, or tlm's fault MSG lines / SITL's SIM_* changes in the log) says them."""
    from tlm_process.logread import read_log_tables, warn_damage

    p = check_log_path(path)
    try:
        lt = read_log_tables(p, source_tables())  # (the parameters always come with them)
    except (OSError, ValueError, KeyError, IndexError) as exc:
        raise DetectError(f"cannot read the log: {exc}", source=str(p)) from None
    warn_damage(lt)
    tables = align({n: df for n, df in lt.tables.items() if len(df)})
    if not tables:
        raise DetectError("the log holds no rows", source=str(p))
    params = dict(lt.params)
    span, how = armed_span(tables, params)
    windows = _log_windows(p, tables) if labels else None
    return LogData(p.stem, str(p), tables, params, span, how, windows, list(lt.notes))


def _log_windows(p: Path, tables: dict[str, pd.DataFrame]) -> list[FaultWindow] | None:
    """The fault windows a sidecar gives (None without one): ``LOG.json``, or tlm's
    ``faults.json`` beside a ``tlm fly --format bin`` log. A log's own MSG/PARM evidence is
    not used (the detector is to find faults, not read them from SITL's parameters)."""
    from tlm_process.pipeline.ingest import Flight, parse_records
    from tlm_sim.flightlog.sidecar import fault_sidecar, load_sidecar_json

    side = fault_sidecar(p)
    if side is None:
        return None
    doc = load_sidecar_json(side)
    recs = parse_records(doc, str(side))
    if "GPS" not in tables:
        return None
    fl = Flight(p.stem, str(p), "bin", tables, recs)
    return anchor_flight(fl, "auto")


def window_labels(time_us: np.ndarray, windows: Sequence[FaultWindow] | None) -> np.ndarray:
    """Label per time (0 outside every window)."""
    from tlm_process.pipeline.anchoring import label_rows

    return label_rows(time_us, windows or [])
