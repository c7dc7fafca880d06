"""How the transfer logs' features differ from the data set's, per class (``--test-on``).

A model trained on tlm flights transfers to real SITL logs only as far as each class's
features are distributed alike in both. :func:`feature_shift` compares, for every table,
feature and class, the data set's rows (all its flights) with the transfer rows: the
two-sample Kolmogorov-Smirnov statistic (0: same distribution, 1: disjoint) and the 5th,
50th and 95th percentiles of both in the feature's raw units (the data set's scaler undone).
The KS statistic is taken on the scaled values rounded to ``resolution`` (1e-4 of the
training range), so that float32-vs-float64 noise (an accelerometer stuck at 1.0 logged as
0.99999994, a vibration floor of 1.8e-15 vs 6e-7) does not count as a difference. Sorted by
KS, the top rows point at the simulator's largest departures from the reference.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import ks_2samp

from tlm_process.labels import class_labels, class_name

__all__ = ["feature_shift", "format_shift"]

#: Fewer rows than this in either sample: no KS statistic (NaN).
MIN_ROWS = 20


def _raw(scaler: Any, table: str, df: pd.DataFrame, scaled: bool) -> pd.DataFrame:
    if scaler is None or not scaled:
        return df
    return scaler.inverse_table(table, df)


def _finite(v: pd.Series) -> np.ndarray:
    x = v.to_numpy(np.float64)
    return x[np.isfinite(x)]


def feature_shift(ds_tables: Mapping[str, pd.DataFrame],
                  transfer: Mapping[str, pd.DataFrame],
                  features: Mapping[str, Sequence[str]], scaler: Any = None,
                  scaled: bool = True, resolution: float = 1e-4) -> pd.DataFrame:
    """One row per (table, feature, class) with ``n_ds``, ``n_transfer``, ``ks``,
    ``ds_p5/p50/p95`` and ``transfer_p5/p50/p95`` (raw units), sorted by ``ks``
    (largest first). ``scaled``: the tables hold scaled features (``scaler`` undoes them
    for the percentiles)."""
    rows: list[dict[str, Any]] = []
    for t, xt in transfer.items():
        if t not in ds_tables:
            continue
        a_all = _raw(scaler, t, ds_tables[t], scaled)
        b_all = _raw(scaler, t, xt, scaled)
        labels = class_labels(ds_tables[t]["label"].to_numpy(), xt["label"].to_numpy())
        for label, cname in ((k, class_name(k)) for k in labels):
            a_sel = (ds_tables[t]["label"] == label).to_numpy()
            b_sel = (xt["label"] == label).to_numpy()
            for f in features[t]:
                a = _finite(a_all.loc[a_sel, f])
                b = _finite(b_all.loc[b_sel, f])
                r: dict[str, Any] = {"table": t, "feature": f, "class": cname,
                                     "n_ds": len(a), "n_transfer": len(b), "ks": np.nan}
                if len(a) >= MIN_ROWS and len(b) >= MIN_ROWS:
                    sa = _finite(ds_tables[t].loc[a_sel, f])
                    sb = _finite(xt.loc[b_sel, f])
                    if not scaled and scaler is not None and f in scaler.ranges.get(t, {}):
                        lo, hi = scaler.ranges[t][f]
                        span = hi - lo if hi > lo else 1.0
                        sa, sb = (sa - lo) / span, (sb - lo) / span
                    q = resolution
                    r["ks"] = float(ks_2samp(np.round(sa / q), np.round(sb / q)).statistic)
                for who, v in (("ds", a), ("transfer", b)):
                    q = np.percentile(v, [5, 50, 95]) if len(v) else [np.nan] * 3
                    r.update({f"{who}_p5": q[0], f"{who}_p50": q[1], f"{who}_p95": q[2]})
                rows.append(r)
    out = pd.DataFrame(rows)
    if len(out):
        out = out.sort_values("ks", ascending=False, na_position="last",
                              kind="stable").reset_index(drop=True)
    return out


def format_shift(shift: pd.DataFrame, top: int = 5) -> str:
    """The ``top`` largest shifts per table as text."""
    if not len(shift):
        return "no transfer rows to compare"
    lines = ["largest feature distribution differences, data set vs transfer logs "
             "(KS statistic; 5th/50th/95th percentiles, raw units):"]
    for t, g in shift.groupby("table", sort=False):
        for _, r in g.dropna(subset=["ks"]).head(top).iterrows():
            lines.append(f"  {t:4s} {r['feature']:8s} {r['class']:6s} KS {r['ks']:.2f}  "
                         f"data set {r['ds_p5']:.4g} / {r['ds_p50']:.4g} / {r['ds_p95']:.4g}  "
                         f"transfer {r['transfer_p5']:.4g} / {r['transfer_p50']:.4g} / "
                         f"{r['transfer_p95']:.4g}")
    return "\n".join(lines)
