"""ArduPilot DataFlash logs: tables written out (``tlm convert``) and a summary (``tlm
info``); the commands themselves are :mod:`tlm_process.commands.convert` and ``.info``.

A 4.x ``.bin`` is streamed table by table. A DataFlash text ``.log`` or a ``.bin`` of older
firmware (Copter 3.x: rows stamped ``TimeMS``, ``IMU2``/``IMU3`` messages) is read whole and
normalised by :mod:`tlm_process.logread` (``TimeUS`` on every table, numbered instances folded
into ``I``); ``--format log`` is refused for those.

``convert(IN.bin, DIR, csv|parquet|log)``: one file per message type
(``DIR/GPS.csv``, ``DIR/IMU.parquet``, ... every message of that type, ArduPilot column names,
values as pymavlink and Mission Planner show them), or ``log``: Mission Planner's text log
``DIR/<stem>.log`` (the paper's "convert to text" step, §5.7). ``meta.json`` beside the tables
holds the log's parameters, so ``FlightLog.read(DIR)`` reads the folder back.

``log_info(LOG)``: time span and armed time (:func:`tlm_process.logread.arming_time_us`, with
the rule that found it), firmware, every message type with its count, instances and rate (for
messages logged regularly over at least 1 s), the flight modes, the parameters changed in
flight, and the faults found (from SIM_* parameter changes, tlm's fault MSG lines, and a
sidecar ``LOG.json`` or tlm fly's ``faults.json`` if present), each fault once with every
source that shows it.
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
    from tlm_sim.flightlog.schema import MessageSchema

__all__ = ["CONVERT_FORMATS", "LogError", "check_format", "check_types", "convert",
           "format_info", "log_info", "open_log", "write_tables"]

CONVERT_FORMATS = ("csv", "parquet", "log")

#: Parameters the autopilot rewrites by itself (statistics, mission bookkeeping, learned
#: values): left out of "parameters changed in flight" unless --all-params.
_HOUSEKEEPING = ("STAT_", "MIS_TOTAL", "BARO1_GND", "BARO2_GND", "BARO3_GND",
                 "MOT_THST_HOVER", "EK3_SRC1_POSXY")
ARMED, DISARMED = 10, 11
#: messages whose ``I`` column is the instance (4.x, and folded numbered instances)
_I_TABLES = ("IMU", "BARO", "MAG", "GPS", "GPA")


class LogError(Exception):
    """A log that cannot be used (reported by the CLI as one line)."""


def open_log(path: str | Path) -> tuple[BinLog, Iterator[tuple[str, pd.DataFrame]], list[str]]:
    """Index a log: (context, its tables one at a time, what was damaged: one line each).

    A 4.x ``.bin`` (every timed message has ``TimeUS``, instances in an instance column) is
    streamed as it is. A DataFlash text ``.log``, and a ``.bin`` of older firmware (rows
    stamped ``TimeMS``, numbered instances such as ``IMU2``), are read whole through
    :func:`tlm_process.logread.read_log_tables` and come back normalised: ``TimeUS`` on every
    table, ``IMU2``/``IMU3`` as ``IMU`` rows with ``I`` 1/2, and so on;
    ``context.info["notes"]`` says what was normalised.

    Raises:
        FileNotFoundError: no such file.
        LogError: not a regular file, not a DataFlash log, unreadable, or no messages.
    """
    from tlm_process.logread import is_text_log
    from tlm_sim.flightlog.binreader import BinLogWarning, iter_log

    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(2, "no such log", str(p))
    if p.is_file() and is_text_log(p):
        return _open_normalised(p)
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
    if _needs_normalising(log):
        return _open_normalised(p)
    log.info["notes"] = []
    return log, tables, damage


def _needs_normalising(log: BinLog) -> bool:
    """Whether a ``.bin`` is of older firmware: a message with rows is stamped ``TimeMS``
    without ``TimeUS``, or a numbered instance (``IMU2``, ``BAR2``, ...) has rows."""
    from tlm_process.logread import FOLDS

    present = [n for n, c in log.info["messages"].items() if c]
    return any(n in FOLDS or ("TimeMS" in log.schemas[n].columns
                              and "TimeUS" not in log.schemas[n].columns)
               for n in present if n in log.schemas)


def _open_normalised(p: Path) -> tuple[BinLog, Iterator[tuple[str, pd.DataFrame]], list[str]]:
    """``open_log`` of a text log or an old-firmware ``.bin``: the normalised tables of
    :func:`tlm_process.logread.read_log_tables` and a context built from them."""
    import pandas as pd

    from tlm_process.logread import LogReadError, read_log_tables
    from tlm_sim.flightlog import SCHEMAS, BinLog
    from tlm_sim.flightlog.binreader import (
        MISSION_FIELDS,
        empty_table,
        mission_from_cmd,
        modes_with_names,
        param_changes_from_parm,
    )

    try:
        lt = read_log_tables(p)
    except LogReadError as e:
        raise LogError(str(e)) from None
    except OSError as e:
        raise LogError(f"{p}: cannot read: {e.strerror or e}") from None
    tables = lt.tables
    damage = [n.removeprefix("damage: ") for n in lt.notes if n.startswith("damage: ")]
    notes = [n for n in lt.notes if not n.startswith("damage: ")]
    msg = tables.get("MSG")
    if msg is None or "Message" not in msg.columns:
        msg = empty_table(SCHEMAS["MSG"])
    mode = tables.get("MODE")
    if mode is not None and {"ModeNum", "Mode"} & set(mode.columns):
        num = mode["ModeNum" if "ModeNum" in mode.columns else "Mode"]
        rsn = mode["Rsn"] if "Rsn" in mode.columns else -1  # 3.x logs no reason
        mode = pd.DataFrame({"TimeUS": mode["TimeUS"],
                             "ModeNum": pd.to_numeric(num, errors="coerce").fillna(-1)
                             .astype("int64"), "Rsn": rsn})
    else:
        mode = pd.DataFrame({"TimeUS": pd.Series([], dtype="int64"),
                             "ModeNum": pd.Series([], dtype="int64"),
                             "Rsn": pd.Series([], dtype="int64")})
    parm = tables.get("PARM")
    changes = (param_changes_from_parm(parm) if parm is not None
               and {"Name", "Value"} <= set(parm.columns) else param_changes_from_parm(
                   empty_table(SCHEMAS["PARM"])))
    cmd = tables.get("CMD")
    mission = (mission_from_cmd(cmd) if cmd is not None
               and {"CTot", *MISSION_FIELDS} <= set(cmd.columns) else [])
    info = {
        "size_bytes": p.stat().st_size,
        "messages": {n: len(df) for n, df in tables.items()},
        "skipped_bytes": 0,
        "tail_bytes": 0,
        "lost_messages": {},
        "issues": damage,
        "cut_off": False,
        "notice": None,
        "notes": notes,
        "log_kind": lt.kind,
    }
    log = BinLog(str(p), {}, _normalised_schemas(tables), lt.params, changes, mission, msg,
                 modes_with_names(mode), info)
    return log, iter(list(tables.items())), damage


def _normalised_schemas(tables: dict[str, pd.DataFrame]) -> dict[str, MessageSchema]:
    """Schemas of normalised tables: each column's format character from the log's FMT
    (``TimeUS`` q, ``I`` B; a folded instance's columns from its own FMT), ``d`` for an
    integer column that holds NaN (a text log's damaged value), ``Z`` for text."""
    from tlm_process.logread import _INSTANCED, FOLDS
    from tlm_sim.flightlog.schema import FORMAT_CHARS, schema_from_fmt

    chars: dict[str, dict[str, str]] = {}
    fmt = tables.get("FMT")
    if fmt is not None and {"Name", "Format", "Columns"} <= set(fmt.columns):
        for name, f, cols in zip(fmt["Name"], fmt["Format"], fmt["Columns"], strict=True):
            cols = [c for c in str(cols).split(",") if c]
            base = FOLDS.get(str(name), (str(name), 0))[0]
            if len(cols) == len(str(f)):
                for c, ch in zip(cols, str(f), strict=True):
                    chars.setdefault(base, {}).setdefault(c, ch)
    out = {}
    for name, df in tables.items():
        known = chars.get(name, {})
        fmt_chars = []
        for c in df.columns:
            ch = "q" if c == "TimeUS" else "B" if c == "I" and name in _INSTANCED else \
                known.get(c)
            kind = df[c].dtype.kind
            if ch is None or ch not in FORMAT_CHARS:
                ch = "q" if kind in "iu" else "d" if kind == "f" else "Z"
            elif FORMAT_CHARS[ch].kind == "int" and kind not in "iu":
                ch = "d" if kind == "f" else "Z"
            elif FORMAT_CHARS[ch].kind in ("str", "array") and kind != "O":
                ch = "d" if kind == "f" else "q"
            elif FORMAT_CHARS[ch].kind == "array":
                ch = "Z"  # a text log's array: its text
            elif FORMAT_CHARS[ch].kind in ("float", "scaled") and kind == "O":
                ch = "Z"
            fmt_chars.append(ch)
        out[name] = schema_from_fmt(name, "".join(fmt_chars), tuple(df.columns))
    return out


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
    "ARM": ("TimeUS", "ArmState"), "RCOU": ("TimeUS",),
}
#: a message rate is given only for messages logged over a real time span: at least this many
#: rows per instance, spanning at least ``_RATE_MIN_SPAN_US``
_RATE_MIN_ROWS = 3
_RATE_MIN_SPAN_US = 1_000_000
#: ... and logged regularly: the median interval at least 1/4 of the mean one (events and
#: start-up bursts, FMTU as each type first appears, have no rate)
_IRREGULAR = 4


def _table_summary(df: pd.DataFrame, inst: str | None
                   ) -> tuple[dict[str, Any], tuple[int, int] | None]:
    """({count, instances, rate_hz, logged}, (first, last TimeUS) or None) of one table.

    ``rate_hz``: mean per-instance rate [Hz] over the instances logged at least
    ``_RATE_MIN_ROWS`` times over at least 1 s at regular intervals (median interval at least
    a quarter of the mean); None otherwise, and ``logged`` then says why: "once" (one row per
    instance), "at start" (a burst in the log's first second, as FMTU, UNIT, MULT and PARM
    are written at start-up), "burst" (a few rows close together) or "irregular" (events,
    mode changes, formats written as each type first appears)."""
    import numpy as np

    info: dict[str, Any] = {"count": len(df), "instances": None, "rate_hz": None,
                            "logged": None}
    if not len(df) or "TimeUS" not in df.columns:
        return info, None
    t = df["TimeUS"].to_numpy()
    groups = [t] if inst is None or inst not in df.columns else [
        g["TimeUS"].to_numpy() for _, g in df.groupby(inst, sort=True)]
    info["instances"] = len(groups)
    spread = [g for g in groups if len(g) >= _RATE_MIN_ROWS
              and g.max() - g.min() >= _RATE_MIN_SPAN_US]
    dts = [np.diff(np.sort(g)) for g in spread]
    regular = [g for g, dt in zip(spread, dts, strict=True)
               if np.median(dt) * _IRREGULAR >= dt.mean()]
    if regular:
        info["rate_hz"] = float(np.mean([(len(g) - 1) / ((g.max() - g.min()) * 1e-6)
                                         for g in regular]))
    elif all(len(g) == 1 for g in groups):
        info["logged"] = "once"
    elif spread:
        info["logged"] = "irregular"
    else:  # log_info tells "at start" from the log's first row
        info["logged"] = "burst"
    return info, (int(t.min()), int(t.max()))


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
    import pandas as pd

    from tlm_process.logread import arming_time_us, disarm_time_us
    from tlm_sim.ardupilot import MODE_NAMES, MODE_REASONS
    from tlm_sim.faults.detect import faults_from_messages, faults_from_param_changes
    from tlm_sim.flightlog.binreader import param_changes_from_parm

    p = Path(path)
    log, tables, damage = open_log(p)
    kept: dict[str, pd.DataFrame] = {}
    summaries: dict[str, dict[str, Any]] = {}
    spans: dict[str, tuple[int, int]] = {}
    for name, df in tables:
        schema = log.schemas[name]
        inst = schema.instance_field or ("I" if "I" in df.columns and name in _I_TABLES
                                         else None)
        summaries[name], span = _table_summary(df, inst)
        if span is not None:
            spans[name] = span
        if name in _INFO_TABLES:
            kept[name] = df
    t0 = min((a for a, _ in spans.values()), default=None)
    t1 = max((b for _, b in spans.values()), default=None)
    for name, (_, b) in spans.items():  # "at start" needs the log's start
        if summaries[name]["logged"] == "burst" and t0 is not None \
                and b - t0 < _RATE_MIN_SPAN_US:
            summaries[name]["logged"] = "at start"
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
    arming = {"EV": ev, **{n: kept[n] for n in ("ARM", "RCOU") if n in kept
                           and "TimeUS" in kept[n].columns}}
    if t0 is not None:  # the log's first and last row, for "log start" / "log end"
        arming["_span"] = pd.DataFrame({"TimeUS": [t0, t1]})
    a, a_src = arming_time_us(arming, log.params)
    info["armed_source"] = a_src
    if a is not None:
        d, d_src = disarm_time_us(arming, log.params, a)
        info["armed_s"] = [a * 1e-6, None if d is None else d * 1e-6]
        info["disarm_source"] = d_src
        info["flight_time_s"] = None if d is None else (d - a) * 1e-6
        info["arming_periods"] = max(1, int((ev.Id == ARMED).sum()))
    info["messages"] = {
        n: {"count": t["count"], "instances": t["instances"], "rate_hz": t["rate_hz"],
            "logged": t["logged"]}
        for n, t in sorted(summaries.items())
    }
    info["normalised"] = list(log.info.get("notes", []))
    mode = log.modes
    info["modes"] = [
        {"time_s": int(t) * 1e-6, "mode": int(m),
         "name": MODE_NAMES.get(int(m), str(int(m))),
         "reason": None if int(r) < 0 else MODE_REASONS.get(int(r), str(int(r)))}
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
        periods = info.get("arming_periods", 1)
        lines.append(f"armed              {_fmt_s(a)} - {_fmt_s(d)} s"
                     + ("" if ft is None else f" ({ft:.1f} s)")
                     + f"  [armed: {info['armed_source']}; disarmed: {info['disarm_source']}]"
                     + (f" (the first of {periods} arming periods)" if periods > 1 else ""))
    elif info.get("armed_source"):
        lines.append(f"armed              - ({info['armed_source']})")
    for k, note in enumerate(info.get("normalised", [])):
        lines.append(f"{'normalised' if k == 0 else '':<19}{note}")
    lines.append("messages           name   count  inst  rate/inst [Hz]")
    for n, m in info["messages"].items():
        r = m["rate_hz"]
        rate = (f"{r:.1f}" if r >= 0.1 else f"{r:.3f}") if r is not None else {
            "once": "once", "at start": "at start", "irregular": "irregular"}.get(
                m.get("logged"), "-")
        inst = "" if m["instances"] is None else str(m["instances"])
        lines.append(f"                   {n:<5} {m['count']:>7} {inst:>5}  {rate:>8}")
    lines.append("modes")
    for m in info["modes"]:
        reason = "" if m["reason"] is None else f", reason {m['reason']}"
        lines.append(f"  {m['time_s']:9.2f} s  {m['name']} ({m['mode']}){reason}")
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


def check_format(log: BinLog, fmt: str) -> None:
    """Refuse ``--format log`` for a normalised log (a text log or an old-firmware ``.bin``,
    ``open_log``): its tables (``TimeUS`` and instance columns added, instances folded) no
    longer fit DataFlash's FMT limits, and a text log is already text."""
    if fmt == "log" and log.info.get("log_kind"):
        what = "a DataFlash text log" if log.info["log_kind"] == "text" else \
            "an old-firmware log (TimeMS stamps or numbered instances)"
        raise LogError(f"--format log: {Path(log.path).name} is {what}; its normalised tables "
                       "(TimeUS, instances as rows) do not fit a DataFlash text log: convert "
                       "it to csv or parquet")


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
    check_format(log, fmt)
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
