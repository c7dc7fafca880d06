"""The paper's row-image CNN: images, a short training whose loss falls, determinism, the
training-curve PNG."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")

from tlm_process.evaluate.cnn import RowImageCNN, image_side, rows_to_images  # noqa: E402


def test_rows_become_zero_padded_square_images():
    assert [image_side(d) for d in (3, 6, 8, 9, 13, 16)] == [2, 3, 3, 3, 4, 4]
    img = rows_to_images(np.array([[0.1, 0.2, 0.3, 0.4, 0.5, np.nan]]))
    assert img.shape == (1, 1, 3, 3)
    assert np.allclose(img[0, 0], [[0.1, 0.2, 0.3], [0.4, 0.5, 0.0], [0.0, 0.0, 0.0]])


def _data(n: int = 1500, seed: int = 0):
    rng = np.random.default_rng(seed)
    X = rng.random((n, 6))
    y = np.digitize(X[:, 0] + 0.5 * X[:, 3], [0.4, 0.8, 1.1])
    return X, y


def test_cnn_trains_its_loss_falls_and_it_is_deterministic(tmp_path):
    X, y = _data()
    groups = np.repeat(np.arange(10), 150)
    kw = {"epochs": 2, "batch_size": 64, "lr": 3e-3, "seed": 5, "device": "cpu"}
    m = RowImageCNN(**kw).fit(X, y, groups=groups)
    h = m.history_
    assert len(h) == 2 and h[1]["loss"] < h[0]["loss"]
    assert np.isfinite(h[1]["val_loss"])  # one of ten flights held out for validation
    Xt, yt = _data(500, seed=1)
    assert (m.predict(Xt) == yt).mean() > 0.6  # 4 classes: chance is < 0.4
    p = m.predict_proba(Xt)
    assert p.shape == (500, 4) and np.allclose(p.sum(axis=1), 1, atol=1e-5)
    again = RowImageCNN(**kw).fit(X, y, groups=groups)
    assert np.array_equal(again.predict_proba(Xt), p)
    png = m.plot_history(tmp_path / "curves.png", "test")
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_cnn_sample_weights_are_a_weighted_mean_loss():
    """Unit weights train the same network as none; heavier rows pull the network to
    their class."""
    X, y = _data(600)
    kw = {"epochs": 1, "batch_size": 600, "lr": 3e-3, "seed": 2, "device": "cpu",
          "val_fraction": 0.0}
    plain = RowImageCNN(**kw).fit(X, y)
    ones = RowImageCNN(**kw).fit(X, y, sample_weight=np.ones(len(y)))
    assert np.allclose(ones.predict_proba(X), plain.predict_proba(X), atol=1e-5)
    assert np.isclose(ones.history_[0]["loss"], plain.history_[0]["loss"], rtol=1e-5)
    # weight 5 on the class-0 rows: the network calls class 0 more likely
    w = np.where(y == 0, 5.0, 1.0)
    heavy = RowImageCNN(**kw).fit(X, y, sample_weight=w)
    assert not np.allclose(heavy.predict_proba(X), plain.predict_proba(X), atol=1e-4)
    assert heavy.predict_proba(X)[:, 0].mean() > plain.predict_proba(X)[:, 0].mean()
