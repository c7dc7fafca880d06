"""ArduPilot DataFlash ``.bin`` logs: tables written out (``tlm convert``) and a summary (``tlm
info``); the commands themselves are :mod:`tlm_process.commands.convert` and ``.info``.

``convert(IN.bin, DIR, csv|parquet|log)``: one file per message type
(``DIR/GPS.csv``, ``DIR/IMU.parquet``, ... every message of that type, ArduPilot column names,
values as pymavlink and Mission Planner show them), or ``log``: Mission Planner's text log
``DIR/<stem>.log`` (the paper's "convert to text" step, §5.7). ``meta.json`` beside the tables
holds the log's parameters, so ``FlightLog.read(DIR)`` reads the folder back.

``log_info(LOG.bin)``: time span and armed time, firmware, every message type with its count,
instances and rate, the flight modes, the parameters changed in flight, and the faults found
(from SIM_* parameter changes, tlm's fault MSG lines, and a sidecar ``LOG.json`` or tlm fly's
``faults.json`` if present), each fault once with every source that shows it.
"""

from __future__ import annotations

import contextlib
import io
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd

    from tlm_sim.flightlog import BinLog, FlightLog

__all__ = ["CONVERT_FORMATS", "LogError", "check_types", "convert", "format_info", "log_info",
           "open_log", "write_tables"]

CONVERT_FORMATS = ("csv", "parquet", "log")

#: Parameters the autopilot rewrites by itself (statistics, mission bookkeeping, learned
#: values): left out of "parameters changed in flight" unless --all-params.
_HOUSEKEEPING = ("STAT_", "MIS_TOTAL", "BARO1_GND", "BARO2_GND", "BARO3_GND",
                 "MOT_THST_HOVER", "EK3_SRC1_POSXY")
ARMED, DISARMED = 10, 11


class LogError(Exception):
    """A log that cannot be used (reported by the CLI as one line)."""


def open_log(path: str | Path) -> tuple[BinLog, Iterator[tuple[str, pd.DataFrame]], list[str]]:
    """Index a log: (context, its tables one at a time, what was damaged: one line each).

    Raises:
        FileNotFoundError: no such file.
        LogError: not a regular file, not a DataFlash log, unreadable, or no messages.
    """
    from tlm_sim.flightlog.binreader import BinLogWarning, iter_log

    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(2, "no such log", str(p))
    try:
        with warnings.catch_warnings(record=True) as caught, \
                contextlib.redirect_stdout(io.StringIO()):
            warnings.simplefilter("always", BinLogWarning)
            log, tables = iter_log(p)
    except ValueError as e:  # BinLogError names the file
        raise LogError(str(e)) from None
    except OSError as e:
        raise LogError(f"{p}: cannot read: {e.strerror or e}") from None
    damage = []
    for w in caught:
        if issubclass(w.category, BinLogWarning):
            damage.append(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if not any(log.info["messages"].values()):
        raise LogError(f"{p}: not an ArduPilot DataFlash log (no messages found)")
    return log, tables, damage


def _usable(tables: dict[str, pd.DataFrame], name: str, cols: tuple[str, ...],
            path: Path, damage: list[str]) -> pd.DataFrame:
    """Table ``name`` if it has ``cols`` (a damaged FMT can rename them), else an empty one
    and a line in ``damage``; an empty one too when the log has no such table."""
    from tlm_sim.flightlog import SCHEMAS
    from tlm_sim.flightlog.binreader import empty_table

    df = tables.get(name)
    if df is None:
        return empty_table(SCHEMAS[name])
    missing = [c for c in cols if c not in df.columns]
    if missing:
        line = f"{path.name}: {name} has no {', '.join(missing)} column; ignored"
        if line not in damage:
            damage.append(line)
        return empty_table(SCHEMAS[name])
    return df


#: tables ``tlm info`` keeps (besides the context ``read_log`` gives) and the columns it uses
_INFO_TABLES: dict[str, tuple[str, ...]] = {
    "VER": ("FWS",), "EV": ("TimeUS", "Id"), "PARM": ("TimeUS", "Name", "Value"),
}


# --------------------------------------------------------------------------- info ----------
def _sidecar_faults(path: Path, info: dict[str, Any]) -> list[dict[str, Any]]:
    """Faults of the sidecar beside the log (``<log>.json``, or tlm fly's ``faults.json``:
    ``tlm_sim.flightlog.sidecar.fault_sidecar``); [] if none, or if it is not a fault
    sidecar (``info["sidecar_error"]`` then says why)."""
    from tlm_sim.flightlog.sidecar import fault_sidecar, read_sidecar_faults

    sidecar = fault_sidecar(path)
    if sidecar is None:
        return []
    try:
        faults = read_sidecar_faults(sidecar)
    except (ValueError, OSError) as exc:
        info["sidecar_error"] = (f"{sidecar}: {exc.strerror}" if isinstance(exc, OSError)
                                 and exc.strerror else str(exc))
        return []
    return [{**{k: f.get(k) for k in ("type", "label", "start_time_us", "end_time_us")},
             "source": "sidecar"} for f in faults]


#: two records of the same fault type starting this close are the same fault [us]
_SAME_FAULT_US = 1_000_000


def _merge_faults(*sources: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The fault records of every source (PARM changes, tlm's MSG lines, the sidecar), each
    fault once: a record of the same type as one already listed, starting within 1 s of it,
    adds its source to that one's ``source`` ("PARM, MSG, sidecar") instead of a line of its
    own; the first source's times are kept."""
    out: list[dict[str, Any]] = []
    for found in sources:
        for s in found:
            twin = next((f for f in out if f.get("type") == s.get("type")
                         and s["source"] not in f["source"].split(", ")
                         and f.get("start_time_us") is not None
                         and s.get("start_time_us") is not None
                         and abs(f["start_time_us"] - s["start_time_us"]) <= _SAME_FAULT_US),
                        None)
            if twin is None:
                out.append(dict(s))
            else:
                twin["source"] += f", {s['source']}"
    return out


def log_info(path: str | Path, *, all_params: bool = False) -> dict[str, Any]:
    """Everything ``tlm info`` reports, as plain JSON-able data (times in seconds).

    The tables are decoded one at a time (only VER, EV and PARM are kept), so memory stays
    near the file's size. Tables whose columns a damaged FMT renamed are ignored and named in
    ``damage``, with what the reader skipped; ``lost_messages`` counts the messages dropped.

    Raises:
        FileNotFoundError, LogError: as ``open_log``.
    """
    from tlm_sim.faults.detect import faults_from_messages, faults_from_param_changes
    from tlm_sim.flightlog.binreader import COPTER_MODES, MODE_REASONS, param_changes_from_parm
    from tlm_sim.flightlog.flightlog import table_summary

    p = Path(path)
    log, tables, damage = open_log(p)
    kept: dict[str, pd.DataFrame] = {}
    summaries: dict[str, dict[str, Any]] = {}
    t0 = t1 = None
    for name, df in tables:
        summaries[name], span = table_summary(df, log.schemas[name])
        if span is not None:
            t0 = span[0] if t0 is None else min(t0, span[0])
            t1 = span[1] if t1 is None else max(t1, span[1])
        if name in _INFO_TABLES:
            kept[name] = df
    info: dict[str, Any] = {
        "file": str(path),
        "size_bytes": log.info["size_bytes"],
        "time_span_s": [t0 * 1e-6, t1 * 1e-6] if t0 is not None else None,
        "duration_s": (t1 - t0) * 1e-6 if t0 is not None else 0.0,
    }
    msg = log.messages
    ver = _usable(kept, "VER", _INFO_TABLES["VER"], p, damage)
    info["firmware"] = (str(ver["FWS"].iloc[0]) if len(ver) else
                        next((m for m in msg["Message"] if "Copter" in str(m)), None))
    ev = _usable(kept, "EV", _INFO_TABLES["EV"], p, damage)
    armed = ev[ev.Id == ARMED].TimeUS
    disarmed = ev[ev.Id == DISARMED].TimeUS
    if len(armed):
        a = float(armed.iloc[0])
        d = float(disarmed[disarmed > a].iloc[-1]) if (disarmed > a).any() else None
        info["armed_s"] = [a * 1e-6, None if d is None else d * 1e-6]
        info["flight_time_s"] = None if d is None else (d - a) * 1e-6
    info["messages"] = {
        n: {"count": t["rows"], "instances": t.get("instances"), "rate_hz": t.get("rate_hz")}
        for n, t in sorted(summaries.items())
    }
    mode = log.modes
    info["modes"] = [
        {"time_s": int(t) * 1e-6, "mode": int(m),
         "name": COPTER_MODES.get(int(m), str(int(m))),
         "reason": MODE_REASONS.get(int(r), str(int(r)))}
        for t, m, r in zip(mode.TimeUS, mode.ModeNum, mode.Rsn, strict=True)
    ]
    changes = param_changes_from_parm(_usable(kept, "PARM", _INFO_TABLES["PARM"], p, damage),
                                      exclude=())
    shown = changes if all_params else changes[
        ~changes["Name"].astype(str).str.startswith(_HOUSEKEEPING)]
    info["params_changed"] = [
        {"time_s": int(t) * 1e-6, "name": str(n), "value": float(v)}
        for t, n, v in zip(shown.TimeUS, shown.Name, shown.Value, strict=True)
    ]
    info["params_changed_hidden"] = len(changes) - len(shown)
    info["faults"] = _merge_faults(faults_from_param_changes(changes),
                                   faults_from_messages(msg), _sidecar_faults(p, info))
    info["damage"] = damage
    info["lost_messages"] = log.info["lost_messages"]
    info["skipped_bytes"] = log.info["skipped_bytes"]
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
    if info.get("damage"):
        lines.append("damage (read as far as possible; the rest of this report is what "
                     "could be read)")
        lines += [f"  {d}" for d in info["damage"]]
        if info.get("lost_messages"):
            lost = ", ".join(f"{k} {v}" for k, v in info["lost_messages"].items())
            lines.append(f"  messages lost: {lost}")
    lines.append("faults found")
    if not info["faults"]:
        lines.append("  none")
    for f in info["faults"]:
        t0 = f.get("start_time_us")
        t1 = f.get("end_time_us")
        dur = "" if t0 is None or t1 is None else f" ({(t1 - t0) * 1e-6:.1f} s)"
        end = "s - end of log" if t1 is None else f"- {_fmt_s(t1 * 1e-6)} s"
        lines.append(f"  {f.get('type')} (label {f.get('label')}): "
                     f"{_fmt_s(None if t0 is None else t0 * 1e-6)} {end}{dur}  "
                     f"[{f['source']}]")
    return "\n".join(lines)


# ------------------------------------------------------------------------- convert ---------
def _flightlog(log: BinLog, tables: dict[str, pd.DataFrame]) -> FlightLog:
    """FlightLog of ``tables`` with the log's parameters, mission and reader info."""
    from tlm_sim.flightlog import FlightLog

    return FlightLog(tables, params=log.params, mission=log.mission,
                     schemas={n: log.schemas[n] for n in tables},
                     meta={"source": log.path, **log.info})


def check_types(log: BinLog, types: list[str] | None) -> list[str]:
    """The tables to convert: ``types`` (each must have messages in the log) or all."""
    present = [n for n, c in log.info["messages"].items() if c]
    if types:
        missing = [t for t in types if t not in present]
        if missing:
            raise LogError(f"--types: not in this log: {', '.join(missing)} "
                           f"(it has {', '.join(sorted(present))})")
    return list(types or present)


def convert(path: str | Path, out: Path, fmt: str,
            types: list[str] | None = None) -> tuple[list[Path], dict[str, int], list[str]]:
    """Write a log's tables to ``out`` as ``fmt`` (csv, parquet or log).

    csv/parquet tables are decoded, written and dropped one at a time (memory near the file's
    size); a table whose name is not a safe file name is skipped (``damage`` says so), never
    written outside ``out``.

    Returns:
        (files written, name → rows of each table written, damage: one line per problem).
    Raises:
        FileNotFoundError, LogError: as ``open_log``; LogError for ``types`` not in the log.
    """
    log, tables, damage = open_log(path)
    names = check_types(log, types)
    files, rows = write_tables(log, tables, names, out, fmt, Path(path).stem, damage)
    return files, rows, damage


def write_tables(log: BinLog, tables: Iterator[tuple[str, pd.DataFrame]], names: list[str],
                 out: Path, fmt: str, stem: str, damage: list[str]
                 ) -> tuple[list[Path], dict[str, int]]:
    """Write tables ``names`` (in that order in meta.json) of ``tables`` to ``out`` as ``fmt``;
    what ``convert`` does once the log is open. Returns (files written, rows per table)."""
    from tlm_sim.flightlog.flightlog import is_safe_table_name, write_table
    from tlm_sim.flightlog.mplog import write_mp_log

    wanted = set(names)
    if fmt == "log":
        keep = {n: df for n, df in tables if n in wanted}
        keep = {n: keep[n] for n in names if n in keep}
        path = write_mp_log(_flightlog(log, keep), out / f"{stem}.log")
        return [path], {n: len(df) for n, df in keep.items()}
    files: list[Path] = []
    rows: dict[str, int] = {}
    for n, df in tables:
        if n not in wanted:
            continue
        if not is_safe_table_name(n):
            damage.append(f"skipped table {n!r}: not a safe file name")
            continue
        files += write_table(out, n, df, log.schemas[n], [fmt])
        rows[n] = len(df)
    rows = {n: rows[n] for n in names if n in rows}
    files.append(_flightlog(log, {}).write_meta(out, rows, log.schemas))
    return files, rows
