"""One-screen flight summaries and the trajectory plot used by ``tlm fly`` and ``tlm demo``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from tlm_sim import ardupilot as AP
from tlm_sim.flightlog import FlightLog
from tlm_sim.geo import latlon_to_ne

#: What each ``meta["end_reason"]`` (tlm_sim.flight.END_REASONS) means, for the summary.
END_REASON_TEXT = {"landed": "landed and disarmed",
                   "crash": "the crash check disarmed it",
                   "time_cap": "still armed at the time cap: the flight was cut off",
                   "not_armed": "never armed: the pre-arm checks failed until the driver gave "
                                "up"}


def flight_summary(log: FlightLog) -> dict[str, Any]:
    """Duration, distance flown (true path), waypoints reached, final mode, row counts."""
    meta = log.meta or {}
    sim = log.tables.get("SIM")
    dist = 0.0
    max_alt = 0.0
    if sim is not None and len(sim) > 1:
        n, e = latlon_to_ne(sim["Lat"].to_numpy(float), sim["Lng"].to_numpy(float),
                            float(sim["Lat"].iloc[0]), float(sim["Lng"].iloc[0]))
        dist = float(np.sum(np.hypot(np.diff(n), np.diff(e))))
        max_alt = float(sim["Alt"].max() - sim["Alt"].iloc[0])
    final_mode = int(meta.get("final_mode", -1))
    return {
        "duration_s": round(float(meta.get("duration_s", 0.0)), 1),
        "armed_s": None if meta.get("armed_s") is None else round(meta["armed_s"], 1),
        "disarmed_s": None if meta.get("disarmed_s") is None else round(meta["disarmed_s"], 1),
        "distance_m": round(dist, 1),
        "max_alt_m": round(max_alt, 1),
        "waypoints_reached": ("none: flown by a pilot's sticks" if meta.get("mission") == "pilot"
                              else f"{meta.get('waypoints_reached', '?')}/"
                                   f"{meta.get('n_waypoints', '?')}"),
        "final_mode": f"{AP.MODE_NAMES.get(final_mode, final_mode)} ({final_mode})",
        "landed": meta.get("landed"),
        "end_reason": meta.get("end_reason"),
        "arm_failures": last_arm_failures(meta),
        "earth_field": meta.get("earth_field"),
        "rows": {k: len(v) for k, v in log.tables.items()},
    }


def last_arm_failures(meta: dict[str, Any]) -> list[str]:
    """The "Arm: ..." lines of a flight's last failed arm attempt when it never armed (why it
    did not fly), else []."""
    if meta.get("armed_s") is not None or not meta.get("texts"):
        return []
    from tlm_sim.flightlog.texts import logged_texts

    arm = [(t, s) for t, s in logged_texts(meta["texts"]) if s.startswith("Arm: ")]
    return [s for t, s in arm if t == arm[-1][0]] if arm else []


def format_summary(s: dict[str, Any]) -> str:
    """Human-readable lines of a flight summary."""
    rows = ", ".join(f"{k} {v}" for k, v in s["rows"].items() if k in
                     ("GPS", "IMU", "RATE", "VIBE", "ATT", "MODE", "EV", "ERR"))
    return "\n".join([
        f"duration           {s['duration_s']} s (armed {s['armed_s']} s -> "
        + (f"disarmed {s['disarmed_s']} s)" if s['disarmed_s'] is not None
           else "never disarmed)"),
        f"distance flown     {s['distance_m']} m, max altitude {s['max_alt_m']} m",
        f"waypoints reached  {s['waypoints_reached']}",
        f"final mode         {s['final_mode']}, landed {s['landed']}",
        f"end reason         {s.get('end_reason')} "
        f"({END_REASON_TEXT.get(str(s.get('end_reason')), 'unknown')}"
        + (f"; last attempt: {', '.join(s['arm_failures'])}" if s.get("arm_failures") else "")
        + ")",
        *([_earth_field_line(s["earth_field"])] if s.get("earth_field") else []),
        f"rows               {rows}",
    ])


def _earth_field_line(f: dict[str, Any]) -> str:
    """The summary line of a flight's earth field (``meta["earth_field"]``)."""
    return (f"earth field        declination {f['declination_deg']:.2f} deg, inclination "
            f"{f['inclination_deg']:.2f} deg, {f['intensity_gauss']:.4f} gauss: {f['source']}")


def fault_windows_s(log: FlightLog) -> list[tuple[int, str, int, float, float]]:
    """The flight's fault windows for the plots: (number counted from 1, type, label, start,
    end [s since boot]); a fault without an end runs to the end of the log."""
    sim = log.tables.get("SIM")
    t_end = float(sim["TimeUS"].iloc[-1]) * 1e-6 if sim is not None and len(sim) else None
    out = []
    for k, f in enumerate(log.faults):
        t0, t1 = f.get("start_time_us"), f.get("end_time_us")
        if t0 is None:
            continue
        end = t1 * 1e-6 if t1 is not None else t_end
        if end is not None:
            out.append((k + 1, str(f.get("type")), int(f.get("label") or 0), t0 * 1e-6, end))
    return out


def plot_trajectory(log: FlightLog, path: Path, title: str = "") -> Path:
    """Top view of the true path (SIM) over the mission waypoints, and altitude over time; each
    fault's window (start to end, or to the end of the log) shaded on the altitude plot and its
    stretch of the path drawn in its label's colour, labelled "fault N: TYPE" (N from 1)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tlm_process.labels import label_colour

    sim = log.tables["SIM"]
    home_lat, home_lon = float(sim["Lat"].iloc[0]), float(sim["Lng"].iloc[0])
    n, e = latlon_to_ne(sim["Lat"].to_numpy(float), sim["Lng"].to_numpy(float), home_lat, home_lon)
    t = sim["TimeUS"].to_numpy(float) * 1e-6
    windows = fault_windows_s(log)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    if log.mission is not None:
        wp = np.asarray(log.mission.waypoints)
        wn, we = latlon_to_ne(wp[:, 0], wp[:, 1], home_lat, home_lon)
        ax1.plot(we, wn, "o", ms=3, color="0.6", label="waypoints")
    ax1.plot(e, n, lw=1.2, color="k", label="true path (SIM)")
    for k, ftype, label, a, b in windows:
        m = (t >= a) & (t <= b)
        ax1.plot(e[m], n[m], lw=2.4, color=label_colour(label), label=f"fault {k}: {ftype}")
    ax1.plot([0], [0], "k^", label="home")
    ax1.set_xlabel("east [m]")
    ax1.set_ylabel("north [m]")
    ax1.set_aspect("equal")
    ax1.legend(loc="best", fontsize=8)
    ax2.plot(t, sim["Alt"].to_numpy(float) - sim["Alt"].iloc[0], color="k",
             label="true altitude")
    if "CTUN" in log.tables:
        ct = log.tables["CTUN"]
        ax2.plot(ct["TimeUS"] * 1e-6, ct["DAlt"], "--", lw=0.8, color="0.45",
                 label="desired altitude")
    for k, ftype, label, a, b in windows:
        ax2.axvspan(a, b, color=label_colour(label), alpha=0.2, lw=0,
                    label=f"fault {k}: {ftype} (label {label})")
        ax2.annotate(f"{k}: {ftype}", (a, 1.0), xycoords=("data", "axes fraction"),
                     xytext=(2, -2), textcoords="offset points", va="top", fontsize=8)
    ax2.set_xlabel("time since boot [s]")
    ax2.set_ylabel("altitude above home [m]")
    ax2.legend(loc="best", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
