"""From a log to the detector's rows, and from per-row probabilities to faults found.

:func:`log_features`: the log's armed span on the :data:`~.channels.GRID_HZ` grid, its
channels and features (the same function at training and detection time, so a model sees a
user's log as it saw its training flights). :func:`predict_rows`: probabilities per class and
the predicted label on every row. :func:`find_faults`: the faults a log holds by the
predictions: runs of one fault class that last at least :data:`MIN_FAULT_S` (a persistence
filter, as :data:`tlm_process.evaluate.events.PERSISTENCE_S`), merged across gaps shorter than
:data:`MERGE_GAP_S`, and runs of several classes that touch taken as one fault named by its
main class. :func:`fault_rows`: the detector's decision per row, the class of the fault found
over it (0 outside every fault found).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.detect.channels import GRID_HZ, armed_grid, channel_table
from tlm_process.detect.data import LogData
from tlm_process.detect.features import feature_matrix
from tlm_process.detect.model import Detector
from tlm_process.evaluate.events import PERSISTENCE_S
from tlm_process.labels import class_name

__all__ = ["MERGE_GAP_S", "MIN_FAULT_S", "Finding", "fault_rows", "find_faults",
           "log_features", "predict_rows"]

#: A fault class must be predicted on consecutive rows covering this long to be reported [s].
MIN_FAULT_S: float = PERSISTENCE_S
#: Runs closer than this are one fault [s] (a jammed GPS regains its fix for a few seconds at
#: a time; faults that follow each other in tlm generate's sequences are 15 s apart or more).
MERGE_GAP_S: float = 5.0


def log_features(log: LogData, channels: Sequence[str]
                 ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(grid times [µs since boot], feature matrix, log columns the log lacks for
    ``channels``) of ``log``'s armed span."""
    grid = armed_grid(*log.span_us, GRID_HZ)
    table, lacking = channel_table(log.tables, log.params, channels, grid)
    return grid, feature_matrix(table, channels, GRID_HZ), lacking


def predict_rows(detector: Detector, time_us: np.ndarray, X: np.ndarray,
                 windows: Sequence[Any] | None) -> pd.DataFrame:
    """``TimeUS``, ``p_<class>``, ``label`` (and ``true_label`` when ``windows`` is not
    None) of rows at ``time_us`` with features ``X``."""
    from tlm_process.detect.data import window_labels

    p = detector.predict_proba(X)
    classes = np.asarray(detector.classes)
    out = pd.DataFrame({"TimeUS": np.asarray(time_us, dtype=np.int64)})
    for j, c in enumerate(classes):
        out[f"p_{class_name(int(c))}"] = p[:, j].astype(np.float32)
    out["label"] = classes[p.argmax(axis=1)].astype(np.int16)
    if windows is not None:
        out["true_label"] = window_labels(out["TimeUS"].to_numpy(), windows).astype(np.int16)
    return out


@dataclass(frozen=True)
class Finding:
    """One fault the detector reports: its class ``label``, ``start_s`` / ``end_s`` (log time,
    s since boot; end = the last row predicted + one grid step) and the highest probability
    of the class inside (``peak``); ``also``: other classes predicted for a shorter time
    within the same event (:func:`find_faults`)."""

    label: int
    start_s: float
    end_s: float
    peak: float
    also: tuple[int, ...] = ()

    @property
    def name(self) -> str:
        return class_name(self.label)


def _runs(t: np.ndarray, lab: np.ndarray, classes: Sequence[int], min_s: float,
          gap_s: float, dt: float) -> list[tuple[int, np.ndarray]]:
    """Per fault class, (class, row indices) of its runs of consecutive predicted rows that
    cover ``min_s`` (rows ``dt`` apart), runs of one class less than ``gap_s`` apart
    merged."""
    out: list[tuple[int, np.ndarray]] = []
    for c in classes:
        if int(c) == 0:
            continue
        rows = np.flatnonzero(lab == c)
        runs = np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1) if len(rows) else []
        runs = [r for r in runs if len(r) * dt >= min_s - dt / 2]
        merged: list[list[np.ndarray]] = []
        for r in runs:
            if merged and t[r[0]] - (t[merged[-1][-1][-1]] + dt) < gap_s:
                merged[-1].append(r)
            else:
                merged.append([r])
        out += [(int(c), np.concatenate(g)) for g in merged]
    return sorted(out, key=lambda x: t[x[1][0]])


def find_faults(pred: pd.DataFrame, classes: Sequence[int],
                min_s: float = MIN_FAULT_S, gap_s: float = MERGE_GAP_S) -> list[Finding]:
    """The faults in ``pred`` (:func:`predict_rows`'s table: rows on the 10 Hz grid, or a
    table's rows for a per-table detector; the row interval is their median step), in order
    of start.

    Per fault class, the runs of consecutive rows predicted as it that cover at least
    ``min_s`` (shorter ones are flicker), runs of a class less than ``gap_s`` apart merged.
    Runs of different classes that overlap or lie less than ``gap_s`` apart are one event
    (one fault at a time: a fault's onset often resembles another class for a second, a
    weak motor that brings the copter down ends looking like a dead one): it starts at its
    first run, ends at its last, and is named by the class predicted on most of its rows;
    the other classes go to :attr:`Finding.also`."""
    t = pred["TimeUS"].to_numpy(np.float64) * 1e-6
    if not len(t):
        return []
    steps = np.diff(t)
    dt = float(np.median(steps[steps > 0])) if (steps > 0).any() else 1.0 / GRID_HZ
    lab = pred["label"].to_numpy()
    prob = {int(c): pred[f"p_{class_name(int(c))}"].to_numpy() for c in classes}
    runs = _runs(t, lab, classes, min_s, gap_s, dt)
    events: list[list[tuple[int, np.ndarray]]] = []
    end = -np.inf
    for c, idx in runs:
        if events and t[idx[0]] - end < gap_s:
            events[-1].append((c, idx))
        else:
            events.append([(c, idx)])
        end = max(end if len(events[-1]) > 1 else -np.inf, t[idx[-1]] + dt)
    out = []
    for ev in events:
        rows: dict[int, int] = {}
        for c, idx in ev:
            rows[c] = rows.get(c, 0) + len(idx)
        main = max(rows, key=lambda c: (rows[c], -c))
        first = min(int(idx[0]) for _, idx in ev)
        last = max(int(idx[-1]) for _, idx in ev)
        peak = max(float(prob[main][idx].max()) for c, idx in ev if c == main)
        out.append(Finding(main, float(t[first]), float(t[last] + dt), peak,
                           tuple(sorted(c for c in rows if c != main))))
    return out


def fault_rows(time_us: np.ndarray, findings: Sequence[Finding]) -> np.ndarray:
    """The detector's decision on rows at ``time_us`` [µs]: the label of the finding whose
    span (``start_s`` <= t < ``end_s``) holds the row, 0 (normal) for rows outside every
    finding. Unlike the per-row most probable class, a flicker shorter than
    :data:`MIN_FAULT_S` is not a fault, and the short gaps inside a fault are."""
    t = np.asarray(time_us, dtype=np.float64) * 1e-6
    out = np.zeros(len(t), dtype=np.int16)
    for f in findings:
        out[(t >= f.start_s - 1e-9) & (t < f.end_s - 1e-9)] = f.label
    return out
