"""Run models on a data set's tables: split, fit, predict, score, plot.

:func:`evaluate` is what ``tlm evaluate`` runs. For each table and model it fits a fresh,
seeded estimator on each fold's training rows, predicts the fold's test rows and sums the
confusion matrices over folds (as Weka's cross-validation does); the metrics of
:mod:`.metrics` are computed from the sum. With transfer tables (``--test-on``) the model
fitted on the training rows of the hold-out split (or, for cross-validation, on every row)
also predicts the transfer rows.
"""

from __future__ import annotations

import inspect
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.exceptions import ConvergenceWarning

from tlm_process.evaluate.data import EvalDataset, EvaluateError
from tlm_process.evaluate.metrics import (
    CLASS_NAMES,
    classification_metrics,
    confusion_matrix,
    plot_confusion,
)
from tlm_process.evaluate.models import ALL_MODELS, TIME_MODELS, make_model
from tlm_process.evaluate.splits import SPLITS, Fold, flight_folds, random_folds
from tlm_process.evaluate.temporal import (
    CIRCULAR_DEG,
    WindowFeatures,
    row_rate_hz,
    train_rows,
    window_features,
    window_spec_for,
)

__all__ = ["evaluate", "resolve_models", "window_spec"]


def resolve_models(text: str | Sequence[str]) -> list[str]:
    """Model names from ``all`` or ``NAME,NAME`` (case-insensitive); :class:`EvaluateError`
    names an unknown one."""
    items = [s.strip() for s in (text.split(",") if isinstance(text, str) else text)
             if s.strip()]
    if not items:
        raise EvaluateError("--models: no model given")
    if any(s.lower() == "all" for s in items):
        return list(ALL_MODELS)
    lower = {m.lower(): m for m in ALL_MODELS}
    out = []
    for s in items:
        if s.lower() not in lower:
            raise EvaluateError(f"unknown model {s!r}; choose from all, "
                                f"{', '.join(ALL_MODELS)}")
        name = lower[s.lower()]
        if name not in out:
            out.append(name)
    return out


def window_spec(ds: EvalDataset, table: str, model: str = "WindowHGB") -> WindowFeatures:
    """Window features of window model ``model`` for ``table``: circular periods in the
    table's (scaled) units."""
    circ = {}
    scaled = bool((ds.report.get("scaling") or {}).get("applied", True))
    for f, period in CIRCULAR_DEG.get(table, {}).items():
        if f not in ds.features[table]:
            continue
        if scaled and ds.scaler is not None and f in ds.scaler.ranges.get(table, {}):
            lo, hi = ds.scaler.ranges[table][f]
            circ[f] = period / (hi - lo) if hi > lo else period
        else:
            circ[f] = period
    return window_spec_for(model, circ)


def _folds(df: pd.DataFrame, split: str, seed: int, folds: int | None,
           test_frac: float | None) -> list[Fold]:
    if split == "flight":
        return flight_folds(df, seed=seed, folds=folds)
    if split == "random":
        return random_folds(df, seed=seed, folds=folds, test_frac=test_frac)
    raise EvaluateError(f"unknown split {split!r}; use {' or '.join(SPLITS)}")


def _fit(est: Any, X: np.ndarray, y: np.ndarray, groups: np.ndarray | None) -> Any:
    """``est.fit``; estimators whose fit takes ``groups`` (the CNN: validation by flight)
    get the flight ids."""
    if groups is not None and "groups" in inspect.signature(est.fit).parameters:
        return est.fit(X, y, groups=groups)
    return est.fit(X, y)


def evaluate(ds: EvalDataset, *, tables: Sequence[str] | None = None,
             models: Sequence[str] = ALL_MODELS, split: str = "flight", seed: int = 0,
             folds: int | None = None, test_frac: float | None = None,
             transfer: Mapping[str, pd.DataFrame] | None = None,
             out_dir: str | Path | None = None,
             progress: Callable[[str], None] | None = None, n_jobs: int = 1,
             cnn_epochs: int | None = None) -> dict[str, dict[str, dict[str, Any]]]:
    """``{table: {model: metrics}}`` (see :func:`.metrics.classification_metrics`; plus
    ``split``, ``folds``, ``n_train``, ``n_fit`` (training rows the model was fitted on: fewer
    than ``n_train`` for the window models, :data:`.temporal.TRAIN_HZ`), ``n_test``,
    ``fit_seconds``, ``predict_seconds``,
    with cross-validation ``per_fold`` (accuracy and macro-F1 of each fold), for the CNN
    ``history``, and with ``transfer``, ``transfer``: the metrics on the transfer rows).
    ``out_dir``: confusion matrix PNGs (and the CNN's training curves) are written there.
    ``n_jobs``:
    threads for every library (BLAS, OpenMP, torch); 1 by default, as on a shared machine
    more threads than free cores slow OpenMP code down several times. Convergence warnings
    (liblinear for SMO, lbfgs for Logistic) are silenced: those models are used as they
    stand after their iteration limit (see ``docs/evaluation.md``)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=n_jobs), warnings.catch_warnings():
        warnings.simplefilter("ignore", category=ConvergenceWarning)
        return _evaluate(ds, tables=tables, models=models, split=split, seed=seed, folds=folds,
                         test_frac=test_frac, transfer=transfer, out_dir=out_dir,
                         progress=progress, n_jobs=n_jobs, cnn_epochs=cnn_epochs)


def _evaluate(ds: EvalDataset, *, tables: Sequence[str] | None, models: Sequence[str],
              split: str, seed: int, folds: int | None, test_frac: float | None,
              transfer: Mapping[str, pd.DataFrame] | None, out_dir: str | Path | None,
              progress: Callable[[str], None] | None, n_jobs: int,
              cnn_epochs: int | None) -> dict[str, dict[str, dict[str, Any]]]:
    say = progress or (lambda s: None)
    tables = list(tables) if tables is not None else list(ds.tables)
    unknown = [m for m in models if m not in ALL_MODELS]
    if unknown:
        raise EvaluateError(f"unknown model {unknown[0]!r}; choose from {', '.join(ALL_MODELS)}")
    out = Path(out_dir) if out_dir is not None else None
    results: dict[str, dict[str, dict[str, Any]]] = {}
    for t in tables:
        if t not in ds.tables:
            raise EvaluateError(f"table {t} is not loaded")
        df = ds.tables[t]
        feats = ds.features[t]
        y = df["label"].to_numpy(np.int64)
        groups = df["flight"].astype(str).to_numpy()
        X_rows = df[feats].to_numpy(np.float64)
        try:
            fold_list = _folds(df, split, seed, folds, test_frac)
        except ValueError as exc:
            raise EvaluateError(f"{t}: {exc}") from None
        specs = {m: window_spec(ds, t, m) for m in models if m in TIME_MODELS}
        rate = row_rate_hz(df) if specs else None  # measured once for every window model
        X_win = {m: window_features(df, feats, sp, rate)[0] for m, sp in specs.items()}
        thin = train_rows(df, rate) if specs else None
        xt = transfer.get(t) if transfer is not None else None
        if xt is not None:
            yt = xt["label"].to_numpy(np.int64)
            Xt_rows = xt[feats].to_numpy(np.float64)
            Xt_win = {m: window_features(xt, feats, sp)[0] for m, sp in specs.items()}
        say(f"[{t}] {len(df):,} rows, {len(pd.unique(groups))} flights, {len(feats)} features; "
            f"{fold_list[0].name if len(fold_list) == 1 else f'{len(fold_list)} folds'}"
            + (f"; transfer {len(xt):,} rows" if xt is not None else ""))
        results[t] = {}
        for name in models:
            X = X_win[name] if name in TIME_MODELS else X_rows
            cm = np.zeros((len(CLASS_NAMES),) * 2, dtype=np.int64)
            fit_s = pred_s = 0.0
            n_train = n_test = n_fit = 0
            last = None
            per_fold: list[dict[str, Any]] = []
            for fold in fold_list:
                est = make_model(name, n_features=X.shape[1], seed=seed, n_jobs=n_jobs,
                                 progress=lambda s, t=t: say(f"[{t}]   {s}"),
                                 cnn_epochs=cnn_epochs)
                fit_rows = fold.train
                if name in TIME_MODELS:
                    fit_rows = fit_rows[thin[fit_rows]]
                t0 = time.perf_counter()
                _fit(est, X[fit_rows], y[fit_rows], groups[fit_rows])
                t1 = time.perf_counter()
                pred = est.predict(X[fold.test])
                t2 = time.perf_counter()
                fit_s += t1 - t0
                pred_s += t2 - t1
                n_train += len(fold.train)
                n_fit += len(fit_rows)
                n_test += len(fold.test)
                fold_cm = confusion_matrix(y[fold.test], pred)
                cm += fold_cm
                last = est
                if len(fold_list) > 1:
                    fm = classification_metrics(fold_cm)
                    per_fold.append({"fold": fold.name, "n_test": len(fold.test),
                                     "accuracy": fm["accuracy"], "macro_f1": fm["macro_f1"]})
                    say(f"[{t}]   {name} {fold.name}: accuracy {100 * fm['accuracy']:.2f}%, "
                        f"macro-F1 {fm['macro_f1']:.3f} (fit {t1 - t0:.1f} s)")
            r = classification_metrics(cm)
            r.update({"split": split, "folds": len(fold_list), "n_train": n_train,
                      "n_fit": n_fit, "n_test": n_test, "fit_seconds": round(fit_s, 3),
                      "predict_seconds": round(pred_s, 3)})
            if per_fold:
                r["per_fold"] = per_fold
            if xt is not None:
                if len(fold_list) > 1:
                    last = make_model(name, n_features=X.shape[1], seed=seed, n_jobs=n_jobs,
                                      progress=lambda s, t=t: say(f"[{t}]   {s}"),
                                      cnn_epochs=cnn_epochs)
                    every = thin if name in TIME_MODELS else slice(None)
                    _fit(last, X[every], y[every], groups[every])
                Xt = Xt_win[name] if name in TIME_MODELS else Xt_rows
                r["transfer"] = classification_metrics(confusion_matrix(yt, last.predict(Xt)))
            results[t][name] = r
            msg = (f"[{t}] {name}: accuracy {100 * r['accuracy']:.2f}%, macro-F1 "
                   f"{r['macro_f1']:.3f} (fit {fit_s:.1f} s)")
            if "transfer" in r:
                msg += (f"; transfer accuracy {100 * r['transfer']['accuracy']:.2f}%, macro-F1 "
                        f"{r['transfer']['macro_f1']:.3f}")
            say(msg)
            if out is not None:
                plot_confusion(cm, out / f"{t}_{name}_confusion.png",
                               f"{t}: {name} ({split} split), accuracy "
                               f"{100 * r['accuracy']:.2f}%, macro-F1 {r['macro_f1']:.3f}")
                if "transfer" in r:
                    tr = r["transfer"]
                    plot_confusion(tr["confusion"], out / f"{t}_{name}_transfer_confusion.png",
                                   f"{t}: {name} on the transfer logs, accuracy "
                                   f"{100 * tr['accuracy']:.2f}%, macro-F1 {tr['macro_f1']:.3f}")
                if hasattr(last, "plot_history"):
                    last.plot_history(out / f"{t}_{name}_training.png",
                                      f"{t}: {name} training accuracy and loss (paper Figs. "
                                      "20-21)")
            if hasattr(last, "history_"):
                r["history"] = last.history_
    return results
