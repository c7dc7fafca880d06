"""The paper's CNN (§5.3): each scaled row becomes a small grayscale image.

The paper turned its 16- and 9-feature rows into 4x4 and 3x3 grayscale images and trained a
CNN on them (Figs. 20-21, Table 14); it gives no architecture. Here a row of ``d`` min-max
scaled features is zero-padded to ``s * s`` pixels with ``s = ceil(sqrt(d))`` (GPS 6 -> 3x3,
IMU 8 -> 3x3, RATE 13 -> 4x4, VIBE 3 -> 2x2) and classified by two 3x3 convolutions (32 and
64 channels, padding 1, ReLU), a 128-unit dense layer with dropout 0.2 and a 5-way output,
trained with Adam (learning rate 1e-3) on cross-entropy in mini-batches of 512 for
``epochs`` epochs (default 10). A validation share of the training data (whole flights when
``groups`` are given to :meth:`RowImageCNN.fit`) gives the curves of Figs. 20-21
(:meth:`RowImageCNN.plot_history`).

torch is optional (``pip install -e '.[cnn]'`` in the clone); it is imported when a CNN is
fitted. The network runs on the GPU when one is present (``device="auto"``), else on the
CPU; results are deterministic for a seed on the CPU. On the CPU it uses ``n_threads``
threads (default 1: a network this small is faster on one thread than on cores other work shares).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

__all__ = ["RowImageCNN", "image_side", "require_torch", "rows_to_images"]


def require_torch() -> Any:
    """Import torch, or fail with a one-line hint (ImportError) when it is not installed."""
    try:
        import torch
    except ImportError:  # pragma: no cover - depends on the environment
        raise ImportError("the CNN needs PyTorch: pip install -e '.[cnn]' in tlm's clone, or "
                          "pip install torch (CPU build: --index-url "
                          "https://download.pytorch.org/whl/cpu); the other models do not"
                          ) from None
    return torch


def image_side(n_features: int) -> int:
    """Side of the square image a row of ``n_features`` values is drawn in."""
    return max(1, math.ceil(math.sqrt(n_features)))


def rows_to_images(X: np.ndarray) -> np.ndarray:
    """(n, d) scaled rows -> (n, 1, s, s) float32 images, row-major, zero-padded; NaN -> 0."""
    X = np.nan_to_num(np.asarray(X, dtype=np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    n, d = X.shape
    s = image_side(d)
    img = np.zeros((n, s * s), dtype=np.float32)
    img[:, :d] = X
    return img.reshape(n, 1, s, s)


def _network(torch: Any, side: int, n_classes: int) -> Any:
    nn = torch.nn
    return nn.Sequential(
        nn.Conv2d(1, 32, 3, padding=1), nn.ReLU(),
        nn.Conv2d(32, 64, 3, padding=1), nn.ReLU(),
        nn.Flatten(),
        nn.Linear(64 * side * side, 128), nn.ReLU(), nn.Dropout(0.2),
        nn.Linear(128, n_classes),
    )


class RowImageCNN(ClassifierMixin, BaseEstimator):
    """The paper's row-image CNN as a scikit-learn classifier (see the module docstring).

    ``history_``: per epoch ``epoch``, ``loss``, ``accuracy`` (training, as the network
    trains), ``val_loss``, ``val_accuracy`` (NaN without validation data), ``seconds``.
    """

    def __init__(self, epochs: int = 10, batch_size: int = 512, lr: float = 1e-3,
                 val_fraction: float = 0.1, seed: int = 0, device: str = "auto",
                 n_threads: int | None = 1,
                 progress: Callable[[str], None] | None = None) -> None:
        self.epochs = epochs
        self.batch_size = batch_size
        self.lr = lr
        self.val_fraction = val_fraction
        self.seed = seed
        self.device = device
        self.n_threads = n_threads
        self.progress = progress

    def _device(self, torch: Any) -> Any:
        if self.device == "auto":
            return torch.device("cuda" if torch.cuda.is_available() else "cpu")
        return torch.device(self.device)

    def _validation(self, n: int, groups: Any) -> np.ndarray:
        """Boolean mask of validation rows: whole groups (flights) when given."""
        rng = np.random.default_rng(self.seed)
        mask = np.zeros(n, dtype=bool)
        if not self.val_fraction:
            return mask
        if groups is not None:
            g = np.asarray(groups).astype(str)
            ids = np.unique(g)
            k = int(math.floor(self.val_fraction * len(ids)))
            if k >= 1 and k < len(ids):
                mask = np.isin(g, rng.choice(ids, size=k, replace=False))
            return mask
        k = int(math.floor(self.val_fraction * n))
        if k >= 1 and k < n:
            mask[rng.choice(n, size=k, replace=False)] = True
        return mask

    def fit(self, X: Any, y: Any, groups: Any = None) -> RowImageCNN:
        torch = require_torch()
        threads = torch.get_num_threads()
        if self.n_threads:
            torch.set_num_threads(int(self.n_threads))
        try:
            return self._fit(torch, X, y, groups)
        finally:
            torch.set_num_threads(threads)

    def _fit(self, torch: Any, X: Any, y: Any, groups: Any) -> RowImageCNN:
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float32)
        check_classification_targets(y)
        self.classes_, yi = np.unique(y, return_inverse=True)
        torch.manual_seed(self.seed)
        dev = self._device(torch)
        self.device_ = str(dev)
        self.side_ = image_side(X.shape[1])
        val = self._validation(len(yi), groups)
        img = torch.from_numpy(rows_to_images(X))
        target = torch.from_numpy(yi.astype(np.int64))
        tr_idx = np.flatnonzero(~val)
        va_idx = np.flatnonzero(val)
        net = _network(torch, self.side_, len(self.classes_)).to(dev)
        opt = torch.optim.Adam(net.parameters(), lr=self.lr)
        lossf = torch.nn.CrossEntropyLoss()
        gen = torch.Generator().manual_seed(self.seed)
        self.history_: list[dict[str, float]] = []
        for epoch in range(1, int(self.epochs) + 1):
            t0 = time.perf_counter()
            net.train()
            perm = torch.from_numpy(tr_idx)[torch.randperm(len(tr_idx), generator=gen)]
            tot_loss = tot_ok = 0.0
            for a in range(0, len(perm), self.batch_size):
                b = perm[a:a + self.batch_size]
                xb, yb = img[b].to(dev), target[b].to(dev)
                opt.zero_grad()
                out = net(xb)
                loss = lossf(out, yb)
                loss.backward()
                opt.step()
                tot_loss += loss.item() * len(b)
                tot_ok += float((out.argmax(1) == yb).sum())
            rec = {"epoch": epoch, "loss": tot_loss / max(len(perm), 1),
                   "accuracy": tot_ok / max(len(perm), 1), "val_loss": math.nan,
                   "val_accuracy": math.nan}
            if len(va_idx):
                logits = self._logits(torch, net, img[torch.from_numpy(va_idx)], dev)
                vt = target[torch.from_numpy(va_idx)]
                rec["val_loss"] = float(lossf(logits, vt))
                rec["val_accuracy"] = float((logits.argmax(1) == vt).float().mean())
            rec["seconds"] = time.perf_counter() - t0
            self.history_.append(rec)
            if self.progress is not None:
                self.progress(f"CNN epoch {epoch}/{self.epochs}: loss {rec['loss']:.4f}, "
                              f"accuracy {rec['accuracy']:.4f}"
                              + (f", val loss {rec['val_loss']:.4f}, val accuracy "
                                 f"{rec['val_accuracy']:.4f}" if len(va_idx) else "")
                              + f" ({rec['seconds']:.1f} s)")
        net.eval()
        self.net_ = net.cpu()
        return self

    def _logits(self, torch: Any, net: Any, img: Any, dev: Any) -> Any:
        net.eval()
        outs = []
        with torch.no_grad():
            for a in range(0, len(img), 8192):
                outs.append(net(img[a:a + 8192].to(dev)).cpu())
        net.train()
        return torch.cat(outs) if outs else torch.zeros((0, len(self.classes_)))

    def predict_proba(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        torch = require_torch()
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float32)
        logits = self._logits(torch, self.net_, torch.from_numpy(rows_to_images(X)),
                              torch.device("cpu"))
        self.net_.eval()
        return torch.softmax(logits, dim=1).numpy().astype(np.float64)

    def predict(self, X: Any) -> np.ndarray:
        proba = self.predict_proba(X)
        return self.classes_[proba.argmax(axis=1)]

    def plot_history(self, path: str | Path, title: str = "") -> Path:
        """Training (and validation) accuracy and loss per epoch, as the paper's Figs.
        20-21."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        check_is_fitted(self)
        h = self.history_
        ep = [r["epoch"] for r in h]
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.4))
        a1.plot(ep, [r["accuracy"] for r in h], "o-", label="training")
        a2.plot(ep, [r["loss"] for r in h], "o-", label="training")
        if any(math.isfinite(r["val_loss"]) for r in h):
            a1.plot(ep, [r["val_accuracy"] for r in h], "s--", label="validation")
            a2.plot(ep, [r["val_loss"] for r in h], "s--", label="validation")
        a1.set_xlabel("epoch")
        a1.set_ylabel("accuracy")
        a2.set_xlabel("epoch")
        a2.set_ylabel("cross-entropy loss")
        for a in (a1, a2):
            a.grid(alpha=0.3)
            a.legend()
        fig.suptitle(title, fontsize=10)
        fig.tight_layout()
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(p, dpi=110, bbox_inches="tight")
        plt.close(fig)
        return p
