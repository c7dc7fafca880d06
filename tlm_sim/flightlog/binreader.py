"""Read ArduPilot DataFlash ``.bin`` logs into tlm tables (pandas, DataFrame units).

``binscan.scan_bin`` indexes the file once (FMT messages, the byte offset of every message; the
same offsets as pymavlink's indexer on well-formed logs, defined behaviour on damaged ones).
The payloads of the requested types are then decoded in bulk with a numpy structured dtype
built from the FMT format (``method="index"``, the default). ``method="messages"`` decodes
message by message through pymavlink's ``DFReader_binary.recv_match`` instead (slower, kept
as an independent cross-check). Both give the same tables: one DataFrame per message type,
columns = FMT column names, one row per message (instances stay rows, e.g. IMU rows with I=0
and I=1; ``split_instances`` separates them), values and dtypes as in
``tlm_sim.flightlog.schema`` (c/C/e/E as raw/100, L as raw/1e7, f as float32 values in float64
columns, integers as integers, strings as str).

Damaged files: an empty file, one that is not a regular file, or one without a valid FMT
message raises ``BinLogError`` (a ``ValueError`` naming the file). Skipped bytes, damaged,
conflicting or unsafely named FMT messages (a name must be 1-4 of A-Z, 0-9), and a type whose
FMT name looks damaged (its layout is that of a known message the log lacks) give a partial
result; ``read_log(...).info["lost_messages"]`` counts the messages dropped per type. An
incomplete final message is dropped, as pymavlink does (``read_log(...).info["tail_bytes"]``);
ArduPilot's logger leaves one at the end of most logs (every reference SITL log ends so), so
it is reported only when the log was cut off (``cut_off``: the vehicle still armed, or a
tlm log, which never ends so). A damaged or cut-off log gives ONE ``BinLogWarning``, one line
saying how much was read and what was skipped (``read_notice``), e.g.
``flight.bin: read 2.6 MB to 105.0 s (log time); cut off while armed: the last 37 bytes (an
incomplete message) skipped`` or ``...; skipped 45 bytes that are not messages (1 place, first
at byte 999999)``; ``tlm`` prints it as one ``tlm: warning:`` line.

Log context: ``read_params`` (values at log start), ``read_param_changes`` (PARM after the
initial block), ``read_mission`` (CMD), ``read_messages`` (MSG), ``read_modes`` (MODE with mode
and reason names), ``read_events``; ``read_log`` gives all of these and the tables from one
pass over the file.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from numpy.lib.stride_tricks import sliding_window_view

from tlm_sim.ardupilot import MODE_NAMES, MODE_REASONS

from .binscan import (
    BinIndex,
    BinLogError,
    BinLogWarning,
    LogFormat,
    check_log_file,
    is_message_name,
    scan_bin,
)
from .quantise import raw_to_column
from .schema import (
    EVENT_MESSAGES,
    FORMAT_CHARS,
    MULTS,
    SCHEMAS,
    UNITS,
    MessageSchema,
    schema_from_fmt,
)

__all__ = [
    "BinLogError",
    "BinLogWarning",
    "BinLog",
    "BOOKKEEPING_PARAMS",
    "read_bin",
    "read_log",
    "iter_log",
    "read_params",
    "read_param_changes",
    "read_mission",
    "read_messages",
    "read_modes",
    "read_events",
    "read_schemas",
    "split_instances",
    "empty_table",
    "cut_off",
    "read_notice",
    "mission_from_cmd",
    "param_changes_from_parm",
    "modes_with_names",
]

_NP_CODE = {
    "b": "i1", "B": "u1", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4", "q": "<i8",
    "Q": "<u8", "M": "i1", "f": "<f4", "d": "<f8", "g": "<f2", "c": "<i2", "C": "<u2",
    "e": "<i4", "E": "<u4", "L": "<i4", "n": "S4", "N": "S16", "Z": "S64", "a": "V64",
}

#: Parameters ArduPilot rewrites by itself (mission upload counter, statistics): left out of
#: ``read_param_changes`` by default.
BOOKKEEPING_PARAMS: tuple[str, ...] = (
    "MIS_TOTAL", "STAT_BOOTCNT", "STAT_FLTTIME", "STAT_RUNTIME", "STAT_RESET",
)

#: Fields of one mission item (``read_mission``), CMD column names.
MISSION_FIELDS: tuple[str, ...] = (
    "CNum", "CId", "Prm1", "Prm2", "Prm3", "Prm4", "Lat", "Lng", "Alt", "Frame",
)


# --- decoding ----------------------------------------------------------------------------------
def _index(path: str | os.PathLike) -> BinIndex:
    """Scan ``path`` and warn (one BinLogWarning, ``read_notice``) when it was damaged or cut
    off."""
    ix = scan_bin(path)
    notice = read_notice(ix)
    if notice is not None:
        warnings.warn(notice, BinLogWarning, stacklevel=3)
    return ix


# --- what was read -----------------------------------------------------------------------------
_EV_ARMED, _EV_DISARMED = 10, 11


def _last_time_us(ix: BinIndex) -> int | None:
    """TimeUS of the last complete message that has one (the one at the highest offset)."""
    last_at = -1
    for t, f in ix.formats.items():
        offs = ix.offsets.get(t)
        if f.columns[:1] == ("TimeUS",) and f.format[:1] == "Q" and offs is not None \
                and offs.size and int(offs[-1]) > last_at:
            last_at = int(offs[-1])
    if last_at < 0:
        return None
    return int(ix.data[last_at + 3 : last_at + 11].view("<u8")[0])


def _raw_column(ix: BinIndex, name: str, col: str) -> np.ndarray | None:
    """Raw values of column ``col`` of every ``name`` message (numpy, no DataFrame: this runs
    on every read); None when the log does not define ``name`` with that column."""
    f = ix.by_name.get(name)
    if f is None or col not in f.columns:
        return None
    offs = ix.offsets.get(f.type)
    if offs is None or offs.size == 0:
        return np.zeros(0)
    dtype = _record_dtype(f)
    rec = sliding_window_view(ix.data, dtype.itemsize)[offs + 3].view(dtype).reshape(-1)
    return rec[f"f{f.columns.index(col)}"]


def _ends_armed(ix: BinIndex) -> bool:
    """Whether the log's last arming event (EV 10 ARMED / 11 DISARMED) is ARMED."""
    ids = _raw_column(ix, "EV", "Id")
    if ids is None:
        return False
    arming = ids[(ids == _EV_ARMED) | (ids == _EV_DISARMED)]
    return bool(arming.size) and int(arming[-1]) == _EV_ARMED


def _written_by_tlm(ix: BinIndex) -> bool:
    """Whether a MSG line is tlm's firmware string (``binwriter.FIRMWARE_STRING``)."""
    from .binwriter import FIRMWARE_STRING

    text = _raw_column(ix, "MSG", "Message")
    return text is not None and text.dtype.kind == "S" and bool(
        (text == FIRMWARE_STRING.encode("ascii")).any())


def cut_off(ix: BinIndex) -> bool:
    """Whether the log was cut off (truncated): it ends in an incomplete message and either
    the vehicle was still armed (its last arming event is EV 10 ARMED) or it is tlm's own log
    (tlm writes whole messages only). ArduPilot leaves an incomplete final message at the end
    of most complete logs too (every reference SITL log ends so, disarmed), so that alone says
    nothing; a log cut exactly between two messages, or cut while disarmed, cannot be told
    from a complete one."""
    return ix.tail_bytes > 0 and (_ends_armed(ix) or _written_by_tlm(ix))


def read_notice(ix: BinIndex) -> str | None:
    """One line saying how much of a damaged or cut-off log was read and what was skipped,
    e.g. ``"flight.bin: read 2.6 MB to 105.0 s (log time); cut off while armed: the last 37
    bytes (an incomplete message) skipped"``; None for an intact log (one that ends in an
    incomplete message but not cut off, ``cut_off``, is intact)."""
    name = ix.path.name
    parts = [m.removeprefix(f"{name}: ") for m in ix.issues]
    if cut_off(ix):
        parts.insert(0, f"cut off{' while armed' if _ends_armed(ix) else ''}: the last "
                        f"{ix.tail_bytes} bytes (an incomplete message) skipped")
    if not parts:
        return None
    read = ix.size - ix.skipped_bytes - ix.tail_bytes
    t = _last_time_us(ix)
    at = "" if t is None else f" to {t * 1e-6:.1f} s (log time)"
    return f"{name}: read {read / 1e6:.1f} MB{at}; " + "; ".join(parts)


def _log_schema(fmt: LogFormat) -> MessageSchema:
    """Schema of a log's message type (registry schema when its layout matches)."""
    known = SCHEMAS.get(fmt.name)
    if known is not None and known.fmt == fmt.format and known.columns == tuple(fmt.columns):
        return known
    return schema_from_fmt(fmt.name, fmt.format, tuple(fmt.columns))


def empty_table(schema: MessageSchema) -> pd.DataFrame:
    """Empty DataFrame with the schema's columns and dtypes."""
    cols = {
        c: raw_to_column(np.zeros(0, dtype=np.int64) if FORMAT_CHARS[f].kind != "str" else [], f)
        for c, f in zip(schema.columns, schema.fmt, strict=True)
    }
    return pd.DataFrame(cols)  # dict order = column order (columns= would reindex: 2x slower)


def _frame_from_raw(schema: MessageSchema, raw_cols: list) -> pd.DataFrame:
    # signalling NaNs in damaged payloads raise "invalid" when cast to float64: quiet them
    with np.errstate(invalid="ignore", over="ignore"):
        cols = {
            c: raw_to_column(r, f)
            for c, f, r in zip(schema.columns, schema.fmt, raw_cols, strict=True)
        }
    return pd.DataFrame(cols)  # dict order = column order (columns= would reindex: 2x slower)


def _record_dtype(fmt: LogFormat) -> np.dtype:
    return np.dtype([(f"f{k}", _NP_CODE[c]) for k, c in enumerate(fmt.format)])


def _decode_index(ix: BinIndex, fmt: LogFormat) -> pd.DataFrame:
    """Bulk-decode every message of one type from the offsets of ``ix``."""
    schema = _log_schema(fmt)
    dtype = _record_dtype(fmt)
    offsets = ix.offsets.get(fmt.type)
    if offsets is None or offsets.size == 0:
        return empty_table(schema)
    # rows of payload bytes: a window view of the file, gathered at the payload starts
    rows = sliding_window_view(ix.data, dtype.itemsize)[offsets + 3]
    rec = rows.view(dtype).reshape(-1)
    raw_cols = []
    for k, c in enumerate(fmt.format):
        col = rec[f"f{k}"]
        if FORMAT_CHARS[c].kind == "array":
            col = [bytes(v) for v in col]
        elif FORMAT_CHARS[c].kind == "str":
            col = col.tolist()
        raw_cols.append(col)
    return _frame_from_raw(schema, raw_cols)


def _decode_types(ix: BinIndex, names: Iterable[str]) -> dict[str, pd.DataFrame]:
    out = {}
    for n in names:
        f = ix.by_name.get(n)
        if f is not None:
            out[n] = _decode_index(ix, f)
        elif n in SCHEMAS:
            out[n] = empty_table(SCHEMAS[n])
    return out


def _present(ix: BinIndex) -> list[str]:
    """Names of the types with at least one message, in the order of their FMT."""
    return [n for n, f in ix.by_name.items() if len(ix.offsets.get(f.type, ())) > 0]


def _open_pymavlink(path: str | os.PathLike):  # noqa: ANN202 - pymavlink type
    from pymavlink import DFReader

    p = check_log_file(path)
    reader = DFReader.DFReader_binary.__new__(DFReader.DFReader_binary)
    try:
        sink = io.StringIO()
        with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
            reader.__init__(str(p), zero_time_base=True)
    except Exception as e:  # pymavlink raises whatever its parsing meets
        _close_pymavlink(reader)  # its constructor leaves the file open when it fails
        raise BinLogError(f"{p}: pymavlink cannot read it ({type(e).__name__}: {e})") from e
    if reader.counts[0x80] == 0:
        _close_pymavlink(reader)
        raise BinLogError(f"{p}: not an ArduPilot DataFlash log (no FMT message)")
    return reader


def _close_pymavlink(reader: Any) -> None:
    if hasattr(reader, "data_map"):
        with contextlib.suppress(BufferError, ValueError):
            reader.data_map.close()
    if hasattr(reader, "filehandle"):
        reader.filehandle.close()


def _decode_messages(path: str | os.PathLike, names: list[str] | None) -> dict[str, pd.DataFrame]:
    """Decode through pymavlink's ``recv_match``, one message object at a time (slow path)."""
    reader = _open_pymavlink(path)
    try:
        fmts = {f.name: f for f in reader.formats.values() if is_message_name(f.name)}
        if names is None:
            names = [n for n, f in fmts.items() if reader.counts[f.type] > 0]
        want = [n for n in names if n in fmts]
        rows: dict[str, list] = {n: [] for n in want}
        try:
            sink = io.StringIO()
            with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
                reader.rewind()
                while want:
                    m = reader.recv_match(type=want)
                    if m is None:
                        break
                    lst = rows.get(m.get_type())
                    if lst is not None:
                        lst.append(m._elements)
        except Exception as e:
            raise BinLogError(
                f"{reader.filehandle.name}: pymavlink failed while decoding "
                f"({type(e).__name__}: {e})"
            ) from e
    finally:
        _close_pymavlink(reader)
    out: dict[str, pd.DataFrame] = {}
    for name in names:
        if name not in rows:
            if name in SCHEMAS:
                out[name] = empty_table(SCHEMAS[name])
            continue
        pf = fmts[name]
        fmt = LogFormat(pf.type, pf.name, pf.len, pf.format, tuple(pf.columns))
        try:
            schema = _log_schema(fmt)
        except ValueError as e:  # a damaged FMT that pymavlink took as it was
            raise BinLogError(f"{Path(path)}: unusable FMT message for {name} ({e})") from e
        r = rows[name]
        if not r:
            out[name] = empty_table(schema)
            continue
        raw_cols: list = [list(col) for col in zip(*r, strict=True)]
        for k, c in enumerate(fmt.format):
            if FORMAT_CHARS[c].kind == "array":
                raw_cols[k] = [v.tobytes() if hasattr(v, "tobytes") else v for v in raw_cols[k]]
            elif FORMAT_CHARS[c].kind != "str":
                raw_cols[k] = np.asarray(raw_cols[k], dtype=_NP_CODE[c])
        out[name] = _frame_from_raw(schema, raw_cols)
    return out


def read_bin(
    path: str | os.PathLike,
    types: Iterable[str] | None = None,
    *,
    method: str = "index",
) -> dict[str, pd.DataFrame]:
    """Read message tables from a DataFlash ``.bin`` log.

    Args:
        path: the ``.bin`` file.
        types: message names to read (e.g. ``["GPS", "IMU"]``); None = every type in the log
            that has messages. Requested types absent from the log are omitted from the
            result, except those tlm has a schema for, which come back as empty tables with
            the right columns.
        method: "index" (bulk numpy decoding, default) or "messages" (pymavlink
            ``recv_match`` iteration, an independent cross-check for well-formed logs).
    Returns:
        name → DataFrame, one row per message in log order, ArduPilot column names, tlm
        dtypes.
    Raises:
        FileNotFoundError: no such file.
        BinLogError: empty file or not a DataFlash log (no valid FMT message).
    Warns:
        BinLogWarning: parts of the file were damaged and skipped (``method="index"``).
    """
    if method not in ("index", "messages"):
        raise ValueError(f"method must be 'index' or 'messages', not {method!r}")
    names = None if types is None else list(dict.fromkeys(types))
    if method == "messages":
        return _decode_messages(path, names)
    ix = _index(path)
    return _decode_types(ix, _present(ix) if names is None else names)


# --- schemas -----------------------------------------------------------------------------------
def _fmtu_units(ix: BinIndex) -> dict[int, tuple[str, str]]:
    """type id → (unit ids, multiplier ids) from the log's FMTU messages (first per type)."""
    f = ix.by_name.get("FMTU")
    if f is None or f.columns[:4] != ("TimeUS", "FmtType", "UnitIds", "MultIds"):
        return {}
    fmtu = _decode_index(ix, f)
    out: dict[int, tuple[str, str]] = {}
    for ftype, u, m in zip(fmtu["FmtType"], fmtu["UnitIds"], fmtu["MultIds"], strict=True):
        out.setdefault(int(ftype), (u, m))
    return out


def _schemas(ix: BinIndex, prefer_registry: bool) -> dict[str, MessageSchema]:
    units = _fmtu_units(ix)
    out: dict[str, MessageSchema] = {}
    for name, f in ix.by_name.items():
        u, m = units.get(f.type, (None, None))
        if u is not None and not (
            len(u) == len(m) == len(f.format) and all(c in UNITS for c in u)
            and all(c in MULTS for c in m)
        ):
            u = m = None
        s = schema_from_fmt(name, f.format, f.columns, u, m)
        known = SCHEMAS.get(name)
        if prefer_registry and known is not None and (
            known.fmt, known.columns, known.units, known.mults
        ) == (s.fmt, s.columns, s.units, s.mults):
            s = known
        out[name] = s
    return out


def read_schemas(path: str | os.PathLike) -> dict[str, MessageSchema]:
    """Schemas of every message type defined in a log, from its FMT and FMTU messages."""
    return _schemas(_index(path), prefer_registry=False)


# --- parameters --------------------------------------------------------------------------------
def _initial_block_end(names: np.ndarray) -> int:
    """Rows of the initial PARM block: up to the first name that repeats."""
    dup = pd.Series(names).duplicated().to_numpy()
    return int(np.argmax(dup)) if dup.any() else len(names)


def _params_from_parm(parm: pd.DataFrame) -> dict[str, float]:
    first = parm.drop_duplicates("Name", keep="first")
    return {str(n): float(v) for n, v in zip(first["Name"], first["Value"], strict=True)}


def param_changes_from_parm(
    parm: pd.DataFrame,
    *,
    exclude: Iterable[str] = BOOKKEEPING_PARAMS,
    value_changes_only: bool = True,
) -> pd.DataFrame:
    """Parameter changes recorded after the initial PARM block (see ``read_param_changes``)."""
    names = parm["Name"].to_numpy()
    values = parm["Value"].to_numpy(dtype=np.float64)
    times = parm["TimeUS"].to_numpy()
    end = _initial_block_end(names)
    last: dict[str, float] = dict(zip(names[:end].tolist(), values[:end].tolist(), strict=True))
    skip = set(exclude)
    rows_t, rows_n, rows_v, rows_o = [], [], [], []
    for t, n, v in zip(times[end:].tolist(), names[end:].tolist(), values[end:].tolist(),
                       strict=True):
        old = last.get(n, math.nan)
        last[n] = v
        if n in skip:
            continue
        if value_changes_only and (old == v or (math.isnan(old) and math.isnan(v))):
            continue
        rows_t.append(t)
        rows_n.append(n)
        rows_v.append(v)
        rows_o.append(old)
    return pd.DataFrame({
        "TimeUS": np.asarray(rows_t, dtype=np.int64),
        "Name": np.asarray(rows_n, dtype=object),
        "Value": np.asarray(rows_v, dtype=np.float64),
        "Old": np.asarray(rows_o, dtype=np.float64),
    })


def read_params(path: str | os.PathLike) -> dict[str, float]:
    """Parameter values at log start: the first PARM value of each name."""
    return _params_from_parm(read_bin(path, ["PARM"])["PARM"])


def read_param_changes(
    path: str | os.PathLike,
    *,
    exclude: Iterable[str] = BOOKKEEPING_PARAMS,
    value_changes_only: bool = True,
) -> pd.DataFrame:
    """Parameters changed after log start (e.g. fault injection by PARAM_SET).

    ArduPilot logs every parameter once at log start (the initial PARM block: the rows up to
    the first name that repeats), then one PARM per parameter set. In the reference SITL logs a
    PARAM_SET is logged twice, ~0.8 ms apart, and the firmware also logs its own bookkeeping
    (MIS_TOTAL per uploaded mission item, STAT_FLTTIME/STAT_RUNTIME every 31 s).

    Args:
        path: the ``.bin`` file.
        exclude: parameter names left out (default ``BOOKKEEPING_PARAMS``; ``()`` keeps all).
        value_changes_only: drop rows that set a parameter to the value it already had.
    Returns:
        DataFrame TimeUS (µs since boot, int64), Name, Value (new value), Old (value before,
        NaN for a parameter not in the initial block), in log order.
    """
    parm = read_bin(path, ["PARM"])["PARM"]
    return param_changes_from_parm(parm, exclude=exclude, value_changes_only=value_changes_only)


# --- mission, messages, modes ------------------------------------------------------------------
def mission_from_cmd(cmd: pd.DataFrame) -> list[dict[str, Any]]:
    """Mission items from a CMD table; when the mission is logged again, the last one wins.

    A CMD row with CNum 0 starts a new mission (an upload rewrites it from the home item);
    other rows set item CNum of the current mission (a single-item update, or the same item
    logged again). Items with CNum ≥ the last row's CTot are dropped (the mission shrank).

    Returns:
        items sorted by CNum, each a dict of ``MISSION_FIELDS`` (Python int/float; Lat/Lng in
        degrees, Alt in m, Frame = MAV_FRAME, CId = MAV_CMD, item 0 = home).
    """
    if len(cmd) == 0:
        return []
    current: dict[int, dict[str, Any]] = {}
    cols = {c: cmd[c].tolist() for c in (*MISSION_FIELDS, "CTot")}
    for k in range(len(cmd)):
        num = int(cols["CNum"][k])
        if num == 0:
            current = {}
        current[num] = {
            c: (int(cols[c][k]) if c in ("CNum", "CId", "Frame") else float(cols[c][k]))
            for c in MISSION_FIELDS
        }
    total = int(cols["CTot"][-1])
    return [current[k] for k in sorted(current) if k < total]


def read_mission(path: str | os.PathLike) -> list[dict[str, Any]]:
    """The mission logged in CMD messages (see ``mission_from_cmd``); [] when none."""
    return mission_from_cmd(read_bin(path, ["CMD"])["CMD"])


def read_messages(path: str | os.PathLike) -> pd.DataFrame:
    """Text messages (MSG: TimeUS, Message), e.g. the firmware string, "Radio Failsafe"."""
    return read_bin(path, ["MSG"])["MSG"]


def modes_with_names(mode: pd.DataFrame) -> pd.DataFrame:
    """MODE table plus ModeName (``ardupilot.MODE_NAMES``) and RsnName
    (``ardupilot.MODE_REASONS``) columns.

    Numbers without a name become "MODE<n>" / "RSN<n>".
    """
    out = mode.copy()
    out["ModeName"] = np.asarray(
        [MODE_NAMES.get(int(m), f"MODE{int(m)}") for m in mode["ModeNum"]], dtype=object
    )
    out["RsnName"] = np.asarray(
        [MODE_REASONS.get(int(r), f"RSN{int(r)}") for r in mode["Rsn"]], dtype=object
    )
    return out


def read_modes(path: str | os.PathLike) -> pd.DataFrame:
    """Flight-mode changes: MODE (TimeUS, Mode, ModeNum, Rsn) with ModeName and RsnName."""
    return modes_with_names(read_bin(path, ["MODE"])["MODE"])


def read_events(path: str | os.PathLike) -> dict[str, pd.DataFrame]:
    """Event tables MODE, ERR, EV and MSG (empty tables where the log has none)."""
    return read_bin(path, EVENT_MESSAGES)


# --- instances ---------------------------------------------------------------------------------
def split_instances(
    df: pd.DataFrame, schema: MessageSchema | str
) -> dict[int | str, pd.DataFrame]:
    """Split a multi-instance table by its instance field (IMU by I, VIBE by IMU, XKF1 by C).

    Args:
        df: one message table (rows of all instances, as ``read_bin`` gives them).
        schema: its MessageSchema, or a message name known to ``SCHEMAS``.
    Returns:
        instance → rows of that instance in log order (fresh RangeIndex, instance column kept),
        sorted by instance; ``{0: df}`` for single-instance messages.
    """
    if isinstance(schema, str):
        if schema not in SCHEMAS:
            raise KeyError(f"no schema for message {schema!r}: pass its MessageSchema")
        schema = SCHEMAS[schema]
    inst = schema.instance_field
    if inst is None:
        return {0: df.reset_index(drop=True)}
    if inst not in df.columns:
        raise KeyError(f"{schema.name}: table has no instance column {inst!r}")
    keys = df[inst].to_numpy()
    out: dict[int | str, pd.DataFrame] = {}
    for k in sorted(set(keys.tolist())):
        key = int(k) if isinstance(k, int | np.integer) else k
        out[key] = df[keys == k].reset_index(drop=True)
    return out


# --- everything at once ------------------------------------------------------------------------
@dataclass
class BinLog:
    """One DataFlash log read in a single pass (``read_log``).

    Attributes:
        path: the file.
        tables: message name → DataFrame (as ``read_bin``).
        schemas: name → MessageSchema of every type the log defines (the registry schema where
            the log's FMT/FMTU equal it, else one built from FMT and FMTU).
        params: parameter values at log start (``read_params``).
        param_changes: ``read_param_changes`` (default arguments).
        mission: ``read_mission``.
        messages: MSG table (TimeUS, Message).
        modes: ``read_modes`` (MODE with ModeName, RsnName).
        info: size_bytes, messages (name → count of complete messages), skipped_bytes,
            tail_bytes (incomplete final message, dropped), lost_messages (``BinIndex.lost``:
            what → messages dropped), issues (one line per kind of damage), cut_off (the log
            was truncated: ``cut_off``), notice (the one line warned: ``read_notice``; None
            for an intact log).
    """

    path: str
    tables: dict[str, pd.DataFrame]
    schemas: dict[str, MessageSchema]
    params: dict[str, float]
    param_changes: pd.DataFrame
    mission: list[dict[str, Any]]
    messages: pd.DataFrame
    modes: pd.DataFrame
    info: dict[str, Any] = field(default_factory=dict)


#: context tables and the columns ``read_log`` needs from each
_CONTEXT: dict[str, tuple[str, ...]] = {
    "PARM": ("TimeUS", "Name", "Value"),
    "CMD": ("CTot", *MISSION_FIELDS),
    "MSG": ("TimeUS", "Message"),
    "MODE": ("TimeUS", "ModeNum", "Rsn"),
}


def _context_table(ix: BinIndex, tables: dict[str, pd.DataFrame], name: str) -> pd.DataFrame:
    """Table ``name`` for the log context; empty (with a warning) if its layout lacks columns."""
    df = tables[name] if name in tables else _decode_types(ix, [name])[name]
    missing = [c for c in _CONTEXT[name] if c not in df.columns]
    if missing:
        warnings.warn(f"{ix.path.name}: {name} has no {', '.join(missing)} column; ignored",
                      BinLogWarning, stacklevel=3)
        df = empty_table(SCHEMAS[name])
    return df


def _bin_log(ix: BinIndex, path: str | os.PathLike, tables: dict[str, pd.DataFrame]) -> BinLog:
    """BinLog of an indexed log with ``tables`` (context tables decoded here if not given)."""
    ctx = {n: _context_table(ix, tables, n) for n in _CONTEXT}
    info = {
        "size_bytes": ix.size,
        "messages": {n: int(ix.offsets[f.type].size) for n, f in ix.by_name.items()
                     if f.type in ix.offsets},
        "skipped_bytes": ix.skipped_bytes,
        "tail_bytes": ix.tail_bytes,
        "lost_messages": dict(ix.lost),
        "issues": list(ix.issues),
        "cut_off": cut_off(ix),
        "notice": read_notice(ix),
    }
    return BinLog(
        path=os.fspath(path),
        tables=tables,
        schemas=_schemas(ix, prefer_registry=True),
        params=_params_from_parm(ctx["PARM"]),
        param_changes=param_changes_from_parm(ctx["PARM"]),
        mission=mission_from_cmd(ctx["CMD"]),
        messages=ctx["MSG"],
        modes=modes_with_names(ctx["MODE"]),
        info=info,
    )


def read_log(path: str | os.PathLike, types: Iterable[str] | None = None) -> BinLog:
    """Tables and context of a DataFlash log, indexing the file once.

    Args:
        path: the ``.bin`` file.
        types: tables to decode (as ``read_bin``; None = all types with messages, ``()`` =
            context only). PARM, CMD, MSG and MODE are decoded for the context either way.
    Raises / warns: as ``read_bin``.
    """
    ix = _index(path)
    names = _present(ix) if types is None else list(dict.fromkeys(types))
    return _bin_log(ix, path, _decode_types(ix, names))


def iter_log(path: str | os.PathLike) -> tuple[BinLog, Iterator[tuple[str, pd.DataFrame]]]:
    """A log's context now and its tables one at a time: at most one table is held.

    Returns:
        (BinLog with every field but ``tables`` (empty), an iterator of (name, table) over
        the types with messages, in FMT order, each decoded when reached, as ``read_log``).
        The iterator holds the file's bytes until it is exhausted or dropped.
    Raises / warns: as ``read_bin`` (when called, not while iterating).
    """
    ix = _index(path)
    log = _bin_log(ix, path, {})

    def tables() -> Iterator[tuple[str, pd.DataFrame]]:
        for n in _present(ix):
            yield n, _decode_index(ix, ix.by_name[n])

    return log, tables()
