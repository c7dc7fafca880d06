"""A random fault judged by distribution: re-fly one SITL log with N tlm seeds (``tlm crosscheck
LOG --seeds N``).

GPS jamming (and any fault whose signature moves with the seed by more than its tolerance)
cannot be judged on one flight: SITL drew one outcome, tlm draws another. ``crosscheck_seeds``
flies the log's scenario with seeds ``first, first + 1, ...`` (:func:`~tlm_process.crosscheck.
compare.crosscheck` each) and reports per signature metric tlm's 10 / 50 / 90 % values (linear
percentiles over the seeds), its range (min..max) and SITL's value, and whether SITL's lies
inside tlm's range. Flight time and trajectory RMS are summarised the same way.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["DEFAULT_FIRST_SEED", "crosscheck_seeds", "distribution_rows", "format_seeds_report",
           "plot_seeds"]

#: first tlm seed of ``--seeds`` when ``--seed`` is not given
DEFAULT_FIRST_SEED = 1


def distribution_rows(values: Mapping[str, list[float]],
                      sitl: Mapping[str, float]) -> list[dict[str, Any]]:
    """One row per SITL metric: ``metric``, ``n`` (seeds with a value), ``p10`` / ``p50`` /
    ``p90`` and ``min`` / ``max`` of tlm's values, ``sitl`` and ``inside`` (SITL's value within
    tlm's min..max; NaN-aware: a NaN SITL value is inside when some seed gave NaN too)."""
    rows = []
    for k, b in sitl.items():
        v = np.asarray(values.get(k, []), float)
        finite = v[np.isfinite(v)]
        b = float(b) if b is not None else math.nan
        if finite.size:
            p10, p50, p90 = (float(x) for x in np.percentile(finite, [10, 50, 90]))
            lo, hi = float(finite.min()), float(finite.max())
        else:
            p10 = p50 = p90 = lo = hi = math.nan
        if math.isnan(b):
            inside = bool((~np.isfinite(v)).any())
        else:
            inside = bool(finite.size) and lo <= b <= hi
        rows.append({"metric": k, "n": int(finite.size), "p10": p10, "p50": p50, "p90": p90,
                     "min": lo, "max": hi, "sitl": b, "inside": inside})
    return rows


def crosscheck_seeds(bin_path: str | Path, sidecar: str | Path | None = None, seeds: int = 8,
                     first_seed: int = DEFAULT_FIRST_SEED,
                     params: Mapping[str, float] | None = None,
                     progress: Callable[[int], None] | None = None) -> dict[str, Any]:
    """Cross-check one SITL log over ``seeds`` tlm seeds (``first_seed`` on).

    Returns ``{"scenario", "seeds", "faults": [{"type", "label", "rows", "values"}],
    "flight_time_s": {"values", "sitl"}, "trajectory_rms_m": {"values"}}``; ``rows`` are
    :func:`distribution_rows`, ``values`` tlm's value per metric and seed. ``progress`` is
    called with the number of flights flown after each."""
    from tlm_process.crosscheck.compare import crosscheck

    if seeds < 1:
        raise ValueError(f"seeds must be at least 1 (got {seeds})")
    runs = []
    for i in range(seeds):
        r = crosscheck(bin_path, sidecar, first_seed + i, params=params)
        r.pop("_log", None)
        r.pop("_series", None)
        runs.append(r)
        if progress is not None:
            progress(i + 1)
    first = runs[0]
    faults = []
    for j, f in enumerate(first["faults"]):
        values: dict[str, list[float]] = {k: [] for k in f["sitl"]}
        for r in runs:
            tlm = r["faults"][j]["tlm"] if j < len(r["faults"]) else {}
            for k in values:
                values[k].append(float(tlm.get(k, math.nan)))
        faults.append({"type": f["type"], "label": f.get("label"),
                       "rows": distribution_rows(values, f["sitl"]), "values": values})
    return {
        "scenario": {k: first["scenario"][k] for k in ("log", "name", "source", "waypoints")
                     if k in first["scenario"]},
        "seeds": [first_seed + i for i in range(seeds)],
        "faults": faults,
        "flight_time_s": {"values": [r["flight_time_s"]["tlm"] for r in runs],
                          "sitl": first["flight_time_s"]["sitl"]},
        "trajectory_rms_m": {"values": [r["trajectory_rms_m"] for r in runs]},
    }


def format_seeds_report(d: dict[str, Any]) -> str:
    """Markdown report of :func:`crosscheck_seeds`."""
    from tlm_process.crosscheck.compare import cell as _c

    sd = d["seeds"]
    ft = np.asarray(d["flight_time_s"]["values"], float)
    rms = np.asarray(d["trajectory_rms_m"]["values"], float)
    lines = [f"# Cross-check over seeds: {d['scenario'].get('name', '?')} (SITL) vs tlm", "",
             f"tlm flew the log's scenario with {len(sd)} seeds ({sd[0]}..{sd[-1]}); per metric "
             "tlm's 10 / 50 / 90 % values and range over the seeds beside SITL's one flight. "
             "*inside*: SITL's value lies within tlm's range.", "",
             f"* flight time: tlm {ft.min():.1f}..{ft.max():.1f} s (median "
             f"{np.median(ft):.1f}), SITL {d['flight_time_s']['sitl']:.1f} s",
             f"* trajectory RMS outside the fault windows: median {np.median(rms):.2f} m "
             f"(max {rms.max():.2f} m)"]
    for f in d["faults"]:
        lines += ["", f"## Fault: {f['type']} (label {f['label']})", "",
                  "| signature | tlm 10 % | tlm 50 % | tlm 90 % | tlm range | SITL | inside |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| {x['metric']} | {_c(x['p10'])} | {_c(x['p50'])} | {_c(x['p90'])} | "
                  f"{_c(x['min'])}..{_c(x['max'])} | {_c(x['sitl'])} | "
                  f"{'yes' if x['inside'] else '**no**'} |" for x in f["rows"]]
    lines += ["", "![distributions](seeds.png)", ""]
    return "\n".join(lines)


def plot_seeds(d: dict[str, Any], out: Path) -> Path:
    """``out/seeds.png``: per signature metric of the first fault, tlm's value per seed (dots,
    10-90 % band) and SITL's (red line)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [x for f in d["faults"][:1] for x in f["rows"] if x["n"]]
    values = d["faults"][0]["values"] if d["faults"] else {}
    n = max(len(rows), 1)
    cols = min(4, n)
    nrows = (n + cols - 1) // cols
    fig, axs = plt.subplots(nrows, cols, figsize=(3.2 * cols, 2.4 * nrows), squeeze=False)
    for ax in axs.flat[n:]:
        ax.set_visible(False)
    for ax, x in zip(axs.flat, rows, strict=False):
        v = np.asarray(values[x["metric"]], float)
        ax.axhspan(x["p10"], x["p90"], color="C0", alpha=0.15)
        ax.plot(np.arange(len(v)), v, "o", ms=4, color="C0", label="tlm seeds")
        if math.isfinite(x["sitl"]):
            ax.axhline(x["sitl"], color="C3", lw=1.5, label="SITL")
        ax.set_title(x["metric"], fontsize=9)
        ax.set_xticks([])
    if rows:
        axs.flat[0].legend(fontsize=7)
    fig.suptitle(f"{d['scenario'].get('name', '')}: tlm over {len(d['seeds'])} seeds vs SITL",
                 fontsize=10)
    fig.tight_layout()
    path = out / "seeds.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
