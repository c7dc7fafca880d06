"""From a log to the detector's rows, and from per-row probabilities to faults found.

:func:`log_features`: the log's armed span on the :data:`~.channels.GRID_HZ` grid, its
channels and features (the same function at training and detection time, so a model sees a
user's log as it saw its training flights). :func:`predict_log`: probabilities per class and
the predicted label on every grid row. :func:`find_faults`: the faults a log holds by the
predictions: runs of one fault class that last at least :data:`MIN_FAULT_S` (a persistence
filter, as :data:`tlm_process.evaluate.events.PERSISTENCE_S`), merged across gaps shorter than
:data:`MERGE_GAP_S`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from tlm_process.detect.channels import GRID_HZ, armed_grid, channel_table
from tlm_process.detect.data import LogData
from tlm_process.detect.features import feature_matrix
from tlm_process.evaluate.events import PERSISTENCE_S
from tlm_process.labels import class_name

__all__ = ["MERGE_GAP_S", "MIN_FAULT_S", "Finding", "find_faults", "log_features",
           "predict_log"]

#: A fault class must be predicted on consecutive rows covering this long to be reported [s].
MIN_FAULT_S: float = PERSISTENCE_S
#: Runs of one class closer than this are one fault [s].
MERGE_GAP_S: float = 3.0


def log_features(log: LogData, channels: Sequence[str]
                 ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """(grid times [µs since boot], feature matrix, log columns the log lacks for
    ``channels``) of ``log``'s armed span."""
    grid = armed_grid(*log.span_us, GRID_HZ)
    table, lacking = channel_table(log.tables, log.params, channels, grid)
    return grid, feature_matrix(table, channels, GRID_HZ), lacking


def predict_log(detector: object, log: LogData) -> pd.DataFrame:
    """Per grid row of ``log``'s armed span: ``TimeUS``, ``p_<class>`` (one per class of the
    detector, named by :func:`tlm_process.labels.class_name`), ``label`` (the most probable
    class) and ``true_label`` when the log has fault windows."""
    from tlm_process.detect.data import window_labels

    grid, X, _ = log_features(log, detector.channels)  # type: ignore[attr-defined]
    p = detector.predict_proba(X)  # type: ignore[attr-defined]
    classes = np.asarray(detector.classes)  # type: ignore[attr-defined]
    out = pd.DataFrame({"TimeUS": grid})
    for j, c in enumerate(classes):
        out[f"p_{class_name(int(c))}"] = p[:, j].astype(np.float32)
    out["label"] = classes[p.argmax(axis=1)].astype(np.int16)
    if log.windows is not None:
        out["true_label"] = window_labels(grid, log.windows).astype(np.int16)
    return out


@dataclass(frozen=True)
class Finding:
    """One fault the detector reports: its class ``label``, ``start_s`` / ``end_s`` (log time,
    s since boot; end = the last row predicted + one grid step) and the highest probability
    of the class inside (``peak``)."""

    label: int
    start_s: float
    end_s: float
    peak: float

    @property
    def name(self) -> str:
        return class_name(self.label)


def find_faults(pred: pd.DataFrame, classes: Sequence[int],
                min_s: float = MIN_FAULT_S, gap_s: float = MERGE_GAP_S) -> list[Finding]:
    """The faults in ``pred`` (:func:`predict_log`'s table): per fault class, the runs of
    consecutive rows predicted as it that cover at least ``min_s`` (shorter ones are
    flicker), runs of a class closer than ``gap_s`` merged into one; in order of start."""
    t = pred["TimeUS"].to_numpy(np.float64) * 1e-6
    if not len(t):
        return []
    dt = 1.0 / GRID_HZ
    lab = pred["label"].to_numpy()
    out: list[Finding] = []
    for c in classes:
        if int(c) == 0:
            continue
        rows = np.flatnonzero(lab == c)
        if not len(rows):
            continue
        prob = pred[f"p_{class_name(int(c))}"].to_numpy()
        runs = np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1)
        runs = [r for r in runs if len(r) * dt >= min_s - dt / 2]
        merged: list[list[np.ndarray]] = []
        for r in runs:
            if merged and t[r[0]] - (t[merged[-1][-1][-1]] + dt) < gap_s:
                merged[-1].append(r)
            else:
                merged.append([r])
        for grp in merged:
            idx = np.concatenate(grp)
            out.append(Finding(int(c), float(t[idx[0]]), float(t[idx[-1]] + dt),
                               float(prob[idx].max())))
    return sorted(out, key=lambda f: (f.start_s, f.label))
