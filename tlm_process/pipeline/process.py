"""The TLM pipeline end to end: flight -> labelled tables -> features -> merged, scaled data set.

:func:`process_flight` anchors one flight's fault windows (Eq. 4), labels every row of every
table, keeps the flight phase asked for and applies Algorithm 2 (:mod:`.features`).
:func:`build_dataset` merges flights per table, splits them into training and test flights,
fits the Eq. 6 scaler on the training flights and scales everything with it.
The data classes (:class:`ProcessOptions`, :class:`ProcessedFlight`, :class:`Dataset`) are
defined in :mod:`.dataset`. :func:`write_dataset` writes ``DS/<TABLE>.parquet``,
``DS/scaler.json`` and ``DS/report.json``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from tlm_process.pipeline.anchoring import (
    anchor_flight,
    compare_methods,
    extend_rc_failsafe,
    flight_armed_span_us,
    home_altitude,
    label_tables,
)
from tlm_process.pipeline.dataset import PHASES, Dataset, ProcessedFlight, ProcessOptions
from tlm_process.pipeline.errors import IngestError, PipelineError
from tlm_process.pipeline.features import feature_table, merge_tables, trim_to_span
from tlm_process.pipeline.ingest import Flight
from tlm_process.pipeline.report import build_report
from tlm_process.pipeline.scaling import MinMaxScaler, split_flights

__all__ = ["PHASES", "Dataset", "ProcessOptions", "ProcessedFlight", "build_dataset",
           "process_flight", "write_dataset"]


def process_flight(flight: Flight, options: ProcessOptions | None = None) -> ProcessedFlight:
    """Anchor (RC windows run on through the radio failsafe with ``rc_label="failsafe"``),
    label, trim to the phase and apply Algorithm 2 to one flight."""
    opt = options or ProcessOptions()
    missing = [t for t in opt.tables if t not in flight.tables or not len(flight.tables[t])]
    if missing:
        raise IngestError(f"no {', '.join(missing)} table(s) in the log", source=flight.source)
    windows = anchor_flight(flight, opt.method, opt.max_match_m)
    if opt.rc_label == "failsafe":
        windows = extend_rc_failsafe(windows, flight.tables, flight.id)
    home_alt = home_src = None
    if any(r.start_pos is not None for r in flight.records):
        home_alt, home_src = home_altitude(flight)
    comparison = compare_methods(flight, home_alt) if home_alt is not None else []
    labelled = label_tables(flight.tables, windows)
    span = flight_armed_span_us(flight) if opt.phase == "armed" else None
    phase = opt.phase if span is not None or opt.phase == "all" else "all (no arming event)"
    labelled = trim_to_span(labelled, span)
    features = {t: feature_table(t, labelled[t], flight.id, opt.instance) for t in opt.tables}
    return ProcessedFlight(flight, windows, comparison, labelled, features, span, phase,
                           home_alt, home_src)


def build_dataset(processed: Sequence[ProcessedFlight], *, test_frac: float = 0.0,
                  seed: int = 0, test_patterns: Sequence[str] = (),
                  scale: bool = True, options: ProcessOptions | None = None) -> Dataset:
    """Merge flights per table, split them (whole flights; see
    :func:`~.scaling.split_flights`), fit the min-max scaler on the training flights and
    scale every table with it (``scale=False`` keeps raw values; the scaler is fitted
    anyway). ``options``: the processing options, recorded in the report."""
    if not processed:
        raise PipelineError("no flights to build a data set from")
    merged = merge_tables([p.features for p in processed])
    ids = [p.flight.id for p in processed]
    train, test = split_flights(ids, test_frac, seed, test_patterns)
    scaler = MinMaxScaler.fit(merged, train)
    tables = scaler.transform(merged) if scale else merged
    test_set = set(test)
    out = {}
    for name, df in tables.items():
        split = df["flight"].map(lambda f: "test" if f in test_set else "train")
        df = df.copy()
        df.insert(1, "split", split.astype("string"))
        out[name] = df
    features = {n: list(scaler.ranges[n]) for n in out}
    opt = options or ProcessOptions()
    return Dataset(out, features, train, test, scaler, [p.summary() for p in processed],
                   {"scaled": scale, "test_frac": test_frac, "seed": seed,
                    "test_patterns": list(test_patterns), "anchoring": opt.method,
                    "max_match_m": opt.max_match_m, "phase": opt.phase,
                    "instance": opt.instance, "rc_label": opt.rc_label})


def write_dataset(ds: Dataset, out: str | os.PathLike,
                  extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write ``OUT/<TABLE>.parquet``, ``OUT/scaler.json`` and ``OUT/report.json``; returns
    the report.

    ``report.json`` is the commit record: an old one is removed before anything else is
    written, every file goes to a hidden temporary name and is renamed into place, and the
    report comes last. A folder killed while being written has no report.json, which
    ``tlm evaluate`` refuses, so old and new tables are never read as one data set."""
    d = Path(out)
    d.mkdir(parents=True, exist_ok=True)
    (d / "report.json").unlink(missing_ok=True)
    for name, df in ds.tables.items():
        _replace_with(d / f"{name}.parquet",
                      lambda fh, df=df: df.to_parquet(fh, index=False, compression="zstd"))
    if ds.scaler is not None:
        ds.scaler.save(d / "scaler.json")
    report = build_report(ds, extra or {})
    text = (json.dumps(report, indent=1) + "\n").encode("utf-8")
    _replace_with(d / "report.json", lambda fh: fh.write(text))
    return report


def _replace_with(path: Path, write: Any) -> None:
    """Write ``path`` atomically: ``write(file)`` fills ``.<name>.tmp``, which is renamed."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with tmp.open("wb") as fh:
            write(fh)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
