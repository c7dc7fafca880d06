"""``timeline.png`` of ``tlm detect``: what the detector said about one log, over log time.

Top: the probability of each fault class the detector gave at some point more than
:data:`SHOW_P` (one line per class, in the class's colour), the faults it reports as bars
along the top, and when the log has a sidecar the true fault windows shaded. Bottom strip: the
log's own marks: flight modes (MODE, named), errors (ERR subsystem/code) and events (EV ids:
arming 10, disarming 11, landing 18, ...), so a reader can see what the autopilot itself
noticed beside what the detector says.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from tlm_process.detect.data import LogData
from tlm_process.detect.predict import Finding
from tlm_process.labels import class_name, label_colour, long_name

__all__ = ["SHOW_P", "plot_timeline"]

#: A class's probability line is drawn when it exceeds this somewhere in the log.
SHOW_P: float = 0.2


def plot_timeline(log: LogData, pred: pd.DataFrame, classes: Sequence[int],
                  findings: Sequence[Finding], path: str | Path, title: str = "") -> Path:
    """Write the timeline of ``log`` (predictions ``pred`` of :func:`.predict.predict_rows`,
    reported ``findings``) to ``path`` (PNG); returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = pred["TimeUS"].to_numpy(np.float64) * 1e-6
    fig, (ax, marks) = plt.subplots(2, 1, figsize=(12, 5.2), sharex=True,
                                    gridspec_kw={"height_ratios": [3.2, 1.0]})
    for w in log.windows or []:
        end = w.end_us * 1e-6 if np.isfinite(w.end_us) else (t[-1] if len(t) else 0.0)
        ax.axvspan(w.start_us * 1e-6, end, color=label_colour(w.label), alpha=0.15, lw=0)
        ax.text(w.start_us * 1e-6, 0.42, f" true: {long_name(w.label)}", fontsize=7,
                color=label_colour(w.label), va="bottom", ha="left",
                transform=ax.get_xaxis_transform())
    for c in classes:
        col = f"p_{class_name(int(c))}"
        if col not in pred.columns:
            continue
        p = pred[col].to_numpy()
        if int(c) != 0 and (not len(p) or p.max() < SHOW_P):
            continue
        ax.plot(t, p, lw=0.9 if c else 0.7, color=label_colour(int(c)),
                label=long_name(int(c)), alpha=1.0 if c else 0.6)
    for f in findings:
        ax.plot([f.start_s, f.end_s], [1.06, 1.06], color=label_colour(f.label), lw=5,
                solid_capstyle="butt", clip_on=False)
    ax.set_ylim(-0.02, 1.1)
    ax.set_ylabel("class probability")
    ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=8, frameon=False)
    ax.grid(alpha=0.3)
    ax.set_title(title or f"{log.id}: detector probabilities (bars: faults reported; "
                 "shaded: true fault windows)", fontsize=10)
    _marks(marks, log)
    marks.set_xlabel("log time [s since boot]")
    if len(t):
        marks.set_xlim(t[0], t[-1])
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def _marks(ax: object, log: LogData) -> None:
    """MODE, ERR and EV rows of the log as labelled ticks on three lanes."""
    from tlm_sim.flightlog.binreader import modes_with_names

    t0, t1 = (v * 1e-6 for v in log.span_us)
    lanes = {"MODE": 2, "ERR": 1, "EV": 0}
    mode = log.tables.get("MODE")
    if mode is not None and len(mode) and {"ModeNum", "Rsn"} <= set(mode.columns):
        named = modes_with_names(mode)
        for tm, name in zip(named["TimeUS"] * 1e-6, named["ModeName"], strict=True):
            _tick(ax, tm, lanes["MODE"], str(name), "tab:blue", t0, t1)
    err = log.tables.get("ERR")
    if err is not None and len(err):
        for tm, s, e in zip(err["TimeUS"] * 1e-6, err["Subsys"], err["ECode"], strict=True):
            _tick(ax, tm, lanes["ERR"], f"{int(s)}/{int(e)}", "tab:red", t0, t1)
    ev = log.tables.get("EV")
    if ev is not None and len(ev):
        for tm, i in zip(ev["TimeUS"] * 1e-6, ev["Id"], strict=True):
            _tick(ax, tm, lanes["EV"], str(int(i)), "0.3", t0, t1)
    ax.set_yticks(list(lanes.values()), list(lanes))  # type: ignore[attr-defined]
    ax.set_ylim(-0.6, 2.8)  # type: ignore[attr-defined]
    ax.grid(axis="x", alpha=0.3)  # type: ignore[attr-defined]


def _tick(ax: object, t: float, lane: int, text: str, colour: str, t0: float,
          t1: float) -> None:
    if not t0 - 1.0 <= t <= t1 + 1.0:
        return
    ax.plot([t, t], [lane - 0.3, lane + 0.3], color=colour, lw=1)  # type: ignore[attr-defined]
    ax.text(t, lane + 0.32, text, fontsize=6, color=colour, rotation=30,  # type: ignore
            ha="left", va="bottom")
