"""SeqCNN, the causal sequence model: its inputs (whole flights in time order), causality
(never later rows, never another flight), determinism whatever the thread count, probabilities,
and a small problem only a model that sees the rows before a row can solve."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("torch")

from tlm_process.evaluate.sequence import FlightContext, SeqCNN  # noqa: E402

#: A small, quick network (receptive field 1 + 2 * 7 = 15 coarse steps).
SMALL = {"channels": 16, "dilations": (1, 2, 4), "head": 16, "crop": 32, "batch": 8}


def _flights(n_flights: int, n: int, hz: float, seed: int) -> pd.DataFrame:
    """Flights of ``n`` rows at ``hz``: feature ``x`` is noise around 0 (class 0) with
    oscillating bursts of +-1 at 1 Hz (class 1), so that a burst row near a zero crossing looks
    like a class-0 row and only the rows before it tell them apart; ``c`` is a heading in
    degrees (circular, 0-360)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n_flights):
        t = np.arange(n) / hz
        lab = np.zeros(n, dtype=np.int64)
        for a in rng.choice(n - int(8 * hz), size=2, replace=False):
            lab[a:a + int(6 * hz)] = 1
        x = 0.05 * rng.standard_normal(n) + lab * np.sin(2 * np.pi * t)
        out.append(pd.DataFrame({"flight": f"f{i}", "TimeUS": (t * 1e6).astype(np.int64) + 10**7,
                                 "label": lab, "x": x, "c": (37.0 * t) % 360.0}))
    df = pd.concat(out, ignore_index=True)
    return df.sample(frac=1.0, random_state=seed).reset_index(drop=True)  # any row order


def _ctx(df: pd.DataFrame) -> FlightContext:
    return FlightContext.of(df, ["x", "c"], {"c": 360.0})


def test_inputs_are_whole_flights_in_time_order():
    df = _flights(3, 60, 5.0, seed=0)
    ctx = _ctx(df)
    rows = np.flatnonzero(df["flight"].to_numpy() == "f1")[[5, 2, 9]]
    X = ctx.inputs(rows)
    assert X.shape == (60, 2 + 3)  # every row of flight f1, context included
    assert np.all(np.diff(X[:, -2]) > 0)  # time order
    assert np.all(X[:, -3] == X[0, -3])  # one flight
    want = X[:, -1]
    assert sorted(want[want >= 0]) == [0, 1, 2]
    for k, r in enumerate(rows):  # the asked rows, at their position
        assert X[want == k, 0][0] == df["x"].iloc[r]
    # a circular feature enters as its wrapped change: 37 deg/s at 5 Hz, 0 at the start
    assert X[0, 1] == 0 and np.allclose(X[1:, 1], 37.0 / 5.0)


@pytest.mark.parametrize("hz", [5.0, 25.0])  # coarse stride 1 and 5
def test_a_row_depends_only_on_itself_and_earlier_rows_of_its_flight(hz):
    df = _flights(3, int(24 * hz), hz, seed=1)
    df["label"] = (df.index % 3).to_numpy()  # any labels: causality holds for any weights
    ctx = _ctx(df)
    rows = np.arange(len(df))
    m = SeqCNN(steps=3, seed=0, device="cpu", **SMALL).fit(ctx.inputs(rows), df["label"])
    assert m.stride_ == (1 if hz == 5.0 else 5)
    p = m.predict_proba(ctx.inputs(rows))
    f0 = np.flatnonzero(df["flight"].to_numpy() == "f0")
    f0 = f0[np.argsort(df["TimeUS"].to_numpy()[f0])]
    cut = len(f0) // 2
    changed = df.copy()
    changed.loc[f0[cut + 1:], "x"] += 3.0  # later rows of f0
    changed.loc[changed["flight"] == "f2", "x"] *= -2.0  # another flight
    q = m.predict_proba(_ctx(changed).inputs(rows))
    assert np.array_equal(p[f0[:cut + 1]], q[f0[:cut + 1]])
    assert not np.allclose(p[f0[cut + 1:]], q[f0[cut + 1:]])
    f1 = df["flight"].to_numpy() == "f1"
    assert np.array_equal(p[f1], q[f1])
    # asking for some rows only gives the same answers (the flights are the context)
    some = rows[::7]
    assert np.array_equal(m.predict_proba(ctx.inputs(some)), p[some])


def test_it_learns_what_only_the_rows_before_tell_and_is_deterministic():
    hz = 5.0
    train, test = _flights(8, 400, hz, seed=2), _flights(3, 400, hz, seed=3)
    ctx, ctx_t = _ctx(train), _ctx(test)
    rows = np.arange(len(train))
    kw = {**SMALL, "steps": 120, "seed": 4, "device": "cpu"}
    m = SeqCNN(**kw, n_threads=1).fit(ctx.inputs(rows), train["label"])
    X = ctx_t.inputs(np.arange(len(test)))
    p = m.predict_proba(X)
    assert p.shape == (len(test), 2) and np.allclose(p.sum(axis=1), 1.0, atol=1e-6)
    pred = m.predict(X)
    y = test["label"].to_numpy()
    recall1 = (pred[y == 1] == 1).mean()
    assert (pred == y).mean() > 0.95 and recall1 > 0.8, ((pred == y).mean(), recall1)
    # a single row cannot: inside a burst |x| < 0.15 for about a tenth of the rows
    assert ((np.abs(test["x"]) < 0.15) & (y == 1)).sum() > 0.08 * (y == 1).sum()
    assert len(m.history_) == 10 and m.history_[-1]["loss"] < m.history_[0]["loss"]
    two = SeqCNN(**kw, n_threads=2).fit(ctx.inputs(rows), train["label"])
    assert np.array_equal(two.predict_proba(X), p)  # whatever the thread count
    other = SeqCNN(**{**kw, "seed": 5}, n_threads=1).fit(ctx.inputs(rows), train["label"])
    assert not np.array_equal(other.predict_proba(X), p)
