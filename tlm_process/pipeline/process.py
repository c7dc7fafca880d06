"""The TLM pipeline end to end: flight -> labelled tables -> features -> merged, scaled data set.

:func:`process_flight` anchors one flight's fault windows (Eq. 4), labels every row of every
table, keeps the flight phase asked for and applies Algorithm 2 (:mod:`.features`).
:func:`build_dataset` merges flights per table, splits them into training and test flights,
fits the Eq. 6 scaler on the training flights and scales everything with it.
:func:`write_dataset` writes ``DS/<TABLE>.parquet``, ``DS/scaler.json`` and
``DS/report.json``.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from tlm_process.pipeline.anchoring import (
    DEFAULT_MAX_MATCH_M,
    AnchorComparison,
    FaultWindow,
    Method,
    anchor_flight,
    armed_span_us,
    compare_methods,
    home_altitude,
    label_tables,
)
from tlm_process.pipeline.errors import IngestError, PipelineError
from tlm_process.pipeline.features import feature_table, merge_tables, trim_to_span
from tlm_process.pipeline.ingest import DATA_TABLES, Flight
from tlm_process.pipeline.scaling import MinMaxScaler, split_flights
from tlm_process.pipeline.stretching import class_counts

__all__ = ["Dataset", "ProcessOptions", "ProcessedFlight", "build_dataset", "process_flight",
           "write_dataset"]

PHASES = ("armed", "all")


@dataclass(frozen=True)
class ProcessOptions:
    """How flights are processed.

    ``method``: anchoring ("auto", "time", "position"; see :mod:`.anchoring`). ``phase``:
    "armed" keeps rows from arming to disarming (EV 10/11) — what a log with ArduPilot's
    default LOG_DISARMED=0 holds, as the paper's did — or "all" rows of the log. ``instance``:
    sensor instance kept (0; None keeps all, see :mod:`.features`). ``max_match_m``: position
    anchoring's "matches nowhere" distance [m]. ``tables``: data tables to build.
    """

    method: Method = "auto"
    phase: str = "armed"
    instance: int | None = 0
    max_match_m: float = DEFAULT_MAX_MATCH_M
    tables: tuple[str, ...] = DATA_TABLES

    def __post_init__(self) -> None:
        if self.phase not in PHASES:
            raise PipelineError(f"unknown phase {self.phase!r}; use {' or '.join(PHASES)}")
        bad = [t for t in self.tables if t not in DATA_TABLES]
        if bad or not self.tables:
            raise PipelineError(f"unknown data table(s) {', '.join(bad) or '(none)'}; choose "
                                f"from {', '.join(DATA_TABLES)}")


@dataclass
class ProcessedFlight:
    """One processed flight: its windows, the anchoring comparison, labelled raw tables (kept
    phase; for plots) and feature tables (``flight, TimeUS, label, features``)."""

    flight: Flight
    windows: list[FaultWindow]
    comparison: list[AnchorComparison]
    labelled: dict[str, pd.DataFrame]
    features: dict[str, pd.DataFrame]
    span_us: tuple[int, int] | None
    phase: str
    home_alt: float | None = None
    home_source: str | None = None

    def release(self) -> None:
        """Drop the raw and labelled tables (kept: windows, features, summary), to hold many
        flights in memory."""
        self.labelled = {}
        self.flight.tables = {}

    def summary(self) -> dict[str, Any]:
        """JSON-ready summary for report.json."""
        f = self.flight
        windows = []
        for w in self.windows:
            d: dict[str, Any] = {
                "index": w.index, "type": w.type, "label": w.label, "method": w.method,
                "start_us": int(w.start_us),
                "end_us": int(w.end_us) if math.isfinite(w.end_us) else None,
                "held_to_end": not math.isfinite(w.end_us),
                "rows": {n: int(((df["TimeUS"] >= w.start_us) & (df["TimeUS"] < w.end_us)).sum())
                         for n, df in self.features.items()},
            }
            windows.append(d)
        return {
            "id": f.id, "source": f.source, "kind": f.kind,
            "phase": self.phase,
            "span_us": list(self.span_us) if self.span_us is not None else None,
            "rows": {n: len(df) for n, df in self.features.items()},
            "home_alt_m": self.home_alt, "home_alt_source": self.home_source,
            "faults": windows,
            "anchoring_disagreement": [c.to_dict() for c in self.comparison],
            **({"meta": f.meta} if f.meta else {}),
        }


def process_flight(flight: Flight, options: ProcessOptions | None = None) -> ProcessedFlight:
    """Anchor, label, trim to the phase and apply Algorithm 2 to one flight."""
    opt = options or ProcessOptions()
    missing = [t for t in opt.tables if t not in flight.tables or not len(flight.tables[t])]
    if missing:
        raise IngestError(f"no {', '.join(missing)} table(s) in the log", source=flight.source)
    windows = anchor_flight(flight, opt.method, opt.max_match_m)
    home_alt = home_src = None
    if any(r.start_pos is not None for r in flight.records):
        home_alt, home_src = home_altitude(flight)
    comparison = compare_methods(flight, home_alt) if home_alt is not None else []
    labelled = label_tables(flight.tables, windows)
    span = armed_span_us(flight.tables) if opt.phase == "armed" else None
    phase = opt.phase if span is not None or opt.phase == "all" else "all (no arming event)"
    labelled = trim_to_span(labelled, span)
    features = {t: feature_table(t, labelled[t], flight.id, opt.instance) for t in opt.tables}
    return ProcessedFlight(flight, windows, comparison, labelled, features, span, phase,
                           home_alt, home_src)


@dataclass
class Dataset:
    """Merged, split and (optionally) scaled tables of many flights, plus what made them."""

    tables: dict[str, pd.DataFrame]
    features: dict[str, list[str]]
    train: list[str]
    test: list[str]
    scaler: MinMaxScaler | None
    flights: list[dict[str, Any]] = field(default_factory=list)
    options: dict[str, Any] = field(default_factory=dict)

    @property
    def counts(self) -> pd.DataFrame:
        """Rows per class and table (paper Table 7 layout)."""
        return class_counts(self.tables)


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
                    "instance": opt.instance})


def counts_dict(counts: pd.DataFrame) -> dict[str, dict[str, int]]:
    """``{table: {"0": n, ..., "4": n, "total": n}}`` from a class_counts table."""
    out = {}
    for name, row in counts.iterrows():
        vals = row.to_numpy()
        d = {str(k): int(vals[k]) for k in range(5)}
        d["total"] = int(vals[5])
        out[str(name)] = d
    return out


def write_dataset(ds: Dataset, out: str | os.PathLike,
                  extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """Write ``OUT/<TABLE>.parquet``, ``OUT/scaler.json`` and ``OUT/report.json``; returns
    the report.

    ``report.json`` is the commit record: an old one is removed before anything else is
    written, every file goes to a hidden temporary name and is renamed into place, and the
    report comes last. A folder killed while being written has no report.json, which
    ``tlm evaluate`` refuses, so old and new tables are never read as one data set."""
    from tlm_process.pipeline.report import build_report

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
