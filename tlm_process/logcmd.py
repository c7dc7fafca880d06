"""``tlm convert`` and ``tlm info``: ArduPilot DataFlash ``.bin`` logs to tables, and a summary.

``tlm convert IN.bin --out DIR --format csv|parquet|log``: one file per message type
(``DIR/GPS.csv``, ``DIR/IMU.parquet``, ... every message of that type, ArduPilot column names,
values as pymavlink and Mission Planner show them), or ``log``: Mission Planner's text log
``DIR/<stem>.log`` (the paper's "convert to text" step, §5.7). ``meta.json`` beside the tables
holds the log's parameters, so ``FlightLog.read(DIR)`` reads the folder back.

``tlm info LOG.bin``: time span and armed time, firmware, every message type with its count,
instances and rate, the flight modes, the parameters changed in flight, and the faults found
(from SIM_* parameter changes, tlm's fault MSG lines, and a sidecar ``LOG.json`` if present).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from tlm_sim.flightlog import FlightLog

CONVERT_FORMATS = ("csv", "parquet", "log")

#: Parameters the autopilot rewrites by itself (statistics, mission bookkeeping, learned
#: values): left out of "parameters changed in flight" unless --all-params.
_HOUSEKEEPING = ("STAT_", "MIS_TOTAL", "BARO1_GND", "BARO2_GND", "BARO3_GND",
                 "MOT_THST_HOVER", "EK3_SRC1_POSXY")
ARMED, DISARMED = 10, 11


class LogError(Exception):
    """A log that cannot be used (reported by the CLI as one line)."""


def _load(path: str) -> FlightLog:
    from tlm_sim.flightlog import FlightLog

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(2, "no such log", str(p))
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # pymavlink prints while indexing
            log = FlightLog.from_bin(p)
    except (ValueError, OSError) as e:
        raise LogError(f"{p}: cannot read as an ArduPilot DataFlash log: {e}") from None
    if not log.tables:
        raise LogError(f"{p}: not an ArduPilot DataFlash log (no messages found)")
    return log


# --------------------------------------------------------------------------- info ----------
def log_info(log: FlightLog, path: str | Path, *, all_params: bool = False) -> dict[str, Any]:
    """Everything ``tlm info`` reports, as plain JSON-able data (times in seconds)."""
    from tlm_sim.faults.detect import faults_from_param_changes
    from tlm_sim.flightlog.binreader import COPTER_MODES, MODE_REASONS, param_changes_from_parm

    s = log.summary()
    t0, t1 = s["time_us"]
    info: dict[str, Any] = {
        "file": str(path),
        "size_bytes": Path(path).stat().st_size,
        "time_span_s": [t0 * 1e-6, t1 * 1e-6] if t0 is not None else None,
        "duration_s": s["duration_s"],
    }
    msg = log.table("MSG")
    ver = log.table("VER")
    info["firmware"] = (str(ver["FWS"].iloc[0]) if len(ver) else
                        next((m for m in msg["Message"] if "Copter" in str(m)), None))
    ev = log.table("EV")
    armed = ev[ev.Id == ARMED].TimeUS
    disarmed = ev[ev.Id == DISARMED].TimeUS
    if len(armed):
        a = float(armed.iloc[0])
        d = float(disarmed[disarmed > a].iloc[-1]) if (disarmed > a).any() else None
        info["armed_s"] = [a * 1e-6, None if d is None else d * 1e-6]
        info["flight_time_s"] = None if d is None else (d - a) * 1e-6
    info["messages"] = {
        n: {"count": t["rows"], "instances": t.get("instances"), "rate_hz": t.get("rate_hz")}
        for n, t in sorted(s["tables"].items())
    }
    mode = log.table("MODE")
    info["modes"] = [
        {"time_s": int(t) * 1e-6, "mode": int(m),
         "name": COPTER_MODES.get(int(m), str(int(m))),
         "reason": MODE_REASONS.get(int(r), str(int(r)))}
        for t, m, r in zip(mode.TimeUS, mode.ModeNum, mode.Rsn, strict=True)
    ]
    changes = param_changes_from_parm(log.table("PARM"), exclude=())
    shown = changes if all_params else changes[
        ~changes["Name"].astype(str).str.startswith(_HOUSEKEEPING)]
    info["params_changed"] = [
        {"time_s": int(t) * 1e-6, "name": str(n), "value": float(v)}
        for t, n, v in zip(shown.TimeUS, shown.Name, shown.Value, strict=True)
    ]
    info["params_changed_hidden"] = len(changes) - len(shown)
    faults = faults_from_param_changes(changes)
    for m, t in zip(msg["Message"], msg["TimeUS"], strict=True):
        if str(m).startswith("tlm: fault "):
            faults.append({"message": str(m), "time_us": int(t), "source": "MSG"})
    sidecar = Path(path).with_suffix(".json")
    if sidecar.is_file():
        try:
            doc = json.loads(sidecar.read_text(encoding="utf-8"))
            for f in doc.get("faults") or ():
                faults.append({**{k: f.get(k) for k in ("type", "label", "start_time_us",
                                                         "end_time_us")}, "source": "sidecar"})
        except (OSError, ValueError, AttributeError) as exc:  # ValueError: JSON or UTF-8
            why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            info["sidecar_error"] = f"{sidecar} is not a fault sidecar JSON ({why})"
    info["faults"] = faults
    return info


def _fmt_s(t: float | None) -> str:
    return "-" if t is None else f"{t:.2f}"


def format_info(info: dict[str, Any]) -> str:
    """``tlm info`` text from ``log_info``."""
    lines = [f"log                {info['file']} ({info['size_bytes'] / 1e6:.1f} MB)"]
    if info.get("firmware"):
        lines.append(f"firmware           {info['firmware']}")
    span = info.get("time_span_s")
    if span:
        lines.append(f"time span          {span[0]:.2f} - {span[1]:.2f} s "
                     f"({info['duration_s']:.1f} s)")
    if "armed_s" in info:
        a, d = info["armed_s"]
        ft = info.get("flight_time_s")
        lines.append(f"armed              {_fmt_s(a)} - {_fmt_s(d)} s"
                     + ("" if ft is None else f" ({ft:.1f} s)"))
    lines.append("messages           name   count  inst  rate/inst [Hz]")
    for n, m in info["messages"].items():
        rate = "" if m["rate_hz"] is None else f"{m['rate_hz']:.1f}"
        inst = "" if m["instances"] is None else str(m["instances"])
        lines.append(f"                   {n:<5} {m['count']:>7} {inst:>5}  {rate:>8}")
    lines.append("modes")
    for m in info["modes"]:
        lines.append(f"  {m['time_s']:9.2f} s  {m['name']} ({m['mode']}), reason {m['reason']}")
    hidden = info["params_changed_hidden"]
    lines.append("parameters changed in flight"
                 + (f" ({hidden} housekeeping changes hidden; --all-params)" if hidden else ""))
    for c in info["params_changed"]:
        lines.append(f"  {c['time_s']:9.2f} s  {c['name']} = {c['value']:g}")
    lines.append("faults found")
    if not info["faults"]:
        lines.append("  none")
    for f in info["faults"]:
        if f["source"] == "MSG":
            lines.append(f"  {f['time_us'] * 1e-6:9.2f} s  {f['message']}  [MSG]")
            continue
        t0 = f.get("start_time_us")
        t1 = f.get("end_time_us")
        dur = "" if t0 is None or t1 is None else f" ({(t1 - t0) * 1e-6:.1f} s)"
        lines.append(f"  {f.get('type')} (label {f.get('label')}): "
                     f"{_fmt_s(None if t0 is None else t0 * 1e-6)} - "
                     f"{'end of log' if t1 is None else _fmt_s(t1 * 1e-6)} s{dur}  "
                     f"[{f['source']}]")
    return "\n".join(lines)


def cmd_info(args: argparse.Namespace) -> int:
    """Print the summary of one .bin log (and optionally write it as JSON)."""
    log = _load(args.log)
    info = log_info(log, args.log, all_params=args.all_params)
    print(format_info(info))
    if args.json:
        Path(args.json).write_text(json.dumps(info, indent=1) + "\n")
    return 0


# ------------------------------------------------------------------------- convert ---------
def convert(log: FlightLog, out: Path, fmt: str, stem: str,
            types: list[str] | None = None) -> list[Path]:
    """Write ``log``'s tables to ``out`` as ``fmt`` (csv, parquet or log); returns the files."""
    from tlm_sim.flightlog.mplog import write_mp_log

    if types:
        missing = [t for t in types if t not in log.tables]
        if missing:
            raise LogError(f"--types: not in this log: {', '.join(missing)} "
                           f"(it has {', '.join(sorted(log.tables))})")
        log = type(log)({n: log.tables[n] for n in types}, params=log.params,
                        schemas={n: log.schemas[n] for n in types}, meta=log.meta)
    if fmt == "log":
        return [write_mp_log(log, out / f"{stem}.log")]
    log.write(out, formats=[fmt])
    return [out / f"{n}.{fmt}" for n in log.tables] + [out / "meta.json"]


def cmd_convert(args: argparse.Namespace) -> int:
    """Convert one .bin log to per-message CSV/Parquet files or a Mission Planner text log."""
    from tlm_process.cli import UsageError, _prepare_out

    fmt = args.format.lower()
    if fmt not in CONVERT_FORMATS:
        raise UsageError(f"--format: {args.format!r}; choose one of {', '.join(CONVERT_FORMATS)}")
    types = [t.strip().upper() for t in args.types.split(",") if t.strip()] if args.types else None
    log = _load(args.log)
    out = _prepare_out(args.out)
    files = convert(log, out, fmt, Path(args.log).stem, types)
    names = types or list(log.tables)
    rows = sum(len(log.tables[n]) for n in names)
    print(f"converted          {args.log} -> {out}/ ({len(files)} files, {fmt}, "
          f"{len(names)} message types, {rows} messages)")
    return 0


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Add ``convert`` and ``info`` to the ``tlm`` subcommands."""
    c = sub.add_parser(
        "convert", help="convert a DataFlash .bin log to CSV, Parquet or Mission Planner text",
        description="Convert an ArduPilot DataFlash .bin (SITL, a vehicle, or tlm's flight.bin) "
                    "to one file per message type: DIR/GPS.csv, DIR/IMU.csv, ... (every "
                    "message of that type; ArduPilot column names; lat/lon in degrees, "
                    "altitudes in metres, HDop 1.21, as pymavlink and Mission Planner show "
                    "them; instances as rows with their I/IMU/C column) plus meta.json, or "
                    "with --format log to Mission Planner's text log DIR/<name>.log.")
    c.add_argument("log", help="the .bin file")
    c.add_argument("--out", required=True, help="output folder")
    c.add_argument("--format", default="csv", metavar="csv|parquet|log",
                   help="csv (default), parquet, or log (Mission Planner text log)")
    c.add_argument("--types", metavar="GPS,IMU,...",
                   help="only these message types (default all)")
    c.set_defaults(func=cmd_convert)

    i = sub.add_parser(
        "info", help="summarise a DataFlash .bin log: messages, modes, changes, faults",
        description="Summarise an ArduPilot DataFlash .bin log: time span and armed time, "
                    "firmware, each message type's count, instances and rate, flight modes "
                    "with reasons, parameters changed in flight, and faults found (SIM_* "
                    "parameter changes, tlm fault MSG lines, a sidecar LOG.json).")
    i.add_argument("log", help="the .bin file")
    i.add_argument("--json", metavar="R.json", help="also write the summary as JSON")
    i.add_argument("--all-params", action="store_true",
                   help="list housekeeping parameter changes too (STAT_*, MIS_TOTAL, ...)")
    i.set_defaults(func=cmd_info)
