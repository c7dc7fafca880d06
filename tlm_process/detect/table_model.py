"""The paper's per-table view as a saved detector: one window model on one table of a
``tlm process`` data set (``tlm train DS-tlm --models WindowHGB60 --tables GPS``).

The features are exactly ``tlm evaluate``'s for that model (:mod:`tlm_process.evaluate.
temporal`: the table's Algorithm 2 features, min-max scaled with the data set's scaler,
window statistics per flight; causal for ``WindowHGB`` and ``WindowHGB60``, centred for
``CentredHGB``); the trees are fitted as the whole-log detector's (:meth:`.model.Detector.fit`,
class-balanced) on every flight's rows at 5 Hz, its Normal rows at 1 Hz weighted back, as
``tlm evaluate`` thins them for the window models. A log is read and processed
exactly as the data set's flights were (the options in its report: anchoring, phase, sensor
instance, RC labelling), scaled with the scaler saved in the manifest, and every row of the
table gets a probability per class.

Only the window models are offered: the paper's other classifiers are scikit-learn estimators
that save only as pickles, which a model folder never holds.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.detect.data import DetectError, LogData, check_log_path
from tlm_process.detect.table_spec import TABLE_MODELS, check_table_model, window_spec_of

__all__ = ["TABLE_MODELS", "table_log_features", "train_table"]

#: Rows per second fitted, and Normal rows per second (weighted back), as ``tlm evaluate``
#: fits the window models (:data:`tlm_process.evaluate.temporal.TRAIN_HZ`, 1 Hz Normal).
_TRAIN_HZ, _NORMAL_HZ = 5.0, 1.0


def train_table(ds_path: str | Path, table: str, model: str, opt: Any) -> Any:
    """Fit window model ``model`` on ``table`` of the ``tlm process`` data set ``ds_path``;
    returns a :class:`~.train.TrainResult` whose detector's manifest holds what
    :func:`table_log_features` needs (table, window spec, scaler ranges, processing options).
    ``opt``: :class:`~.train.TrainOptions` (``drop`` entries ``TABLE.COL`` of this table)."""
    import time

    from tlm_process.detect.model import Detector
    from tlm_process.detect.train import TrainResult, _is_held_out, _score, class_weights
    from tlm_process.evaluate.data import EvaluateError, load_dataset
    from tlm_process.evaluate.runner import window_spec
    from tlm_process.evaluate.temporal import FlightRuns, normal_rows, window_features

    t0 = time.perf_counter()
    check_table_model(model)
    try:
        ds = load_dataset(ds_path, [table])
    except EvaluateError as exc:
        raise DetectError(str(exc)) from None
    if ds.scaler is None or table not in ds.scaler.ranges:
        raise DetectError("the data set has no scaler for its table: a log cannot be scaled "
                          "like its flights", source=str(ds_path))
    drop = {d.split(".", 1)[1] for d in opt.drop if d.startswith(f"{table}.")}
    unknown = [d for d in opt.drop if not d.startswith(f"{table}.")
               or d.split(".", 1)[1] not in ds.features[table]]
    if unknown:
        raise DetectError(f"--drop-features: {', '.join(unknown)} is no feature of the data "
                          f"set's {table} ({', '.join(ds.features[table])})")
    feats = [f for f in ds.features[table] if f not in drop]
    if not feats:
        raise DetectError("--drop-features leaves no feature to train on")
    spec = window_spec(ds, table, model)
    df = ds.tables[table]
    ids = sorted(df["flight"].astype(str).unique())
    held = {f for f in ids if _is_held_out(f, opt)}
    if len(held) == len(ids):
        raise DetectError("every flight is held out: nothing left to train on")
    y = df["label"].to_numpy(np.int16)
    runs = FlightRuns.of(df)
    every = max(1, int(round(_TRAIN_HZ / _NORMAL_HZ)))
    fit_mask = normal_rows(df, y, every, train_hz=_TRAIN_HZ, runs=runs) \
        & ~df["flight"].astype(str).isin(held).to_numpy()
    rows = np.flatnonzero(fit_mask)
    X, names = window_features(df, feats, spec, rows=rows, runs=runs)
    t_read = time.perf_counter()
    det = Detector.fit(X, y[rows], [f"{table}.{f}" for f in feats], names,
                       sample_weight=class_weights(y[rows], every), rounds=opt.rounds,
                       min_child_weight=opt.min_child_weight, seed=opt.seed,
                       n_jobs=opt.n_jobs)
    t_fit = time.perf_counter()
    blocks = []
    for fid in sorted(held):
        sub = df[df["flight"].astype(str) == fid].sort_values("TimeUS")
        Xh, _ = window_features(sub, feats, spec)
        blocks.append((fid, sub["TimeUS"].to_numpy(), Xh, sub["label"].to_numpy(np.int16)))
    scores = _score(det, blocks) if blocks else {}
    t_end = time.perf_counter()
    ranges = {f: list(ds.scaler.ranges[table][f]) for f in feats}
    det.manifest = {
        "model": model, "table": table,
        "window": {"seconds": list(spec.seconds), "centred": spec.centred,
                   "circular": dict(spec.circular)},
        "scaler": {"table": table, "ranges": ranges,
                   "applied": bool((ds.report.get("scaling") or {}).get("applied", True))},
        "process_options": ds.options,
    }
    return TrainResult(det, [i for i in ids if i not in held], sorted(held), scores,
                       {"read_s": t_read - t0, "fit_s": t_fit - t_read,
                        "score_s": t_end - t_fit, "total_s": t_end - t0},
                       {"fit_rows": len(rows), "flights": len(ids),
                        **{f"rows_label_{k}": int((y[rows] == k).sum())
                           for k in np.unique(y[rows])}})


def table_log_features(det: Any, path: str | Path) -> tuple[LogData, pd.DataFrame,
                                                              np.ndarray]:
    """(the log as :class:`~.data.LogData`, its processed table rows ``flight, TimeUS,
    label``, their window features) for a per-table detector ``det``. Raises
    :class:`DetectError` for a log that lacks a feature (naming the ``--drop-features``)."""
    from tlm_process.evaluate.temporal import window_features
    from tlm_process.pipeline.anchoring import log_span_us
    from tlm_process.pipeline.ingest import read_flights
    from tlm_process.pipeline.process import ProcessOptions, process_flight
    from tlm_process.pipeline.scaling import MinMaxScaler

    man = det.manifest
    table = man["table"]
    options = ProcessOptions.from_recorded(man.get("process_options") or {}, (table,))
    (flight,) = read_flights([check_log_path(path)])
    p = process_flight(flight, options)
    df = p.features[table]
    feats = [c.split(".", 1)[1] for c in det.channels]
    lack = [f for f in feats if f not in df.columns]
    if lack:
        raise DetectError(f"{table} lacks the model's feature(s) {', '.join(lack)}: train a "
                          f"model without them (tlm train ... --drop-features "
                          f"{','.join(f'{table}.{f}' for f in lack)})", source=str(path))
    df = df.sort_values("TimeUS", kind="stable").reset_index(drop=True)
    if man["scaler"].get("applied", True):
        df = MinMaxScaler({table: man["scaler"]["ranges"]}).transform_table(table, df)
    X, _ = window_features(df, feats, window_spec_of(man))
    span = p.span_us or log_span_us(flight.tables)
    how = flight.meta.get("armed_source", "EV 10") if p.phase == "armed" else p.phase
    log = LogData(flight.id, flight.source, flight.tables, {}, span, how,
                  None if flight.unlabelled else p.windows)
    return log, df, X
