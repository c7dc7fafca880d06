"""``tlm detect``'s work: a saved detector over many logs, written as the user reads it.

For each log: ``DIR/<log>/predictions.parquet`` (``TimeUS``, ``p_<class>`` per class,
``label`` the most probable class, ``fault`` the class of the fault found over the row, 0
outside the faults found, and ``true_label`` when the log has a sidecar), ``DIR/<log>/timeline.png``
(:mod:`.plots`); one row per fault found in ``DIR/summary.csv`` (``log``, ``class``,
``label``, ``start_s``, ``end_s``, ``peak_p``, ``also``: other classes predicted briefly
within the same fault; a row with class ``none`` for a log where nothing was found) and, for
logs with sidecars, their scores (row macro-F1 over the labels present, per true fault
whether it was found with the right class and how late).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.detect.channels import needed_columns
from tlm_process.detect.data import DetectError, LogData, read_log
from tlm_process.detect.model import Detector
from tlm_process.detect.predict import Finding, fault_rows, find_faults, log_features, predict_rows
from tlm_process.labels import class_name
from tlm_process.pipeline.errors import PipelineError

__all__ = ["SUMMARY_COLUMNS", "LogResult", "detect_log", "log_folder_name",
           "refuse_missing", "run_detect", "score_log", "write_log_outputs"]

SUMMARY_COLUMNS = ("log", "class", "label", "start_s", "end_s", "peak_p", "also")
#: A true fault counts as found when a finding of its class starts within this of its
#: start [s] (the issue's "start within 3 s"), or inside the window.
FOUND_WITHIN_S: float = 3.0


@dataclass
class LogResult:
    """What ``tlm detect`` found in one log."""

    log: LogData
    findings: list[Finding]
    pred: pd.DataFrame
    missing: list[str] = field(default_factory=list)
    scores: dict[str, Any] = field(default_factory=dict)

    def summary_rows(self) -> list[dict[str, Any]]:
        if not self.findings:
            return [{"log": self.log.source, "class": "none", "label": 0,
                     "start_s": np.nan, "end_s": np.nan, "peak_p": np.nan, "also": ""}]
        return [{"log": self.log.source, "class": f.name, "label": f.label,
                 "start_s": round(f.start_s, 2), "end_s": round(f.end_s, 2),
                 "peak_p": round(f.peak, 3),
                 "also": " ".join(class_name(c) for c in f.also)} for f in self.findings]


def log_folder_name(log: LogData, taken: set[str]) -> str:
    """A folder name for ``log`` under DIR: its file stem, characters other than letters,
    digits, ``._-`` replaced, ``-2``, ``-3`` ... for repeats."""
    base = re.sub(r"[^A-Za-z0-9._-]", "_", log.id) or "log"
    name, k = base, 1
    while name in taken:
        k += 1
        name = f"{base}-{k}"
    taken.add(name)
    return name


def refuse_missing(det: Detector, log: LogData, lacking: Sequence[str]) -> None:
    """Raise :class:`DetectError` naming the log columns ``det`` reads that ``log`` lacks
    (``lacking``) and the ``--drop-features`` that avoids them."""
    need = needed_columns(det.channels)
    chans = sorted({c for col in lacking for c in need.get(col, [])})
    raise DetectError(
        f"the model reads {len(lacking)} log column(s) this log lacks: "
        f"{', '.join(lacking[:8])}{' ...' if len(lacking) > 8 else ''} (channels "
        f"{', '.join(chans[:6])}{' ...' if len(chans) > 6 else ''}); train a model "
        f"without them (tlm train ... --drop-features {','.join(lacking)}) or run with "
        f"--allow-missing", source=log.source)


def detect_log(det: Detector, path: str | Path, *, allow_missing: bool = False) -> LogResult:
    """Read ``path`` and run ``det`` on its armed span (a per-table detector: on the rows of
    its table, processed as its data set's flights were). A log that lacks columns the
    whole-log detector reads is refused (:func:`refuse_missing`) unless ``allow_missing``."""
    if det.kind != "whole-log":
        from tlm_process.detect.table_model import table_log_features

        log, rows, X = table_log_features(det, path)
        time_us, missing = rows["TimeUS"].to_numpy(), []
    else:
        log = read_log(path)
        if log.span_us[1] <= log.span_us[0]:
            raise DetectError("the log's armed span is empty", source=log.source)
        time_us, X, missing = log_features(log, det.channels)
        if missing and not allow_missing:
            refuse_missing(det, log, missing)
    pred = predict_rows(det, time_us, X, log.windows)
    findings = find_faults(pred, det.classes)
    pred.insert(pred.columns.get_loc("label") + 1, "fault",
                fault_rows(pred["TimeUS"].to_numpy(), findings))
    res = LogResult(log, findings, pred, missing)
    if log.windows is not None:
        res.scores = score_log(pred, findings, log)
    return res


def score_log(pred: pd.DataFrame, findings: Sequence[Finding], log: LogData
              ) -> dict[str, Any]:
    """A labelled log's scores: row accuracy and macro-F1 over the labels present, and per
    true fault window whether a finding of its class starts within :data:`FOUND_WITHIN_S`
    of its start (or inside it), with the delay."""
    from sklearn.metrics import f1_score

    yt = pred["true_label"].to_numpy()
    yp = pred["label"].to_numpy()
    present = sorted({int(v) for v in np.unique(yt)})
    faults = []
    for w in log.windows or []:
        s = w.start_us * 1e-6
        e = w.end_us * 1e-6 if np.isfinite(w.end_us) else np.inf
        hits = [f for f in findings if f.label == w.label
                and (abs(f.start_s - s) <= FOUND_WITHIN_S or s <= f.start_s < e)]
        first = min(hits, key=lambda f: f.start_s) if hits else None
        faults.append({"class": class_name(w.label), "label": w.label, "start_s": round(s, 2),
                       "found": first is not None and abs(first.start_s - s)
                       <= FOUND_WITHIN_S,
                       "delay_s": round(first.start_s - s, 2) if first else None})
    return {"rows": len(yt), "accuracy": float((yt == yp).mean()) if len(yt) else None,
            "macro_f1": float(f1_score(yt, yp, labels=present, average="macro",
                                       zero_division=0)) if len(yt) else None,
            "labels": present, "faults": faults}


def write_log_outputs(res: LogResult, folder: Path, classes: Sequence[int],
                      plots: bool) -> None:
    """``folder/predictions.parquet`` and (``plots``) ``folder/timeline.png``."""
    from tlm_process.detect.plots import plot_timeline

    folder.mkdir(parents=True, exist_ok=True)
    res.pred.to_parquet(folder / "predictions.parquet", index=False)
    if plots:
        plot_timeline(res.log, res.pred, classes, res.findings, folder / "timeline.png")


def run_detect(det: Detector, paths: Sequence[str | Path], out: Path, *,
               allow_missing: bool = False, plots: bool = True,
               progress: Callable[[Any], Any] | None = None
               ) -> tuple[list[LogResult], list[str]]:
    """Run ``det`` on every log of ``paths``, write the outputs under ``out`` and
    ``out/summary.csv``; returns the results (predictions dropped after writing) and one
    line per log that could not be used (the others are still done)."""
    taken: set[str] = set()
    results: list[LogResult] = []
    errors: list[str] = []
    rows: list[dict[str, Any]] = []
    it = progress(paths) if progress is not None else paths
    for p in it:
        try:
            res = detect_log(det, p, allow_missing=allow_missing)
        except PipelineError as exc:  # DetectError, or the sidecar's IngestError/AnchorError
            errors.append(str(exc))
            continue
        name = log_folder_name(res.log, taken)
        write_log_outputs(res, out / name, det.classes, plots)
        rows += res.summary_rows()
        res.pred = res.pred.iloc[:0]
        res.log.tables = {}
        results.append(res)
    pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS)).to_csv(out / "summary.csv", index=False)
    return results, errors

