"""Read ArduPilot DataFlash ``.bin`` logs into tlm tables (pandas, DataFrame units).

pymavlink's ``DFReader_binary`` indexes the file (FMT messages, the byte offset of every
message). The payloads of the requested types are then decoded in bulk with a numpy structured
dtype built from the FMT format (``method="index"``, the default), or message by message
through ``recv_match`` (``method="messages"``, slower, kept as a cross-check). Both give the
same tables: one DataFrame per message type, columns = FMT column names, one row per message
(instances stay rows, e.g. IMU rows with I=0 and I=1), values and dtypes as in
``tlm_sim.flightlog.schema`` (c/C/e/E as raw/100, L as raw/1e7, f as float32 values in float64
columns, integers as integers, strings as str).
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import pandas as pd
from pymavlink import DFReader

from .quantise import raw_to_column
from .schema import EVENT_MESSAGES, FORMAT_CHARS, SCHEMAS, MessageSchema, schema_from_fmt

__all__ = ["read_bin", "read_params", "read_events", "read_schemas", "empty_table"]

_NP_CODE = {
    "b": "i1", "B": "u1", "h": "<i2", "H": "<u2", "i": "<i4", "I": "<u4", "q": "<i8",
    "Q": "<u8", "M": "i1", "f": "<f4", "d": "<f8", "g": "<f2", "c": "<i2", "C": "<u2",
    "e": "<i4", "E": "<u4", "L": "<i4", "n": "S4", "N": "S16", "Z": "S64", "a": "V64",
}


def _open(path: str | os.PathLike) -> DFReader.DFReader_binary:
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"no such log: {p}")
    with contextlib.redirect_stdout(io.StringIO()):
        return DFReader.DFReader_binary(str(p), zero_time_base=True)


def _close(reader: DFReader.DFReader_binary) -> None:
    with contextlib.suppress(BufferError, ValueError):
        reader.data_map.close()
    reader.filehandle.close()


def _formats_by_name(reader: DFReader.DFReader_binary) -> dict[str, DFReader.DFFormat]:
    return {f.name: f for f in reader.formats.values()}


def _log_schema(fmt: DFReader.DFFormat) -> MessageSchema:
    """Schema of a log's message type (registry schema when its layout matches)."""
    known = SCHEMAS.get(fmt.name)
    if known is not None and known.fmt == fmt.format and list(known.columns) == fmt.columns:
        return known
    return schema_from_fmt(fmt.name, fmt.format, tuple(fmt.columns))


def empty_table(schema: MessageSchema) -> pd.DataFrame:
    """Empty DataFrame with the schema's columns and dtypes."""
    cols = {
        c: raw_to_column(np.zeros(0, dtype=np.int64) if FORMAT_CHARS[f].kind != "str" else [], f)
        for c, f in zip(schema.columns, schema.fmt, strict=True)
    }
    return pd.DataFrame(cols, columns=list(schema.columns))


def _frame_from_raw(schema: MessageSchema, raw_cols: list) -> pd.DataFrame:
    cols = {
        c: raw_to_column(r, f)
        for c, f, r in zip(schema.columns, schema.fmt, raw_cols, strict=True)
    }
    return pd.DataFrame(cols, columns=list(schema.columns))


def _decode_index(reader: DFReader.DFReader_binary, fmt: DFReader.DFFormat) -> pd.DataFrame:
    """Bulk-decode every message of one type using the reader's offset index."""
    schema = _log_schema(fmt)
    offsets = np.asarray(reader.offsets[fmt.type], dtype=np.int64)
    offsets = offsets[offsets + fmt.len <= reader.data_len]  # drop a truncated last message
    dtype = np.dtype(
        [(f"f{k}", _NP_CODE[c]) for k, c in enumerate(fmt.format)]
    )
    if dtype.itemsize != fmt.len - 3:
        raise ValueError(f"{fmt.name}: FMT length {fmt.len} does not match format {fmt.format}")
    data = np.frombuffer(reader.data_map, dtype=np.uint8)
    if len(offsets):
        idx = (offsets + 3)[:, None] + np.arange(dtype.itemsize, dtype=np.int64)[None, :]
        rec = np.ascontiguousarray(data[idx]).view(dtype).reshape(-1)
    else:
        rec = np.zeros(0, dtype=dtype)
    raw_cols = []
    for k, c in enumerate(fmt.format):
        col = rec[f"f{k}"]
        if FORMAT_CHARS[c].kind == "array":
            col = [bytes(v) for v in col]
        elif FORMAT_CHARS[c].kind == "str":
            col = col.tolist()
        raw_cols.append(col)
    return _frame_from_raw(schema, raw_cols)


def _decode_messages(
    reader: DFReader.DFReader_binary, fmts: dict[str, DFReader.DFFormat]
) -> dict[str, pd.DataFrame]:
    """Decode by iterating ``recv_match`` once over the requested types (slow path)."""
    rows: dict[str, list] = {n: [] for n in fmts}
    reader.rewind()
    want = list(fmts)
    while True:
        m = reader.recv_match(type=want)
        if m is None:
            break
        name = m.get_type()
        if name in rows:
            rows[name].append(m._elements)
    out = {}
    for name, fmt in fmts.items():
        schema = _log_schema(fmt)
        r = rows[name]
        raw_cols = [list(col) for col in zip(*r, strict=True)] if r else [
            [] for _ in fmt.format
        ]
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
        types: message names to read (e.g. ``["GPS", "IMU"]``); None = every type in the log.
            Requested types absent from the log are omitted from the result, except those
            tlm has a schema for, which come back as empty tables with the right columns.
        method: "index" (bulk numpy decoding, default) or "messages" (pymavlink
            ``recv_match`` iteration).
    Returns:
        name → DataFrame, one row per message in log order (TimeUS non-decreasing for
        messages written in time order), ArduPilot column names, tlm dtypes.
    """
    if method not in ("index", "messages"):
        raise ValueError(f"method must be 'index' or 'messages', not {method!r}")
    reader = _open(path)
    try:
        fmts = _formats_by_name(reader)
        if types is None:
            names = [n for n, f in fmts.items() if reader.counts[f.type] > 0]
        else:
            names = list(dict.fromkeys(types))
        present = {n: fmts[n] for n in names if n in fmts}
        if method == "index":
            out = {n: _decode_index(reader, f) for n, f in present.items()}
        else:
            out = _decode_messages(reader, present)
    finally:
        _close(reader)
    result: dict[str, pd.DataFrame] = {}
    for n in names:
        if n in out:
            result[n] = out[n]
        elif n in SCHEMAS:
            result[n] = empty_table(SCHEMAS[n])
    return result


def read_schemas(path: str | os.PathLike) -> dict[str, MessageSchema]:
    """Schemas of every message type defined in a log, from its FMT and FMTU messages."""
    t = read_bin(path, ["FMT", "FMTU"])
    fmt, fmtu = t["FMT"], t["FMTU"]
    units: dict[int, tuple[str, str]] = {}
    for ftype, u, m in zip(fmtu["FmtType"], fmtu["UnitIds"], fmtu["MultIds"], strict=True):
        units.setdefault(int(ftype), (u, m))
    out: dict[str, MessageSchema] = {}
    for ftype, name, f, cols in zip(fmt["Type"], fmt["Name"], fmt["Format"], fmt["Columns"],
                                    strict=True):
        u, m = units.get(int(ftype), (None, None))
        if u is not None and len(u) != len(f):
            u = m = None
        out[name] = schema_from_fmt(name, f, cols, u, m)
    return out


def read_params(path: str | os.PathLike) -> dict[str, float]:
    """Parameter values at log start: the first PARM value of each name."""
    parm = read_bin(path, ["PARM"])["PARM"]
    first = parm.drop_duplicates("Name", keep="first")
    return {str(n): float(v) for n, v in zip(first["Name"], first["Value"], strict=True)}


def read_events(path: str | os.PathLike) -> dict[str, pd.DataFrame]:
    """Event tables MODE, ERR, EV and MSG (empty tables where the log has none)."""
    return read_bin(path, EVENT_MESSAGES)
