"""``DS/report.json`` and the text ``tlm process`` prints.

report.json keys: ``format`` ("tlm.process"), ``tables``, ``features`` (table -> feature
columns), ``non_feature_columns``, ``dropped_columns`` (table -> column -> reason),
``counts`` (table -> label "0".."4", and each other label present, and "total" -> rows),
``counts_by_split``, ``fault_share``
(α per table), ``split`` (train/test flight ids), ``scaling``, ``options`` (anchoring, phase,
instance, rc_label), ``flights`` (per flight: source, windows, rows per fault, anchoring
disagreement) and, when a target γ is given, ``stretching`` (λ per table).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import pandas as pd

from tlm_process.pipeline.dataset import Dataset, ProcessedFlight
from tlm_process.pipeline.features import DROP, INSTANCE_COLUMN, NON_FEATURE, TIME_COLUMNS
from tlm_process.pipeline.stretching import class_counts, fault_share, lambda_for_target

__all__ = ["REPORT_FORMAT", "build_report", "counts_dict", "flight_lines", "stretching_report"]

REPORT_FORMAT = "tlm.process"
#: the report.json (processed data set) version this tlm writes and the newest it reads
REPORT_VERSION = 1


def stretching_report(alpha: Mapping[str, float], gamma: float) -> dict[str, Any]:
    """λ per table to reach fault share ``gamma`` (Eq. 5, both models)."""
    out: dict[str, Any] = {"target_fault_ratio": gamma, "lambda": {}, "lambda_added": {}}
    for t, a in alpha.items():
        ok = 0 < a < 1
        out["lambda"][t] = round(lambda_for_target(a, gamma), 4) if ok else None
        out["lambda_added"][t] = round(lambda_for_target(a, gamma, "added"), 4) if ok else None
    out["note"] = ("lambda: Eq. 5 as printed (gamma = alpha * lambda, flight length fixed); "
                   "lambda_added: if the extra fault time adds to the flight")
    return out


def counts_dict(counts: pd.DataFrame) -> dict[str, dict[str, int]]:
    """``{table: {"0": n, ..., "4": n, "total": n}}`` from a class_counts table (one key per
    class column: the label as text)."""
    from tlm_process.labels import class_column

    label_of = {class_column(k): k for k in range(256)}
    out = {}
    for name, row in counts.iterrows():
        d = {str(label_of[c]): int(row[c]) for c in counts.columns if c != "Total"}
        d["total"] = int(row["Total"])
        out[str(name)] = d
    return out


def build_report(ds: Dataset, extra: Mapping[str, Any]) -> dict[str, Any]:
    """The report.json document of a data set (``extra`` is merged in at the top level)."""
    counts = ds.counts
    alpha = fault_share(counts)
    by_split = {}
    for split in ("train", "test"):
        sub = {n: df[df["split"] == split] for n, df in ds.tables.items()}
        by_split[split] = counts_dict(class_counts(sub))
    rep: dict[str, Any] = {
        "format": REPORT_FORMAT,
        "version": REPORT_VERSION,
        "tables": list(ds.tables),
        "features": ds.features,
        "non_feature_columns": [*NON_FEATURE, "split"],
        "dropped_columns": {
            t: {**{c: r for c, r in DROP[t].items()}, **dict(TIME_COLUMNS)} for t in ds.tables},
        "instance": {"kept": ds.options.get("instance", 0),
                     "columns": {t: c for t, c in INSTANCE_COLUMN.items() if t in ds.tables}},
        "counts": counts_dict(counts),
        "counts_by_split": by_split,
        "fault_share": {t: (None if math.isnan(a) else round(float(a), 6))
                        for t, a in alpha.items()},
        "split": {"train": ds.train, "test": ds.test,
                  **{k: ds.options[k] for k in ("test_frac", "seed", "test_patterns")
                     if k in ds.options}},
        "scaling": {"method": "min-max (paper Eq. 6)", "fitted_on": "train flights",
                    "applied": bool(ds.options.get("scaled", True)), "file": "scaler.json",
                    "constant_features": ds.scaler.constant_features() if ds.scaler else {}},
        "options": {k: v for k, v in ds.options.items()
                    if k not in ("test_frac", "seed", "test_patterns", "scaled")},
        "flights": ds.flights,
    }
    rep.update(extra)
    return rep


def flight_lines(p: ProcessedFlight) -> list[str]:
    """Indented lines about one processed flight: its windows and how far the paper's
    position method is from the recorded times."""
    lines = []
    for w in p.windows:
        end = "end of log" if not math.isfinite(w.end_us) else f"{w.end_us * 1e-6:.2f} s"
        lines.append(f"    {w.type:<6} label {w.label}  {w.start_us * 1e-6:8.2f} s - {end:>10}"
                     f"  (by {w.method})")
    for c in p.comparison:
        text = (f"    position method vs recorded time, {c.type}: start {c.dt_start_s:+.2f} s "
                f"({c.rows_start:+d} GPS rows)")
        if c.dt_end_s is not None:
            text += f", end {c.dt_end_s:+.2f} s ({c.rows_end:+d} rows)"
            if c.offset_end_m is not None and c.offset_end_m > 20:
                text += f"; recorded end position {c.offset_end_m:.0f} m from the GPS"
        lines.append(text)
    return lines
