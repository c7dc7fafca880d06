"""Models that look at time (beyond the paper): window statistics per flight + gradient
boosting (``WindowHGB``, ``WindowHGB60``, ``CentredHGB``; :data:`WINDOW_MODELS`).

The paper classifies single rows. A single GPS row of a flight under RC failsafe (RTL: a
straight line home at WPNAV_SPEED) is a row of normal cruise; an accelerometer fault shows as
vertical speed swinging by metres per second within seconds; an engine fault as a fall and a
vehicle lying still. What tells them apart is how the signals move over a few seconds, so a
window model gives every row the statistics of the rows around it in the same flight:

* for every feature, over windows of ``seconds`` (e.g. 2 s and 10 s, converted to rows with
  the table's logging rate, e.g. 10 and 50 GPS rows at 5 Hz): mean, standard deviation,
  minimum, maximum, mean absolute row-to-row change, and the change over the window (its last
  row minus its first); plus the row's own value;
* a circular feature (``GPS.GCrs``, course over ground, 0-360°) is used only through its
  wrapped row-to-row change (turn rate: mean and maximum over each window), never its value:
  the heading depends on where the route goes, not on a fault;
* optionally (``history``) the mean, minimum and maximum of each feature over the flight so
  far. No registered model uses them: they remember every earlier fault of the flight, and
  with the paper's schedule (RC always last) that is the fault order, not the fault.

Windows are trailing (causal: only the row and earlier rows of its flight, the first rows of
a flight repeating the first value), so the model could run on board as rows arrive, or, with
``centred``, centred on the row (offline analysis of a whole log; the last rows repeat the
last value). Windows never cross flights. The classifier is XGBoost's histogram gradient boosting
(:func:`window_hgb`).

Smoothing the per-row class probabilities over time was measured and is not offered: a
trailing mean over 1-8 s lowers the GPS macro-F1 (0.938 -> 0.929 ... 0.852: it delays every
fault's start and end), a centred one moves it by < 0.003 (``docs/evaluation.md``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import pandas as pd
from numba import njit
from scipy.ndimage import maximum_filter1d

__all__ = ["CIRCULAR_DEG", "TRAIN_HZ", "WINDOW_BOOSTERS", "WINDOW_MODELS", "FlightRuns",
           "SkipConstantColumns", "WindowFeatures", "merged_windows", "normal_rows",
           "row_rate_hz", "row_stride", "train_rows", "window_features", "window_hgb",
           "window_spec_for"]

#: Circular features (table -> feature -> period in the raw unit, degrees).
CIRCULAR_DEG: Mapping[str, Mapping[str, float]] = {"GPS": {"GCrs": 360.0}}

#: The window models of ``tlm evaluate`` -> their windows (:class:`WindowFeatures` fields);
#: all three use :func:`window_hgb`. ``WindowHGB``: causal 2 s and 10 s windows (could run on
#: board). ``WindowHGB60``: causal, adds 30 s and 60 s windows (remembers an RTL that began
#: up to a minute ago: the only trace of how long an RC failsafe has lasted). ``CentredHGB``:
#: the same windows centred on the row, offline only (a row's windows reach 30 s ahead).
WINDOW_MODELS: Mapping[str, Mapping[str, Any]] = {
    "WindowHGB": {"seconds": (2.0, 10.0)},
    "WindowHGB60": {"seconds": (2.0, 10.0, 30.0, 60.0)},
    "CentredHGB": {"seconds": (2.0, 10.0, 30.0, 60.0), "centred": True},
}


#: Window models are fitted on every flight's rows thinned to about this rate [Hz] (every
#: 5th IMU row at 25 Hz, every 2nd RATE/VIBE row at 10 Hz, every GPS row). Rows a fraction
#: of a second apart have near-identical window statistics: on 60 paper-style flights,
#: WindowHGB60 on IMU scores macro-F1 0.939 fitted on every 5th row and 0.938 on all rows,
#: in a quarter of the time (docs/evaluation.md). Every row is still predicted.
TRAIN_HZ: float = 5.0


@dataclass(frozen=True)
class FlightRuns:
    """A table's rows in time order per flight: ``order`` (row positions sorted by flight,
    then ``TimeUS``; stable) and the positions in that order where each flight's rows start
    and end (``ends[-1] == len(df)``). Computed once per table (:meth:`of`) and shared by
    :func:`row_rate_hz`, :func:`train_rows` and :func:`window_features`."""

    order: np.ndarray
    starts: np.ndarray
    ends: np.ndarray

    @classmethod
    def of(cls, df: pd.DataFrame) -> FlightRuns:
        """The runs of ``df`` (columns ``flight`` and ``TimeUS``)."""
        codes, _ = pd.factorize(df["flight"].astype(str), sort=True)  # string order
        order = np.lexsort((df["TimeUS"].to_numpy(), codes))
        ordered = codes[order]
        ends = np.concatenate([np.flatnonzero(ordered[1:] != ordered[:-1]) + 1, [len(df)]])
        return cls(order, np.concatenate([[0], ends[:-1]]), ends)

    @cached_property
    def rank(self) -> np.ndarray:
        """Each row's position within its flight in time order (the first row 0), in table
        order; computed once."""
        n = int(self.ends[-1])
        rank = np.empty(n, dtype=np.int64)
        rank[self.order] = np.arange(n) - np.repeat(self.starts, self.ends - self.starts)
        return rank

    def every(self, k: int) -> np.ndarray:
        """Boolean mask, in table order, of the rows whose position within their flight (in
        time order, the first row 0) is a multiple of ``k``."""
        return self.rank % k == 0


def row_stride(rate_hz: float, hz: float) -> int:
    """k such that keeping every k-th row thins rows logged at ``rate_hz`` to about ``hz``:
    round(``rate_hz`` / ``hz``), at least 1; 1 when ``hz`` is 0 (every row)."""
    return max(1, int(round(rate_hz / hz))) if hz else 1


def _stride(df: pd.DataFrame, rate_hz: float | None, train_hz: float,
            runs: FlightRuns | None) -> tuple[FlightRuns, int]:
    """(``runs`` or ``FlightRuns.of(df)``, k): keeping every k-th row of a flight thins it
    from the table's rate (``rate_hz``, default: measured) to about ``train_hz`` (k = 1 when
    ``train_hz`` is 0)."""
    runs = runs if runs is not None else FlightRuns.of(df)
    if not train_hz:
        return runs, 1
    rate = rate_hz if rate_hz is not None else row_rate_hz(df, runs)
    return runs, row_stride(rate, train_hz)


def train_rows(df: pd.DataFrame, rate_hz: float | None = None,
               train_hz: float = TRAIN_HZ, runs: FlightRuns | None = None) -> np.ndarray:
    """Boolean mask of the rows of ``df`` a window model is fitted on: in each flight, in
    time order, every k-th row from the first, k = round(rate / ``train_hz``) (at least 1;
    every row when ``train_hz`` is 0); ``rate_hz``: the table's logging rate (default:
    measured, :func:`row_rate_hz`); ``runs``: ``FlightRuns.of(df)`` when already known."""
    if not train_hz or not len(df):
        return np.ones(len(df), dtype=bool)
    runs, k = _stride(df, rate_hz, train_hz, runs)
    return runs.every(k)


def normal_rows(df: pd.DataFrame, labels: np.ndarray, every: int,
                rate_hz: float | None = None, train_hz: float = TRAIN_HZ,
                runs: FlightRuns | None = None) -> np.ndarray:
    """Boolean mask of the rows :func:`train_rows` keeps at ``train_hz``, with only every
    ``every``-th of its Normal rows (``labels`` == 0): in each flight, in time order, a
    Normal row is kept when its position is a multiple of ``every`` times the stride at
    ``train_hz``; fault rows are kept as :func:`train_rows` keeps them. A model fitted on
    these rows with sample weight ``every`` on the Normal rows and 1 on the others has, in
    expectation, the loss of the rows at ``train_hz``: the class balance is unchanged."""
    if not len(df):
        return np.ones(0, dtype=bool)
    runs, k = _stride(df, rate_hz, train_hz, runs)
    keep = runs.every(k)
    if every <= 1:
        return keep
    return keep & (runs.every(k * every) | (np.asarray(labels) != 0))


def row_rate_hz(df: pd.DataFrame, runs: FlightRuns | None = None) -> float:
    """Logging rate of a table [Hz]: 1e6 / the median TimeUS step within flights."""
    runs = runs if runs is not None else FlightRuns.of(df)
    t = df["TimeUS"].to_numpy()[runs.order].astype(np.float64)
    steps = np.diff(t)
    if len(steps):
        steps[runs.ends[:-1] - 1] = 0.0  # a flight's last row to the next flight's first
    steps = steps[steps > 0]
    if not len(steps):
        return 1.0
    return float(1e6 / np.median(steps))


@dataclass(frozen=True)
class WindowFeatures:
    """How rows are turned into window statistics (see the module docstring).

    ``seconds``: window lengths [s]. ``circular``: feature -> period in the units the feature
    has in the table (for min-max scaled GCrs: 360 / (max - min)). ``centred``: windows
    centred on the row (rows t - w//2 .. t + w - 1 - w//2: offline only, they see the
    future) instead of trailing ones. ``history``: add whole-history statistics of every
    non-circular feature (mean, minimum, maximum over the flight's rows up to and including
    the row: causal, but they remember every earlier fault of the flight).
    """

    seconds: tuple[float, ...] = (2.0, 10.0)
    circular: Mapping[str, float] = field(default_factory=dict)
    centred: bool = False
    history: bool = False

    def names(self, features: Sequence[str]) -> list[str]:
        out: list[str] = []
        for f in features:
            if f in self.circular:
                for s in self.seconds:
                    out += [f"{f}_turn_mean{s:g}s", f"{f}_turn_max{s:g}s"]
                continue
            out.append(f)
            for s in self.seconds:
                out += [f"{f}_{st}{s:g}s" for st in
                        ("mean", "std", "min", "max", "absdiff", "change")]
            if self.history:
                out += [f"{f}_hist_{st}" for st in ("mean", "min", "max")]
        return out


def window_spec_for(model: str, circular: Mapping[str, float]) -> WindowFeatures:
    """The :class:`WindowFeatures` of window model ``model`` (a :data:`WINDOW_MODELS` name)
    with ``circular`` periods (feature -> period in the table's units)."""
    if model not in WINDOW_MODELS:
        raise ValueError(f"unknown window model {model!r}; choose from "
                         f"{', '.join(WINDOW_MODELS)}")
    return WindowFeatures(circular=dict(circular), **WINDOW_MODELS[model])


def _trailing_sum(x: np.ndarray, w: int) -> np.ndarray:
    """Sum of x[t - w + 1 .. t], the start padded with x[0]."""
    padded = np.concatenate([np.full(w - 1, x[0]), x])
    c = np.concatenate([[0.0], np.cumsum(padded)])
    return c[w:] - c[:-w]


def _trailing_filter(fn, x: np.ndarray, w: int) -> np.ndarray:
    """``fn`` (a scipy.ndimage 1-D min/max filter) over x[t - w + 1 .. t], the start padded
    with x[0]."""
    padded = np.concatenate([np.full(w - 1, x[0]), x])
    centred = fn(padded, size=w, mode="nearest")  # centre c covers c - w//2 .. c - w//2 + w - 1
    return centred[w // 2: w // 2 + len(x)]


@njit(cache=True, nogil=True)
def _trailing_stats(ve: np.ndarray, w: int, lead: int, n: int) -> np.ndarray:
    """Statistics of the trailing windows of ``w`` rows of series ``ve`` (its start padded
    with ``ve[0]``) ending at rows ``lead .. lead + n - 1``: (n, 6) columns mean, standard
    deviation, minimum, maximum, mean absolute row-to-row change, last minus first value.

    One pass (numba): the sums are differences of running sums accumulated in the order
    ``np.cumsum`` adds (the results equal the former numpy code's to the bit), the minimum
    and maximum come from monotonic queues."""
    m = len(ve)
    c1 = np.zeros(m + w)
    c2 = np.zeros(m + w)
    ca = np.zeros(m + w)
    for i in range(m + w - 1):  # running sums of the padded series
        j = i - (w - 1)
        x = ve[0] if j < 0 else ve[j]
        a = 0.0 if j <= 0 else abs(ve[j] - ve[j - 1])
        c1[i + 1] = c1[i] + x
        c2[i + 1] = c2[i] + x * x
        ca[i + 1] = ca[i] + a
    out = np.empty((n, 6))
    qmin = np.empty(m, dtype=np.int64)  # row indices, values increasing
    qmax = np.empty(m, dtype=np.int64)  # values decreasing
    h0 = t0 = h1 = t1 = 0
    for t in range(lead + n):
        x = ve[t]
        while t0 > h0 and ve[qmin[t0 - 1]] >= x:
            t0 -= 1
        qmin[t0] = t
        t0 += 1
        while t1 > h1 and ve[qmax[t1 - 1]] <= x:
            t1 -= 1
        qmax[t1] = t
        t1 += 1
        first = t - w + 1
        while qmin[h0] < first:
            h0 += 1
        while qmax[h1] < first:
            h1 += 1
        if t < lead:
            continue
        r = t - lead
        mean = (c1[t + w] - c1[t]) / w
        out[r, 0] = mean
        out[r, 1] = np.sqrt(max((c2[t + w] - c2[t]) / w - mean * mean, 0.0))
        lo = ve[qmin[h0]]
        hi = ve[qmax[h1]]
        if first < 0:  # the padding repeats ve[0]
            lo = min(lo, ve[0])
            hi = max(hi, ve[0])
        out[r, 2] = lo
        out[r, 3] = hi
        out[r, 4] = (ca[t + w] - ca[t]) / w
        out[r, 5] = x - ve[max(first, 0)]
    return out


def _flight_block(x: np.ndarray, feats: Sequence[str], spec: WindowFeatures,
                  rows: Sequence[int]) -> np.ndarray:
    """Window features of one flight's rows (time order), shape (n, n_out); ``rows``: the
    window lengths in rows.

    Centred windows are trailing windows of the series padded at its end with its last value
    and read ``w - 1 - w//2`` rows later."""
    cols: list[np.ndarray] = []
    n = len(x)
    for j, f in enumerate(feats):
        v = x[:, j]
        v = np.where(np.isfinite(v), v, np.nanmean(v) if np.isfinite(v).any() else 0.0)
        d = np.diff(v, prepend=v[0])
        if f in spec.circular:
            p = spec.circular[f]
            turn = np.abs((d + p / 2) % p - p / 2)
            for w in rows:
                lead = (w - 1 - w // 2) if spec.centred else 0
                te = np.concatenate([turn, np.zeros(lead)])
                cols.append((_trailing_sum(te, w) / w)[lead:lead + n])
                cols.append(_trailing_filter(maximum_filter1d, te, w)[lead:lead + n])
            continue
        cols.append(v)
        for w in rows:
            lead = (w - 1 - w // 2) if spec.centred else 0
            ve = np.concatenate([v, np.full(lead, v[-1])]) if lead else v
            cols.extend(_trailing_stats(ve, w, lead, n).T)
        if spec.history:
            cols.append(np.cumsum(v) / np.arange(1, n + 1))
            cols.append(np.minimum.accumulate(v))
            cols.append(np.maximum.accumulate(v))
    return np.column_stack(cols) if cols else np.empty((n, 0))


def window_features(df: pd.DataFrame, features: Sequence[str],
                    spec: WindowFeatures | None = None, rate_hz: float | None = None,
                    rows: np.ndarray | None = None, runs: FlightRuns | None = None
                    ) -> tuple[np.ndarray, list[str]]:
    """Window statistics of every row of ``df`` (columns ``flight``, ``TimeUS`` and
    ``features``), in ``df``'s row order, or with ``rows`` (distinct row positions) of those
    rows only, in that order (the windows still see every row of the flight); returns
    (float32 matrix, column names). ``rate_hz``: the table's logging rate (default: measured,
    :func:`row_rate_hz`); ``runs``: ``FlightRuns.of(df)`` when already known."""
    spec = spec or WindowFeatures()
    runs = runs if runs is not None else FlightRuns.of(df)
    rate = rate_hz if rate_hz is not None else row_rate_hz(df, runs)
    width = [max(2, int(round(s * rate))) for s in spec.seconds]
    names = spec.names(features)
    n_out = len(df) if rows is None else len(rows)
    out = np.empty((n_out, len(names)), dtype=np.float32)
    dest = None
    if rows is not None:  # table row -> output row (-1: not asked for)
        dest = np.full(len(df), -1, dtype=np.int64)
        dest[rows] = np.arange(len(rows))
    order = runs.order
    x = df[list(features)].to_numpy(np.float64)[order]
    for a, b in zip(runs.starts, runs.ends, strict=True):
        if b <= a:
            continue
        if dest is None:
            out[order[a:b]] = _flight_block(x[a:b], features, spec, width)
            continue
        d = dest[order[a:b]]
        want = d >= 0
        if want.any():
            out[d[want]] = _flight_block(x[a:b], features, spec, width)[want]
    return out, names


def merged_windows(specs: Mapping[str, WindowFeatures], features: Sequence[str]
                   ) -> tuple[list[WindowFeatures], dict[str, tuple[int, np.ndarray | None]]]:
    """Window specs that compute every statistic of ``specs`` (model -> spec) once: models
    whose specs differ only in their window lengths share one spec with every length
    (``WindowHGB``'s 2 s and 10 s windows are columns of ``WindowHGB60``'s). Returns (the
    merged specs, model -> (index of its merged spec, the columns of that spec's matrix that
    are the model's, in its own order; None: all of them))."""
    merged: list[WindowFeatures] = []
    keys: list[tuple[Any, ...]] = []
    for sp in specs.values():
        key = (tuple(sorted(sp.circular.items())), sp.centred, sp.history)
        if key in keys:
            i = keys.index(key)
            secs = tuple(dict.fromkeys(merged[i].seconds + sp.seconds))
            merged[i] = WindowFeatures(secs, sp.circular, sp.centred, sp.history)
        else:
            keys.append(key)
            merged.append(sp)
    which: dict[str, tuple[int, np.ndarray | None]] = {}
    for m, sp in specs.items():
        key = (tuple(sorted(sp.circular.items())), sp.centred, sp.history)
        i = keys.index(key)
        all_names = merged[i].names(features)
        own = sp.names(features)
        if own == all_names:
            which[m] = (i, None)
        else:
            index = {n: j for j, n in enumerate(all_names)}
            which[m] = (i, np.array([index[n] for n in own], dtype=np.int64))
    return merged, which


#: The boosters a window model can be built on (``tlm evaluate --booster``): ``xgboost``
#: (the default) and ``sklearn``, the window models' booster until 2026-11 (see
#: :func:`window_hgb`).
WINDOW_BOOSTERS: tuple[str, ...] = ("xgboost", "sklearn")


def window_hgb(seed: int = 0, n_jobs: int = 1, booster: str = "xgboost") -> Any:
    """The classifier of the window models (fed with :func:`window_features`, wrapped in
    :class:`SkipConstantColumns`).

    ``booster`` "sklearn": scikit-learn's ``HistGradientBoostingClassifier`` as the window
    models had it until 2026-11: 150 rounds, learning rate 0.1, at most 31 leaves grown best
    first, at least 50 rows a leaf, L2 regularisation 1, every column in every tree, no early
    stopping (its threads are OpenMP's, as :func:`~tlm_process.evaluate.runner.evaluate`
    limits them). Three to four times slower than the default; on the 200-flight benchmark set
    its test macro-F1 is 0.02-0.04 higher in three cells (IMU ``WindowHGB60``, VIBE
    ``WindowHGB60`` and ``CentredHGB``) and within the seed's spread elsewhere
    (``docs/evaluation-history.md``, "The booster").

    ``booster`` "xgboost" (the default): XGBoost's histogram gradient boosting (``tree_method=
    "hist"``, 255 bins per column), 150 rounds of one tree per class, learning rate 0.1,
    trees grown level by level to depth 5 (at most 32 leaves), each tree on a random 30 % of
    the columns (``colsample_bytree``: the window statistics of one signal are near copies
    of each other), L2 regularisation 1 on the leaf values, a leaf's summed hessian at least
    1 (XGBoost's default), no early stopping (its validation rows would be drawn at random,
    i.e. leak). ``n_jobs``: OpenMP threads (the trees are the same; on 200 flights the
    probabilities moved in the 7th digit between 1 and 2 threads, no predicted class). Against
    scikit-learn's ``HistGradientBoostingClassifier`` with 150 rounds, rate 0.1 and 31
    leaves (the window models' booster until 2026-11) on the 60-flight benchmark set: fits
    2-5 times faster, macro-F1 0.025 higher in-domain and 0.068 higher on the SITL logs on
    average over the 12 table x model cells (``docs/evaluation-history.md``, "The booster")."""
    if booster == "sklearn":
        from sklearn.ensemble import HistGradientBoostingClassifier

        return HistGradientBoostingClassifier(max_iter=150, learning_rate=0.1,
                                              max_leaf_nodes=31, min_samples_leaf=50,
                                              l2_regularization=1.0, early_stopping=False,
                                              random_state=seed)
    if booster != "xgboost":
        raise ValueError(f"unknown booster {booster!r}; choose from "
                         f"{', '.join(WINDOW_BOOSTERS)}")
    from xgboost import XGBClassifier

    return XGBClassifier(n_estimators=150, learning_rate=0.1, tree_method="hist", max_bin=255,
                         grow_policy="depthwise", max_depth=5, colsample_bytree=0.3,
                         reg_lambda=1.0, min_child_weight=1.0, n_jobs=n_jobs,
                         random_state=seed)


class SkipConstantColumns:
    """``estimator`` fitted and asked on the columns that vary over its training rows only,
    with the classes numbered 0..K-1 (as XGBoost wants them).

    A column with one value in every training row (e.g. the windows of a feature the data
    set holds constant, like ``GPS.HDop``: a quarter of ``WindowHGB60``'s GPS columns) can
    never split a tree, yet gradient boosting builds its histogram for every tree and a
    tree's random share of the columns would draw it. Leaving it out gives the same trees
    where every tree sees every column (a split is only ever found on the other columns, in
    the same order), and more useful columns per tree where it does not. With a single class
    in the training rows nothing is fitted and that class is predicted. Scikit-learn style:
    ``fit``, ``predict``, ``predict_proba``, ``classes_``, ``columns_`` (the columns kept)."""

    def __init__(self, estimator: Any) -> None:
        self.estimator = estimator

    def fit(self, X: np.ndarray, y: Any, sample_weight: Any = None) -> SkipConstantColumns:
        X = np.asarray(X)
        if len(X):
            same = (X == X[:1]).all(axis=0) | np.isnan(X).all(axis=0)
        else:
            same = np.zeros(X.shape[1], dtype=bool)
        self.columns_ = np.flatnonzero(~same) if (~same).any() else np.arange(X.shape[1])
        self.classes_, code = np.unique(np.asarray(y), return_inverse=True)
        if len(self.classes_) > 1:
            self.estimator.fit(self._x(X), code, sample_weight=sample_weight)
        return self

    def _x(self, X: np.ndarray) -> np.ndarray:
        X = np.asarray(X)
        return X if len(self.columns_) == X.shape[1] else X[:, self.columns_]

    def predict(self, X: np.ndarray) -> np.ndarray:
        return self.classes_[self.predict_proba(X).argmax(axis=1)]

    def predict_proba(self, X: np.ndarray) -> np.ndarray:
        if len(self.classes_) == 1:
            return np.ones((len(X), 1))
        return self.estimator.predict_proba(self._x(X))
