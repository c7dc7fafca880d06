"""Metrics as the paper's Table 11 reports them (Weka's), plus macro-F1, per-class scores
(Tables 15-18) and confusion matrices (Tables 12-13) as text and PNG.

All numbers come from the confusion matrix ``C`` (rows: true class, columns: predicted),
with ``N`` rows, class ``k`` support ``n_k = sum(C[k, :])`` and predictions
``p_k = sum(C[:, k])``:

* correctly classified % = ``100 * trace(C) / N`` (accuracy);
* TP rate (recall) of class k = ``C[k, k] / n_k``; FP rate = ``(p_k - C[k, k]) / (N - n_k)``;
* precision of class k = ``C[k, k] / p_k`` — **undefined when the model never predicts k**
  (``p_k = 0``: the paper's Eq. 7 divides by zero). Weka then prints ``?`` and the paper
  ``NaN`` (Table 11: SMO, AdaBoost and ZeroR never predict some class); the F-measure
  ``2PR / (P + R)`` of that class is undefined too;
* the "weighted" averages of Table 11 are Weka's: each class's value weighted by its
  support ``n_k / N``. One undefined precision with ``n_k > 0`` makes the weighted precision
  and weighted F-measure undefined (``?``, ``null`` in JSON), exactly as in the paper.
  Weighted TP rate = weighted recall = accuracy;
* macro-F1 (not in the paper) is the unweighted mean over the classes that occur in the
  true or predicted labels of ``F1_k = 2 C[k, k] / (n_k + p_k)``, which is defined whenever
  ``n_k + p_k > 0``: a class that is never predicted scores 0 instead of ``?``. It is the
  score to compare models on: it does not reward ignoring rare classes. Equal to
  ``sklearn.metrics.f1_score(average="macro")``.

A TP rate or FP rate with a zero denominator (no rows of the class, or only rows of the
class) is 0, as Weka reports it; it carries no weight in the weighted averages.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from tlm_process.labels import PAPER_CLASS_NAMES

__all__ = [
    "CLASS_NAMES",
    "aligned_table",
    "classification_metrics",
    "confusion_matrix",
    "format_cell",
    "format_confusion",
    "format_per_class",
    "format_results_table",
    "format_timing_table",
    "plot_confusion",
    "train_rate_label",
]

#: Class names of labels 0-4 as the paper's Tables 12-18 write them (other labels:
#: ``tlm_process.labels.class_name``, the fault type's name).
CLASS_NAMES: tuple[str, ...] = PAPER_CLASS_NAMES

#: Printed for an undefined value (Weka's "?"; the paper's "NaN").
UNDEFINED = "?"


def confusion_matrix(y_true: Any, y_pred: Any, n_classes: int = len(CLASS_NAMES),
                     labels: Sequence[int] | None = None) -> np.ndarray:
    """``C[true, predicted]`` counts for integer labels ``0 .. n_classes - 1``, or with
    ``labels`` for those labels (row/column i is ``labels[i]``; e.g. ``[0, 5, 9]``)."""
    t = np.asarray(y_true, dtype=np.int64)
    p = np.asarray(y_pred, dtype=np.int64)
    if t.shape != p.shape:
        raise ValueError(f"y_true and y_pred differ in shape: {t.shape} vs {p.shape}")
    if labels is not None:
        lab = np.asarray(labels, dtype=np.int64)
        index = np.full(int(max(lab.max(), t.max(initial=0), p.max(initial=0))) + 1, -1)
        index[lab] = np.arange(len(lab))
        if (t < 0).any() or (p < 0).any():
            raise ValueError(f"labels must be among {list(lab)}")
        t, p, n_classes = index[t], index[p], len(lab)
        if (t < 0).any() or (p < 0).any():
            raise ValueError(f"labels must be among {lab.tolist()}")
    bad = (t < 0) | (t >= n_classes) | (p < 0) | (p >= n_classes)
    if bad.any():
        raise ValueError(f"labels must be in 0..{n_classes - 1}")
    c = np.zeros((n_classes, n_classes), dtype=np.int64)
    np.add.at(c, (t, p), 1)
    return c


def _div(a: float, b: float, undefined: float) -> float:
    return a / b if b else undefined


def classification_metrics(cm: Any,
                           class_names: Sequence[str] = CLASS_NAMES) -> dict[str, Any]:
    """Every metric of the module docstring from a confusion matrix. Undefined values are
    NaN (``null`` after :func:`to_jsonable`). Keys: ``n``, ``accuracy`` (fraction),
    ``correct_pct``, ``incorrect_pct``, ``weighted_tp_rate``, ``weighted_fp_rate``,
    ``weighted_precision``, ``weighted_recall``, ``weighted_f1``, ``macro_f1``,
    ``undefined_precision`` (class names never predicted but present), ``per_class``
    (name -> support, predicted, tp_rate, fp_rate, precision, recall, f1, in the matrix's
    order), ``classes`` (the class names), ``confusion``."""
    c = np.asarray(cm, dtype=np.float64)
    k = c.shape[0]
    class_names = list(class_names)
    if c.shape != (k, k) or len(class_names) != k:
        raise ValueError(f"confusion matrix must be {len(class_names)}x{len(class_names)}")
    n = c.sum()
    support = c.sum(axis=1)
    predicted = c.sum(axis=0)
    tp = np.diag(c)
    per: dict[str, dict[str, Any]] = {}
    prec = np.full(k, math.nan)
    rec = np.zeros(k)
    f1w = np.full(k, math.nan)
    fpr = np.zeros(k)
    f1_macro_terms = []
    for i in range(k):
        prec[i] = _div(tp[i], predicted[i], math.nan)
        rec[i] = _div(tp[i], support[i], 0.0)
        fpr[i] = _div(predicted[i] - tp[i], n - support[i], 0.0)
        if math.isnan(prec[i]):
            f1w[i] = math.nan
        else:
            f1w[i] = _div(2 * prec[i] * rec[i], prec[i] + rec[i], 0.0)
        if support[i] + predicted[i] > 0:
            f1_macro_terms.append(2 * tp[i] / (support[i] + predicted[i]))
        per[class_names[i]] = {
            "support": int(support[i]), "predicted": int(predicted[i]),
            "tp_rate": float(rec[i]) if support[i] else math.nan,
            "fp_rate": float(fpr[i]) if n - support[i] else math.nan,
            "precision": float(prec[i]),
            "recall": float(rec[i]) if support[i] else math.nan,
            "f1": float(f1w[i]) if support[i] else (
                0.0 if predicted[i] else math.nan),
        }
    w = support / n if n else np.zeros(k)
    has = support > 0

    def weighted(v: np.ndarray) -> float:
        return float(np.sum(v[has] * w[has])) if n else math.nan

    acc = float(tp.sum() / n) if n else math.nan
    return {
        "n": int(n),
        "accuracy": acc,
        "correct_pct": 100.0 * acc,
        "incorrect_pct": 100.0 * (1.0 - acc),
        "weighted_tp_rate": weighted(rec),
        "weighted_fp_rate": weighted(fpr),
        "weighted_precision": weighted(prec),
        "weighted_recall": weighted(rec),
        "weighted_f1": weighted(f1w),
        "macro_f1": float(np.mean(f1_macro_terms)) if f1_macro_terms else math.nan,
        "undefined_precision": [class_names[i] for i in range(k)
                                if support[i] > 0 and predicted[i] == 0],
        "per_class": per,
        "classes": class_names,
        "confusion": c.astype(np.int64).tolist(),
    }


def to_jsonable(x: Any) -> Any:
    """``x`` with NaN/inf floats replaced by None (JSON ``null``) and numpy scalars and
    arrays made plain."""
    if isinstance(x, Mapping):
        return {str(k): to_jsonable(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_jsonable(x.tolist())
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    return x


def format_cell(v: Any, digits: int = 3, pct: bool = False) -> str:
    """A number as Weka prints it, ``?`` when undefined."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return UNDEFINED
    return f"{v:.2f}%" if pct else f"{v:.{digits}f}"


def format_results_table(results: Mapping[str, Mapping[str, Any]], title: str = "",
                         transfer: bool = False) -> str:
    """Table 11's layout: one row per model (``results[model]`` = metrics dict), columns
    correctly / incorrectly classified %, weighted TP rate, FP rate, precision, recall, F1,
    then macro-F1 and, with ``transfer``, accuracy and macro-F1 on the transfer logs.
    The best correctly-classified % is marked with ``*`` (the paper's bold)."""
    head = ["Method", "Correct%", "Incorrect%", "TP", "FP", "Precision", "Recall", "F1",
            "macro-F1"]
    if transfer:
        head += ["xfer acc%", "xfer macro-F1"]
    rows = []
    accs = {m: r.get("accuracy") for m, r in results.items()}
    finite = [a for a in accs.values() if a is not None and math.isfinite(a)]
    best = max(finite) if finite else None
    for model, r in results.items():
        mark = "*" if best is not None and accs[model] == best else ""
        row = [model, format_cell(r["correct_pct"], pct=True) + mark,
               format_cell(r["incorrect_pct"], pct=True),
               format_cell(r["weighted_tp_rate"]), format_cell(r["weighted_fp_rate"]),
               format_cell(r["weighted_precision"]), format_cell(r["weighted_recall"]),
               format_cell(r["weighted_f1"]), format_cell(r["macro_f1"])]
        if transfer:
            t = r.get("transfer") or {}
            row += [format_cell(t.get("correct_pct"), pct=True) if t else "-",
                    format_cell(t.get("macro_f1")) if t else "-"]
        rows.append(row)
    return aligned_table(head, rows, title)


def train_rate_label(train_hz: float | None, normal_hz: float | None = None) -> str:
    """The training-row rate as the time tables print it: ``all`` (every row), ``5`` [Hz],
    ``5 (N 1)`` (5 Hz, the Normal rows at 1 Hz), to 3 significant digits (a row budget,
    ``--max-rows``, gives rates such as ``all (N 2.5)``)."""
    if train_hz is None:
        return "-"
    text = "all" if not train_hz else f"{train_hz:.3g}"
    return text + (f" (N {normal_hz:.3g})" if normal_hz else "")


def format_timing_table(results: Mapping[str, Mapping[str, Any]], title: str = "") -> str:
    """Per model: the rate its training rows were thinned to (``all``: every row), the rows
    it was fitted on, and its fit and predict wall seconds (summed over folds; predict
    includes the transfer rows, refitting for them after cross-validation is added to fit)."""
    head = ["Method", "train Hz", "rows fitted", "fit s", "predict s"]
    rows = []
    for model, r in results.items():
        hz = r.get("train_hz")
        fit = r.get("fit_seconds", 0.0) + r.get("transfer_fit_seconds", 0.0)
        pred = r.get("predict_seconds", 0.0) + r.get("transfer_predict_seconds", 0.0)
        rows.append([model, train_rate_label(hz, r.get("normal_hz")), f"{r.get('n_fit', 0):,}",
                     f"{fit:.2f}", f"{pred:.2f}"])
    rows.append(["total", "", "", f"{sum(float(r[3]) for r in rows):.2f}",
                 f"{sum(float(r[4]) for r in rows):.2f}"])
    return aligned_table(head, rows, title)


def aligned_table(head: Sequence[str], rows: Sequence[Sequence[str]], title: str = "") -> str:
    """A plain-text table: ``title``, then ``head`` and ``rows`` (strings) in columns two
    spaces apart, the first left-aligned, the others right-aligned."""
    widths = [max([len(h), *(len(r[i]) for r in rows)]) for i, h in enumerate(head)]
    lines = [title] if title else []
    for r in [head, *rows]:
        lines.append("  ".join(c.ljust(widths[0]) if i == 0 else c.rjust(widths[i])
                               for i, c in enumerate(r)))
    return "\n".join(lines)


def format_confusion(cm: Any, class_names: Sequence[str] = CLASS_NAMES,
                     title: str = "") -> str:
    """A confusion matrix in the layout of Tables 12-13: predicted classes as columns, the
    true class as the last column."""
    c = np.asarray(cm, dtype=np.int64)
    cells = [[str(v) for v in row] for row in c]
    w = max([len(n) for n in class_names] + [len(x) for row in cells for x in row])
    lines = [title] if title else []
    lines.append("  ".join(n.rjust(w) for n in class_names) + "  Class")
    for name, row in zip(class_names, cells, strict=True):
        lines.append("  ".join(x.rjust(w) for x in row) + f"  {name}")
    return "\n".join(lines)


def format_per_class(metrics: Mapping[str, Any], title: str = "") -> str:
    """Per-class F1, precision and recall in the layout of Tables 15-18 (the paper heads
    precision "Accuracy")."""
    lines = [title] if title else []
    w = max(8, *(len(n) + 1 for n in metrics["per_class"]))
    lines.append(f"{'':{w}s}{'F1-Score':>10s}{'Precision':>11s}{'Recall':>9s}{'Support':>9s}")
    for name, d in metrics["per_class"].items():
        lines.append(f"{name:{w}s}{format_cell(d['f1'], 4):>10s}"
                     f"{format_cell(d['precision'], 4):>11s}"
                     f"{format_cell(d['recall'], 4):>9s}{d['support']:>9d}")
    return "\n".join(lines)


def plot_confusion(cm: Any, path: str | Path, title: str = "",
                   class_names: Sequence[str] = CLASS_NAMES) -> Path:
    """Confusion matrix PNG: counts in each cell, colour = share of the true class's rows
    (so rare classes are as visible as the normal class)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = np.asarray(cm, dtype=np.float64)
    share = c / np.maximum(c.sum(axis=1, keepdims=True), 1)
    k = len(class_names)
    side = max(1.0, k / 5)
    fig, ax = plt.subplots(figsize=(5.6 * side, 4.6 * side), layout="constrained")
    im = ax.imshow(share, cmap="Blues", vmin=0, vmax=1)
    for i in range(k):
        for j in range(k):
            ax.text(j, i, f"{int(c[i, j])}", ha="center", va="center", fontsize=8,
                    color="white" if share[i, j] > 0.6 else "black")
    ax.set_xticks(range(k), class_names, rotation=45 if k > 5 else 0,
                  ha="right" if k > 5 else "center")
    ax.set_yticks(range(k), class_names)
    ax.set_xlabel("predicted")
    ax.set_ylabel("true")
    ax.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax, fraction=0.046, label="share of true class")
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(p, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return p
