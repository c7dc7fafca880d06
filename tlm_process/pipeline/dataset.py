"""What the TLM pipeline works with: its options, a processed flight, and the data set of
many flights (:mod:`.process` makes them, :mod:`.report` describes them)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import pandas as pd

from tlm_process.pipeline.anchoring import (
    DEFAULT_MAX_MATCH_M,
    RC_LABELS,
    AnchorComparison,
    FaultWindow,
    Method,
)
from tlm_process.pipeline.errors import PipelineError
from tlm_process.pipeline.ingest import DATA_TABLES, Flight
from tlm_process.pipeline.scaling import MinMaxScaler
from tlm_process.pipeline.stretching import class_counts

__all__ = ["PHASES", "Dataset", "ProcessOptions", "ProcessedFlight"]

PHASES = ("armed", "all")


@dataclass(frozen=True)
class ProcessOptions:
    """How flights are processed.

    ``method``: anchoring ("auto", "time", "position"; see :mod:`.anchoring`). ``phase``:
    "armed" keeps rows from arming to disarming (EV 10/11) — what a log with ArduPilot's
    default LOG_DISARMED=0 holds, as the paper's did — or "all" rows of the log. ``instance``:
    sensor instance kept (0; None keeps all, see :mod:`.features`). ``max_match_m``: position
    anchoring's "matches nowhere" distance [m]. ``tables``: data tables to build.
    ``rc_label``: "window" (the paper's: RC rows while the radio is lost) or "failsafe" (also
    the radio failsafe's RTL until it lands; :func:`.anchoring.extend_rc_failsafe`).
    """

    method: Method = "auto"
    phase: str = "armed"
    instance: int | None = 0
    max_match_m: float = DEFAULT_MAX_MATCH_M
    tables: tuple[str, ...] = DATA_TABLES
    rc_label: str = "window"

    @classmethod
    def from_recorded(cls, recorded: Mapping[str, Any], tables: Sequence[str]
                      ) -> ProcessOptions:
        """The options a data set was processed with, from what its report records
        (``report.json["options"]``: ``anchoring``, ``phase``, ``instance``, ``max_match_m``,
        ``rc_label``; a report older than an option had its default), for ``tables``: how a
        log is processed to be seen as the data set's flights were (``tlm evaluate
        --test-on``, a per-table ``tlm detect``)."""
        return cls(method=recorded.get("anchoring", "auto"),
                   phase=recorded.get("phase", "armed"),
                   instance=recorded.get("instance", 0),
                   max_match_m=recorded.get("max_match_m") or DEFAULT_MAX_MATCH_M,
                   tables=tuple(tables), rc_label=recorded.get("rc_label") or "window")

    def __post_init__(self) -> None:
        if self.rc_label not in RC_LABELS:
            raise PipelineError(f"unknown RC labelling {self.rc_label!r}; use "
                                f"{' or '.join(RC_LABELS)}")
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
