"""Window features (trailing, centred, whole-history) and the WindowHGB models on synthetic
flights with known answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tlm_process.evaluate.temporal import (
    WINDOW_BOOSTERS,
    WINDOW_MODELS,
    SkipConstantColumns,
    WindowFeatures,
    normal_rows,
    train_rows,
    window_features,
    window_hgb,
    window_spec_for,
)


def _two_flights(n: int = 30) -> pd.DataFrame:
    t = np.arange(n) * 200_000  # 5 Hz
    return pd.DataFrame({
        "flight": ["a"] * n + ["b"] * n, "TimeUS": np.concatenate([t, t]), "label": 0,
        "Spd": np.concatenate([np.arange(n, dtype=float), np.full(n, 100.0)])})


def _cols(df: pd.DataFrame, spec: WindowFeatures) -> dict[str, np.ndarray]:
    X, names = window_features(df, ["Spd"], spec)
    assert X.shape == (len(df), len(names))
    return {n: X[:, i] for i, n in enumerate(names)}


def test_centred_windows_see_both_sides_but_never_another_flight():
    df = _two_flights()
    col = _cols(df, WindowFeatures(seconds=(1.0,), centred=True))  # 5 rows: t-2 .. t+2
    assert col["Spd_mean1s"][10] == pytest.approx(10.0)
    assert col["Spd_min1s"][10] == 8 and col["Spd_max1s"][10] == 12
    assert col["Spd_change1s"][10] == pytest.approx(4.0)  # last minus first of the window
    # flight a's last rows repeat its last value (29), they do not reach flight b's 100
    assert col["Spd_max1s"][29] == 29 and col["Spd_mean1s"][29] == pytest.approx(
        np.mean([27, 28, 29, 29, 29]))
    assert col["Spd_min1s"][30] == 100  # flight b's first row does not see flight a
    # an even window (4 rows: t-2 .. t+1)
    even = _cols(df, WindowFeatures(seconds=(0.8,), centred=True))
    assert even["Spd_mean0.8s"][10] == pytest.approx(np.mean([8, 9, 10, 11]))


def test_trailing_windows_and_history_are_causal():
    df = _two_flights()
    spec = WindowFeatures(seconds=(1.0,), history=True)
    col = _cols(df, spec)
    assert col["Spd_hist_mean"][10] == pytest.approx(5.0)  # mean of 0..10
    assert col["Spd_hist_min"][10] == 0 and col["Spd_hist_max"][10] == 10
    assert col["Spd_hist_min"][30] == 100  # a new flight starts a new history
    changed = df.copy()
    changed.loc[20, "Spd"] = -1e6  # later rows must not change earlier rows' features
    X, _ = window_features(df, ["Spd"], spec)
    X2, _ = window_features(changed, ["Spd"], spec)
    assert np.array_equal(X2[:20], X[:20]) and not np.array_equal(X2[20:], X[20:])
    assert np.array_equal(X2[30:], X[30:])  # nor another flight's
    # centred windows do see the next rows (that is why they are offline only)
    cen = WindowFeatures(seconds=(1.0,), centred=True)
    Xc, _ = window_features(df, ["Spd"], cen)
    Xc2, _ = window_features(changed, ["Spd"], cen)
    assert not np.array_equal(Xc2[18:20], Xc[18:20]) and np.array_equal(Xc2[:18], Xc[:18])


def _noise_flights(n_flights: int, seed: int) -> pd.DataFrame:
    """Flights whose class shows only in how a signal moves: 'fault' segments are noise of
    standard deviation 1 around 0, 'normal' segments a slow ramp within -1 .. 1. Single rows
    overlap; a 2-s window's spread separates them."""
    rng = np.random.default_rng(seed)
    frames = []
    for i in range(n_flights):
        lab = np.repeat([0, 1, 0, 1, 0], 60)
        x = np.where(lab == 1, rng.normal(0.0, 1.0, lab.size),
                     np.sin(np.arange(lab.size) / 40.0))
        frames.append(pd.DataFrame({"flight": f"f{i}", "TimeUS": np.arange(lab.size) * 200_000,
                                    "label": lab, "x": x}))
    return pd.concat(frames, ignore_index=True)


def test_window_hgb_learns_what_single_rows_cannot_show():
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):  # OpenMP on a busy shared machine is many times slower
        _check_window_hgb()


def _check_window_hgb() -> None:
    from sklearn.ensemble import HistGradientBoostingClassifier


    train, test = _noise_flights(6, 1), _noise_flights(3, 2)
    spec = WindowFeatures(seconds=(2.0,))
    Xtr, _ = window_features(train, ["x"], spec)
    Xte, _ = window_features(test, ["x"], spec)
    model = SkipConstantColumns(window_hgb(seed=0)).fit(Xtr, train["label"])
    acc = float((model.predict(Xte) == test["label"].to_numpy()).mean())
    row = HistGradientBoostingClassifier(max_iter=50, random_state=0).fit(train[["x"]],
                                                                          train["label"])
    row_acc = float((row.predict(test[["x"]]) == test["label"].to_numpy()).mean())
    assert acc > 0.9 and row_acc < 0.8, (acc, row_acc)
    again = SkipConstantColumns(window_hgb(seed=0, n_jobs=2)).fit(Xtr, train["label"])
    again = again.predict_proba(Xte)
    assert np.array_equal(again, model.predict_proba(Xte))  # seeded, whatever the threads


def test_window_hgb_sklearn_booster_is_the_former_one_and_learns_the_windows():
    from sklearn.ensemble import HistGradientBoostingClassifier
    from threadpoolctl import threadpool_limits

    est = window_hgb(seed=3, booster="sklearn")
    assert isinstance(est, HistGradientBoostingClassifier)
    p = est.get_params()
    assert (p["max_iter"], p["learning_rate"], p["max_leaf_nodes"], p["min_samples_leaf"],
            p["l2_regularization"], p["early_stopping"], p["random_state"]) == (
        150, 0.1, 31, 50, 1.0, False, 3)
    train, test = _noise_flights(6, 1), _noise_flights(3, 2)
    spec = WindowFeatures(seconds=(2.0,))
    Xtr, _ = window_features(train, ["x"], spec)
    Xte, _ = window_features(test, ["x"], spec)
    with threadpool_limits(limits=1):
        model = SkipConstantColumns(est).fit(Xtr, train["label"])
    acc = float((model.predict(Xte) == test["label"].to_numpy()).mean())
    assert acc > 0.9, acc
    assert set(WINDOW_BOOSTERS) == {"xgboost", "sklearn"}
    with pytest.raises(ValueError, match="unknown booster"):
        window_hgb(booster="lightgbm")


def test_window_model_specs():
    assert set(WINDOW_MODELS) >= {"WindowHGB"}
    base = window_spec_for("WindowHGB", {"GCrs": 2.0})
    assert base.seconds == (2.0, 10.0) and not base.centred and not base.history
    assert base.circular == {"GCrs": 2.0}
    for name in WINDOW_MODELS:
        spec = window_spec_for(name, {})
        assert spec.seconds and all(s > 0 for s in spec.seconds)
        assert not spec.history  # no registered model remembers the whole flight
    assert not window_spec_for("WindowHGB60", {}).centred  # causal: could run on board
    assert window_spec_for("CentredHGB", {}).centred
    with pytest.raises(ValueError, match="unknown"):
        window_spec_for("nope", {})


def test_window_models_fit_on_rows_thinned_per_flight_in_time_order():
    t = np.arange(12) * 40_000  # 25 Hz: every 5th row is kept (TRAIN_HZ 5)
    df = pd.DataFrame({"flight": ["b"] * 12 + ["a"] * 7,
                       "TimeUS": np.concatenate([t, t[:7]]), "Spd": 0.0})
    shuffled = df.sample(frac=1.0, random_state=3)
    keep = train_rows(shuffled)
    kept = shuffled[keep].sort_values(["flight", "TimeUS"])
    assert list(zip(kept["flight"], kept["TimeUS"] // 40_000, strict=True)) == [
        ("a", 0), ("a", 5), ("b", 0), ("b", 5), ("b", 10)]
    assert train_rows(df, rate_hz=5.0).all()  # GPS rate: every row
    assert train_rows(df, rate_hz=10.0).sum() == 6 + 4  # every 2nd row of each flight


def test_normal_rows_are_thinned_apart_from_fault_rows_per_flight():
    t = np.arange(30) * 40_000  # 25 Hz: 5 Hz keeps every 5th row, Normal 1 Hz every 25th
    label = np.where((np.arange(30) >= 10) & (np.arange(30) < 20), 3, 0)
    df = pd.DataFrame({"flight": ["b"] * 30 + ["a"] * 30, "TimeUS": np.concatenate([t, t]),
                       "label": np.concatenate([label, label])})
    shuffled = df.sample(frac=1.0, random_state=5)
    keep = normal_rows(shuffled, shuffled["label"].to_numpy(), 5)
    kept = shuffled[keep].sort_values(["flight", "TimeUS"])
    per_flight = [(int(r.TimeUS // 40_000), int(r.label)) for r in kept.itertuples()
                  if r.flight == "a"]
    assert per_flight == [(0, 0), (10, 3), (15, 3), (25, 0)]  # faults every 5th, Normal 25th
    assert kept["flight"].value_counts().to_dict() == {"a": 4, "b": 4}
    # every = 1: exactly train_rows; a subset of train_rows always
    assert (normal_rows(df, df["label"].to_numpy(), 1) == train_rows(df)).all()
    assert not (keep & ~train_rows(shuffled)).any()


def test_merged_windows_give_every_model_its_own_features_for_the_rows_asked():
    from tlm_process.evaluate.temporal import FlightRuns, merged_windows, row_rate_hz

    df = _noise_flights(4, 3).sample(frac=1.0, random_state=1)  # rows in no order
    df["y"] = np.cos(np.arange(len(df)) / 7.0)
    feats = ["x", "y"]
    specs = {m: window_spec_for(m, {"y": 2.0}) for m in WINDOW_MODELS}
    merged, which = merged_windows(specs, feats)
    assert len(merged) == 2  # trailing windows shared by WindowHGB and WindowHGB60; centred
    runs = FlightRuns.of(df)
    rate = row_rate_hz(df, runs)
    assert rate == pytest.approx(5.0)
    rows = np.flatnonzero(np.random.default_rng(0).random(len(df)) < 0.3)[::-1].copy()
    mats = [window_features(df, feats, sp, rate, rows, runs)[0] for sp in merged]
    for m, sp in specs.items():
        own, names = window_features(df, feats, sp)
        i, cols = which[m]
        got = mats[i] if cols is None else mats[i][:, cols]
        assert got.shape == (len(rows), len(names))
        assert np.array_equal(got, own[rows]), m


def test_skipping_constant_columns_gives_the_same_model():
    from threadpoolctl import threadpool_limits

    train, test = _noise_flights(4, 1), _noise_flights(2, 2)
    Xtr, _ = window_features(train, ["x"], WindowFeatures(seconds=(2.0,)))
    Xte, _ = window_features(test, ["x"], WindowFeatures(seconds=(2.0,)))

    def spread(X):  # constant columns between the informative ones
        n = len(X)
        return np.column_stack([np.full(n, 3.0), X[:, :3], np.full(n, -1.0), X[:, 3:],
                                np.zeros(n)])

    with threadpool_limits(limits=1):
        def booster():  # every column in every tree: the same trees
            return window_hgb(seed=0).set_params(n_estimators=30, colsample_bytree=1.0)

        plain = booster().fit(spread(Xtr), train["label"])
        skip = SkipConstantColumns(booster())
        skip.fit(spread(Xtr), train["label"])
    assert len(skip.columns_) == Xtr.shape[1]
    assert np.array_equal(skip.predict_proba(spread(Xte)), plain.predict_proba(spread(Xte)))
    assert list(skip.classes_) == [0, 1]


@settings(max_examples=60, deadline=None)
@given(sizes=st.lists(st.integers(1, 80), min_size=1, max_size=5),
       fault_share=st.floats(0.0, 1.0), max_rows=st.integers(1, 300),
       weighted=st.booleans(), every=st.integers(1, 4))
def test_row_budget_keeps_at_most_max_rows_with_the_smallest_strides(
        sizes, fault_share, max_rows, weighted, every):
    """row_budget: at most max_rows training rows, Normal rows thinned first (weighted), and
    one step less thinning would keep more than max_rows."""
    from tlm_process.evaluate.runner import row_budget
    from tlm_process.evaluate.temporal import FlightRuns

    flight = np.repeat(np.arange(len(sizes)), sizes).astype(str)
    t = np.concatenate([np.arange(n) for n in sizes]) * 200_000
    rng = np.random.default_rng(len(flight))
    y = np.where(rng.random(len(flight)) < fault_share, 2, 0)
    runs = FlightRuns.of(pd.DataFrame({"flight": flight, "TimeUS": t}))
    train = np.flatnonzero(rng.random(len(flight)) < 0.8)

    def kept(k, e):
        keep = runs.every(k) & ((y != 0) | runs.every(k * e))
        return int(keep[train].sum())

    k, e = row_budget(y, runs, train, 1, every, weighted, max_rows)
    assert kept(k, e) <= max_rows or k == max(sizes)  # or one row per flight is left
    assert e >= every if weighted else e == 1
    if k > 1:  # one step less thinning would keep too many
        assert kept(k - 1, e) > max_rows
        assert not weighted or kept(1, len(flight)) > max_rows  # Normal rows went first
    if e > every:
        assert kept(k, e - 1) > max_rows
    assert row_budget(y, runs, train, 1, every, weighted, 0) == (1, every)
