"""Min-max feature scaling (paper Eq. 6), fitted on training flights only.

``scaled = (x − min) / (max − min)`` per table and feature, with min and max taken over the
rows of the *training* flights only; test flights (and any later flight) are scaled with the
same numbers, so their values may fall outside [0, 1] (they are not clipped: a value beyond
the training range is information). A feature that is constant on the training flights
(max = min) scales to 0. NaN stays NaN. The scaler is saved with the data set as JSON
(``DS/scaler.json``) and read back with :meth:`MinMaxScaler.load`.

Flights are split into training and test sets as whole flights (:func:`split_flights`), never
row by row: rows of one flight are strongly correlated in time.
"""

from __future__ import annotations

import fnmatch
import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_process.pipeline.errors import PipelineError
from tlm_process.pipeline.features import NON_FEATURE

__all__ = ["SCALER_FORMAT", "MinMaxScaler", "split_flights"]

SCALER_FORMAT = "tlm.minmax"


def split_flights(flight_ids: Sequence[str], test_frac: float = 0.0, seed: int = 0,
                  test_patterns: Sequence[str] = ()) -> tuple[list[str], list[str]]:
    """(train, test) flight ids. Flights matching any of ``test_patterns`` (shell globs, e.g.
    ``combined_*``) are test flights; otherwise ``floor(test_frac · n)`` flights drawn with
    ``numpy.random.default_rng(seed)``. At least one flight must stay for training."""
    ids = list(dict.fromkeys(flight_ids))
    if not 0 <= test_frac < 1 or math.isnan(test_frac):
        raise PipelineError(f"test fraction must be in [0, 1), got {test_frac!r}")
    if test_patterns:
        test = [f for f in ids if any(fnmatch.fnmatchcase(f, p) for p in test_patterns)]
        unmatched = [p for p in test_patterns
                     if not any(fnmatch.fnmatchcase(f, p) for f in ids)]
        if unmatched:
            raise PipelineError(f"test flight pattern {unmatched[0]!r} matches no flight "
                                f"(flights: {', '.join(ids[:6])}{' ...' if len(ids) > 6 else ''})")
    else:
        k = int(math.floor(test_frac * len(ids)))
        rng = np.random.default_rng(seed)
        pick = set(rng.choice(len(ids), size=k, replace=False).tolist()) if k else set()
        test = [f for i, f in enumerate(ids) if i in pick]
    train = [f for f in ids if f not in set(test)]
    if not train:
        raise PipelineError("every flight is a test flight: keep at least one for training "
                            "(the scaler is fitted on training flights)")
    return train, test


@dataclass
class MinMaxScaler:
    """Eq. 6 min-max scaling per table and feature.

    ``ranges[table][feature] = (min, max)`` over the training flights' rows;
    ``train_flights``: the ids of those flights.
    """

    ranges: dict[str, dict[str, tuple[float, float]]] = field(default_factory=dict)
    train_flights: list[str] = field(default_factory=list)

    @classmethod
    def fit(cls, tables: Mapping[str, pd.DataFrame],
            train_flights: Sequence[str]) -> MinMaxScaler:
        """Fit on the rows of ``train_flights`` (matched on the ``flight`` column) of every
        table; features = all columns but the non-feature ones (flight, TimeUS, label, and any
        other non-numeric column)."""
        train = list(dict.fromkeys(train_flights))
        if not train:
            raise PipelineError("no training flights to fit the scaler on")
        ranges: dict[str, dict[str, tuple[float, float]]] = {}
        for name, df in tables.items():
            if "flight" not in df.columns:
                raise PipelineError(f"{name} has no 'flight' column")
            rows = df[df["flight"].isin(train)]
            if not len(rows):
                raise PipelineError(f"{name}: none of the training flights has rows")
            ranges[name] = {}
            for c in _features(df):
                v = rows[c].to_numpy(np.float64)
                v = v[np.isfinite(v)]
                lo, hi = (float(v.min()), float(v.max())) if len(v) else (math.nan, math.nan)
                ranges[name][c] = (lo, hi)
        return cls(ranges, train)

    def constant_features(self) -> dict[str, list[str]]:
        """Per table, the features whose training rows hold one value (or none): Eq. 6 maps
        them to 0 in every row, so they carry nothing (e.g. GPS ``NSats`` when every
        training flight keeps 10 satellites)."""
        out = {}
        for name, feats in self.ranges.items():
            flat = [c for c, (lo, hi) in feats.items() if not hi > lo]
            if flat:
                out[name] = flat
        return out

    def transform_table(self, name: str, df: pd.DataFrame) -> pd.DataFrame:
        """A copy of table ``name`` with its features scaled (non-feature columns as they
        are). Every fitted feature must be present."""
        if name not in self.ranges:
            raise PipelineError(f"the scaler knows no table {name!r} "
                                f"(it has {', '.join(self.ranges)})")
        missing = [c for c in self.ranges[name] if c not in df.columns]
        if missing:
            raise PipelineError(f"{name} lacks feature(s) the scaler was fitted on: "
                                f"{', '.join(missing)}")
        out = df.copy()
        for c, (lo, hi) in self.ranges[name].items():
            v = df[c].to_numpy(np.float64)
            span = hi - lo
            out[c] = (v - lo) / span if span > 0 else np.where(np.isnan(v), np.nan, 0.0)
        return out

    def transform(self, tables: Mapping[str, pd.DataFrame]) -> dict[str, pd.DataFrame]:
        """:meth:`transform_table` of every table."""
        return {n: self.transform_table(n, df) for n, df in tables.items()}

    def inverse_table(self, name: str, df: pd.DataFrame) -> pd.DataFrame:
        """Undo :meth:`transform_table` (constant features come back as their value)."""
        out = df.copy()
        for c, (lo, hi) in self.ranges[name].items():
            out[c] = df[c].to_numpy(np.float64) * (hi - lo) + lo
        return out

    # -- files ----------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return {
            "format": SCALER_FORMAT,
            "equation": "scaled = (x - min) / (max - min); 0 where max == min (paper Eq. 6)",
            "train_flights": list(self.train_flights),
            "tables": {t: {c: {"min": _num(lo), "max": _num(hi)} for c, (lo, hi) in r.items()}
                       for t, r in self.ranges.items()},
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> MinMaxScaler:
        if not isinstance(d, Mapping) or d.get("format") != SCALER_FORMAT:
            raise PipelineError(f"not a tlm min-max scaler (expected format {SCALER_FORMAT!r})")
        try:
            ranges = {t: {c: (_float(v["min"]), _float(v["max"])) for c, v in r.items()}
                      for t, r in d["tables"].items()}
            return cls(ranges, list(d.get("train_flights") or []))
        except (KeyError, TypeError, AttributeError) as exc:
            raise PipelineError(f"malformed scaler: {exc}") from None

    def save(self, path: str | os.PathLike) -> Path:
        p = Path(path)
        p.write_text(json.dumps(self.to_dict(), indent=1) + "\n")
        return p

    @classmethod
    def load(cls, path: str | os.PathLike) -> MinMaxScaler:
        from tlm_sim.textfile import TextFileError, read_text

        p = Path(path)
        try:
            return cls.from_dict(json.loads(read_text(p)))
        except TextFileError as exc:
            raise PipelineError(f"cannot read: {exc}", source=str(p)) from None
        except json.JSONDecodeError as exc:
            raise PipelineError(f"invalid JSON: {exc}", source=str(p)) from None
        except PipelineError as exc:
            raise PipelineError(exc.reason, source=str(p)) from None


def _features(df: pd.DataFrame) -> list[str]:
    return [c for c in df.columns
            if c not in NON_FEATURE and pd.api.types.is_float_dtype(df[c])]


def _num(x: float) -> float | None:
    return None if math.isnan(x) else x


def _float(x: Any) -> float:
    return math.nan if x is None else float(x)
