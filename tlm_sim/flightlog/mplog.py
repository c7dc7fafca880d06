"""Mission Planner's text export of a DataFlash log (the ``.log`` of "Convert .Bin to .Log").

The paper (§4.2) converted its SITL logs to text in Mission Planner and cut the per-message
tables out of that. This module writes the same text from a FlightLog and reads it back
(``ardupilot-reference.md`` §5.7):

* one line per message, CRLF, fields joined by ``", "``; first field the message name, then
  the fields in FMT order; the FMT lines come first and name the columns;
* integers as integers; ``f``/``d``/``g`` as .NET prints a float by default (shortest
  round-trip decimal, no trailing ``.0``, ``E`` exponents such as ``1E-05``, ``NaN``);
* ``c C e E`` divided by 100 with exactly two decimals; ``L`` divided by 1e7 as the
  shortest decimal of the double; ``M`` (flight mode) as the ArduCopter mode name (pymavlink's
  ``mode_mapping_acm``); strings without their zero padding.

Message order is the ``.bin`` writer's (``binwriter.message_stream``/``merge_order``), so the
text and the ``.bin`` of a flight list the same messages in the same order.

pymavlink's own text reader (``DFReader_text``) skips lines whose mode is a name, so
``read_mp_log`` is the reader for these files: it parses every line with the FMT layouts and
returns canonical tables (equal to the FlightLog's within the text's precision: exact for all
but ``f`` values printed in exponent form beyond float32 round trip, which .NET's format keeps
exact as well).
"""

from __future__ import annotations

import os
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from tlm_sim.ardupilot import MODE_NAMES

from .binwriter import merge_order, message_stream
from .quantise import quantise_frame
from .schema import FORMAT_CHARS, SCHEMAS, MessageSchema, schema_from_fmt

__all__ = ["write_mp_log", "read_mp_log", "format_column"]

_MODE_NUMBERS = {v: k for k, v in MODE_NAMES.items()}
SEP = ", "
EOL = "\r\n"


def _dotnet_float(text: str) -> str:
    """.NET's default float text from Python/numpy's shortest repr ("90.0" → "90")."""
    if text in ("nan", "-nan"):
        return "NaN"
    if text in ("inf", "-inf"):
        return text.replace("inf", "∞")
    if "e" in text:
        mant, exp = text.split("e")
        if mant.endswith(".0"):
            mant = mant[:-2]
        sign = "-" if exp.startswith("-") else "+"
        return f"{mant}E{sign}{exp.lstrip('+-').zfill(2)}"
    return text[:-2] if text.endswith(".0") else text


def format_column(values: Any, char: str) -> list[str]:
    """Mission Planner text of one canonical table column of format character ``char``."""
    kind = FORMAT_CHARS[char].kind
    v = np.asarray(values) if kind not in ("str", "array") else list(values)
    if char == "M":
        return [MODE_NAMES.get(int(x), str(int(x))) for x in v]
    if kind == "int":
        return v.astype(np.int64).astype(str).tolist()
    if char == "f":
        return [_dotnet_float(t) for t in v.astype(np.float32).astype(str).tolist()]
    if char == "g":
        return [_dotnet_float(t) for t in v.astype(np.float16).astype(str).tolist()]
    if kind == "float" or char == "L":
        return [_dotnet_float(repr(float(x))) for x in v]
    if kind == "scaled":
        return [format(x, ".2f") for x in v.tolist()]
    if kind == "array":
        return [" ".join(str(int(x)) for x in a) for a in v]
    return [str(x) for x in v]


def _lines(name: str, schema: MessageSchema, df: pd.DataFrame) -> list[str]:
    cols = [format_column(df[c].to_numpy() if FORMAT_CHARS[f].kind not in ("str", "array")
                          else df[c].tolist(), f)
            for c, f in zip(schema.columns, schema.fmt, strict=True)]
    return [SEP.join((name, *fields)) for fields in zip(*cols, strict=True)]


def write_mp_log(log: Any, path: str | os.PathLike) -> Path:
    """Write ``log`` (a FlightLog) as Mission Planner's DataFlash text log; returns the path."""
    preamble, timed = message_stream(log)
    out: list[str] = []
    for _, schema, df in preamble:
        out += _lines(schema.name, schema, df)
    timed = [(t, s, df) for t, s, df in timed if len(df)]
    if timed:
        lines = [ln for _, s, df in timed for ln in _lines(s.name, s, df)]
        order = merge_order([df for _, _, df in timed])
        out += [lines[k] for k in order]
    p = Path(path)
    tmp = p.with_name(p.name + ".part")
    tmp.write_text(EOL.join(out) + EOL, encoding="utf-8", newline="")
    os.replace(tmp, p)
    return p


def _parse_value(text: str, char: str) -> Any:
    kind = FORMAT_CHARS[char].kind
    if char == "M" and not text.lstrip("-").isdigit():
        return _MODE_NUMBERS[text]
    if kind == "int":
        return int(text)
    if kind in ("str", "array"):
        return text
    return float(text.replace("∞", "inf").replace("NaN", "nan"))


def read_mp_log(path: str | os.PathLike) -> dict[str, pd.DataFrame]:
    """Tables of a Mission Planner text log (as written by ``write_mp_log``), by message name.

    Raises:
        ValueError: a line names a message without an earlier FMT line, or has the wrong
            number of fields (with the line number).
    """
    schemas: dict[str, MessageSchema] = {}
    rows: dict[str, list[list[Any]]] = defaultdict(list)
    with open(path, encoding="utf-8", newline="") as fh:
        for lineno, raw in enumerate(fh, 1):
            line = raw.rstrip("\r\n")
            if not line:
                continue
            name, _, rest = line.partition(SEP)
            if name == "FMT":
                parts = rest.split(SEP, 4)
                ftype, length, fname, fmt, cols = parts
                schemas[fname] = (SCHEMAS[fname] if fname in SCHEMAS
                                  and SCHEMAS[fname].fmt == fmt else
                                  schema_from_fmt(fname, fmt, cols))
                rows["FMT"].append([int(ftype), int(length), fname, fmt, cols])
                continue
            schema = schemas.get(name)
            if schema is None:
                raise ValueError(f"{path}:{lineno}: message {name!r} before its FMT line")
            fields = rest.split(SEP) if rest else [""]
            if len(fields) != len(schema.fmt):
                if FORMAT_CHARS[schema.fmt[-1]].kind == "str" and len(fields) > len(schema.fmt):
                    k = len(schema.fmt) - 1  # a text field that itself holds ", "
                    fields = fields[:k] + [SEP.join(fields[k:])]
                else:
                    raise ValueError(f"{path}:{lineno}: {name} has {len(fields)} fields, "
                                     f"FMT says {len(schema.fmt)}")
            rows[name].append([_parse_value(t, c) for t, c in
                               zip(fields, schema.fmt, strict=True)])
    out = {}
    for name, r in rows.items():
        schema = schemas.get(name, SCHEMAS["FMT"] if name == "FMT" else None)
        df = pd.DataFrame(r, columns=list(schema.columns))
        out[name] = quantise_frame(df, schema)
    return out
