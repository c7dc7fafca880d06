"""Fault Time Window Stretching (paper Eq. 5): class counts, fault share α, factor λ.

Eq. 5 defines the fault share of a data set, α = (rows inside fault windows) / (all rows), and
the target share γ = α·λ, where λ scales every fault window's duration. Hence
:func:`lambda_for_target`: λ = γ / α. The paper's relation is linear because the flight's
total length stays what the mission makes it: longer faults replace normal flight. When the
added fault time is *added* to the flight instead (normal time unchanged), the share becomes
γ = λα / (1 − α + λα), i.e. λ = γ(1 − α) / (α(1 − γ)) (``model="added"``). Which one a tlm
flight follows depends on the fault (an engine fault grounds the vehicle and stops the
mission; a GPS fault lets it fly on): ``docs/pipeline.md`` has the measured numbers.

λ is realised by flying with longer windows (:meth:`tlm_sim.faults.FaultSchedule.stretched`,
:func:`stretch_schedule`), not by copying rows.

The paper's Tables 7 and 8 are here as data (:data:`PAPER_TABLE_7`, :data:`PAPER_TABLE_8`)
for comparisons; the λ they imply is :func:`implied_lambda`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Literal

import numpy as np
import pandas as pd

from tlm_process.pipeline.errors import PipelineError
from tlm_sim.faults import FaultSchedule

__all__ = [
    "CLASS_COLUMNS",
    "PAPER_TABLE_7",
    "PAPER_TABLE_8",
    "class_counts",
    "fault_share",
    "format_counts",
    "implied_lambda",
    "lambda_for_target",
    "stretch_schedule",
    "target_for_lambda",
]

Model = Literal["paper", "added"]

#: Column headings of the paper's Tables 7 and 8, by label 0..4, then the total (a data set
#: with other labels gets a column per label present: ``tlm_process.labels.class_column``).
CLASS_COLUMNS: tuple[str, ...] = ("Normal", "GPS Fail", "Accelerometer Fail", "Engine Fail",
                                  "RC Fail", "Total")


def _paper_table(rows: dict[str, list[int]]) -> pd.DataFrame:
    return pd.DataFrame.from_dict(rows, orient="index", columns=list(CLASS_COLUMNS))


#: Paper Table 7: rows per class before balancing (GPS, IMU, RATE, VIBE).
PAPER_TABLE_7 = _paper_table({
    "GPS": [1896, 129, 108, 104, 318, 2555],
    "IMU": [9479, 645, 539, 519, 1591, 12773],
    "RATE": [3794, 258, 216, 208, 633, 5109],
    "VIBE": [3793, 258, 216, 208, 634, 5109],
})
#: Paper Table 8: rows per class after balancing (fault windows stretched, four flights).
PAPER_TABLE_8 = _paper_table({
    "GPS": [3609, 1096, 1305, 606, 1277, 7893],
    "IMU": [18032, 5480, 6528, 3033, 6393, 39466],
    "RATE": [7215, 2188, 2610, 1215, 2558, 15786],
    "VIBE": [7218, 2189, 2612, 1210, 2557, 15786],
})


def class_counts(tables: Mapping[str, pd.DataFrame], label: str = "label") -> pd.DataFrame:
    """Rows per class per table, as the paper's Tables 7/8: index = table names, columns
    one per class (:func:`tlm_process.labels.class_labels` of every table's labels: the
    paper's :data:`CLASS_COLUMNS` for labels 0-4, else normal and each label present, headed
    :func:`tlm_process.labels.class_column`) and ``Total``."""
    from tlm_process.labels import class_column, class_labels

    arrays = {}
    for name, df in tables.items():
        if label not in df.columns:
            raise PipelineError(f"{name} has no {label!r} column: label the rows first")
        arrays[name] = df[label].to_numpy(np.int64)
        if len(arrays[name]) and arrays[name].min() < 0:
            raise PipelineError(f"{name}: negative labels (0 is normal, faults 1-14)")
    labels = class_labels(*arrays.values())
    rows = {}
    for name, y in arrays.items():
        counts = np.bincount(y, minlength=max(labels) + 1)
        rows[name] = [*(int(counts[k]) for k in labels), int(counts.sum())]
    return pd.DataFrame.from_dict(rows, orient="index",
                                  columns=[*(class_column(k) for k in labels), "Total"])


def fault_share(counts: pd.DataFrame | pd.Series) -> pd.Series | float:
    """α of Eq. 5: fault rows / all rows, per table (a DataFrame from :func:`class_counts`) or
    for one row (a Series). NaN for an empty table."""
    faults = counts.drop([CLASS_COLUMNS[0], "Total"], axis=1 if isinstance(
        counts, pd.DataFrame) else 0)
    total = counts["Total"]
    if isinstance(counts, pd.Series):
        return float(faults.sum() / total) if total else math.nan
    return (faults.sum(axis=1) / total.where(total > 0)).astype(float)


def _check_share(x: float, what: str, open_low: bool = True) -> float:
    if not isinstance(x, int | float | np.floating) or isinstance(x, bool) or not math.isfinite(x):
        raise PipelineError(f"{what} must be a number in (0, 1), got {x!r}")
    x = float(x)
    if not (0 < x < 1 if open_low else 0 <= x < 1):
        raise PipelineError(f"{what} must be in (0, 1), got {x:g}")
    return x


def lambda_for_target(alpha: float, gamma: float, model: Model = "paper") -> float:
    """λ that turns fault share ``alpha`` into the target share ``gamma`` (Eq. 5).

    ``model="paper"``: γ = αλ, so λ = γ/α (the flight's length unchanged; needs γ ≤ 1).
    ``model="added"``: the extra fault time adds to the flight, γ = λα/(1 − α + λα), so
    λ = γ(1 − α)/(α(1 − γ)). Both need 0 < α < 1 and 0 < γ < 1; λ > 1 lengthens the faults."""
    a = _check_share(alpha, "alpha (the fault share)")
    g = _check_share(gamma, "gamma (the target fault share)")
    if model == "paper":
        return g / a
    if model == "added":
        return g * (1 - a) / (a * (1 - g))
    raise PipelineError(f"unknown stretching model {model!r}; use 'paper' or 'added'")


def target_for_lambda(alpha: float, lam: float, model: Model = "paper") -> float:
    """The fault share γ that stretching by ``lam`` gives from ``alpha`` (inverse of
    :func:`lambda_for_target`). ``model="paper"`` raises when αλ > 1 (more fault time than the
    flight has)."""
    a = _check_share(alpha, "alpha (the fault share)")
    if not math.isfinite(lam) or lam <= 0:
        raise PipelineError(f"lambda must be a finite number > 0, got {lam!r}")
    if model == "paper":
        if a * lam > 1:
            raise PipelineError(f"alpha {a:g} x lambda {lam:g} > 1: a flight cannot be more "
                                "than all fault")
        return a * lam
    if model == "added":
        return lam * a / (1 - a + lam * a)
    raise PipelineError(f"unknown stretching model {model!r}; use 'paper' or 'added'")


def implied_lambda(before: pd.DataFrame, after: pd.DataFrame,
                   model: Model = "paper") -> pd.Series:
    """Per table, the λ that takes the fault share of ``before`` to that of ``after`` (two
    :func:`class_counts` tables, e.g. the paper's Tables 7 and 8)."""
    a, g = fault_share(before), fault_share(after)
    return pd.Series({t: lambda_for_target(a[t], g[t], model) for t in before.index
                      if t in after.index}, dtype=float)


def stretch_schedule(schedule: FaultSchedule, lam: float, **kwargs: object) -> FaultSchedule:
    """The schedule with every fault window scaled by ``lam``
    (:meth:`tlm_sim.faults.FaultSchedule.stretched`; keyword arguments go to it)."""
    return schedule.stretched(lam, **kwargs)  # type: ignore[arg-type]


def format_counts(counts: pd.DataFrame, title: str = "") -> str:
    """Table 7-style text: rows per class and table, plus the fault share α per table."""
    alpha = fault_share(counts)
    columns = list(counts.columns)
    widths = [max(len(c), 7) + 2 for c in columns]
    lines = [title] if title else []
    lines.append(f"{'':6}" + "".join(f"{c:>{w}}" for c, w in zip(columns, widths,
                                                                  strict=True))
                 + f"{'faults':>9}")
    for name, row in counts.iterrows():
        cells = "".join(f"{int(row[c]):>{w},}" for c, w in zip(columns, widths,
                                                               strict=True))
        a = alpha[name]
        share = "" if math.isnan(a) else f"{100 * a:8.2f}%"
        lines.append(f"{name!s:6}{cells}{share}")
    return "\n".join(lines)
