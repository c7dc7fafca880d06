"""CSV and Parquet files of one message table each (values exact to the format character).

CSV: header = ArduPilot column names, one row per message, no index. Numbers are written so
that reading them back and re-quantising gives bit-identical tables:

* integers as integers;
* ``f`` (float32) as the shortest decimal that round-trips the float32 ("0.1", "1e-05",
  "nan", "inf"); ``g`` likewise for float16; ``d`` as the shortest float64 round-trip decimal;
* ``c C e E`` with exactly two decimals ("584.12"), ``L`` with seven ("-35.3632610");
* strings as text (quoted by the CSV writer where needed); ``a`` arrays as 32
  space-separated integers.

Parquet (pyarrow, zstd): ``f`` columns are stored as float32, everything else in its table
dtype; the schema (fmt, units, mults) is kept in the file's key-value metadata.
"""

from __future__ import annotations

import os

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from .quantise import quantise_frame
from .schema import FORMAT_CHARS, MessageSchema

__all__ = ["write_csv", "read_csv", "write_parquet", "read_parquet"]


def _format_column(values: np.ndarray, char: str) -> np.ndarray | list[str]:
    kind = FORMAT_CHARS[char].kind
    if kind == "int":
        return values.astype(np.int64).astype(str)
    if char == "f":
        return values.astype(np.float32).astype(str)
    if char == "g":
        return values.astype(np.float16).astype(str)
    if char == "d":
        return values.astype(np.float64).astype(str)
    if kind == "scaled":
        spec = ".7f" if char == "L" else ".2f"
        return [format(v, spec) for v in values.tolist()]
    if kind == "array":
        return [" ".join(str(int(x)) for x in v) for v in values]
    return values  # strings


def write_csv(df: pd.DataFrame, schema: MessageSchema, path: str | os.PathLike) -> None:
    """Write one table as CSV (see module docstring for the number formats)."""
    text = {
        c: _format_column(df[c].to_numpy(), f)
        for c, f in zip(schema.columns, schema.fmt, strict=True)
    }
    pd.DataFrame(text, columns=list(schema.columns)).to_csv(path, index=False, lineterminator="\n")


def read_csv(path: str | os.PathLike, schema: MessageSchema) -> pd.DataFrame:
    """Read a table written by ``write_csv`` (canonical values and dtypes)."""
    dtypes: dict[str, object] = {}
    na: dict[str, list[str]] = {}
    for c, f in zip(schema.columns, schema.fmt, strict=True):
        kind = FORMAT_CHARS[f].kind
        if kind in ("str", "array"):
            dtypes[c] = str
        elif kind == "int":
            dtypes[c] = np.int64 if f != "Q" else np.uint64
        else:
            dtypes[c] = np.float64
            na[c] = ["nan", "NaN", "-nan"]
    df = pd.read_csv(path, dtype=dtypes, keep_default_na=False, na_values=na)
    return quantise_frame(df, schema)


def _schema_metadata(schema: MessageSchema) -> dict[bytes, bytes]:
    return {
        b"tlm.message": schema.name.encode(),
        b"tlm.fmt": schema.fmt.encode(),
        b"tlm.units": schema.units.encode(),
        b"tlm.mults": schema.mults.encode(),
    }


def write_parquet(df: pd.DataFrame, schema: MessageSchema, path: str | os.PathLike) -> None:
    """Write one table as Parquet (``f`` columns as float32, exact)."""
    arrays, fields = [], []
    for c, f in zip(schema.columns, schema.fmt, strict=True):
        v = df[c].to_numpy()
        kind = FORMAT_CHARS[f].kind
        if f in ("f", "g"):
            arr = pa.array(v.astype(np.float32), type=pa.float32())
        elif kind == "str":
            arr = pa.array([str(x) for x in v], type=pa.string())
        elif kind == "array":
            arr = pa.array([np.asarray(x, dtype=np.int16) for x in v], type=pa.list_(pa.int16()))
        else:
            arr = pa.array(v.astype(FORMAT_CHARS[f].dtype))
        arrays.append(arr)
        fields.append(pa.field(c, arr.type))
    pa_schema = pa.schema(fields, metadata=_schema_metadata(schema))
    table = pa.Table.from_arrays(arrays, schema=pa_schema)
    pq.write_table(table, path, compression="zstd")


def read_parquet(path: str | os.PathLike, schema: MessageSchema) -> pd.DataFrame:
    """Read a table written by ``write_parquet`` (canonical values and dtypes)."""
    table = pq.read_table(path)
    cols = {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.column_names}
    return quantise_frame(pd.DataFrame(cols), schema)


def parquet_schema(path: str | os.PathLike) -> tuple[str, str, str, str] | None:
    """(name, fmt, units, mults) stored in a tlm Parquet file's metadata, or None."""
    md = pq.read_schema(path).metadata or {}
    try:
        return tuple(md[k].decode() for k in (b"tlm.message", b"tlm.fmt", b"tlm.units",
                                               b"tlm.mults"))  # type: ignore[return-value]
    except KeyError:
        return None
