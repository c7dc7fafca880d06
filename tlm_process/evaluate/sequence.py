"""A causal sequence model on the raw table rows (beyond the paper): ``SeqCNN``.

The window models (:mod:`.temporal`) describe the rows before a row by hand-chosen statistics;
``SeqCNN`` learns them. It reads each flight's scaled rows in time order and classifies every
row from that row and the rows before it in its flight (never later rows, never another
flight), so it could run on board as rows arrive.

Architecture (a temporal convolutional network, :class:`SeqCNN`):

1. Every feature is standardised with the training rows' mean and standard deviation and
   clipped to +-:data:`CLIP`; a circular feature (``GPS.GCrs``) enters as its wrapped
   row-to-row change (turn), never as a heading (as in the window models).
2. A flight's rows are cut into consecutive blocks of ``stride`` rows, ``stride = round(table
   rate / coarse_hz)`` (5 Hz: GPS 1, RATE/VIBE 2, IMU 5), and each block becomes one step of
   a coarse sequence: the mean of each feature over the block (and, for ``stride > 1``, its
   standard deviation: the vibration within 0.2 s of IMU rows).
3. A 1x1 convolution and ``len(dilations)`` residual blocks ``h + W1x1 relu(conv_k,dil(h))``
   of causal dilated convolutions (``channels`` wide, kernel ``kernel``, left zero padding
   only) turn the coarse sequence into a context vector per step; the receptive field is
   ``1 + (kernel - 1) * sum(dilations)`` coarse steps (default 255 at 5 Hz: 51 s).
4. Row ``t`` (counted from its flight's first row) gets the context of the last block that
   is complete at ``t`` (block ``(t + 1) // stride - 1``: the context is held between blocks;
   zeros before the first block is complete), concatenated with the row's own standardised
   features, and a two-layer head (``head`` units, ReLU) gives one logit per class.

Training: a fixed number of Adam steps (``steps``; not proportional to the data, so a table
of 20 flights and one of 200 take the same time), each on ``batch`` crops of
``receptive field + crop`` coarse steps cut at random from the training flights (half of them
ending at a random step of the flights, half shortly after a random row of a class other
than the majority one: faults are a few percent of the rows). A crop that starts inside a
flight gives no loss on its first ``receptive field - 1`` steps (their context is cut off);
one that starts at the flight's start is exactly what prediction sees. The loss is the mean
cross-entropy over the crop rows that are training rows (``y`` given), each class weighted by
``class_weight``; the learning rate warms up over the first 5 % of the steps and decays as a
cosine to zero. No early stopping: the step budget is fixed, and a validation share would
make the result depend on which flights are held out (``history_`` has the training loss).

Inputs: not rows but whole flights. :class:`FlightContext` (built once per table by the
runner) turns a set of table rows into the matrix :meth:`SeqCNN.fit` and
:meth:`SeqCNN.predict` read: every row of the flights those rows belong to, in time order,
columns ``features..., flight, time [s], want`` (``want``: the row's position among the rows
asked for, -1 for a row that is context only). ``predict`` returns one answer per asked row,
in the order asked; ``fit`` takes the labels of the asked rows.

Determinism (as :mod:`.cnn`): the crops are drawn by a NumPy generator seeded with ``seed``;
on the CPU each step's crops are cut into :data:`.cnn.SHARDS` fixed parts whose gradients are
computed on up to that many threads (one torch thread each) and summed in a fixed order, and
each flight is predicted alone on one thread: results do not depend on the thread count. The
network runs on the GPU when one is present (``device="auto"``).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted

from tlm_process.evaluate.cnn import SHARDS, RowImageCNN, _parts, require_torch, torch_pool
from tlm_process.evaluate.temporal import FlightRuns

__all__ = ["CLIP", "STEPS", "FlightContext", "SeqCNN"]

#: Standardised features are clipped to +-CLIP (a transfer log's outlier cannot blow up).
CLIP = 10.0
#: Adam steps of a fit when ``SeqCNN(steps=None)``.
STEPS = 300
#: Extra columns of the input matrix after the features: flight, time [s], want.
EXTRA_COLS = 3


@dataclass(frozen=True)
class FlightContext:
    """A table's rows in time order per flight, as :class:`SeqCNN` reads them.

    ``x``: (n, d) features in :class:`~.temporal.FlightRuns` order (circular features
    replaced by their wrapped row-to-row change, 0 at a flight's first row); ``time``: [s] in
    that order; ``runs``; ``flight_of``: table row -> flight number (index into
    ``runs.starts``); ``rank``: table row -> position in the run order."""

    x: np.ndarray
    time: np.ndarray
    runs: FlightRuns
    flight_of: np.ndarray
    rank: np.ndarray

    @classmethod
    def of(cls, df: pd.DataFrame, features: Sequence[str],
           circular: Mapping[str, float] | None = None,
           runs: FlightRuns | None = None) -> FlightContext:
        """The context of ``df`` (columns ``flight``, ``TimeUS``, ``features``); ``circular``:
        feature -> period in the table's units."""
        runs = runs if runs is not None else FlightRuns.of(df)
        order = runs.order
        x = df[list(features)].to_numpy(np.float64)[order]
        for j, f in enumerate(features):
            if f in (circular or {}):
                p = float(circular[f])  # type: ignore[index]
                d = np.diff(x[:, j], prepend=x[:1, j])
                d[runs.starts[runs.ends > runs.starts]] = 0.0
                x[:, j] = (d + p / 2) % p - p / 2
        flight_sorted = np.repeat(np.arange(len(runs.starts)), runs.ends - runs.starts)
        flight_of = np.empty(len(df), dtype=np.int64)
        flight_of[order] = flight_sorted
        rank = np.empty(len(df), dtype=np.int64)
        rank[order] = np.arange(len(df))
        t = df["TimeUS"].to_numpy(np.float64)[order] * 1e-6
        return cls(x, t, runs, flight_of, rank)

    def inputs(self, rows: np.ndarray) -> np.ndarray:
        """The :class:`SeqCNN` input of table rows ``rows`` (distinct): every row of their
        flights in time order, columns features, flight, time [s], want (position in
        ``rows``, -1: context only)."""
        rows = np.asarray(rows, dtype=np.int64)
        flights = np.unique(self.flight_of[rows])
        starts, ends = self.runs.starts[flights], self.runs.ends[flights]
        pos = np.concatenate([np.arange(a, b) for a, b in zip(starts, ends, strict=True)]
                             ) if len(flights) else np.empty(0, dtype=np.int64)
        want = np.full(len(self.x), -1.0)
        want[self.rank[rows]] = np.arange(len(rows))
        fl = np.repeat(flights, ends - starts).astype(np.float64)
        return np.column_stack([self.x[pos], fl, self.time[pos], want[pos]])


@dataclass
class _Flight:
    """One flight of a :class:`SeqCNN` input: standardised rows ``z`` (n, d) float32, coarse
    steps ``c`` (n // stride, channels) float32, ``want`` (n,) positions (-1: context)."""

    z: np.ndarray
    c: np.ndarray
    want: np.ndarray


def _network(torch: Any, c_in: int, d: int, n_classes: int, channels: int, kernel: int,
             dilations: Sequence[int], head: int, arch: str = "tcn") -> Any:
    """The TCN (module docstring): ``context(c)`` (B, c_in, T) -> (B, channels, T) causal;
    ``classify(h, z)`` (m, channels), (m, d) -> (m, n_classes) logits."""
    nn = torch.nn
    f = torch.nn.functional

    class SeqNet(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.inp = nn.Conv1d(c_in, channels, 1)
            dils = list(dilations) if arch == "tcn" else []
            self.convs = nn.ModuleList([nn.Conv1d(channels, channels, kernel, dilation=dl)
                                        for dl in dils])
            self.mix = nn.ModuleList([nn.Conv1d(channels, channels, 1) for _ in dils])
            self.pads = [(kernel - 1) * dl for dl in dils]
            self.fc1 = nn.Linear(channels + d, head)
            self.fc2 = nn.Linear(head, n_classes)
            if arch == "gru":
                self.gru = nn.GRU(channels, channels, batch_first=True)

        def context(self, c: Any) -> Any:
            h = self.inp(c)
            if arch == "gru":
                return self.gru(h.transpose(1, 2))[0].transpose(1, 2)
            for conv, mix, pad in zip(self.convs, self.mix, self.pads, strict=True):
                h = h + mix(f.relu(conv(f.pad(h, (pad, 0)))))  # left padding only: causal
            return f.relu(h)

        def classify(self, h: Any, z: Any) -> Any:
            return self.fc2(f.relu(self.fc1(torch.cat([h, z], dim=1))))

    return SeqNet()


class SeqCNN(ClassifierMixin, BaseEstimator):
    """Causal temporal convolutional network on a table's rows (see the module docstring).

    ``coarse_hz``: rate of the coarse sequence [Hz]; ``channels``, ``kernel``,
    ``dilations``, ``head``: the network; ``steps`` (None: :data:`STEPS`), ``batch`` (crops
    per step), ``crop`` (coarse steps with a loss per crop, after the receptive field),
    ``lr`` (Adam's peak), ``arch`` (``"tcn"``; ``"gru"``: one GRU layer instead of the
    convolutions, measured and not the default, ``docs/evaluation-history.md``),
    ``class_weight`` (None, ``"balanced"``: n / (k n_c), ``"sqrt"``: its square root,
    normalised to a mean of 1 over the rows); ``fault_share``: share of crops drawn to end
    shortly after a row of a minority class. ``history_``: per ``steps / 10`` steps the mean
    training loss and accuracy (``epoch``, ``loss``, ``accuracy``, ``val_loss`` and
    ``val_accuracy`` NaN, ``seconds``). ``n_threads``: CPU threads (at most
    :data:`.cnn.SHARDS`; the result does not depend on it)."""

    def __init__(self, coarse_hz: float = 5.0, channels: int = 32, kernel: int = 3,
                 dilations: Sequence[int] = (1, 2, 4, 8, 16, 32, 64), head: int = 64,
                 steps: int | None = None, batch: int = 8, crop: int = 192, lr: float = 1e-2,
                 class_weight: str | None = None, fault_share: float = 0.5,
                 arch: str = "tcn", seed: int = 0, device: str = "auto", n_threads: int | None = 1,
                 progress: Callable[[str], None] | None = None) -> None:
        self.coarse_hz = coarse_hz
        self.channels = channels
        self.kernel = kernel
        self.dilations = dilations
        self.head = head
        self.steps = steps
        self.batch = batch
        self.crop = crop
        self.lr = lr
        self.class_weight = class_weight
        self.fault_share = fault_share
        self.arch = arch
        self.seed = seed
        self.device = device
        self.n_threads = n_threads
        self.progress = progress

    # -- inputs ----------------------------------------------------------------------------

    @property
    def receptive_field(self) -> int:
        """Coarse steps a context vector sees (its own included)."""
        return 1 + (int(self.kernel) - 1) * int(sum(self.dilations))

    def _split(self, X: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """(features, want) of each flight of input ``X`` (rows of a flight are consecutive
        and in time order: :meth:`FlightContext.inputs`)."""
        fl = X[:, -3]
        cut = np.flatnonzero(fl[1:] != fl[:-1]) + 1
        bounds = np.concatenate([[0], cut, [len(X)]]) if len(X) else np.zeros(1, np.int64)
        return [(X[a:b, :-EXTRA_COLS], X[a:b, -1].astype(np.int64))
                for a, b in zip(bounds[:-1], bounds[1:], strict=True) if b > a]

    def _rate_stride(self, X: np.ndarray) -> int:
        """Rows per coarse step: the table's rate (median time step within flights) over
        ``coarse_hz``."""
        dt = np.diff(X[:, -2])
        same = X[1:, -3] == X[:-1, -3]
        dt = dt[same & (dt > 0)]
        rate = 1.0 / float(np.median(dt)) if len(dt) else self.coarse_hz
        return max(1, int(round(rate / float(self.coarse_hz))))

    def _flight(self, x: np.ndarray, want: np.ndarray) -> _Flight:
        """Standardised rows and coarse steps of one flight."""
        z = np.nan_to_num((x - self.mean_) / self.scale_, nan=0.0, posinf=CLIP, neginf=-CLIP)
        z = np.clip(z, -CLIP, CLIP).astype(np.float32)
        s = self.stride_
        nc = len(z) // s
        blocks = z[:nc * s].reshape(nc, s, z.shape[1])
        c = blocks.mean(axis=1)
        if s > 1:
            c = np.concatenate([c, blocks.std(axis=1)], axis=1)
        return _Flight(z, np.ascontiguousarray(c, dtype=np.float32), want)

    # -- fitting -----------------------------------------------------------------------------

    def fit(self, X: Any, y: Any, groups: Any = None) -> SeqCNN:
        """Fit on input ``X`` (:meth:`FlightContext.inputs`) with ``y`` the labels of its
        asked rows (``want`` order); ``groups`` is not needed (the flights are in ``X``)."""
        torch = require_torch()
        X = np.asarray(X, dtype=np.float64)
        y = np.asarray(y)
        check_classification_targets(y)
        self.classes_, yi = np.unique(y, return_inverse=True)
        self.n_features_in_ = X.shape[1]
        dev = (torch.device("cuda" if torch.cuda.is_available() else "cpu")
               if self.device == "auto" else torch.device(self.device))
        self.device_ = str(dev)
        feats = X[:, :-EXTRA_COLS]
        self.mean_ = np.nanmean(feats, axis=0) if len(feats) else np.zeros(feats.shape[1])
        sd = np.nanstd(feats, axis=0) if len(feats) else np.ones(feats.shape[1])
        self.mean_ = np.nan_to_num(self.mean_)
        self.scale_ = np.where(np.isfinite(sd) & (sd > 1e-9), sd, 1.0)
        self.stride_ = self._rate_stride(X)
        self.steps_ = int(self.steps if self.steps is not None else STEPS)
        flights = [self._flight(x, w) for x, w in self._split(X)]
        if not any(len(f.c) for f in flights):
            raise ValueError(f"SeqCNN: no training flight has {self.stride_} rows (one coarse "
                             "step)")
        labels = [np.where(f.want >= 0, yi[np.maximum(f.want, 0)], -1) for f in flights]
        torch.manual_seed(int(self.seed))
        d = feats.shape[1]
        net = _network(torch, flights[0].c.shape[1] if flights else d, d,
                       len(self.classes_), int(self.channels), int(self.kernel),
                       list(self.dilations), int(self.head), self.arch).to(dev)
        with torch_pool(torch, dev, self.n_threads) as run:
            self._train(torch, dev, run, net, flights, labels, self._weights(yi))
        net.eval()
        self.net_ = net.cpu()
        return self

    def _weights(self, yi: np.ndarray) -> np.ndarray:
        """Loss weight of each class index."""
        k = len(self.classes_)
        n = np.bincount(yi, minlength=k).astype(np.float64)
        if self.class_weight is None:
            return np.ones(k)
        w = np.where(n > 0, n.sum() / (k * np.maximum(n, 1)), 0.0)
        if self.class_weight == "sqrt":
            w = np.sqrt(w)
        elif self.class_weight != "balanced":
            raise ValueError(f"class_weight must be None, 'balanced' or 'sqrt', got "
                             f"{self.class_weight!r}")
        return w * n.sum() / max(float((w * n).sum()), 1e-12)  # mean 1 over the rows

    def _crops(self, rng: np.random.Generator, flights: list[_Flight],
               labels: list[np.ndarray], minority: list[np.ndarray]) -> list[tuple[int, int]]:
        """(flight, end coarse step, exclusive) of one step's crops."""
        s = self.stride_
        lens = np.array([len(f.c) for f in flights], dtype=np.float64)
        n_min = np.array([len(m) if len(f.c) else 0 for f, m in zip(flights, minority,
                                                                     strict=True)],
                         dtype=np.float64)
        out = []
        for _ in range(int(self.batch)):
            if n_min.sum() > 0 and rng.random() < float(self.fault_share):
                i = int(rng.choice(len(flights), p=n_min / n_min.sum()))
                row = int(minority[i][rng.integers(len(minority[i]))])
                end = (row + 1) // s + int(rng.integers(1, int(self.crop) + 1))
            else:
                i = int(rng.choice(len(flights), p=lens / lens.sum()))
                end = int(rng.integers(1, int(lens[i]) + 1))
            out.append((i, int(min(max(end, 1), len(flights[i].c)))))
        return out

    def _batch(self, flights: list[_Flight], labels: list[np.ndarray],
               crops: list[tuple[int, int]], w_cls: np.ndarray
               ) -> tuple[np.ndarray, list[tuple[np.ndarray, ...]]]:
        """The coarse input (B, c_in, W) of ``crops`` and per crop its loss rows: (coarse
        index in the crop, -1: no context yet; standardised row; class; weight)."""
        s, rf = self.stride_, self.receptive_field
        width = rf - 1 + int(self.crop)
        c_in = flights[0].c.shape[1]
        cb = np.zeros((len(crops), c_in, width), dtype=np.float32)
        rows = []
        for b, (i, end) in enumerate(crops):
            f, lab = flights[i], labels[i]
            start = max(0, end - width)
            cb[b, :, :end - start] = f.c[start:end].T
            first = 0 if start == 0 else start + rf - 1  # first coarse step with full context
            lo = 0 if start == 0 else (first + 1) * s - 1
            hi = min(len(f.z), (end + 1) * s - 1)  # rows whose block is < end
            t = np.arange(lo, hi)
            t = t[lab[t] >= 0]
            k = (t + 1) // s - 1 - start
            rows.append((k, f.z[t], lab[t], w_cls[lab[t]]))
        return cb, rows

    def _train(self, torch: Any, dev: Any, run: Callable[..., list[Any]], net: Any,
               flights: list[_Flight], labels: list[np.ndarray], w_cls: np.ndarray) -> None:
        """``steps`` Adam steps (module docstring)."""
        rng = np.random.default_rng(int(self.seed))
        major = int(np.argmax(np.bincount(np.concatenate(labels)[np.concatenate(labels) >= 0],
                                          minlength=len(self.classes_))))
        minority = [np.flatnonzero((lab >= 0) & (lab != major)) for lab in labels]
        params = list(net.parameters())
        opt = torch.optim.Adam(params, lr=float(self.lr))
        steps = self.steps_
        warm = max(1, steps // 20)
        sched = torch.optim.lr_scheduler.LambdaLR(
            opt, lambda i: min(1.0, (i + 1) / warm) * 0.5 * (1 + math.cos(math.pi * i / steps)))
        f = torch.nn.functional

        def part(cb: Any, rows: list[tuple[np.ndarray, ...]]) -> tuple[Any, ...]:
            h = net.context(cb)  # (b, C, W)
            bi = np.concatenate([np.full(len(r[0]), j) for j, r in enumerate(rows)])
            k = np.concatenate([r[0] for r in rows])
            hz = h.new_zeros((len(k), h.shape[1]))
            ok = k >= 0
            hz[torch.from_numpy(ok).to(dev)] = h[torch.from_numpy(bi[ok]).to(dev), :,
                                                torch.from_numpy(k[ok]).to(dev)]
            z = torch.from_numpy(np.concatenate([r[1] for r in rows])).to(dev)
            yb = torch.from_numpy(np.concatenate([r[2] for r in rows])).to(dev)
            wb = torch.from_numpy(np.concatenate([r[3] for r in rows]).astype(np.float32)
                                  ).to(dev)
            out = net.classify(hz, z)
            loss = (f.cross_entropy(out, yb, reduction="none") * wb).sum()
            grads = torch.autograd.grad(loss, params)
            return grads, loss.detach().double(), (out.argmax(1) == yb).sum()

        self.history_: list[dict[str, float]] = []
        every = max(1, steps // 10)
        acc_loss = acc_ok = acc_n = 0.0
        t0 = time.perf_counter()
        for step in range(steps):
            cb, rows = self._batch(flights, labels, self._crops(rng, flights, labels, minority),
                                   w_cls)
            wsum = float(sum(r[3].sum() for r in rows))
            n = sum(len(r[0]) for r in rows)
            if n == 0 or wsum <= 0:
                continue
            parts = _parts(len(rows), SHARDS) if dev.type == "cpu" else [slice(0, len(rows))]
            cbt = torch.from_numpy(cb).to(dev)
            res = run(lambda sl, cbt=cbt, rows=rows: part(cbt[sl], rows[sl]), parts)
            for i, p in enumerate(params):
                g = res[0][0][i]
                for r in res[1:]:
                    g = g + r[0][i]
                p.grad = g / wsum
            opt.step()
            sched.step()
            acc_loss += sum(float(r[1]) for r in res) / wsum
            acc_ok += sum(int(r[2]) for r in res)
            acc_n += n
            if (step + 1) % every == 0 or step + 1 == steps:
                self._record(len(self.history_) + 1, acc_loss / every, acc_ok / max(acc_n, 1),
                             time.perf_counter() - t0)
                acc_loss = acc_ok = acc_n = 0.0
                t0 = time.perf_counter()

    def _record(self, epoch: int, loss: float, acc: float, seconds: float) -> None:
        rec = {"epoch": epoch, "loss": loss, "accuracy": acc, "val_loss": math.nan,
               "val_accuracy": math.nan, "seconds": seconds}
        self.history_.append(rec)
        if self.progress is not None:
            self.progress(f"SeqCNN steps {min(epoch * max(1, self.steps_ // 10), self.steps_)}/"
                          f"{self.steps_}: "
                          f"loss {loss:.4f}, accuracy {acc:.4f} ({seconds:.1f} s)")

    # -- prediction --------------------------------------------------------------------------

    def predict_proba(self, X: Any) -> np.ndarray:
        """Class probabilities of the asked rows of input ``X``, in ``want`` order."""
        check_is_fitted(self)
        torch = require_torch()
        X = np.asarray(X, dtype=np.float64)
        if X.shape[1] != self.n_features_in_:
            raise ValueError(f"X has {X.shape[1]} columns, the model was fitted on "
                             f"{self.n_features_in_}")
        flights = [self._flight(x, w) for x, w in self._split(X)]
        n_out = int(X[:, -1].max()) + 1 if len(X) else 0
        out = np.zeros((n_out, len(self.classes_)))
        net, s = self.net_, self.stride_

        def one(f: _Flight) -> tuple[np.ndarray, np.ndarray]:
            t = np.flatnonzero(f.want >= 0)
            with torch.no_grad():
                h = (net.context(torch.from_numpy(f.c.T[None].copy()))[0].T if len(f.c)
                     else torch.zeros((0, int(self.channels))))  # (nc, C)
                k = (t + 1) // s - 1
                hz = torch.zeros((len(t), h.shape[1]))
                ok = k >= 0
                hz[torch.from_numpy(ok)] = h[torch.from_numpy(k[ok])]
                p = torch.softmax(net.classify(hz, torch.from_numpy(f.z[t])), dim=1)
            return f.want[t], p.double().numpy()

        with torch_pool(torch, torch.device("cpu"), self.n_threads) as run:
            for pos, p in run(one, flights):
                out[pos] = p
        return out

    def predict(self, X: Any) -> np.ndarray:
        return self.classes_[self.predict_proba(X).argmax(axis=1)]

    def plot_history(self, path: str | Path, title: str = "") -> Path:
        """Training accuracy and loss per tenth of the steps."""
        return RowImageCNN.plot_history(self, path, title)  # type: ignore[arg-type]
