"""Plots of the TLM pipeline (matplotlib, Agg backend, PNG files).

* :func:`plot_trajectory` — top view of the GPS track with each fault segment in its label's
  colour and the boundaries lettered A, B, C, ... as in the paper's Figs. 6, 9, 11, 13 and 15
  (A-B first fault, C-D second, ...); the positions a ground station recorded (the paper's
  Eq. 4 input) are drawn as crosses, so a recorded position far from the track (after a GPS
  loss) shows. Right: height above home over time with the windows shaded.
* :func:`plot_fault_traces` — GPS speed, satellites and course, accelerations and attitude
  around one fault with its window shaded, one unit per axis (Figs. 10, 12, 14, 16).
* :func:`plot_label_shares` — share of each label per table (Figs. 17 and 18).
"""

from __future__ import annotations

import os
import string
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from tlm_process.labels import label_colour, long_name
from tlm_process.pipeline.anchoring import FaultWindow
from tlm_process.pipeline.ingest import FaultRecord
from tlm_process.pipeline.stretching import class_counts
from tlm_sim.geo import latlon_to_ne

__all__ = ["plot_fault_traces", "plot_label_shares", "plot_trajectory"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _shade(ax, windows: Sequence[FaultWindow], t_max_s: float) -> None:
    for w in windows:
        end = min(w.end_us * 1e-6, t_max_s)
        ax.axvspan(w.start_us * 1e-6, end, color=label_colour(w.label), alpha=0.18, lw=0)


def plot_trajectory(tables: Mapping[str, pd.DataFrame], windows: Sequence[FaultWindow],
                    path: str | os.PathLike, title: str = "",
                    records: Sequence[FaultRecord] = (), home_alt: float | None = None) -> Path:
    """Top view (north/east metres from the first GPS row of the plotted span) of the GPS
    track, fault segments coloured by label and lettered, recorded positions as crosses; and
    height above home [m] over time (GPS altitude minus ``home_alt``, or minus the first row's
    altitude when unknown). ``tables["GPS"]`` needs a ``label`` column."""
    plt = _plt()
    gps = tables["GPS"]
    lat0, lon0 = float(gps["Lat"].iloc[0]), float(gps["Lng"].iloc[0])
    n, e = latlon_to_ne(gps["Lat"].to_numpy(float), gps["Lng"].to_numpy(float), lat0, lon0)
    t = gps["TimeUS"].to_numpy(np.float64) * 1e-6
    lab = gps["label"].to_numpy()
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 5.5), width_ratios=(1.1, 1))
    ax.plot(e, n, "-", color=label_colour(0), lw=1.0, label="normal", zorder=1)
    seen = set()
    for w in windows:
        m = lab == w.label
        m &= (t * 1e6 >= w.start_us) & (t * 1e6 < w.end_us)
        if not m.any():
            continue
        kw = {"label": long_name(w.label)} if w.label not in seen else {}
        seen.add(w.label)
        ax.plot(e[m], n[m], ".", ms=3, color=label_colour(w.label), zorder=2, **kw)
    letters = iter(string.ascii_uppercase)
    for w in windows:
        for edge_us in (w.start_us, w.end_us):
            letter = next(letters, "?")
            if not np.isfinite(edge_us):
                continue
            j = min(int(np.searchsorted(t * 1e6, edge_us)), len(t) - 1)
            ax.annotate(letter, (e[j], n[j]), xytext=(4, 4), textcoords="offset points",
                        fontsize=10, fontweight="bold", color=label_colour(w.label))
    first = True
    for r in records:
        for pos in (r.start_pos, r.end_pos):
            if pos is None:
                continue
            pn, pe = latlon_to_ne(pos[0], pos[1], lat0, lon0)
            ax.plot(float(pe), float(pn), "kx", ms=7, mew=1.5, zorder=3,
                    label="recorded position (Eq. 4)" if first else None)
            first = False
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="best", fontsize=8)
    ref = home_alt if home_alt is not None else float(gps["Alt"].iloc[0])
    ax2.plot(t, gps["Alt"].to_numpy(float) - ref, color="k", lw=1)
    _shade(ax2, windows, float(t[-1]))
    ax2.set_xlabel("time since boot [s]")
    ax2.set_ylabel("GPS height above home [m]")
    fig.suptitle(title)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def _panel(ax, df: pd.DataFrame | None, cols: Sequence[str], t0: float, t1: float,
           ylabel: str) -> None:
    if df is None or not len(df):
        ax.text(0.5, 0.5, "not logged", transform=ax.transAxes, ha="center")
        return
    t = df["TimeUS"].to_numpy(np.float64) * 1e-6
    m = (t >= t0) & (t <= t1)
    for c in cols:
        if c in df.columns:
            ax.plot(t[m], df[c].to_numpy(float)[m], lw=0.9, label=c)
    ax.set_ylabel(ylabel)
    ax.legend(loc="upper right", fontsize=7, ncol=len(cols))


def plot_fault_traces(tables: Mapping[str, pd.DataFrame], window: FaultWindow,
                      path: str | os.PathLike, title: str = "",
                      margin_s: float | None = None) -> Path:
    """Five panels around one fault (window shaded), one unit per axis: GPS ground speed
    [m/s], GPS satellites [count], GPS course [deg], IMU 0 acceleration [m/s^2], roll/pitch
    [deg] (ATT) or body rates [deg/s] (RATE) when ATT is not logged. ``margin_s``: time shown
    before and after the window (default: the window's length, at least 20 s)."""
    plt = _plt()
    gps = tables["GPS"]
    t_end_log = float(gps["TimeUS"].max()) * 1e-6
    w0 = window.start_us * 1e-6
    w1 = min(window.end_us * 1e-6, t_end_log)
    margin = margin_s if margin_s is not None else max(20.0, w1 - w0)
    t0, t1 = w0 - margin, w1 + margin
    imu = tables.get("IMU")
    if imu is not None and "I" in imu.columns:
        imu = imu[imu["I"] == 0]
    fig, axes = plt.subplots(5, 1, figsize=(10, 10.5), sharex=True,
                             height_ratios=(1, 0.6, 1, 1, 1))
    _panel(axes[0], gps, ["Spd"], t0, t1, "GPS speed [m/s]")
    _panel(axes[1], gps, ["NSats"], t0, t1, "GPS satellites")
    _panel(axes[2], gps, ["GCrs"], t0, t1, "GPS course [deg]")
    _panel(axes[3], imu, ["AccX", "AccY", "AccZ"], t0, t1, "IMU0 accel [m/s^2]")
    if tables.get("ATT") is not None and len(tables["ATT"]):
        _panel(axes[4], tables["ATT"], ["Roll", "Pitch"], t0, t1, "attitude [deg]")
    else:
        _panel(axes[4], tables.get("RATE"), ["R", "P"], t0, t1, "body rate [deg/s]")
    for ax in axes:
        ax.axvspan(w0, w1, color=label_colour(window.label), alpha=0.2, lw=0)
    axes[-1].set_xlabel("time since boot [s]")
    axes[-1].set_xlim(t0, t1)
    fig.suptitle(title or f"{window.name}: {long_name(window.label)} fault "
                 f"(label {window.label}), window shaded")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def plot_label_shares(counts: pd.DataFrame | Mapping[str, pd.DataFrame],
                      path: str | os.PathLike, title: str = "") -> Path:
    """Share of each label per table as stacked bars with the percentages written in
    (Figs. 17/18). ``counts``: a :func:`class_counts` table, or labelled tables to count."""
    plt = _plt()
    if not isinstance(counts, pd.DataFrame):
        counts = class_counts(counts)
    from tlm_process.labels import class_column

    names = list(counts.index)
    label_of = {class_column(k): k for k in range(256)}
    cols = [c for c in counts.columns if c != "Total"]
    labels = [label_of[c] for c in cols]
    vals = counts[cols].to_numpy(float)
    share = 100 * vals / np.maximum(vals.sum(axis=1, keepdims=True), 1)
    fig, ax = plt.subplots(figsize=(10, 1.0 + 0.7 * len(names)))
    left = np.zeros(len(names))
    for k, lab in enumerate(labels):
        ax.barh(names, share[:, k], left=left, color=label_colour(lab),
                label=f"{lab} {long_name(lab)}", edgecolor="white", lw=0.5)
        for i, v in enumerate(share[:, k]):
            if v >= 3:
                ax.text(left[i] + v / 2, i, f"{v:.1f}%", ha="center", va="center", fontsize=8,
                        color="white" if lab else "black")
        left += share[:, k]
    ax.set_yticks(range(len(names)),
                  [f"{n}\n{int(t):,} rows" for n, t in zip(names, vals.sum(axis=1),
                                                            strict=True)])
    ax.invert_yaxis()
    ax.set_xlim(0, 100)
    ax.set_xlabel("share of rows [%]")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.35 if len(names) < 3 else -0.15),
              ncol=min(len(labels), 7), fontsize=8, frameon=False)
    ax.set_title(title or "share of each label")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
