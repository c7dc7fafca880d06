"""Quantise table columns to what their DataFlash format character can store.

``quantise_column(values, char)`` returns the canonical table column for one field, so that a
simulator buffer, a CSV file, a Parquet file, a .bin file and the reference-log reader all hold
bit-identical values:

* ``f`` → the float32 value (held in a float64 column); ``g`` → the float16 value; ``d`` as is.
* ``c C e E`` → raw = rint(value × 100) clipped to the raw integer range (NaN → 0);
  value = raw / 100 (float64, the correctly rounded decimal, exactly what pymavlink returns).
* ``L`` → raw = rint(value × 1e7) clipped to int32 (NaN → 0); value = raw / 1e7 (degrees).
* integers (b B h H i I q Q M) → rint, clipped to the type's range (NaN → 0), integer dtype
  (``Q`` is int64).
* strings (n N Z) → ``str``, truncated to the field width in UTF-8 bytes; numbers (the
  simulator leaves 0 there), None and NaN become "".
* ``a`` (int16[32]) → an object column of int16 arrays of length 32.

Rounding is round-half-to-even (``np.rint``). Quantising is idempotent.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from .schema import FORMAT_CHARS, MessageSchema

__all__ = [
    "quantise_column", "raw_to_column", "column_to_raw", "quantise_frame", "frame_from_columns",
]

_STR_WIDTH = {"n": 4, "N": 16, "Z": 64}


def _float_bounds(lo: int, hi: int) -> tuple[float, float]:
    """Largest float64 interval inside [lo, hi] (64-bit bounds are not exact floats)."""
    flo, fhi = float(lo), float(hi)
    if int(fhi) > hi:
        fhi = math.nextafter(fhi, 0.0)
    if int(flo) < lo:
        flo = math.nextafter(flo, 0.0)
    return flo, fhi


def _to_raw_int(
    values: np.ndarray, divisor: float, lo: int, hi: int, dtype: np.dtype
) -> np.ndarray:
    """Round ``values × divisor`` to the nearest integer in [lo, hi] (NaN → 0) as ``dtype``."""
    if values.dtype.kind in "iub" and divisor == 1.0:
        if values.dtype == np.uint64:
            values = np.minimum(values, np.uint64(hi))
        return np.clip(values.astype(np.int64), lo, hi).astype(dtype)
    x = np.asarray(values, dtype=np.float64)
    if divisor != 1.0:
        with np.errstate(over="ignore"):
            x = x * divisor
    x = np.rint(x)
    x[np.isnan(x)] = 0.0
    flo, fhi = _float_bounds(lo, hi)
    np.clip(x, flo, fhi, out=x)
    return x.astype(dtype)


def _to_str(values: Sequence | np.ndarray, width: int) -> np.ndarray:
    out = np.empty(len(values), dtype=object)
    for k, v in enumerate(values):
        if isinstance(v, bytes | bytearray):
            b = bytes(v)
        elif isinstance(v, str):
            b = v.encode("utf-8")
        else:  # numbers (simulator placeholder 0), None, NaN
            b = b""
        b = b[:width].split(b"\0", 1)[0]
        try:
            out[k] = b.decode("utf-8")
        except UnicodeDecodeError:  # as pymavlink: fall back to Latin-1
            out[k] = b.decode("latin-1")
    return out


def _to_int16_arrays(values: Sequence | np.ndarray) -> np.ndarray:
    """Object column of int16[32] arrays (format ``a``) from bytes, sequences or text."""
    out = np.empty(len(values), dtype=object)
    for k, v in enumerate(values):
        if isinstance(v, bytes | bytearray):
            a = np.frombuffer(bytes(v), dtype="<i2")
        elif isinstance(v, str):
            a = np.array([int(x) for x in v.split()], dtype=np.int64)
        else:
            a = np.asarray(v, dtype=np.float64)
            a = np.clip(np.nan_to_num(np.rint(a)), -32768, 32767)
        b = np.zeros(32, dtype=np.int16)
        b[: min(32, a.size)] = np.asarray(a).reshape(-1)[:32]
        out[k] = b
    return out


def quantise_column(values: Sequence | np.ndarray, char: str) -> np.ndarray:
    """Canonical table column for values of format character ``char`` (see module docstring).

    Args:
        values: table values (DataFrame units) or simulator buffer column.
        char: ArduPilot format character.
    Returns:
        a new numpy array with dtype ``FORMAT_CHARS[char].dtype``.
    """
    fc = FORMAT_CHARS[char]
    if fc.kind == "str":
        return _to_str(values, _STR_WIDTH[char])
    if fc.kind == "array":
        return _to_int16_arrays(values)
    arr = np.asarray(values)
    if fc.kind == "float":
        x = arr.astype(np.float64, copy=False)
        if char == "f":
            with np.errstate(over="ignore"):
                return x.astype(np.float32).astype(np.float64)
        if char == "g":
            with np.errstate(over="ignore"):
                return x.astype(np.float16).astype(np.float64)
        return x.copy()
    if fc.kind == "int":
        return _to_raw_int(arr, 1.0, fc.lo, fc.hi, fc.dtype)
    # scaled integer: raw / divisor, the correctly rounded decimal (pymavlink divides too)
    div = _divisor(fc.reader_scale)
    return _to_raw_int(arr, div, fc.lo, fc.hi, np.dtype(np.int64)) / div


def _divisor(scale: float) -> float:
    return 100.0 if scale == 0.01 else 1e7


def raw_to_column(raw: np.ndarray | Sequence, char: str) -> np.ndarray:
    """Table column from *raw stored* values (as unpacked from a .bin payload)."""
    fc = FORMAT_CHARS[char]
    if fc.kind == "str":
        return _to_str(raw, _STR_WIDTH[char])
    if fc.kind == "array":
        return _to_int16_arrays(raw)
    arr = np.asarray(raw)
    if fc.kind == "scaled":
        return arr.astype(np.float64) / _divisor(fc.reader_scale)
    if char == "M":  # pymavlink unpacks M signed
        return (arr.astype(np.int64) & 0xFF).astype(np.uint8)
    if fc.kind == "float":
        return arr.astype(np.float64)
    if char == "Q" and arr.dtype == np.uint64:
        return np.minimum(arr, np.uint64(fc.hi)).astype(np.int64)
    return arr.astype(fc.dtype)


def column_to_raw(values: Sequence | np.ndarray, char: str) -> np.ndarray:
    """Raw stored values of a canonical table column (inverse of ``raw_to_column``).

    Numbers come back as the little-endian numpy type of the .bin field (``c`` → int16 of
    value × 100, ``L`` → int32 of value × 1e7, ``f`` → float32, ``Q`` → uint64, ...), strings
    as fixed-width zero-padded bytes (``S4``/``S16``/``S64``, UTF-8, truncated), ``a`` arrays
    as int16[32] rows. Values outside the field's range are clipped, NaN integers become 0,
    exactly as ``quantise_column`` does, so ``raw_to_column(column_to_raw(v, c), c)`` equals
    ``quantise_column(v, c)``.
    """
    fc = FORMAT_CHARS[char]
    if fc.kind == "str":
        width = _STR_WIDTH[char]
        return np.array(
            [s.encode("utf-8")[:width] for s in _to_str(values, width)], dtype=f"S{width}"
        )
    if fc.kind == "array":
        arrays = _to_int16_arrays(values)
        return np.stack(list(arrays)) if len(arrays) else np.zeros((0, 32), dtype=np.int16)
    arr = np.asarray(values)
    raw_dtype = np.dtype("<" + fc.struct if fc.struct not in ("b", "B") else fc.struct)
    if fc.kind == "float":
        with np.errstate(over="ignore"):
            return arr.astype(np.float64, copy=False).astype(raw_dtype)
    if char == "Q":  # tables hold Q as int64
        return _to_raw_int(arr, 1.0, 0, 2**63 - 1, np.dtype(np.int64)).astype(np.uint64)
    div = 1.0 if fc.kind == "int" else _divisor(fc.reader_scale)
    return _to_raw_int(arr, div, fc.lo, fc.hi, raw_dtype)


def frame_from_columns(schema: MessageSchema, columns: dict[str, np.ndarray]) -> pd.DataFrame:
    """DataFrame with the schema's columns, in order, from already canonical arrays."""
    return pd.DataFrame({c: columns[c] for c in schema.columns}, columns=list(schema.columns))


def quantise_frame(df: pd.DataFrame, schema: MessageSchema) -> pd.DataFrame:
    """Canonical table for ``schema`` from a DataFrame holding its columns (any dtypes)."""
    missing = [c for c in schema.columns if c not in df.columns]
    if missing:
        raise ValueError(f"{schema.name}: missing columns {missing}")
    cols = {
        c: quantise_column(df[c].to_numpy(), f)
        for c, f in zip(schema.columns, schema.fmt, strict=True)
    }
    return frame_from_columns(schema, cols)
