"""The Table 11 estimators on small synthetic data with known answers, the time-window
features and the splits."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from sklearn.utils.estimator_checks import check_estimator

from tlm_process.evaluate.models import (
    ALL_MODELS,
    J48,
    PAPER_MODELS,
    AdaBoostM1,
    IBk,
    OneR,
    WekaNaiveBayes,
    c45_added_errors,
    make_model,
    weka_num_features,
)
from tlm_process.evaluate.splits import flight_folds, random_folds
from tlm_process.evaluate.temporal import WindowFeatures, window_features

# check_estimator skips its array-API checks (optional libraries) with a warning
pytestmark = pytest.mark.filterwarnings("ignore:Skipping check")

# ---------------------------------------------------------------------------------- OneR


def test_oner_picks_the_informative_feature_and_its_thresholds():
    rng = np.random.default_rng(0)
    X = rng.random((600, 3))
    y = np.digitize(X[:, 1], [0.3, 0.7])  # classes 0, 1, 2 by feature 1
    m = OneR().fit(X, y)
    assert m.feature_ == 1
    assert np.allclose(m.breakpoints_, [0.3, 0.7], atol=0.01)
    assert list(m.interval_classes_) == [0, 1, 2]
    Xn = rng.random((200, 3))
    assert (m.predict(Xn) == np.digitize(Xn[:, 1], [0.3, 0.7])).mean() > 0.97
    assert m.train_accuracy_[1] == 1.0 and m.train_accuracy_.argmax() == 1
    assert m.rule_text(["a", "b", "c"]).startswith("b: < 0.3")


def test_oner_minimum_bucket_size_absorbs_single_exceptions():
    x = np.arange(15.0).reshape(-1, 1)
    y = np.array([0, 0, 0, 0, 0, 1, 0, 0, 1, 1, 1, 1, 1, 1, 1])
    m = OneR(min_bucket_size=6).fit(x, y)
    assert list(m.breakpoints_) == [7.5] and list(m.interval_classes_) == [0, 1]
    m1 = OneR(min_bucket_size=1).fit(x, y)
    assert list(m1.breakpoints_) == [4.5, 5.5, 7.5]
    assert list(m1.interval_classes_) == [0, 1, 0, 1]
    assert m1.predict([[5.0], [5.6], [100.0]]).tolist() == [1, 0, 1]


def test_oner_missing_values_get_their_own_class_and_labels_are_kept():
    x = np.array([[1.0], [2.0], [3.0], [np.nan], [np.nan], [10.0], [11.0], [12.0]])
    y = np.array(["n", "n", "n", "gps", "gps", "rc", "rc", "rc"])
    m = OneR(min_bucket_size=2).fit(x, y)
    assert m.predict([[np.nan], [1.5], [11.5]]).tolist() == ["gps", "n", "rc"]
    assert np.allclose(m.predict_proba([[np.nan]]).sum(axis=1), 1.0)


def test_oner_passes_scikit_learns_estimator_checks():
    # a one-feature rule cannot reach the 83% training accuracy one check asks on 2-D blobs
    check_estimator(OneR(), expected_failed_checks={
        "check_classifiers_train": "a rule on one feature separates at most one blob axis"})

# ------------------------------------------------------------------------------------ IBk


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 300), d=st.integers(1, 9), k=st.integers(1, 5), seed=st.integers(0, 99),
       jobs=st.integers(1, 2))
def test_ibk_answers_as_scikit_learns_one_nearest_neighbour(n, d, k, seed, jobs):
    """IBk (SciPy's k-d tree) predicts what KNeighborsClassifier(n_neighbors=1) does, with
    any number of threads, and its probabilities are the neighbour's class."""
    from sklearn.neighbors import KNeighborsClassifier

    rng = np.random.default_rng(seed)
    X, Q = rng.random((n, d)), rng.random((50, d))
    y = rng.integers(0, k, n) * 10  # labels need not be 0..K-1
    got = IBk(n_jobs=jobs).fit(X, y)
    want = KNeighborsClassifier(n_neighbors=1).fit(X, y)
    assert np.array_equal(got.predict(Q), want.predict(Q))
    assert np.array_equal(got.predict(X), y)  # a training row is its own neighbour
    proba = got.predict_proba(Q)
    assert np.array_equal(got.classes_[proba.argmax(axis=1)], got.predict(Q))
    assert np.allclose(proba.sum(axis=1), 1.0)


def test_ibk_passes_scikit_learns_estimator_checks():
    check_estimator(IBk())

# ------------------------------------------------------------------- ZeroR, AdaBoost, J48


def test_zeror_predicts_the_majority():
    m = make_model("ZeroR", n_features=2).fit(np.zeros((7, 2)), [3, 3, 3, 0, 1, 1, 4])
    assert m.predict(np.ones((4, 2))).tolist() == [3] * 4


def test_adaboost_m1_stops_at_error_one_half_as_weka_does():
    rng = np.random.default_rng(1)
    X = rng.random((500, 2))
    y = np.repeat(np.arange(5), 100)  # 5 balanced classes, no signal: a stump errs >= 0.6
    m = AdaBoostM1().fit(X, y)
    assert len(m.estimators_) == 1 and m.errors_[0] >= 0.5
    assert len(np.unique(m.predict(X))) <= 2  # hence undefined precision (paper Table 11)


def test_adaboost_m1_boosting_beats_one_stump():
    rng = np.random.default_rng(2)
    X = rng.random((1000, 2))
    y = (X[:, 0] + X[:, 1] > 1).astype(int)
    m = AdaBoostM1(n_estimators=10).fit(X, y)
    one = AdaBoostM1(n_estimators=1).fit(X, y)
    assert len(m.estimators_) == 10
    assert (m.predict(X) == y).mean() > (one.predict(X) == y).mean() + 0.05
    check_estimator(AdaBoostM1())


def test_c45_pessimistic_errors_match_quinlans_values():
    # Quinlan (1993), ch. 4: U_25%(0, 6) = 0.206, U_25%(0, 9) = 0.143, U_25%(0, 1) = 0.750,
    # U_25%(1, 16) = 0.157 (the book's binomial value; C4.5's normal approximation is 0.155)
    for n, e, u, tol in ((6, 0, 0.206, 5e-4), (9, 0, 0.143, 5e-4), (1, 0, 0.750, 5e-4),
                         (16, 1, 0.157, 3e-3)):
        assert (e + c45_added_errors(n, e)) / n == pytest.approx(u, abs=tol)
    assert c45_added_errors(4, 4) == 0.0  # all wrong: nothing to add


def test_j48_prunes_noise_but_keeps_the_real_split():
    rng = np.random.default_rng(3)
    X = rng.random((2000, 3))
    y = (X[:, 0] > 0.5).astype(int)
    noisy = np.where(rng.random(2000) < 0.1, 1 - y, y)
    m = J48(random_state=0).fit(X, noisy)
    unpruned = m.tree_model_.get_n_leaves()
    assert unpruned > 50 and m.n_leaves_ < 15
    Xn = rng.random((1000, 3))
    assert (m.predict(Xn) == (Xn[:, 0] > 0.5)).mean() > 0.97
    assert (m.tree_model_.predict(Xn) == (Xn[:, 0] > 0.5)).mean() < 0.95  # unpruned overfits
    check_estimator(J48())


def test_naive_bayes_floors_the_deviation_at_weka_precision():
    X = np.array([[6.0, 0.1], [6.0, 0.4], [6.0, 0.2], [1.0, 0.9], [1.0, 0.8], [1.0, 0.7]])
    y = np.array([0, 0, 0, 1, 1, 1])
    m = WekaNaiveBayes().fit(X, y)
    # feature 0: distinct values 1 and 6 -> precision 5, floor (5/6)^2; feature 1: 8 gaps
    assert m.var_[0, 0] == pytest.approx((5 / 6) ** 2)
    assert m.var_[0, 1] == pytest.approx(np.var([0.1, 0.4, 0.2]))
    assert np.isfinite(m.predict_log_proba([[3.0, 0.5]])).all()
    assert m.predict([[5.5, 0.3], [1.2, 0.85]]).tolist() == [0, 1]


def test_weka_feature_count_and_every_model_fits_and_is_seeded():
    assert [weka_num_features(m) for m in (3, 6, 8, 13)] == [2, 3, 4, 4]
    rng = np.random.default_rng(5)
    X = rng.random((300, 4))
    y = np.digitize(X[:, 0], [0.25, 0.5, 0.75])
    for name in PAPER_MODELS:
        m = make_model(name, n_features=4, seed=1).fit(X, y)
        acc = (m.predict(X) == y).mean()
        assert acc >= (0.25 if name in ("ZeroR", "AdaBoost", "NaiveBayes", "Logistic", "SMO")
                       else 0.9), name
    a = make_model("RandomForest", n_features=4, seed=7).fit(X, y).predict_proba(X)
    b = make_model("RandomForest", n_features=4, seed=7).fit(X, y).predict_proba(X)
    c = make_model("RandomForest", n_features=4, seed=8).fit(X, y).predict_proba(X)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    with pytest.raises(ValueError, match="unknown model"):
        make_model("C4.5", n_features=4)
    assert set(PAPER_MODELS) < set(ALL_MODELS) and {"CNN", "WindowHGB"} < set(ALL_MODELS)


def test_command_model_list_matches_the_models_module():
    from tlm_process.commands.evaluate import MODEL_NAMES

    assert MODEL_NAMES == ALL_MODELS

# ------------------------------------------------------------------------- time windows


def _two_flights(n: int = 30) -> pd.DataFrame:
    t = np.arange(n) * 200_000
    return pd.DataFrame({
        "flight": ["a"] * n + ["b"] * n, "TimeUS": np.concatenate([t, t]),
        "label": 0, "Spd": np.concatenate([np.arange(n, dtype=float), np.full(n, 100.0)]),
        "GCrs": np.concatenate([np.full(n, 0.99), np.full(n, 0.01)])})


def test_window_features_are_causal_and_stay_within_a_flight():
    df = _two_flights()
    spec = WindowFeatures(seconds=(1.0,), circular={"GCrs": 1.0})
    X, names = window_features(df, ["Spd", "GCrs"], spec)
    col = {n: X[:, i] for i, n in enumerate(names)}
    # 5 Hz: 1 s = 5 rows; flight a's Spd = 0, 1, 2, ...: mean of the last 5 rows
    assert col["Spd_mean1s"][10] == pytest.approx(np.mean([6, 7, 8, 9, 10]))
    assert col["Spd_max1s"][10] == 10 and col["Spd_min1s"][10] == 6
    assert col["Spd_change1s"][10] == pytest.approx(4)
    assert col["Spd_min1s"][30] == 100  # flight b's first row does not see flight a
    changed = df.copy()
    changed.loc[20, "Spd"] = -1e6  # a later row must not change earlier rows' features
    X2, _ = window_features(changed, ["Spd", "GCrs"], spec)
    assert np.array_equal(X2[:20], X[:20]) and not np.array_equal(X2[20:25], X[20:25])
    # course only as wrapped turn rate: 0.99 -> 0.01 of a period 1 is a 0.02 turn, no value
    assert "GCrs" not in names and np.allclose(col["GCrs_turn_max1s"], 0)
    wrap = df.copy()
    wrap.loc[5, "GCrs"] = 0.01
    X3, _ = window_features(wrap, ["Spd", "GCrs"], spec)
    assert X3[5, names.index("GCrs_turn_max1s")] == pytest.approx(0.02, abs=1e-6)
    shuffled = df.sample(frac=1.0, random_state=0)
    X4, _ = window_features(shuffled, ["Spd", "GCrs"], spec)
    assert np.array_equal(X4, X[shuffled.index.to_numpy()])  # row order does not matter

# -------------------------------------------------------------------------------- splits


def _flights_table(n_flights: int = 10, rows: int = 40) -> pd.DataFrame:
    rng = np.random.default_rng(6)
    return pd.DataFrame({
        "flight": np.repeat([f"f{i}" for i in range(n_flights)], rows),
        "split": np.repeat(["test" if i < 3 else "train" for i in range(n_flights)], rows),
        "label": rng.integers(0, 5, n_flights * rows)})


def test_flight_split_never_shares_a_flight():
    df = _flights_table()
    (hold,) = flight_folds(df)
    assert set(df.flight.iloc[hold.test]) == {"f0", "f1", "f2"}
    assert not set(df.flight.iloc[hold.train]) & set(df.flight.iloc[hold.test])
    folds = flight_folds(df, seed=3, folds=4)
    seen = np.concatenate([f.test for f in folds])
    assert sorted(seen) == list(range(len(df)))  # every row tested exactly once
    for f in folds:
        assert not set(df.flight.iloc[f.train]) & set(df.flight.iloc[f.test])
    again = flight_folds(df, seed=3, folds=4)
    assert all(np.array_equal(a.test, b.test) for a, b in zip(folds, again, strict=True))
    no_test = df.assign(split="train")
    assert len(flight_folds(no_test)) == 5  # grouped 5-fold when the data set has no test
    with pytest.raises(ValueError, match="at least 20 flights"):
        flight_folds(df, folds=20)


def test_random_split_mixes_flights_and_uses_the_data_sets_test_share():
    df = _flights_table()
    (fold,) = random_folds(df, seed=1)
    assert len(fold.test) == pytest.approx(0.3 * len(df), abs=1)
    shared = set(df.flight.iloc[fold.train]) & set(df.flight.iloc[fold.test])
    assert len(shared) == 10  # every flight on both sides: row-level leakage
    (again,) = random_folds(df, seed=1)
    (other,) = random_folds(df, seed=2)
    assert np.array_equal(fold.test, again.test) and not np.array_equal(fold.test, other.test)
    cv = random_folds(df, folds=5)
    assert sorted(np.concatenate([f.test for f in cv])) == list(range(len(df)))
