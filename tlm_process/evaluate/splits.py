"""Train/test splits of a data table: by flight (honest) or by row (the paper's).

Rows of one flight are strongly correlated in time: at 5-25 Hz neighbouring rows are almost
equal. A split that puts some rows of a flight in training and their neighbours in the test
set ("row-level leakage") lets a model recognise the flight instead of the fault, and its
score says little about a new flight. ``tlm evaluate --split flight`` (default) therefore
keeps every flight whole; ``--split random`` is the paper's random row split, offered so the
difference can be measured.

* :func:`flight_folds` — the data set's own ``split`` column (train/test flights drawn by
  ``tlm process --test-frac/--test-flight``) when it has test flights, else (or with
  ``folds``) grouped k-fold cross-validation over flights (``GroupKFold`` with shuffling).
* :func:`random_folds` — rows drawn at random, stratified by label: one hold-out of
  ``test_frac`` of the rows (by default the data set's own test share, so both splits train
  on as many rows), or stratified k-fold cross-validation over rows (Weka's default
  evaluation is 10-fold row CV).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

__all__ = ["SPLITS", "Fold", "flight_folds", "random_folds"]

SPLITS: tuple[str, ...] = ("flight", "random")

#: Test share of rows when the data set has no test flights and no fraction is given.
DEFAULT_TEST_FRAC = 0.25


@dataclass(frozen=True)
class Fold:
    """Row positions (into the table) of one train/test split; ``name`` describes it."""

    train: np.ndarray
    test: np.ndarray
    name: str


def _check_k(folds: int, n: int, what: str) -> None:
    if folds < 2:
        raise ValueError(f"need at least 2 folds, got {folds}")
    if n < folds:
        raise ValueError(f"{folds}-fold cross-validation needs at least {folds} {what}, "
                         f"the data set has {n}")


def flight_folds(df: pd.DataFrame, *, seed: int = 0, folds: int | None = None) -> list[Fold]:
    """Folds that never put one flight in both training and test rows (see the module
    docstring). ``df`` needs ``flight`` (and, for the hold-out, ``split``) columns."""
    flights = df["flight"].astype(str).to_numpy()
    if folds is None and "split" in df.columns:
        is_test = (df["split"].astype(str) == "test").to_numpy()
        if is_test.any() and not is_test.all():
            return [Fold(np.flatnonzero(~is_test), np.flatnonzero(is_test),
                         "the data set's test flights")]
    ids = pd.unique(flights)
    k = folds if folds is not None else min(5, len(ids))
    _check_k(k, len(ids), "flights")
    from sklearn.model_selection import GroupKFold

    gkf = GroupKFold(n_splits=k, shuffle=True, random_state=seed)
    return [Fold(tr, te, f"flight fold {i + 1}/{k}")
            for i, (tr, te) in enumerate(gkf.split(np.zeros(len(flights)), groups=flights))]


def random_folds(df: pd.DataFrame, *, seed: int = 0, folds: int | None = None,
                 test_frac: float | None = None) -> list[Fold]:
    """Random row folds, stratified by ``label`` (see the module docstring)."""
    y = df["label"].to_numpy()
    if folds is not None:
        from sklearn.model_selection import StratifiedKFold

        _check_k(folds, len(y), "rows")
        skf = StratifiedKFold(n_splits=folds, shuffle=True, random_state=seed)
        return [Fold(tr, te, f"row fold {i + 1}/{folds}")
                for i, (tr, te) in enumerate(skf.split(np.zeros(len(y)), y))]
    if test_frac is None:
        test_frac = DEFAULT_TEST_FRAC
        if "split" in df.columns:
            share = float((df["split"].astype(str) == "test").mean())
            if 0 < share < 1:
                test_frac = share
    if not 0 < test_frac < 1:
        raise ValueError(f"test fraction must be in (0, 1), got {test_frac}")
    from sklearn.model_selection import train_test_split

    idx = np.arange(len(y))
    counts = np.bincount(y)
    strat = y if (counts[counts > 0] >= 2).all() else None
    tr, te = train_test_split(idx, test_size=test_frac, random_state=seed, shuffle=True,
                              stratify=strat)
    return [Fold(np.sort(tr), np.sort(te), f"random {100 * test_frac:.0f}% of rows")]
