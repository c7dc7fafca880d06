"""The paper's CNN (§5.3): each scaled row becomes a small grayscale image.

The paper turned its 16- and 9-feature rows into 4x4 and 3x3 grayscale images and trained a
CNN on them (Figs. 20-21, Table 14); it gives no architecture. Here a row of ``d`` min-max
scaled features is zero-padded to ``s * s`` pixels with ``s = ceil(sqrt(d))`` (GPS 6 -> 3x3,
IMU 8 -> 3x3, RATE 13 -> 4x4, VIBE 3 -> 2x2) and classified by two 3x3 convolutions (32 and
64 channels, padding 1, ReLU), a 128-unit dense layer with dropout 0.2 and one output per
class, trained with Adam (learning rate 1e-3) on cross-entropy in mini-batches of 512 for
``epochs`` epochs (default 10; no early stopping: the validation curves keep falling at 10
epochs, ``docs/evaluation.md``). A validation share of the training data (whole flights when
``groups`` are given to :meth:`RowImageCNN.fit`) gives the curves of Figs. 20-21
(:meth:`RowImageCNN.plot_history`).

torch is optional (``pip install -e '.[cnn]'`` in the clone); it is imported when a CNN is
fitted. The network runs on the GPU when one is present (``device="auto"``), else on the
CPU. On the CPU every mini-batch is cut into :data:`SHARDS` fixed parts whose gradients are
computed on ``n_threads`` threads, each part on one thread, and summed in a fixed order
(predictions likewise): results are the same for a seed whatever the thread count (torch's
own multi-threaded kernels sum in an order that depends on it).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

__all__ = ["SHARDS", "RowImageCNN", "image_side", "require_torch", "rows_to_images",
           "torch_pool"]

#: Parts of a mini-batch computed on separate threads on the CPU (at most this many threads
#: are used); fixed, so that the sums do not depend on the thread count.
SHARDS = 2
#: Rows per prediction call.
PREDICT_ROWS = 8192
#: Dropout probability of the dense layer.
DROPOUT = 0.2


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
    """The network on (n, 1, s, s) images: two 3x3 convolutions (32, 64 channels, ReLU), a
    128-unit dense layer, ``n_classes`` outputs. ``forward(x, keep)``: ``keep`` is the dense
    layer's dropout mask scaled by 1 / (1 - p) (drawn by the caller, so that the parts of a
    batch computed on different threads draw nothing themselves); None: no dropout."""
    nn = torch.nn
    relu = torch.nn.functional.relu

    class RowImageNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.conv1 = nn.Conv2d(1, 32, 3, padding=1)
            self.conv2 = nn.Conv2d(32, 64, 3, padding=1)
            self.fc1 = nn.Linear(64 * side * side, 128)
            self.fc2 = nn.Linear(128, n_classes)

        def forward(self, x: Any, keep: Any = None) -> Any:
            h = relu(self.conv2(relu(self.conv1(x))))
            h = relu(self.fc1(h.flatten(1)))
            return self.fc2(h if keep is None else h * keep)

    return RowImageNet()


def _parts(n: int, k: int | None = None) -> list[slice]:
    """``n`` rows cut into at most ``k`` (default :data:`SHARDS`) nearly equal non-empty
    consecutive parts."""
    k = k or SHARDS
    bounds = np.linspace(0, n, k + 1).round().astype(int)
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a]


@contextmanager
def torch_pool(torch: Any, dev: Any, n_threads: int | None
               ) -> Iterator[Callable[..., list[Any]]]:
    """``run(fn, items)``: ``[fn(i) for i in items]``, on the CPU each call on one torch
    thread, spread over ``min(n_threads, SHARDS)`` threads; on a GPU in turn."""
    threads = torch.get_num_threads()
    workers = 1 if dev.type != "cpu" else max(1, min(int(n_threads or 1), SHARDS))
    if dev.type == "cpu":
        torch.set_num_threads(1)  # this thread's parts too
    pool = (ThreadPoolExecutor(workers, initializer=torch.set_num_threads, initargs=(1,))
            if workers > 1 else None)
    try:
        yield ((lambda fn, items: list(pool.map(fn, items))) if pool is not None
               else (lambda fn, items: [fn(i) for i in items]))
    finally:
        if pool is not None:
            pool.shutdown()
        torch.set_num_threads(threads)


class RowImageCNN(ClassifierMixin, BaseEstimator):
    """The paper's row-image CNN as a scikit-learn classifier (see the module docstring).

    ``history_``: per epoch ``epoch``, ``loss``, ``accuracy`` (training, as the network
    trains), ``val_loss``, ``val_accuracy`` (NaN without validation data), ``seconds``.
    ``n_threads``: CPU threads (at most :data:`SHARDS` are used; the result does not depend
    on it).
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

    def _pool(self, torch: Any, dev: Any) -> Any:
        """:func:`torch_pool` with ``n_threads``."""
        return torch_pool(torch, dev, self.n_threads)

    def fit(self, X: Any, y: Any, groups: Any = None, sample_weight: Any = None
            ) -> RowImageCNN:
        """Train on rows ``X`` with classes ``y``; ``groups``: the flight of each row (the
        validation share is drawn by flight); ``sample_weight``: a weight per row (the
        cross-entropy of each mini-batch is their weighted mean; None: all 1)."""
        torch = require_torch()
        dev = self._device(torch)
        with self._pool(torch, dev) as run:
            return self._fit(torch, dev, run, X, y, groups, sample_weight)

    def _fit(self, torch: Any, dev: Any, run: Callable[..., list[Any]], X: Any, y: Any,
             groups: Any, sample_weight: Any = None) -> RowImageCNN:
        X, y = validate_data(self, X, y, ensure_all_finite="allow-nan", dtype=np.float32)
        weight = None
        if sample_weight is not None:
            weight = torch.from_numpy(np.asarray(sample_weight, dtype=np.float32)).to(dev)
        check_classification_targets(y)
        self.classes_, yi = np.unique(y, return_inverse=True)
        torch.manual_seed(self.seed)
        self.device_ = str(dev)
        self.side_ = image_side(X.shape[1])
        val = self._validation(len(yi), groups)
        img = torch.from_numpy(rows_to_images(X)).to(dev)  # on the device once
        target = torch.from_numpy(yi.astype(np.int64)).to(dev)
        tr_idx = torch.from_numpy(np.flatnonzero(~val))
        va_idx = torch.from_numpy(np.flatnonzero(val)).to(dev)
        net = _network(torch, self.side_, len(self.classes_)).to(dev)
        opt = torch.optim.Adam(net.parameters(), lr=self.lr)
        gen = torch.Generator().manual_seed(self.seed)  # on the CPU: the same order anywhere
        self.history_: list[dict[str, float]] = []
        for epoch in range(1, int(self.epochs) + 1):
            t0 = time.perf_counter()
            net.train()
            perm = tr_idx[torch.randperm(len(tr_idx), generator=gen)]
            loss, ok, total = self._epoch(torch, dev, run, net, opt, img, target, perm, gen,
                                          weight)
            rec = {"epoch": epoch, "loss": loss / max(total, 1),
                   "accuracy": ok / max(len(perm), 1), "val_loss": math.nan,
                   "val_accuracy": math.nan}
            if len(va_idx):
                logits = self._logits(torch, run, net, img[va_idx])
                vt = target[va_idx].cpu()
                rec["val_loss"] = float(torch.nn.functional.cross_entropy(logits, vt))
                rec["val_accuracy"] = float((logits.argmax(1) == vt).float().mean())
            rec["seconds"] = time.perf_counter() - t0
            self.history_.append(rec)
            self._report(rec, bool(len(va_idx)))
        net.eval()
        self.net_ = net.cpu()
        return self

    def _epoch(self, torch: Any, dev: Any, run: Callable[..., list[Any]], net: Any,
               opt: Any, img: Any, target: Any, perm: Any, gen: Any, weight: Any = None
               ) -> tuple[float, int, float]:
        """One pass over the training rows in the order ``perm``; returns (summed loss,
        correctly classified rows, summed row weight). Each mini-batch's gradient is the
        sum, in a fixed order, of its parts' gradients (:data:`SHARDS` parts on the CPU, one
        on a GPU), divided by its rows (with ``weight``: by its summed weight): the
        (weighted) mean cross-entropy's."""
        params = list(net.parameters())
        f = torch.nn.functional

        def part(xb: Any, yb: Any, keep: Any, wb: Any = None) -> tuple[Any, ...]:
            out = net(xb, keep)
            if wb is None:
                loss = f.cross_entropy(out, yb, reduction="sum")
            else:
                loss = (f.cross_entropy(out, yb, reduction="none") * wb).sum()
            grads = torch.autograd.grad(loss, params)
            return grads, loss.detach().double(), (out.argmax(1) == yb).sum()

        tot_loss = torch.zeros((), dtype=torch.float64, device=dev)
        tot_ok = torch.zeros((), dtype=torch.int64, device=dev)
        tot_w = 0.0
        for a in range(0, len(perm), self.batch_size):
            b = perm[a:a + self.batch_size].to(dev)
            keep = (torch.empty((len(b), 128)).bernoulli_(1.0 - DROPOUT, generator=gen)
                    / (1.0 - DROPOUT)).to(dev)
            parts = _parts(len(b)) if dev.type == "cpu" else [slice(0, len(b))]
            if weight is None:
                res = run(lambda s, b=b, keep=keep: part(img[b[s]], target[b[s]], keep[s]),
                          parts)
                norm: Any = len(b)
            else:
                res = run(lambda s, b=b, keep=keep: part(img[b[s]], target[b[s]], keep[s],
                                                         weight[b[s]]), parts)
                norm = float(weight[b].double().sum())
            tot_w += float(norm)
            for i, p in enumerate(params):
                g = res[0][0][i]
                for r in res[1:]:
                    g = g + r[0][i]
                p.grad = g / norm
            opt.step()
            for r in res:
                tot_loss += r[1]
                tot_ok += r[2]
        return float(tot_loss), int(tot_ok), tot_w

    def _report(self, rec: dict[str, float], validation: bool) -> None:
        """One progress line per epoch."""
        if self.progress is not None:
            self.progress(f"CNN epoch {rec['epoch']}/{self.epochs}: loss {rec['loss']:.4f}, "
                          f"accuracy {rec['accuracy']:.4f}"
                          + (f", val loss {rec['val_loss']:.4f}, val accuracy "
                             f"{rec['val_accuracy']:.4f}" if validation else "")
                          + f" ({rec['seconds']:.1f} s)")

    def _logits(self, torch: Any, run: Callable[..., list[Any]], net: Any, img: Any) -> Any:
        """Logits of ``img`` (on the network's device) on the CPU, in parts of at most
        :data:`PREDICT_ROWS` rows (each on one thread)."""
        training = net.training
        net.eval()
        parts = [slice(a, a + PREDICT_ROWS) for a in range(0, len(img), PREDICT_ROWS)]
        if len(parts) == 1 and len(img) > SHARDS:
            parts = _parts(len(img))

        def logits(s: slice) -> Any:
            with torch.no_grad():
                return net(img[s]).cpu()

        outs = run(logits, parts)
        net.train(training)
        return torch.cat(outs) if outs else torch.zeros((0, len(self.classes_)))

    def predict_proba(self, X: Any) -> np.ndarray:
        check_is_fitted(self)
        torch = require_torch()
        X = validate_data(self, X, reset=False, ensure_all_finite="allow-nan", dtype=np.float32)
        with self._pool(torch, torch.device("cpu")) as run:
            logits = self._logits(torch, run, self.net_,
                                  torch.from_numpy(rows_to_images(X)))
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
