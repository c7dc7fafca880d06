"""The ten classifiers of the paper's Table 11 as scikit-learn estimators mirroring Weka's.

The paper ran Weka 3.8 with default options. Each name below is built by :func:`make_model`
with Weka's defaults translated to scikit-learn (the table in ``docs/evaluation.md`` lists
them, with what differs):

==============  =============================================================================
NaiveBayes      :class:`WekaNaiveBayes`: Gaussian per class and feature, standard deviation
                floored at Weka's estimator precision / 6
Logistic        standardise + multinomial logistic regression, ridge 1e-8 (C = 1 / (2 ridge))
SMO             min-max normalise + linear SVM (C = 1, hinge loss), pairwise one-vs-one
KNN             :class:`IBk`: 1 nearest neighbour, Euclidean distance on range-normalised
                features
AdaBoost        :class:`AdaBoostM1`: 10 rounds of decision stumps, reweighting, M1's stop rule
OneR            :class:`OneR`: Holte's 1R, minimum bucket size 6
ZeroR           the training set's most frequent class
J48             :class:`J48`: entropy tree, min 2 per leaf, C4.5 pessimistic pruning (CF 0.25)
RandomForest    100 entropy trees on bootstrap samples, int(log2(M) + 1) features per split
RandomTree      one entropy tree, int(log2(M) + 1) random features per split, unpruned
==============  =============================================================================

``CNN`` (:mod:`.cnn`) and ``WindowHGB`` (:mod:`.temporal`) are built here too, so that every
model name of ``tlm evaluate`` comes from one place. Missing values (NaN) are replaced by the
training mean for the models Weka runs through ``ReplaceMissingValues`` (Logistic, SMO, KNN);
the others handle NaN themselves.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache
from typing import Any

import numpy as np
from scipy.spatial import cKDTree
from scipy.stats import norm
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.dummy import DummyClassifier
from sklearn.ensemble import RandomForestClassifier
from sklearn.impute import SimpleImputer
from sklearn.linear_model import LogisticRegression
from sklearn.multiclass import OneVsOneClassifier
from sklearn.naive_bayes import GaussianNB
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import MinMaxScaler, StandardScaler
from sklearn.svm import LinearSVC
from sklearn.tree import DecisionTreeClassifier
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

__all__ = [
    "ALL_MODELS",
    "DEFAULT_MAX_ROWS",
    "MAX_ROWS",
    "DEFAULT_NORMAL_HZ",
    "DEFAULT_TRAIN_HZ",
    "IBk",
    "PAPER_MODELS",
    "SEQUENCE_MODELS",
    "WEIGHTED_MODELS",
    "TIME_MODELS",
    "AdaBoostM1",
    "J48",
    "OneR",
    "WekaNaiveBayes",
    "c45_added_errors",
    "make_model",
    "weka_num_features",
]

#: Table 11's models, in the paper's order.
PAPER_MODELS: tuple[str, ...] = ("NaiveBayes", "Logistic", "SMO", "KNN", "AdaBoost", "OneR",
                                 "ZeroR", "J48", "RandomForest", "RandomTree")
#: Models whose inputs are whole flights in time order (:mod:`.sequence`).
SEQUENCE_MODELS: tuple[str, ...] = ("SeqCNN",)
#: Models that look at consecutive rows (beyond the paper): the window models
#: (:mod:`.temporal`), then the sequence models.
TIME_MODELS: tuple[str, ...] = ("WindowHGB", "WindowHGB60", "CentredHGB") + SEQUENCE_MODELS
#: Every model ``tlm evaluate --models all`` runs.
ALL_MODELS: tuple[str, ...] = PAPER_MODELS + ("CNN",) + TIME_MODELS

#: Rate [Hz] each model's training rows are thinned to by default (``tlm evaluate
#: --train-hz``; 0: every row): in each flight, in time order, every k-th row, k =
#: round(table rate / Hz) (5 Hz: every GPS row, every 2nd RATE/VIBE row, every 5th IMU
#: row). Test rows are never thinned. Measured on a 60-flight set (``docs/evaluation-history.md``,
#: "Training rows"): a model is thinned to 5 Hz where on every table its macro-F1 on the
#: test flights and on the transfer logs stayed within 0.01 of fitting every row; SMO to
#: 1 Hz (within 0.01 on GPS; on every row it takes hours on IMU); the window models keep the
#: 5 Hz they always had; SeqCNN learns from every row (its cost is a fixed number of steps,
#: whatever the rows). Logistic and RandomForest: 5 Hz with their Normal rows at 1 Hz
#: (:data:`DEFAULT_NORMAL_HZ`).
DEFAULT_TRAIN_HZ: dict[str, float] = {
    "NaiveBayes": 5.0, "Logistic": 5.0, "SMO": 1.0, "KNN": 5.0, "AdaBoost": 5.0,
    "OneR": 5.0, "ZeroR": 5.0, "J48": 0.0, "RandomForest": 5.0, "RandomTree": 0.0,
    "CNN": 0.0, **{m: 5.0 for m in TIME_MODELS}, "SeqCNN": 0.0}

#: Models whose fit takes per-row sample weights, so that their Normal training rows can be
#: thinned more than the fault rows and weighted back (``tlm evaluate --normal-hz``).
WEIGHTED_MODELS: tuple[str, ...] = ("NaiveBayes", "Logistic", "ZeroR", "RandomForest", "CNN",
                                    "RandomTree", "WindowHGB", "WindowHGB60", "CentredHGB")

#: Rate [Hz] of each model's Normal training rows by default (``--normal-hz``; 0 or missing:
#: the model's training-row rate), for :data:`WEIGHTED_MODELS`. Normal rows are 87 % of a
#: ``tlm generate`` data set. Measured on the 60-flight set (``docs/evaluation-history.md``,
#: "Normal rows"; 3.5-17 times fewer rows fitted): Logistic and RandomForest at 5 Hz with the
#: Normal rows at 1 Hz scored within 0.01 of every row except Logistic's RATE transfer score
#: (-0.07) and RandomForest's VIBE transfer score (-0.011); WindowHGB60 and CentredHGB gained
#: on most tables (up to +0.12) and lost at most 0.035; WindowHGB lost 0.03 / 0.06 on GPS
#: (0.06 / 0.13 on XGBoost) and keeps every 5 Hz row. The CNN (every row) with its Normal
#: rows at 2 Hz: within 0.007 on GPS, RATE and VIBE, +0.04 / +0.08 on IMU, fit 2.1 times
#: faster on GPS (at 1 Hz it lost 0.021 on GPS and 0.045 on VIBE transfer).
DEFAULT_NORMAL_HZ: dict[str, float] = {"Logistic": 1.0, "RandomForest": 1.0, "CNN": 2.0,
                                       "WindowHGB60": 1.0, "CentredHGB": 1.0}

#: The most training rows each model is fitted on per fold by default (``--max-rows``; 0 or
#: missing: no limit): beyond it its rates are lowered, evenly in every flight, the Normal
#: rows first for :data:`WEIGHTED_MODELS` (``runner.row_budget``), so that its fit costs
#: about the same on 60 flights or 1,000. 100,000 rows for the models whose fit (or, for
#: KNN, prediction) grows with the rows; 30,000 for WindowHGB60 and CentredHGB (their 325
#: RATE columns make them the costliest fits). On the 60-flight benchmark set it binds only
#: for the CNN on IMU, RATE and VIBE (every row: 495,402 and 198,146 rows; IMU fit 229 s ->
#: 17 s); on 200 flights WindowHGB60 and CentredHGB at 30,000 rows instead of 94,755 scored
#: within 0.005 test macro-F1 on GPS and 0.012-0.032 higher on RATE in a third of the time
#: (``docs/evaluation.md`` "Row budget"). J48, RandomTree and the other cheap models fit
#: every row their rate keeps, SeqCNN a fixed number of steps.
MAX_ROWS: int = 100_000
DEFAULT_MAX_ROWS: dict[str, int] = {m: MAX_ROWS for m in (
    "Logistic", "SMO", "KNN", "RandomForest", "CNN", "WindowHGB")} | {
    "WindowHGB60": 30_000, "CentredHGB": 30_000}

#: Passes of liblinear's dual coordinate descent per SMO class pair. The pairs of Normal
#: against a fault overlap and do not converge within 20,000 passes either (hinge loss,
#: C = 1); on 200 flights 300 passes scored within 0.003 of 20,000 (test macro-F1; the
#: transfer scores were the same) and fitted RATE in 9 s instead of 135-207 s
#: (``docs/evaluation.md``, "Iterations").
SMO_MAX_ITER = 300

#: L-BFGS iterations of Logistic. On 200 flights 100 iterations scored within 0.0005 of 500
#: on every table (test and transfer macro-F1) and fitted in 3.4 s instead of 7-15 s
#: (``docs/evaluation.md``, "Iterations").
LOGISTIC_MAX_ITER = 100

#: Weka's default ridge of ``weka.classifiers.functions.Logistic``.
LOGISTIC_RIDGE = 1e-8


def weka_num_features(n_features: int) -> int:
    """Features tried per split by Weka's RandomTree/RandomForest with K = 0:
    ``int(log2(M) + 1)``."""
    return max(1, int(math.log2(max(n_features, 1)) + 1))


def _tags_allow_nan(tags: Any) -> Any:
    tags.input_tags.allow_nan = True
    return tags


def _one_hot(idx: np.ndarray, n_classes: int) -> np.ndarray:
    """Class probabilities of a model that gives one class per row: 1 at class index ``idx``
    of each row, 0 elsewhere (rows x ``n_classes``)."""
    out = np.zeros((len(idx), n_classes))
    out[np.arange(len(idx)), idx] = 1.0
    return out


# ---------------------------------------------------------------------------------------------
# OneR
# ---------------------------------------------------------------------------------------------

class OneR(ClassifierMixin, BaseEstimator):
    """Holte's 1R (Weka ``weka.classifiers.rules.OneR``): a rule on one feature.

    For every feature the training rows are sorted by value and cut into intervals: an
    interval grows until its most frequent class has at least ``min_bucket_size`` rows and
    the next value's most frequent class differs (rows with equal values are never split);
    adjacent intervals with the same class are merged; the breakpoints lie half-way between
    neighbouring values. Missing values (NaN) form their own bucket. The feature whose rule
    classifies the most training rows correctly is chosen (the first on ties).

    Attributes: ``feature_`` (index of the chosen feature), ``breakpoints_`` (ascending),
    ``interval_classes_`` (``len(breakpoints_) + 1`` classes: value < breakpoints_[0] gives
    the first), ``missing_class_``, ``train_accuracy_`` (per feature), ``classes_``.
    """

    def __init__(self, min_bucket_size: int = 6) -> None:
        self.min_bucket_size = min_bucket_size

    def __sklearn_tags__(self) -> Any:
        return _tags_allow_nan(super().__sklearn_tags__())

    def fit(self, X: Any, y: Any) -> OneR:
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float64)
        check_classification_targets(y)
        if not isinstance(self.min_bucket_size, int | np.integer) or self.min_bucket_size < 1:
            raise ValueError(f"min_bucket_size must be a positive integer, got "
                             f"{self.min_bucket_size!r}")
        self.classes_, yi = np.unique(y, return_inverse=True)
        k = len(self.classes_)
        majority = int(np.argmax(np.bincount(yi, minlength=k)))
        best: tuple[int, np.ndarray, np.ndarray, int] | None = None
        best_correct = -1
        acc = np.zeros(X.shape[1])
        for j in range(X.shape[1]):
            bps, cls, miss_cls, correct = self._rule(X[:, j], yi, k, majority)
            acc[j] = correct / len(yi)
            if correct > best_correct:
                best_correct = correct
                best = (j, bps, cls, miss_cls)
        assert best is not None
        self.feature_, self.breakpoints_, self.interval_classes_, self.missing_class_ = best
        self.train_accuracy_ = acc
        return self

    def _rule(self, x: np.ndarray, y: np.ndarray, k: int,
              majority: int) -> tuple[np.ndarray, np.ndarray, int, int]:
        """(breakpoints, interval classes, missing class, correct training rows) of one
        feature."""
        nan = np.isnan(x)
        correct = 0
        miss_cls = majority
        if nan.any():
            c = np.bincount(y[nan], minlength=k)
            miss_cls = int(np.argmax(c))
            correct += int(c.max())
        xv, yv = x[~nan], y[~nan]
        if not len(xv):
            return np.empty(0), np.array([majority]), miss_cls, correct
        values, inv = np.unique(xv, return_inverse=True)
        counts = np.zeros((len(values), k), dtype=np.int64)
        np.add.at(counts, (inv, yv), 1)
        group_major = counts.argmax(axis=1)
        # 1. intervals of at least min_bucket_size rows of their majority class
        cut_after: list[int] = []
        cur = np.zeros(k, dtype=np.int64)
        for g in range(len(values) - 1):
            cur += counts[g]
            m = int(cur.argmax())
            if cur[m] >= self.min_bucket_size and group_major[g + 1] != m:
                cut_after.append(g)
                cur[:] = 0
        bounds = [0] + [g + 1 for g in cut_after] + [len(values)]
        interval_counts = [counts[a:b].sum(axis=0) for a, b in zip(bounds[:-1], bounds[1:],
                                                                     strict=True)]
        classes = [int(c.argmax()) for c in interval_counts]
        # 2. merge neighbours predicting the same class
        bps: list[float] = []
        merged: list[int] = [classes[0]]
        for i, g in enumerate(cut_after):
            if classes[i + 1] == merged[-1]:
                continue
            bps.append((values[g] + values[g + 1]) / 2.0)
            merged.append(classes[i + 1])
        correct += int(sum(c.max() for c in interval_counts))
        return np.asarray(bps, dtype=np.float64), np.asarray(merged), miss_cls, correct

    def _class_index(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float64)
        x = X[:, self.feature_]
        idx = self.interval_classes_[np.searchsorted(self.breakpoints_, x, side="right")
                                     .clip(0, len(self.interval_classes_) - 1)]
        return np.where(np.isnan(x), self.missing_class_, idx)

    def predict(self, X: Any) -> np.ndarray:
        idx = self._class_index(X)
        return self.classes_[idx]

    def predict_proba(self, X: Any) -> np.ndarray:
        """One-hot: a rule gives one class (as Weka's OneR distribution)."""
        return _one_hot(self._class_index(X), len(self.classes_))

    def rule_text(self, feature_names: list[str] | None = None) -> str:
        """The rule as Weka prints it: ``Spd: < 0.12 -> 3, < 0.5 -> 0, >= 0.5 -> 4``."""
        check_is_fitted(self)
        name = (feature_names[self.feature_] if feature_names is not None
                else f"x{self.feature_}")
        parts = [f"< {b:.6g} -> {self.classes_[c]}" for b, c in
                 zip(self.breakpoints_, self.interval_classes_[:-1], strict=True)]
        last = self.breakpoints_[-1] if len(self.breakpoints_) else None
        parts.append(f">= {last:.6g} -> {self.classes_[self.interval_classes_[-1]]}"
                     if last is not None else f"-> {self.classes_[self.interval_classes_[-1]]}")
        return f"{name}: " + ", ".join(parts)


# ---------------------------------------------------------------------------------------------
# AdaBoost.M1
# ---------------------------------------------------------------------------------------------

class AdaBoostM1(ClassifierMixin, BaseEstimator):
    """Freund & Schapire's AdaBoost.M1 with decision stumps (Weka ``AdaBoostM1`` with its
    default ``DecisionStump``, 10 iterations, reweighting).

    Each round fits an entropy stump to the weighted rows; with weighted error ``e`` the
    round gets the vote ``log((1 - e) / e)`` and the weights of correctly classified rows are
    multiplied by ``e / (1 - e)``. Boosting stops when ``e >= 0.5`` or ``e == 0`` (in the
    first round that stump is kept alone, with vote 1) — with five classes a stump often
    cannot get below 0.5, which is why the paper's AdaBoost predicts only some classes
    (undefined precision in Table 11). scikit-learn's SAMME differs exactly there (it adds
    ``log(K - 1)`` and stops only at ``e >= 1 - 1/K``).
    """

    def __init__(self, n_estimators: int = 10, random_state: int | None = None) -> None:
        self.n_estimators = n_estimators
        self.random_state = random_state

    def __sklearn_tags__(self) -> Any:
        return _tags_allow_nan(super().__sklearn_tags__())

    def fit(self, X: Any, y: Any) -> AdaBoostM1:
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float64)
        check_classification_targets(y)
        if not isinstance(self.n_estimators, int | np.integer) or self.n_estimators < 1:
            raise ValueError(f"n_estimators must be a positive integer, got "
                             f"{self.n_estimators!r}")
        self.classes_, yi = np.unique(y, return_inverse=True)
        w = np.full(len(yi), 1.0 / len(yi))
        self.estimators_: list[DecisionTreeClassifier] = []
        votes: list[float] = []
        self.errors_: list[float] = []
        for m in range(self.n_estimators):
            stump = DecisionTreeClassifier(max_depth=1, criterion="entropy",
                                           random_state=self.random_state)
            stump.fit(X, yi, sample_weight=w)
            miss = stump.predict(X) != yi
            err = float(w[miss].sum() / w.sum())
            self.errors_.append(err)
            if err >= 0.5 or err == 0.0:
                if m == 0:
                    self.estimators_.append(stump)
                    votes.append(1.0)
                break
            self.estimators_.append(stump)
            votes.append(math.log((1.0 - err) / err))
            total = w.sum()
            w = np.where(miss, w, w * err / (1.0 - err))
            w *= total / w.sum()
        self.estimator_weights_ = np.asarray(votes)
        return self

    def _scores(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float64)
        s = np.zeros((X.shape[0], len(self.classes_)))
        rows = np.arange(X.shape[0])
        for est, a in zip(self.estimators_, self.estimator_weights_, strict=True):
            s[rows, est.predict(X).astype(int)] += a
        return s

    def predict(self, X: Any) -> np.ndarray:
        scores = self._scores(X)
        return self.classes_[scores.argmax(axis=1)]

    def predict_proba(self, X: Any) -> np.ndarray:
        s = self._scores(X)
        return s / s.sum(axis=1, keepdims=True)


# ---------------------------------------------------------------------------------------------
# J48 (C4.5)
# ---------------------------------------------------------------------------------------------

@lru_cache(maxsize=8)
def _upper_z(cf: float) -> float:
    """The standard normal quantile at 1 - ``cf`` (asked once per confidence: SciPy's
    ``norm.ppf`` costs 80 µs a call, 6 of J48's 33 s on 1.5 million IMU rows per node)."""
    return float(norm.ppf(1.0 - cf))


def c45_added_errors(n: float, e: float, cf: float = 0.25) -> float:
    """C4.5's pessimistic extra errors for a leaf with ``n`` rows of which ``e`` are
    misclassified: the upper limit of the binomial confidence interval at confidence ``cf``
    (Quinlan 1993; the leaf's estimated errors are ``e + c45_added_errors(n, e, cf)``)."""
    if n <= 0:
        return 0.0
    if e < 1.0:
        base = n * (1.0 - cf ** (1.0 / n))
        if e == 0.0:
            return base
        return base + e * (c45_added_errors(n, 1.0, cf) - base)
    if e + 0.5 >= n:
        return max(n - e, 0.0)
    z = _upper_z(cf)
    f = (e + 0.5) / n
    r = (f + z * z / (2 * n) + z * math.sqrt(f / n - f * f / n + z * z / (4 * n * n))) \
        / (1.0 + z * z / n)
    return r * n - e


class J48(ClassifierMixin, BaseEstimator):
    """C4.5 as Weka's J48 (default ``-C 0.25 -M 2``): an entropy tree with at least
    ``min_samples_leaf`` rows per leaf, pruned bottom-up by subtree replacement with C4.5's
    pessimistic error (confidence ``confidence``): a subtree becomes a leaf when the leaf's
    estimated errors are at most the subtree's + 0.1 (as Weka compares them).

    Differences from Weka: the split criterion is information gain (C4.5 uses gain ratio;
    for binary splits of numeric features the two rank splits alike except for the split
    information term) and subtree raising is not done.

    Attributes: ``tree_`` (the unpruned scikit-learn tree), ``pruned_node_`` (for every node
    the node that answers for it after pruning), ``n_leaves_`` (after pruning).
    """

    def __init__(self, confidence: float = 0.25, min_samples_leaf: int = 2,
                 random_state: int | None = None) -> None:
        self.confidence = confidence
        self.min_samples_leaf = min_samples_leaf
        self.random_state = random_state

    def __sklearn_tags__(self) -> Any:
        return _tags_allow_nan(super().__sklearn_tags__())

    def fit(self, X: Any, y: Any) -> J48:
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float64)
        check_classification_targets(y)
        if not 0.0 < float(self.confidence) < 0.5:
            raise ValueError(f"confidence must be in (0, 0.5), got {self.confidence!r}")
        self.classes_, yi = np.unique(y, return_inverse=True)
        self.tree_model_ = DecisionTreeClassifier(
            criterion="entropy", min_samples_leaf=self.min_samples_leaf,
            random_state=self.random_state).fit(X, yi)
        t = self.tree_model_.tree_
        self.tree_ = t
        counts = t.value[:, 0, :] * t.weighted_n_node_samples[:, None]
        n = t.weighted_n_node_samples
        leaf_err = n - counts.max(axis=1)
        left, right = t.children_left, t.children_right
        est = np.zeros(t.node_count)
        collapsed = np.zeros(t.node_count, dtype=bool)
        # nodes are numbered depth-first: children after parents, so go backwards
        for node in range(t.node_count - 1, -1, -1):
            as_leaf = leaf_err[node] + c45_added_errors(n[node], leaf_err[node],
                                                         self.confidence)
            if left[node] == -1:
                est[node] = as_leaf
                continue
            subtree = est[left[node]] + est[right[node]]
            if as_leaf <= subtree + 0.1:
                collapsed[node] = True
                est[node] = as_leaf
            else:
                est[node] = subtree
        answer = np.arange(t.node_count)
        for node in range(t.node_count):  # parents first: inherit a collapsed ancestor
            for child in (left[node], right[node]):
                if child != -1:
                    answer[child] = answer[node] if (collapsed[node] or
                                                     answer[node] != node) else child
        self.pruned_node_ = answer
        is_leaf = (answer == np.arange(t.node_count)) & ((left == -1) | collapsed)
        self.n_leaves_ = int(is_leaf.sum())
        self._proba = t.value[:, 0, :]
        return self

    def predict_proba(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float64)
        leaves = self.tree_model_.apply(X)
        return self._proba[self.pruned_node_[leaves]]

    def predict(self, X: Any) -> np.ndarray:
        proba = self.predict_proba(X)
        return self.classes_[proba.argmax(axis=1)]


# ---------------------------------------------------------------------------------------------
# IBk (1 nearest neighbour)
# ---------------------------------------------------------------------------------------------

class IBk(ClassifierMixin, BaseEstimator):
    """Weka's ``IBk`` with its defaults: the class of the single nearest training row in
    Euclidean distance (feed it range-normalised rows). The neighbour is found in SciPy's
    k-d tree (``cKDTree``, ``workers`` = ``n_jobs`` threads): on the 200-flight IMU table
    (96,570 training rows, 8 columns) 17 times faster than scikit-learn's
    ``KNeighborsClassifier`` with the same answers."""

    def __init__(self, n_jobs: int = 1) -> None:
        self.n_jobs = n_jobs

    def fit(self, X: Any, y: Any) -> IBk:
        X, y = validate_data(self, X, y)
        check_classification_targets(y)
        self.classes_, self.y_ = np.unique(y, return_inverse=True)
        self.tree_ = cKDTree(X)
        return self

    def _nearest(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        X = validate_data(self, X, reset=False)
        return self.y_[self.tree_.query(X, k=1, workers=max(1, int(self.n_jobs)))[1]]

    def predict(self, X: Any) -> np.ndarray:
        near = self._nearest(X)
        return self.classes_[near]

    def predict_proba(self, X: Any) -> np.ndarray:
        """One-hot: the neighbour's class."""
        return _one_hot(self._nearest(X), len(self.classes_))


# ---------------------------------------------------------------------------------------------
# Naive Bayes
# ---------------------------------------------------------------------------------------------

class WekaNaiveBayes(GaussianNB):
    """Gaussian naive Bayes with Weka's floor on the standard deviation.

    Weka's ``NaiveBayes`` models each numeric feature per class with a normal distribution
    whose standard deviation is at least ``precision / 6``, where ``precision`` is the mean
    gap between the feature's distinct training values (0.01 when it has one value). A
    feature that is constant within a class (e.g. ``GPS.Status`` in every class but GPS
    failure) then has a narrow but finite density instead of scikit-learn's variance
    ``var_smoothing * max variance``. Rows with NaN are not supported (Weka skips missing
    values; impute first).
    """

    def __init__(self, *, priors: Any = None, var_smoothing: float = 1e-9,
                 default_precision: float = 0.01) -> None:
        super().__init__(priors=priors, var_smoothing=var_smoothing)
        self.default_precision = default_precision

    def fit(self, X: Any, y: Any, sample_weight: Any = None) -> WekaNaiveBayes:
        super().fit(X, y, sample_weight=sample_weight)
        X = np.asarray(X, dtype=np.float64)
        prec = np.full(X.shape[1], float(self.default_precision))
        for j in range(X.shape[1]):
            v = np.unique(X[:, j][np.isfinite(X[:, j])])
            if len(v) > 1:
                prec[j] = (v[-1] - v[0]) / (len(v) - 1)
        self.precision_ = prec
        self.var_ = np.maximum(self.var_, (prec / 6.0) ** 2)
        return self


# ---------------------------------------------------------------------------------------------
# Factory
# ---------------------------------------------------------------------------------------------

def _impute(est: Any) -> Any:
    return make_pipeline(SimpleImputer(strategy="mean", keep_empty_features=True), est)


def make_model(name: str, *, n_features: int, seed: int = 0, n_jobs: int = 1,
               progress: Callable[[str], None] | None = None,
               cnn_epochs: int | None = None, booster: str = "xgboost") -> Any:
    """A fresh estimator for model ``name`` (one of :data:`ALL_MODELS`) on ``n_features``
    features, seeded with ``seed``. ``n_jobs``: threads of RandomForest (trees), KNN
    (queries) and the CNN (torch), worker processes of SMO (its class pairs: liblinear's
    random generator is one per process, so threads would share it) and the window models
    (XGBoost's OpenMP threads). The results do not depend on them (tested), though XGBoost's
    probabilities can move in the 7th digit with its thread count.
    ``progress`` receives one line per epoch from the neural network; ``cnn_epochs``
    overrides its epoch count; ``booster``: the window models' (``temporal.WINDOW_BOOSTERS``,
    :func:`.temporal.window_hgb`)."""
    s = int(seed)
    k = weka_num_features(n_features)
    builders: dict[str, Callable[[], Any]] = {
        "NaiveBayes": lambda: _impute(WekaNaiveBayes()),
        "Logistic": lambda: _impute(make_pipeline(StandardScaler(), LogisticRegression(
            C=1.0 / (2.0 * LOGISTIC_RIDGE), max_iter=LOGISTIC_MAX_ITER, tol=1e-6))),
        "SMO": lambda: _impute(make_pipeline(MinMaxScaler(), OneVsOneClassifier(
            LinearSVC(C=1.0, loss="hinge", dual=True, max_iter=SMO_MAX_ITER, random_state=s),
            n_jobs=n_jobs if n_jobs > 1 else None))),
        "KNN": lambda: _impute(make_pipeline(MinMaxScaler(), IBk(n_jobs=n_jobs))),
        "AdaBoost": lambda: AdaBoostM1(n_estimators=10, random_state=s),
        "OneR": lambda: OneR(min_bucket_size=6),
        "ZeroR": lambda: DummyClassifier(strategy="most_frequent"),
        "J48": lambda: J48(confidence=0.25, min_samples_leaf=2, random_state=s),
        "RandomForest": lambda: RandomForestClassifier(
            n_estimators=100, criterion="entropy", max_features=k, bootstrap=True,
            random_state=s, n_jobs=n_jobs),
        "RandomTree": lambda: DecisionTreeClassifier(criterion="entropy", max_features=k,
                                                     random_state=s),
    }
    if name in builders:
        return builders[name]()
    if name == "CNN":
        from tlm_process.evaluate.cnn import RowImageCNN

        kw: dict[str, Any] = {"seed": s, "progress": progress, "n_threads": n_jobs}
        if cnn_epochs is not None:
            kw["epochs"] = cnn_epochs
        return RowImageCNN(**kw)
    if name == "SeqCNN":
        from tlm_process.evaluate.sequence import SeqCNN

        return SeqCNN(seed=s, progress=progress, n_threads=n_jobs)
    if name in TIME_MODELS:
        from tlm_process.evaluate.temporal import SkipConstantColumns, window_hgb

        return SkipConstantColumns(window_hgb(seed=s, n_jobs=n_jobs, booster=booster))
    raise ValueError(f"unknown model {name!r}; choose from {', '.join(ALL_MODELS)}")
