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
import os
import sys
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.exceptions import ConvergenceWarning
from sklearn.pipeline import Pipeline

from tlm_process.evaluate.data import EvalDataset, EvaluateError
from tlm_process.evaluate.events import detection_summary
from tlm_process.evaluate.metrics import (
    classification_metrics,
    confusion_matrix,
    plot_confusion,
)
from tlm_process.evaluate.models import (
    ALL_MODELS,
    DEFAULT_MAX_ROWS,
    DEFAULT_NORMAL_HZ,
    DEFAULT_TRAIN_HZ,
    SEQUENCE_MODELS,
    WEIGHTED_MODELS,
    make_model,
)
from tlm_process.evaluate.splits import SPLITS, Fold, flight_folds, random_folds
from tlm_process.evaluate.temporal import (
    CIRCULAR_DEG,
    WINDOW_BOOSTERS,
    WINDOW_MODELS,
    FlightRuns,
    WindowFeatures,
    merged_windows,
    normal_rows,
    row_rate_hz,
    row_stride,
    window_features,
    window_spec_for,
)
from tlm_process.evaluate.visible import visible_scores
from tlm_process.labels import class_labels, class_names

__all__ = ["default_jobs", "evaluate", "resolve_models", "window_spec"]


def default_jobs() -> int:
    """Cores this process may run on (``--jobs``' default)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not Linux
        return max(1, os.cpu_count() or 1)


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


def _fit(est: Any, X: np.ndarray, y: np.ndarray, groups: np.ndarray | None,
         weight: np.ndarray | None = None) -> Any:
    """``est.fit``; estimators whose fit takes ``groups`` (the CNN: validation by flight)
    get the flight ids; ``weight``: per-row sample weights (None: all 1), given to the
    estimator, or to the last step of a pipeline."""
    kw: dict[str, Any] = {}
    if groups is not None and "groups" in inspect.signature(est.fit).parameters:
        kw["groups"] = groups
    if weight is not None:
        prefix, step = "", est
        while isinstance(step, Pipeline):  # the final estimator of (nested) pipelines
            name, step = step.steps[-1]
            prefix += f"{name}__"
        kw[prefix + "sample_weight"] = weight
    return est.fit(X, y, **kw)


def evaluate(ds: EvalDataset, *, tables: Sequence[str] | None = None,
             models: Sequence[str] = ALL_MODELS, split: str = "flight", seed: int = 0,
             folds: int | None = None, test_frac: float | None = None,
             transfer: Mapping[str, pd.DataFrame] | None = None,
             out_dir: str | Path | None = None,
             progress: Callable[[str], None] | None = None, n_jobs: int | None = None,
             cnn_epochs: int | None = None,
             train_hz: float | Mapping[str, float] | None = None,
             normal_hz: float | Mapping[str, float] | None = None,
             max_rows: int | Mapping[str, int] | None = None, bar: bool | None = False,
             booster: str = "xgboost") -> dict[str, dict[str, dict[str, Any]]]:
    """``{table: {model: metrics}}`` (see :func:`.metrics.classification_metrics`; plus
    ``split``, ``folds``, ``n_train``, ``n_fit`` (training rows the model was fitted on: fewer
    than ``n_train`` where they are thinned, ``train_hz``), ``train_hz``, ``n_test``,
    ``fit_seconds``, ``predict_seconds`` (wall seconds summed over folds; with transfer rows
    ``transfer_predict_seconds`` and, after cross-validation, ``transfer_fit_seconds`` of the
    model refitted on every flight),
    with cross-validation ``per_fold`` (accuracy and macro-F1 of each fold), for the CNN
    ``history``, where :func:`.data.drop_features` took features out of the table
    ``dropped_features`` (``TABLE.COL``), and with ``transfer``, ``transfer``: the metrics
    on the transfer rows),
    and the event metrics of :func:`.events.detection_summary` (``detection`` per fault
    class, ``false_alarms_per_hour``, ...) of every fold's test rows pooled and, under
    ``transfer``, of the transfer rows.
    ``out_dir``: confusion matrix PNGs (and the CNN's training curves) are written there.
    ``n_jobs``: threads for every library (BLAS, OpenMP, torch, joblib; default: this
    machine's cores, :func:`default_jobs`); results are the same whatever it is. On a
    machine whose cores other work keeps busy, fewer threads can be faster (OpenMP threads
    wait for each other). ``train_hz``: the rate [Hz] the training rows of every model (a
    number) or of some (model -> rate) are thinned to, 0 for every row; the others'
    :data:`.models.DEFAULT_TRAIN_HZ`. ``normal_hz``: likewise the rate of the Normal
    training rows (0: the model's training-row rate; the others' :data:`.models.
    DEFAULT_NORMAL_HZ`), for the models that take sample weights
    (:data:`.models.WEIGHTED_MODELS`; a number leaves the others alone): the kept Normal
    rows are weighted so the class balance stays. ``max_rows``: the most training rows a
    model is fitted on per fold (a number for every model, or model -> rows; 0: no limit;
    the others' :data:`.models.DEFAULT_MAX_ROWS`): where the rows its rates keep are more,
    they are thinned further, evenly in every flight (the Normal rows first for the models
    that take sample weights; :func:`row_budget`), so a fit costs the same whatever the
    number of flights. Test and transfer rows are never thinned. ``bar``: a
    progress bar per table on stderr (None: when stderr is a terminal). ``booster``: the
    window models' gradient boosting, one of :data:`.temporal.WINDOW_BOOSTERS`
    (:func:`.temporal.window_hgb`; ``booster`` in their results). Convergence
    warnings
    (liblinear for SMO, lbfgs for Logistic) are silenced: those models are used as they
    stand after their iteration limit (see ``docs/evaluation.md``)."""
    from threadpoolctl import threadpool_limits

    if booster not in WINDOW_BOOSTERS:
        raise EvaluateError(f"unknown booster {booster!r}; choose from "
                            f"{', '.join(WINDOW_BOOSTERS)}")
    n_jobs = n_jobs or default_jobs()
    with threadpool_limits(limits=n_jobs), warnings.catch_warnings():
        warnings.simplefilter("ignore", category=ConvergenceWarning)
        return _evaluate(ds, tables=tables, models=models, split=split, seed=seed, folds=folds,
                         test_frac=test_frac, transfer=transfer, out_dir=out_dir,
                         progress=progress, n_jobs=n_jobs, cnn_epochs=cnn_epochs,
                         train_hz=_train_hz(models, train_hz),
                         normal_hz=_normal_hz(models, normal_hz),
                         max_rows=_max_rows(models, max_rows), bar=bar, booster=booster)


def _rates(models: Sequence[str], given: float | Mapping[str, float] | None,
           defaults: Mapping[str, float], what: str, unit: str = " Hz",
           kind: type = float) -> dict[str, Any]:
    """Model -> rate [Hz] (0: off), or another setting of ``kind``: ``given`` (one number for
    every model, or model -> number) over ``defaults``; ``what`` and ``unit`` name it in the
    error of a negative one."""
    out = {m: kind(defaults.get(m, 0)) for m in models}
    if isinstance(given, Mapping):
        out.update({m: kind(v) for m, v in given.items() if m in out})
    elif given is not None:
        out = dict.fromkeys(out, kind(given))
    bad = [m for m, v in out.items() if not v >= 0]
    if bad:
        raise EvaluateError(f"{what} of {bad[0]} must be >= 0{unit}, got {out[bad[0]]}")
    return out


def _train_hz(models: Sequence[str], given: float | Mapping[str, float] | None
              ) -> dict[str, float]:
    """Model -> training-row rate [Hz] (0: every row): ``given`` over the defaults."""
    return _rates(models, given, DEFAULT_TRAIN_HZ, "training-row rate")


def _normal_hz(models: Sequence[str], given: float | Mapping[str, float] | None
               ) -> dict[str, float]:
    """Model -> Normal training-row rate [Hz] (0: as the other rows): ``given`` over the
    defaults, for the models that take sample weights."""
    if isinstance(given, Mapping):
        odd = [m for m in given if m in models and m not in WEIGHTED_MODELS]
        if odd:
            raise EvaluateError(f"{odd[0]} takes no sample weights, so its Normal rows "
                                f"cannot be thinned apart (models that can: "
                                f"{', '.join(WEIGHTED_MODELS)})")
    return _rates([m for m in models if m in WEIGHTED_MODELS], given, DEFAULT_NORMAL_HZ,
                  "Normal-row rate")


def _max_rows(models: Sequence[str], given: int | Mapping[str, int] | None
              ) -> dict[str, int]:
    """Model -> the most rows it is fitted on per fold (0: no limit): ``given`` over the
    defaults."""
    return _rates(models, given, DEFAULT_MAX_ROWS, "row budget", unit="", kind=int)


def row_budget(y: np.ndarray, runs: FlightRuns, train: np.ndarray, stride: int, every: int,
               weighted: bool, max_rows: int) -> tuple[int, int]:
    """(stride, every): the row stride per flight and the further stride of the Normal rows
    (``y`` == 0; :func:`.temporal.normal_rows`) that keep at most ``max_rows`` of the
    training rows ``train`` (positions), starting from ``stride`` and ``every``. The Normal
    rows are thinned first where the model takes sample weights (``weighted``), the fault
    rows only when they alone are more than ``max_rows`` (then every row, by ``stride``);
    ``max_rows`` 0: no limit. A flight's first row is always kept, so a budget below the
    number of flights keeps one row per flight."""
    if not max_rows:
        return stride, every
    r = runs.rank[train]
    fault = np.asarray(y)[train] != 0

    def count(k: int, e: int) -> int:
        return int(((r % k == 0) & (fault | (r % (k * e) == 0))).sum())

    longest = int((runs.ends - runs.starts).max()) if len(y) else 1
    k, e = max(1, stride), max(1, every) if weighted else 1
    if count(k, e) <= max_rows:
        return k, e
    if weighted and count(k, longest) <= max_rows:  # Normal rows first
        while count(k, e) > max_rows:
            e += 1
        return k, e
    while count(k, e) > max_rows and k < longest:  # then every row
        k += 1
    return k, e


def _evaluate(ds: EvalDataset, *, tables: Sequence[str] | None, models: Sequence[str],
              split: str, seed: int, folds: int | None, test_frac: float | None,
              transfer: Mapping[str, pd.DataFrame] | None, out_dir: str | Path | None,
              progress: Callable[[str], None] | None, n_jobs: int,
              cnn_epochs: int | None, train_hz: dict[str, float],
              normal_hz: dict[str, float], max_rows: dict[str, int], bar: bool | None,
              booster: str) -> dict[str, dict[str, dict[str, Any]]]:
    tables = list(tables) if tables is not None else list(ds.tables)
    unknown = [m for m in models if m not in ALL_MODELS]
    if unknown:
        raise EvaluateError(f"unknown model {unknown[0]!r}; choose from {', '.join(ALL_MODELS)}")
    out = Path(out_dir) if out_dir is not None else None
    results: dict[str, dict[str, dict[str, Any]]] = {}
    for t in tables:
        t0 = time.perf_counter()
        tab = _Table.build(ds, t, models, split, seed, folds, test_frac,
                           transfer.get(t) if transfer is not None else None, train_hz,
                           normal_hz, max_rows)
        prep_s = time.perf_counter() - t0
        with _Progress(t, tab, models, progress, bar) as prog:
            prog.say(tab.describe() + f" (prepared in {prep_s:.1f} s)")
            results[t] = {}

            def make_of(name: str, tab: _Table = tab, prog: _Progress = prog
                        ) -> Callable[[], Any]:
                return partial(make_model, name, n_features=tab.n_inputs(name), seed=seed,
                               n_jobs=n_jobs, progress=prog.epoch_line, cnn_epochs=cnn_epochs,
                               booster=booster)

            side = _side_by_side(tab, [m for m in models if m in SINGLE_CORE_MODELS],
                                 make_of, prog, n_jobs)
            for name in models:
                prog.start(name)
                r, cm, last = side.pop(name, None) or _run_model(tab, name, make_of(name),
                                                                 prog.say)
                r["split"] = split
                if ds.dropped.get(t):
                    r["dropped_features"] = [f"{t}.{c}" for c in ds.dropped[t]]
                if name in WINDOW_MODELS:
                    r["booster"] = booster
                results[t][name] = r
                prog.done(name, r)
                if out is not None:
                    _plot_model(out, t, name, split, r, cm, last)
    return results


#: Models whose fit and prediction use one core (scikit-learn's tree building, NumPy). With
#: ``n_jobs`` > 1 they run side by side, each on its own thread (:func:`_side_by_side`): on
#: 200 flights J48 and RandomTree alone fit IMU's 1.5 million rows for 26 s and 15 s.
SINGLE_CORE_MODELS: frozenset[str] = frozenset(
    {"NaiveBayes", "AdaBoost", "OneR", "ZeroR", "J48", "RandomTree"})


def _side_by_side(tab: _Table, names: Sequence[str], make_of: Callable[[str], Any],
                  prog: _Progress, n_jobs: int
                  ) -> dict[str, tuple[dict[str, Any], np.ndarray, Any]]:
    """:func:`_run_model` of the one-core models ``names`` on ``n_jobs`` threads at once,
    the costliest first; their results (the same as one after the other) by name. Nothing
    with fewer than two models or threads."""
    if n_jobs < 2 or len(names) < 2:
        return {}
    order = sorted(names, key=lambda m: -prog.cost[m])
    prog.start(", ".join(order))
    with ThreadPoolExecutor(max_workers=n_jobs) as pool:
        futures = {m: pool.submit(_run_model, tab, m, make_of(m), prog.say) for m in order}
        return {m: f.result() for m, f in futures.items()}


def _run_model(tab: _Table, name: str, make: Callable[[], Any], say: Callable[[str], None]
               ) -> tuple[dict[str, Any], np.ndarray, Any]:
    """Fit and score model ``name`` on ``tab`` (folds, then the transfer rows); returns (its
    results, the summed confusion matrix, the model last fitted)."""
    counts, cm, last, test_pred = _fit_folds(tab, name, make, say)
    r = classification_metrics(cm, class_names(tab.labels))
    tested = test_pred >= 0  # every fold's test rows, pooled: their events
    r.update(detection_summary(tab.groups[tested], tab.time_us[tested], tab.y[tested],
                               test_pred[tested]))
    r["labels"] = list(tab.labels)
    r["train_hz"] = tab.train_hz[name]
    r["normal_every"] = tab.normal_every[name]
    r["normal_hz"] = tab.normal_hz(name)
    r["max_rows"] = tab.max_rows.get(name, 0)
    r.update(counts)
    if tab.yt is not None:  # transfer rows
        if len(tab.folds) > 1:
            t0 = time.perf_counter()
            last = _fit_all(tab, name, make)
            r["transfer_fit_seconds"] = round(time.perf_counter() - t0, 3)
        t0 = time.perf_counter()
        pred = _predict(last, partial(tab.transfer_inputs, name), np.arange(len(tab.yt)))
        r["transfer_predict_seconds"] = round(time.perf_counter() - t0, 3)
        r["transfer"] = classification_metrics(
            confusion_matrix(tab.yt, pred, labels=tab.labels), class_names(tab.labels))
        r["transfer"].update(detection_summary(tab.gt, tab.tt_us, tab.yt, pred))
        vis = visible_scores(tab.name, tab.yt, pred)
        if vis is not None:
            r["transfer"]["visible"] = vis
    if hasattr(last, "history_"):
        r["history"] = last.history_
    return r, cm, last


#: Seconds to fit 1,000 training rows x input columns, and to predict 1,000 rows, per model
#: (GPS, 60 flights, 14 classes, two threads of a 2-core machine;
#: ``benchmarks/bench_evaluate.py``): the progress bar's weights, so that its ETA is not
#: fooled by a table's cheap models coming first.
_COST: Mapping[str, tuple[float, float]] = {
    "NaiveBayes": (2e-4, 1e-3), "Logistic": (6e-3, 1e-3), "SMO": (0.02, 5e-3),
    "KNN": (2e-4, 7e-4), "AdaBoost": (3e-4, 1e-3), "OneR": (7e-4, 1e-3), "ZeroR": (0.0, 0.0),
    "J48": (1.6e-3, 1e-3), "RandomForest": (0.022, 5e-3), "RandomTree": (7e-4, 1e-3),
    "CNN": (0.034, 5e-3), "WindowHGB": (2e-3, 0.012), "WindowHGB60": (2.2e-3, 0.008),
    "CentredHGB": (2e-3, 0.01), "SeqCNN": (0.0, 0.01)}
#: Seconds per fit that do not grow with the rows (SeqCNN: a fixed number of steps).
_FIXED_COST: Mapping[str, float] = {"SeqCNN": 20.0}


class _Progress:
    """A table's progress: its lines (``say``) and, when ``bar`` is not False, a tqdm bar on
    stderr (shown only on a terminal when ``bar`` is None) with the model being fitted and
    an ETA; the bar advances by each model's estimated cost (:data:`_COST`)."""

    def __init__(self, table: str, tab: _Table, models: Sequence[str],
                 say: Callable[[str], None] | None, bar: bool | None) -> None:
        self.table = table
        self._say = say or (lambda s: None)
        n_pred = sum(len(f.test) for f in tab.folds) + (len(tab.yt) if tab.yt is not None
                                                        else 0)
        self.cost = {}
        for m in models:
            fit, pred = _COST.get(m, (0.01, 0.01))
            n_fit = sum(len(tab.fit_rows(m, f.train)) for f in tab.folds)
            self.cost[m] = (1e-3 * (fit * n_fit * tab.n_inputs(m) + pred * n_pred) + 0.01
                            + _FIXED_COST.get(m, 0.0) * len(tab.folds))
        self.bar = None
        if bar is not False:
            from tqdm import tqdm

            self.bar = tqdm(total=sum(self.cost.values()), desc=f"[{table}]", unit="",
                            dynamic_ncols=True, file=sys.stderr, leave=False,
                            disable=None if bar is None else False,
                            bar_format="{desc} {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]")

    def __enter__(self) -> _Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.bar is not None:
            self.bar.close()

    def say(self, msg: str) -> None:
        """A progress line (above the bar)."""
        if self.bar is not None and not self.bar.disable:
            self.bar.clear()
        self._say(msg)
        if self.bar is not None and not self.bar.disable:
            self.bar.refresh()

    def epoch_line(self, msg: str) -> None:
        """A model's own progress line (the CNN's epochs)."""
        self.say(f"[{self.table}]   {msg}")

    def start(self, model: str) -> None:
        if self.bar is not None:
            self.bar.set_description_str(f"[{self.table}] {model}")

    def done(self, model: str, r: dict[str, Any]) -> None:
        self.say(_model_line(self.table, model, r))
        if self.bar is not None:
            self.bar.update(self.cost[model])


#: Rows predicted per call: bounds the copies (window matrices as float64 inside
#: scikit-learn) whatever the table's size; every model predicts rows independently.
PREDICT_CHUNK = 65_536


@dataclass
class _Inputs:
    """Model inputs of a set of rows (a table's or the transfer rows): ``rows`` (n, d)
    float64, the matrices of the merged window specs (``win``) over the rows ``pos`` maps
    to (table row -> matrix row; None: every row, in table order)."""

    rows: np.ndarray
    win: list[np.ndarray] = field(default_factory=list)
    pos: np.ndarray | None = None
    seq: Any = None  # the sequence models' FlightContext

    def of(self, model: str, which: tuple[int, np.ndarray | None] | None, rows: np.ndarray
           ) -> np.ndarray:
        """Inputs of ``model``: :meth:`get`, or whole flights for a sequence model."""
        return self.seq.inputs(rows) if model in SEQUENCE_MODELS else self.get(which, rows)

    def get(self, which: tuple[int, np.ndarray | None] | None, rows: np.ndarray
            ) -> np.ndarray:
        """Inputs of table rows ``rows``: the rows' features (``which`` None), else the
        columns ``which[1]`` of window matrix ``which[0]`` (one copy)."""
        if which is None:
            return self.rows[rows]
        i, cols = which
        at = rows if self.pos is None else self.pos[rows]
        mat = self.win[i]
        return mat[at] if cols is None else mat[np.ix_(at, cols)]


@dataclass
class _Table:
    """One table's rows as every model needs them, computed once and shared by all models:
    labels, flights, the feature matrix, the window statistics of every window model (each
    statistic once: :func:`.temporal.merged_windows`; only for the rows some model is fitted
    on or predicts), folds, and the transfer rows (``xt`` None without). ``labels``: the
    classes of its confusion matrices (``tlm_process.labels.class_labels`` of the table's and
    the transfer rows' labels)."""

    name: str
    n_rows: int
    n_flights: int
    n_features: int
    y: np.ndarray
    groups: np.ndarray
    x: _Inputs
    win_of: dict[str, tuple[int, np.ndarray | None]]  # window model -> its columns
    train_hz: dict[str, float]  # model -> rate its training rows are thinned to [Hz]; 0: all
    normal_every: dict[str, int]  # model -> keeps every n-th of those rows that are Normal
    thin: dict[tuple[float, int], np.ndarray]  # (rate, n) -> mask of the rows kept
    folds: list[Fold]
    rate_hz: float = 0.0  # the table's logging rate [Hz]
    max_rows: dict[str, int] = field(default_factory=dict)  # model -> row budget; 0: none
    yt: np.ndarray | None = None
    xt: _Inputs | None = None
    labels: list[int] = field(default_factory=list)
    time_us: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))  # TimeUS
    gt: np.ndarray | None = None  # flight of each transfer row
    tt_us: np.ndarray | None = None  # TimeUS of each transfer row

    @classmethod
    def build(cls, ds: EvalDataset, t: str, models: Sequence[str], split: str, seed: int,
              folds: int | None, test_frac: float | None, xt: pd.DataFrame | None,
              train_hz: Mapping[str, float], normal_hz: Mapping[str, float] | None = None,
              max_rows: Mapping[str, int] | None = None) -> _Table:
        """Table ``t`` of ``ds`` (and its transfer rows ``xt``) split into folds;
        ``train_hz``: model -> the rate its training rows are thinned to [Hz] (0: all);
        ``normal_hz``: model -> the rate of its Normal training rows [Hz] (0 or missing:
        ``train_hz``; weighted so the class balance stays, :func:`.temporal.normal_rows`);
        ``max_rows``: model -> the most rows it is fitted on per fold (0 or missing: no
        limit; :func:`row_budget`: the rates are lowered where needed, ``train_hz`` and
        ``normal_every`` hold the rates used)."""
        if t not in ds.tables:
            raise EvaluateError(f"table {t} is not loaded")
        df = ds.tables[t]
        feats = ds.features[t]
        try:
            fold_list = _folds(df, split, seed, folds, test_frac)
        except ValueError as exc:
            raise EvaluateError(f"{t}: {exc}") from None
        train_hz = {m: float(train_hz.get(m, 0.0)) for m in models}
        runs = FlightRuns.of(df)
        rate = row_rate_hz(df, runs)  # measured once for every model
        # keep every n-th Normal row: the model's training-row rate over its Normal-row rate
        every = {m: row_stride(train_hz[m] or rate, (normal_hz or {}).get(m, 0.0))
                 for m in models}
        y = df["label"].to_numpy(np.int64)
        budget = {m: int((max_rows or {}).get(m, 0)) for m in models}
        widest = max((f.train for f in fold_list), key=len)
        for m in models:
            if budget[m]:
                k = row_stride(rate, train_hz[m])
                k2, every[m] = row_budget(y, runs, widest, k, every[m],
                                          m in WEIGHTED_MODELS, budget[m])
                if k2 != k:
                    train_hz[m] = rate / k2
        thin = {(hz, n): normal_rows(df, y, n, rate, hz, runs)
                for hz, n in {(train_hz[m], every[m]) for m in models} if hz or n > 1}
        groups = df["flight"].astype(str).to_numpy()
        specs = {m: window_spec(ds, t, m) for m in models if m in WINDOW_MODELS}
        merged, win_of = merged_windows(specs, feats)
        x = _Inputs(df[feats].to_numpy(np.float64))
        if merged:
            need = np.zeros(len(df), dtype=bool)  # rows some window model fits or predicts
            for f in fold_list:
                need[f.test] = True
                for m in specs:
                    mask = thin.get((train_hz[m], every[m]))
                    need[f.train[mask[f.train]] if mask is not None else f.train] = True
            if len(fold_list) > 1:
                for m in specs:
                    need |= thin.get((train_hz[m], every[m]), True)
            rows = np.flatnonzero(need)
            x.pos = np.full(len(df), -1, dtype=np.int64)
            x.pos[rows] = np.arange(len(rows))
            x.win = [window_features(df, feats, sp, rate, rows, runs)[0] for sp in merged]
        tab = cls(t, len(df), len(pd.unique(groups)), len(feats),
                  y, groups, x, win_of, train_hz, every, thin, fold_list, rate_hz=rate,
                  max_rows=budget)
        tab.time_us = df["TimeUS"].to_numpy(np.int64)
        if xt is not None:
            tab.yt = xt["label"].to_numpy(np.int64)
            tab.gt = xt["flight"].astype(str).to_numpy()
            tab.tt_us = xt["TimeUS"].to_numpy(np.int64)
            xt_runs = FlightRuns.of(xt)
            xt_rate = row_rate_hz(xt, xt_runs) if merged else None
            tab.xt = _Inputs(xt[feats].to_numpy(np.float64),
                             [window_features(xt, feats, sp, xt_rate, None, xt_runs)[0]
                              for sp in merged])
        if any(m in SEQUENCE_MODELS for m in models):
            from tlm_process.evaluate.sequence import FlightContext

            circ = window_spec(ds, t).circular
            tab.x.seq = FlightContext.of(df, feats, circ, runs)
            if xt is not None:
                assert tab.xt is not None
                tab.xt.seq = FlightContext.of(xt, feats, circ)
        tab.labels = class_labels(tab.y, tab.yt if tab.yt is not None else [])
        return tab

    def n_inputs(self, model: str) -> int:
        """Number of input columns of ``model``."""
        if model not in self.win_of:
            return self.x.rows.shape[1]
        i, cols = self.win_of[model]
        return self.x.win[i].shape[1] if cols is None else len(cols)

    def inputs(self, model: str, rows: np.ndarray) -> np.ndarray:
        """The model's inputs of table rows ``rows``: window features for a window model,
        else the rows' features."""
        return self.x.of(model, self.win_of.get(model), rows)

    def transfer_inputs(self, model: str, rows: np.ndarray) -> np.ndarray:
        """The model's inputs of transfer rows ``rows``."""
        assert self.xt is not None
        return self.xt.of(model, self.win_of.get(model), rows)

    def fit_rows(self, model: str, train: np.ndarray) -> np.ndarray:
        """The training rows ``train`` that ``model`` is fitted on (thinned to its rate)."""
        mask = self.thin.get((self.train_hz[model], self.normal_every[model]))
        return train[mask[train]] if mask is not None else train

    def normal_hz(self, model: str) -> float:
        """The rate [Hz] ``model``'s Normal training rows were thinned to; 0: as its other
        rows."""
        n = self.normal_every[model]
        return round((self.train_hz[model] or self.rate_hz) / n, 4) if n > 1 else 0.0

    def fit_weight(self, model: str, rows: np.ndarray) -> np.ndarray | None:
        """Sample weights of the fitted rows ``rows`` (None: all 1): ``normal_every`` on the
        Normal rows where they are thinned more than the others."""
        n = self.normal_every[model]
        return np.where(self.y[rows] == 0, float(n), 1.0) if n > 1 else None

    def describe(self) -> str:
        """The progress line of the table."""
        folds = self.folds
        return (f"[{self.name}] {self.n_rows:,} rows, {self.n_flights} flights, "
                f"{self.n_features} features; "
                f"{folds[0].name if len(folds) == 1 else f'{len(folds)} folds'}"
                + (f"; transfer {len(self.yt):,} rows" if self.yt is not None else ""))


def _predict(est: Any, get: Callable[[np.ndarray], np.ndarray], rows: np.ndarray
             ) -> np.ndarray:
    """``est.predict`` of rows ``rows`` (``get(rows)``: their inputs), in chunks of
    :data:`PREDICT_CHUNK` rows."""
    if not len(rows):
        return np.empty(0, dtype=np.int64)
    return np.concatenate([est.predict(get(rows[a:a + PREDICT_CHUNK]))
                           for a in range(0, len(rows), PREDICT_CHUNK)])


def _fit_folds(tab: _Table, name: str, make: Callable[[], Any], say: Callable[[str], None]
               ) -> tuple[dict[str, Any], np.ndarray, Any, np.ndarray]:
    """Fit a fresh model ``make()`` on each fold's training rows and predict its test rows.

    Returns (counts and timings [s], the summed confusion matrix, the last fold's model, the
    prediction of every row tested (-1: not tested))."""
    y, groups, t = tab.y, tab.groups, tab.name
    cm = np.zeros((len(tab.labels),) * 2, dtype=np.int64)
    fit_s = pred_s = 0.0
    n_train = n_test = n_fit = 0
    last = None
    per_fold: list[dict[str, Any]] = []
    test_pred = np.full(len(y), -1, dtype=np.int64)
    for fold in tab.folds:
        est = make()
        fit_rows = tab.fit_rows(name, fold.train)
        t0 = time.perf_counter()
        _fit(est, tab.inputs(name, fit_rows), y[fit_rows], groups[fit_rows],
             tab.fit_weight(name, fit_rows))
        t1 = time.perf_counter()
        pred = _predict(est, partial(tab.inputs, name), fold.test)
        t2 = time.perf_counter()
        fit_s += t1 - t0
        pred_s += t2 - t1
        n_train += len(fold.train)
        n_fit += len(fit_rows)
        n_test += len(fold.test)
        fold_cm = confusion_matrix(y[fold.test], pred, labels=tab.labels)
        test_pred[fold.test] = pred
        cm += fold_cm
        last = est
        if len(tab.folds) > 1:
            fm = classification_metrics(fold_cm, class_names(tab.labels))
            per_fold.append({"fold": fold.name, "n_test": len(fold.test),
                             "accuracy": fm["accuracy"], "macro_f1": fm["macro_f1"]})
            say(f"[{t}]   {name} {fold.name}: accuracy {100 * fm['accuracy']:.2f}%, "
                f"macro-F1 {fm['macro_f1']:.3f} (fit {t1 - t0:.1f} s)")
    r: dict[str, Any] = {"folds": len(tab.folds), "n_train": n_train, "n_fit": n_fit,
                         "n_test": n_test, "fit_seconds": round(fit_s, 3),
                         "predict_seconds": round(pred_s, 3)}
    if per_fold:
        r["per_fold"] = per_fold
    return r, cm, last, test_pred


def _fit_all(tab: _Table, name: str, make: Callable[[], Any]) -> Any:
    """A fresh model fitted on every row (thinned to the model's rate) of the table: the one
    tested on the transfer rows after cross-validation."""
    est = make()
    rows = tab.fit_rows(name, np.arange(tab.n_rows))
    _fit(est, tab.inputs(name, rows), tab.y[rows], tab.groups[rows], tab.fit_weight(name, rows))
    return est


def _model_line(t: str, name: str, r: dict[str, Any]) -> str:
    """The progress line of one model's result."""
    msg = (f"[{t}] {name}: accuracy {100 * r['accuracy']:.2f}%, macro-F1 "
           f"{r['macro_f1']:.3f} (fit {r['fit_seconds']:.1f} s, predict "
           f"{r['predict_seconds'] + r.get('transfer_predict_seconds', 0.0):.1f} s)")
    if "transfer" in r:
        msg += (f"; transfer accuracy {100 * r['transfer']['accuracy']:.2f}%, macro-F1 "
                f"{r['transfer']['macro_f1']:.3f}")
        vis = (r["transfer"].get("visible") or {}).get("macro_f1")
        if vis is not None:
            msg += f" ({vis:.3f} over the classes {t} sees)"
    return msg


def _plot_model(out: Path, t: str, name: str, split: str, r: dict[str, Any], cm: np.ndarray,
                model: Any) -> None:
    """``OUT/<t>_<name>_confusion.png`` (+ ``_transfer_confusion.png``, and the CNN's
    ``_training.png``)."""
    plot_confusion(cm, out / f"{t}_{name}_confusion.png",
                   f"{t}: {name} ({split} split), accuracy "
                   f"{100 * r['accuracy']:.2f}%, macro-F1 {r['macro_f1']:.3f}",
                   class_names=r["classes"])
    if "transfer" in r:
        tr = r["transfer"]
        plot_confusion(tr["confusion"], out / f"{t}_{name}_transfer_confusion.png",
                       f"{t}: {name} on the transfer logs, accuracy "
                       f"{100 * tr['accuracy']:.2f}%, macro-F1 {tr['macro_f1']:.3f}",
                       class_names=tr["classes"])
    if hasattr(model, "plot_history"):
        model.plot_history(out / f"{t}_{name}_training.png",
                           f"{t}: {name} training accuracy and loss (paper Figs. "
                           "20-21)")
