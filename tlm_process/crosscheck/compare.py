"""Fly a SITL log's scenario in tlm and report how far apart they are (``tlm crosscheck``,
:mod:`tlm_process.commands.crosscheck`).

``crosscheck(bin, sidecar)`` rebuilds the scenario (``scenario.reconstruct``), flies it, and
compares (``metrics.crosscheck_metrics``); ``format_report`` and ``plot`` make ``report.md``
and its overlay plots (trajectory, altitude and speed, IMU spectrum), ``to_json`` the JSON
document, and ``gate`` the threshold violations of a regression gate. ``checks`` are issue
19's targets for every reference flight: flight time within 10 %, trajectory RMS outside the
fault windows within 5 m, each fault-signature metric within 35 % of SITL's
(``metrics.signature_rows``). ``r["messages"]`` compares the two ``.bin`` files' message types
and flight-text kinds (:mod:`tlm_process.crosscheck.messages`, the report's "Messages and
flight text").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["DEFAULT_MAX_FLIGHT_TIME_DIFF", "DEFAULT_MAX_TRAJECTORY_RMS_M",
           "CHECK_MAX_FLIGHT_TIME_DIFF", "CHECK_MAX_TRAJECTORY_RMS_M", "checks", "crosscheck",
           "format_report", "gate", "cell", "plot", "signature_rows", "to_json"]

#: Issue 8's targets: flight time within 10 %, trajectory RMS <= 3 m (normal and combined).
DEFAULT_MAX_FLIGHT_TIME_DIFF = 0.10
DEFAULT_MAX_TRAJECTORY_RMS_M = 3.0
#: Issue 19's targets on every reference flight (the report's pass/fail lines).
CHECK_MAX_FLIGHT_TIME_DIFF = 0.10
CHECK_MAX_TRAJECTORY_RMS_M = 5.0


def signature_rows(tlm: dict[str, float], sitl: dict[str, float],
                   rel_tol: float | None = None) -> list[dict[str, Any]]:
    """:func:`tlm_process.crosscheck.metrics.signature_rows` (imported when first used)."""
    from tlm_process.crosscheck import metrics

    return metrics.signature_rows(tlm, sitl, metrics.SIGNATURE_REL_TOL if rel_tol is None
                                  else rel_tol)


def crosscheck(bin_path: str | Path, sidecar: str | Path | None = None,
               seed: int | None = None,
               params: Mapping[str, float] | None = None) -> dict[str, Any]:
    """Cross-check one SITL log: returns the metrics dict (with ``scenario`` information).

    ``params``: ArduPilot parameters tlm flies on top of the log's (e.g. ``{"FRAME_TYPE": 1}``
    or a wind): the SITL flight's mission and faults on another frame or in other weather,
    compared with the SITL flight as it was (``scenario["overrides"]`` records them)."""
    from tlm_process.crosscheck.messages import compare_messages, sitl_message_types
    from tlm_process.crosscheck.metrics import crosscheck_metrics
    from tlm_process.crosscheck.scenario import reconstruct
    from tlm_sim import fly
    from tlm_sim.flightlog.binwriter import message_types, msg_table

    sc = reconstruct(bin_path, sidecar, seed)
    flown = sc.params.updated(dict(params)) if params else sc.params
    log = fly(sc.mission, faults=sc.fly_faults, params=flown, seed=sc.seed)
    route = sc.mission.waypoints[:, :2]
    r = crosscheck_metrics(log.tables, sc.tables, sc.mission.home,
                           sc.tlm_fault_records(log.faults), sc.faults, route)
    r["checks"] = checks(r)
    sitl_msg = sc.tables.get("MSG")
    r["messages"] = compare_messages(
        message_types(log), sitl_message_types(bin_path), msg_table(log)["Message"],
        [] if sitl_msg is None else sitl_msg["Message"])
    r["_log"] = log
    r["scenario"] = {
        "log": str(bin_path), "name": sc.name, "source": sc.source, "seed": sc.seed,
        "waypoints": int(sc.mission.n_waypoints), "params_from_log": sc.params.changed(),
        "unmodelled_params": sc.params.unmodelled(),
        "faults": [{k: f.get(k) for k in ("type", "label", "start_time_us", "end_time_us")}
                   for f in sc.faults],
        "sitl_arm_s": sc.sitl_arm_us * 1e-6, "tlm_arm_s": sc.tlm_arm_s,
        "flown_as": "schedule" if sc.schedule is not None else (
            "parameter changes" if sc.changes else "no faults"),
        "notes": list(sc.notes),
        "overrides": {k: float(v) for k, v in (params or {}).items()},
    }
    return r


def checks(r: dict[str, Any]) -> dict[str, Any]:
    """Issue 19's pass/fail per reference flight: ``flight_time`` (relative difference,
    limit 10 %), ``trajectory_rms`` (m outside the fault windows, limit 5 m) and
    ``signatures`` (metrics within 35 %, counted over every fault), each ``{value, limit,
    pass}``; ``pass`` for all three."""
    ft = r["flight_time_s"]
    rel = abs(ft["tlm"] - ft["sitl"]) / ft["sitl"] if ft["sitl"] else math.nan
    rms = r["trajectory_rms_m"]
    passed = sum(f.get("passed", 0) for f in r["faults"])
    compared = sum(f.get("compared", 0) for f in r["faults"])
    out = {
        "flight_time": {"value": rel, "limit": CHECK_MAX_FLIGHT_TIME_DIFF,
                        "pass": bool(rel <= CHECK_MAX_FLIGHT_TIME_DIFF)},
        "trajectory_rms": {"value": rms, "limit": CHECK_MAX_TRAJECTORY_RMS_M,
                           "pass": bool(rms <= CHECK_MAX_TRAJECTORY_RMS_M)},
        "signatures": {"value": f"{passed}/{compared}", "limit": 0.35,
                       "pass": passed == compared},
    }
    out["pass"] = all(v["pass"] for v in out.values())
    return out


def gate(r: dict[str, Any], max_ft: float | None, max_rms: float | None) -> list[str]:
    """Threshold violations (empty when within)."""
    bad = []
    ft = r["flight_time_s"]
    rel = abs(ft["tlm"] - ft["sitl"]) / ft["sitl"]
    if max_ft is not None and rel > max_ft:
        bad.append(f"flight time differs by {rel:.1%} (> {max_ft:.0%})")
    if max_rms is not None and not r["trajectory_rms_m"] <= max_rms:
        bad.append(f"trajectory RMS {r['trajectory_rms_m']:.2f} m (> {max_rms:g} m)")
    return bad


def cell(v: Any) -> str:
    """A metric as a report cell: 4 significant digits, ``-`` for None or NaN."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _pct(v: Any) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{100 * v:.0f} %"


def _verdict(ok: bool) -> str:
    return "pass" if ok else "**FAIL**"


def format_report(r: dict[str, Any]) -> str:
    """Markdown report of one cross-check."""
    sc = r["scenario"]
    lines = [f"# Cross-check: {sc['name']} (SITL) vs tlm", "",
             f"Scenario from the {sc['source']} ({sc['waypoints']} waypoints, seed {sc['seed']}, "
             f"{len(sc['faults'])} faults); aligned at arming (SITL {sc['sitl_arm_s']:.1f} s, "
             f"tlm {sc['tlm_arm_s']:.1f} s after boot).", "",
             f"* trajectory RMS (path-based, outside fault windows): "
             f"**{r['trajectory_rms_m']:.2f} m** (max {r['trajectory_max_m']:.1f} m); "
             f"{r['trajectory_rms_settled_m']:.2f} m also leaving out 30 s after each fault",
             f"* altitude RMS {r['altitude_rms_m']:.2f} m, ground-speed RMS "
             f"{r['speed_rms_ms']:.2f} m/s (same time since arming, outside faults)", "",
             "| metric | tlm | SITL | tlm - SITL |", "|---|---|---|---|"]
    for k, v in r.items():
        if isinstance(v, dict) and set(v) == {"tlm", "sitl"}:
            d = (v["tlm"] - v["sitl"]) if all(isinstance(x, float | int) for x in v.values()) \
                else None
            lines.append(f"| {k} | {cell(v['tlm'])} | {cell(v['sitl'])} | {cell(d)} |")
    if "checks" in r:
        lines += ["", "## Checks (issue 19)", "", "| check | value | limit | result |",
                  "|---|---|---|---|"]
        c = r["checks"]
        lines += [
            f"| flight time | {100 * c['flight_time']['value']:.2f} % | 10 % | "
            f"{_verdict(c['flight_time']['pass'])} |",
            f"| trajectory RMS outside the fault windows | {c['trajectory_rms']['value']:.2f} m "
            f"| 5 m | {_verdict(c['trajectory_rms']['pass'])} |",
            f"| signature metrics within 35 % | {c['signatures']['value']} | all | "
            f"{_verdict(c['signatures']['pass'])} |"]
    for note in sc.get("notes") or ():
        lines += ["", f"Note: {note}."]
    if "messages" in r:
        from tlm_process.crosscheck.messages import format_messages

        lines += format_messages(r["messages"])
    for f in r["faults"]:
        lines += ["", f"## Fault: {f['type']} (label {f['label']})", ""]
        rows = f.get("rows") or signature_rows(f["tlm"], f["sitl"])
        if not rows:
            lines.append("No signature for this fault type (flown as its parameter changes).")
            continue
        lines += ["| signature | tlm | SITL | rel. diff | within 35 % |", "|---|---|---|---|---|"]
        lines += [f"| {x['metric']} | {cell(x['tlm'])} | {cell(x['sitl'])} | "
                  f"{_pct(x['rel_diff'])} | {_verdict(x['pass'])} |" for x in rows]
    lines += ["", "![trajectory](trajectory.png)", "", "![profiles](profiles.png)", "",
              "![IMU spectrum](imu_psd.png)", ""]
    return "\n".join(lines)


def plot(r: dict[str, Any], out: Path) -> list[Path]:
    """Overlay PNGs: trajectory (north/east), altitude and speed vs time, IMU0 AccZ spectrum."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = r["_series"]
    files = []
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot(s["sitl_ne"][:, 1], s["sitl_ne"][:, 0], lw=2.5, alpha=0.5, label="SITL truth")
    ax.plot(s["tlm_ne"][:, 1], s["tlm_ne"][:, 0], lw=1, label="tlm truth")
    ax.set(xlabel="east [m]", ylabel="north [m]", aspect="equal",
           title=f"{r['scenario']['name']}: trajectory RMS {r['trajectory_rms_m']:.2f} m")
    ax.legend()
    files.append(out / "trajectory.png")
    fig.savefig(files[-1], dpi=110, bbox_inches="tight")
    plt.close(fig)
    fig, axs = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    for ax, key, lab in ((axs[0], "alt", "altitude above home [m]"),
                         (axs[1], "spd", "ground speed [m/s]")):
        ax.plot(s["grid"], s[key][1], lw=2, alpha=0.5, label="SITL")
        ax.plot(s["grid"], s[key][0], lw=1, label="tlm")
        for a, b in s["tlm_windows"]:
            ax.axvspan(a, b, color="red", alpha=0.1)
        ax.set_ylabel(lab)
    axs[1].set_xlabel("time since arming [s] (tlm fault windows shaded)")
    axs[0].legend()
    files.append(out / "profiles.png")
    fig.savefig(files[-1], dpi=110, bbox_inches="tight")
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4))
    for psd, lab in zip(s["psd"], ("tlm", "SITL"), strict=True):
        if psd is not None:
            ax.semilogy(psd[0], psd[1], label=lab)
    ax.set(xlabel="frequency [Hz]", ylabel="PSD of IMU0 AccZ [(m/s/s)^2/Hz]",
           title="IMU0 vertical acceleration in cruise (25 Hz log)")
    ax.legend()
    files.append(out / "imu_psd.png")
    fig.savefig(files[-1], dpi=110, bbox_inches="tight")
    plt.close(fig)
    return files


def to_json(r: dict[str, Any]) -> dict[str, Any]:
    """The JSON-able part of a cross-check result (no plot series; NaN as null)."""
    def clean(v: Any) -> Any:
        if isinstance(v, float):
            return None if math.isnan(v) else v
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        if isinstance(v, list | tuple):
            return [clean(x) for x in v]
        return v

    return clean({k: v for k, v in r.items() if not k.startswith("_")})
