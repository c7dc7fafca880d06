"""Parquet parts of one flight: its message tables and its Eq. 4 fault records, as bytes.

Workers encode (compression is most of the cost of writing, so it runs in parallel), the
writer only puts the bytes in place. Every part carries a ``flight`` column (int32) first.

Tables keep the column types of ``tlm_sim.flightlog.tableio`` (``f`` columns as float32,
exact; integers in their ArduPilot width; scaled integers as float64) and its schema metadata
(``tlm.message``, ``tlm.fmt``, ``tlm.units``, ``tlm.mults``). Encoding: zstd, no dictionary
pages, BYTE_STREAM_SPLIT for floating-point columns, statistics for ``flight`` and ``TimeUS``
only (faster and smaller than pyarrow's defaults; measured in docs/generate.md).

Fault parts have a fixed Arrow schema (:data:`FAULT_SCHEMA`, one row per record, zero rows for
a flight without faults), so every flight's part reads into one table; ``params_start`` /
``params_end`` are JSON text.
"""

from __future__ import annotations

import io
import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from tlm_sim.flightlog.schema import FORMAT_CHARS, MessageSchema

__all__ = ["FAULT_SCHEMA", "fault_table", "table_part", "to_parquet_bytes"]

#: Columns of the fault records part (``flight`` + Eq. 4 record keys of tlm_sim).
FAULT_SCHEMA = pa.schema([
    ("flight", pa.int32()),
    ("fault", pa.int16()),
    ("type", pa.string()),
    ("label", pa.int8()),
    ("start", pa.float64()),
    ("end", pa.float64()),
    ("start_time_us", pa.int64()),
    ("end_time_us", pa.int64()),
    ("duration_s", pa.float64()),
    ("end_by", pa.string()),
    ("time_source", pa.string()),
    ("start_lat", pa.float64()),
    ("start_lon", pa.float64()),
    ("start_alt", pa.float64()),
    ("end_lat", pa.float64()),
    ("end_lon", pa.float64()),
    ("end_alt", pa.float64()),
    ("start_true_lat", pa.float64()),
    ("start_true_lon", pa.float64()),
    ("start_true_alt", pa.float64()),
    ("end_true_lat", pa.float64()),
    ("end_true_lon", pa.float64()),
    ("end_true_alt", pa.float64()),
    ("params_start", pa.string()),
    ("params_end", pa.string()),
], metadata={b"tlm.table": b"faults"})


def _schema_metadata(schema: MessageSchema) -> dict[bytes, bytes]:
    return {b"tlm.message": schema.name.encode(), b"tlm.fmt": schema.fmt.encode(),
            b"tlm.units": schema.units.encode(), b"tlm.mults": schema.mults.encode()}


def _column(values: np.ndarray, char: str) -> pa.Array:
    kind = FORMAT_CHARS[char].kind
    if char in ("f", "g"):
        return pa.array(values.astype(np.float32, copy=False))
    if kind == "str":
        return pa.array([str(x) for x in values], type=pa.string())
    if kind == "array":
        return pa.array([np.asarray(x, dtype=np.int16) for x in values],
                        type=pa.list_(pa.int16()))
    return pa.array(values.astype(FORMAT_CHARS[char].dtype, copy=False))


def table_part(columns: pd.DataFrame | Mapping[str, np.ndarray], schema: MessageSchema,
               flight: int) -> pa.Table:
    """One flight's table as Arrow: ``flight`` (int32) + the schema's columns.

    ``columns``: the canonical table, as a DataFrame or as column name -> array
    (``FlightLog.columns``)."""
    values = [np.asarray(columns[c]) for c in schema.columns]
    arrays = [pa.array(np.full(len(values[0]), flight, dtype=np.int32))]
    names = ["flight"]
    for c, f, v in zip(schema.columns, schema.fmt, values, strict=True):
        arrays.append(_column(v, f))
        names.append(c)
    table = pa.Table.from_arrays(arrays, names=names)
    return table.replace_schema_metadata(_schema_metadata(schema))


def _float_or_none(v: Any) -> float | None:
    if v is None or isinstance(v, str):
        return None
    return float(v)


def fault_table(records: Sequence[Mapping[str, Any]], flight: int) -> pa.Table:
    """Eq. 4 records of one flight as an Arrow table of :data:`FAULT_SCHEMA`.

    Schedule ``start`` / ``end`` are seconds since boot (None for a waypoint trigger or no
    end: the generator draws times only)."""
    cols: dict[str, list[Any]] = {f.name: [] for f in FAULT_SCHEMA}
    for i, r in enumerate(records):
        cols["flight"].append(flight)
        cols["fault"].append(i)
        for name in FAULT_SCHEMA.names[2:]:
            v = r.get(name)
            if name in ("params_start", "params_end"):
                v = json.dumps(v or {}, sort_keys=True)
            elif name in ("start", "end"):
                v = _float_or_none(v)
            cols[name].append(v)
    return pa.Table.from_pydict(cols, schema=FAULT_SCHEMA)


def parquet_options(schema: pa.Schema) -> dict[str, Any]:
    """Parquet writer options of every data set file (see the module docstring)."""
    floats = [f.name for f in schema if pa.types.is_floating(f.type)]
    stats = [n for n in ("flight", "TimeUS") if n in schema.names]
    return {"compression": "zstd", "use_dictionary": False,
            "use_byte_stream_split": floats or False, "write_statistics": stats or False}


def to_parquet_bytes(table: pa.Table) -> bytes:
    """Parquet file bytes of ``table`` (zstd, see the module docstring for the encoding)."""
    buf = io.BytesIO()
    pq.write_table(table, buf, **parquet_options(table.schema))
    return buf.getvalue()
