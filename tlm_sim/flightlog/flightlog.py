"""FlightLog: one flight's message tables (pandas) plus its parameters, mission and fault records.

Simulator contract (``FlightLog.from_buffers``)
-----------------------------------------------
For every message in ``LOGGED_MESSAGES`` the numba loop fills a float64 array
``[max_rows, len(SCHEMAS[name].columns)]``, one row per logged message (one row per instance,
with the instance number in the instance column), columns in schema order, values already in
the table units of ``tlm_sim.flightlog.schema`` (the units pymavlink shows: Lat/Lng in degrees,
GPS.Alt in metres, HDop 1.21, XKF1.Roll in degrees, CTUN.CRt in cm/s, MAG in mGauss). TimeUS is
float64 microseconds since boot (exact below 2**53). String fields (n/N/Z) are left 0.
The loop returns how many rows of each buffer it filled. ``from_buffers`` slices to the counts,
quantises every column to its format character (``tlm_sim.flightlog.quantise``) and sorts each
table stably by TimeUS.

Table dtypes: integer characters → numpy integers (B uint8, b int8, h int16, H uint16, i int32,
I uint32, q/Q int64, M uint8); f → float64 holding the exact float32 value; c/C/e/E/L → float64
(raw/100, raw/1e7); d → float64; strings → pandas' string dtype (object on pandas 2).

Folder layout (``write``/``read``)
----------------------------------
``DIR/<NAME>.csv`` and/or ``DIR/<NAME>.parquet`` per non-empty table, optionally the whole
flight as an ArduPilot DataFlash log ``DIR/flight.bin`` (``tlm_sim.flightlog.binwriter``), and
``DIR/meta.json`` with ``meta``, ``faults``, ``params`` (all), ``params_changed``, ``mission``, the
row count of every table and the layout of any table whose schema is not in ``SCHEMAS``.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import os
import re
from collections.abc import Iterable, Iterator, Mapping, MutableMapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .quantise import frame_from_columns, quantise_column, quantise_frame
from .schema import FORMAT_CHARS, LOGGED_MESSAGES, SCHEMAS, MessageSchema, schema_from_fmt
from .tableio import read_csv, read_parquet, write_csv, write_parquet

__all__ = [
    "BIN_NAME", "FlightLog", "LazyTables", "allocate_buffers", "is_safe_table_name",
    "to_jsonable", "write_table",
]

FORMAT_NAME = "tlm.flightlog"
FORMAT_VERSION = 1
_FORMATS = ("csv", "parquet", "bin")
#: Name of the DataFlash log ``write(..., formats=["bin"])`` puts in the folder.
BIN_NAME = "flight.bin"

#: A table name that is safe as a file name (``write`` makes ``DIR/<name>.csv``): letters,
#: digits, "_" and "-", 1-64 of them; never "/", "\\", ".", NUL or empty.
_TABLE_FILE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_-]{0,63}")


def is_safe_table_name(name: object) -> bool:
    """Whether ``name`` can become ``<name>.csv`` inside a folder without leaving it."""
    return isinstance(name, str) and _TABLE_FILE_NAME.fullmatch(name) is not None


def table_summary(df: pd.DataFrame, schema: MessageSchema
                  ) -> tuple[dict[str, Any], tuple[int, int] | None]:
    """One table's part of ``FlightLog.summary``: ({rows, columns, and with TimeUS: instances,
    rate_hz (mean per-instance message rate [Hz], None if unknown)}, (first, last TimeUS [µs])
    or None when the table has no rows or no TimeUS)."""
    info: dict[str, Any] = {"rows": len(df), "columns": len(df.columns)}
    if not len(df) or "TimeUS" not in df.columns:
        return info, None
    t = df["TimeUS"].to_numpy()
    inst = schema.instance_field
    groups = [t] if inst is None else [
        g["TimeUS"].to_numpy() for _, g in df.groupby(inst, sort=True)
    ]
    info["instances"] = len(groups)
    rates = [
        (len(g) - 1) / ((g[-1] - g[0]) * 1e-6) for g in groups
        if len(g) > 1 and g[-1] > g[0]
    ]
    info["rate_hz"] = float(np.mean(rates)) if rates else None
    return info, (int(t.min()), int(t.max()))


def write_table(out: Path, name: str, df: pd.DataFrame, schema: MessageSchema,
                formats: Iterable[str]) -> list[Path]:
    """Write one table as ``out/<name>.csv`` and/or ``.parquet`` (as ``FlightLog.write``).

    Raises:
        ValueError: ``name`` is not a safe file name (``is_safe_table_name``).
    """
    if not is_safe_table_name(name):
        raise ValueError(f"table name {name!r} is not a safe file name; not written")
    files = []
    if "csv" in formats:
        files.append(out / f"{name}.csv")
        write_csv(df, schema, files[-1])
    if "parquet" in formats:
        files.append(out / f"{name}.parquet")
        write_parquet(df, schema, files[-1])
    return files


def allocate_buffers(
    duration_s: float,
    names: Sequence[str] = LOGGED_MESSAGES,
    instances: Mapping[str, int] | None = None,
    event_rows: int = 256,
    rows: Mapping[str, int] | None = None,
) -> dict[str, np.ndarray]:
    """Zeroed float64 log buffers ``[max_rows, n_columns]`` for a flight of ``duration_s``.

    Rows: ``rate_hz × instances × duration × 1.1 + 16`` (``event_rows`` for on-event
    messages). ``instances`` overrides ``MessageSchema.instances`` per message, ``rows`` the
    row count of a buffer (an on-event message with a known bound, e.g. one per mission item).
    """
    out = {}
    for n in names:
        s = SCHEMAS[n]
        k = (instances or {}).get(n, s.instances)
        n_rows = s.max_rows(duration_s, k) if s.rate_hz > 0 else event_rows
        n_rows = int((rows or {}).get(n, n_rows))
        out[n] = np.zeros((n_rows, len(s.columns)), dtype=np.float64)
    return out


def to_jsonable(obj: Any) -> Any:
    """Plain JSON structures from numpy arrays/scalars, dataclasses, NamedTuples, Paths, and
    objects with a ``to_json()`` method (its result)."""
    if obj is None or isinstance(obj, bool | int | float | str):
        return obj
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    if callable(getattr(obj, "to_json", None)) and not isinstance(obj, type):
        return to_jsonable(obj.to_json())  # an object with a JSON form of its own (Mission)
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if hasattr(obj, "_asdict"):
        return {k: to_jsonable(v) for k, v in obj._asdict().items()}
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, pd.DataFrame):
        return obj.to_dict(orient="list")
    raise TypeError(f"cannot store {type(obj).__name__} in meta.json")


_PLAIN = (float, int, str, bool)


@functools.cache
def _format_groups(schema: MessageSchema) -> tuple[tuple[str, tuple[int, ...]], ...]:
    """Columns 1.. of ``schema`` (all but TimeUS) grouped by format character."""
    groups: dict[str, list[int]] = {}
    for k in range(1, len(schema.columns)):
        groups.setdefault(schema.fmt[k], []).append(k)
    return tuple((char, tuple(idx)) for char, idx in groups.items())


def _params_dict(params: Any) -> dict[str, Any] | None:
    if params is None:
        return None
    if isinstance(params, Mapping) and all(type(v) in _PLAIN for v in params.values()):
        return {str(k): v for k, v in params.items()}  # already JSON (fly's parameter dict)
    d = to_jsonable(params)
    if not isinstance(d, dict):
        raise TypeError("params must be a mapping, dataclass or NamedTuple of ArduPilot names")
    return d


def _params_changed(params: Any) -> dict[str, Any] | None:
    """Parameters that differ from their declared defaults (a :class:`~tlm_sim.params.Params`'
    ``changed()``, or dataclass / NamedTuple fields with defaults)."""
    if params is None:
        return None
    if callable(getattr(params, "changed", None)):  # tlm_sim.params.Params
        return dict(params.changed())
    defaults: dict[str, Any] = {}
    if dataclasses.is_dataclass(params) and not isinstance(params, type):
        for f in dataclasses.fields(params):
            if f.default is not dataclasses.MISSING:
                defaults[f.name] = f.default
            elif f.default_factory is not dataclasses.MISSING:
                defaults[f.name] = f.default_factory()
    elif hasattr(params, "_field_defaults"):
        defaults = dict(params._field_defaults)
    values = _params_dict(params) or {}
    if not defaults:
        return dict(values)  # no defaults known: all are "set"
    out = {}
    for k, v in values.items():
        if k not in defaults or to_jsonable(defaults[k]) != v:
            out[k] = v
    return out


def _json_equal(a: Any, b: Any) -> bool:
    """Equality of JSON-like structures treating NaN == NaN."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, Mapping) and isinstance(b, Mapping):
        return a.keys() == b.keys() and all(_json_equal(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(_json_equal(x, y) for x, y in zip(a, b, strict=True))
    return a == b


def _as_named(
    values: Mapping[str, Any] | Sequence[Any], what: str
) -> dict[str, Any]:
    if isinstance(values, Mapping):
        return dict(values)
    values = list(values)
    if len(values) != len(LOGGED_MESSAGES):
        raise ValueError(
            f"{what}: a sequence must follow LOGGED_MESSAGES ({len(LOGGED_MESSAGES)} entries), "
            f"got {len(values)}"
        )
    return dict(zip(LOGGED_MESSAGES, values, strict=True))


class LazyTables(MutableMapping[str, pd.DataFrame]):
    """Message name -> DataFrame, each built on first access from canonical column arrays.

    ``FlightLog.from_buffers`` fills it, so a flight whose caller reads a few tables (or
    only their columns, :meth:`FlightLog.columns`) pays for no other DataFrame. Assigning a
    DataFrame replaces the table; iteration follows insertion order.
    """

    def __init__(self, schemas: Mapping[str, MessageSchema]) -> None:
        self._schemas = schemas
        self._columns: dict[str, dict[str, np.ndarray]] = {}
        self._frames: dict[str, pd.DataFrame] = {}
        self._order: dict[str, None] = {}

    def add_columns(self, name: str, columns: dict[str, np.ndarray]) -> None:
        """Add table ``name`` as canonical columns (built into a DataFrame when read)."""
        self._columns[name] = columns
        self._frames.pop(name, None)
        self._order[name] = None

    def columns(self, name: str) -> Mapping[str, np.ndarray] | None:
        """The canonical column arrays of a table not yet built or replaced, else None."""
        return self._columns.get(name) if name not in self._frames else None

    def __getitem__(self, name: str) -> pd.DataFrame:
        df = self._frames.get(name)
        if df is None:
            df = frame_from_columns(self._schemas[name], self._columns[name])
            self._frames[name] = df
            del self._columns[name]
        return df

    def __setitem__(self, name: str, df: pd.DataFrame) -> None:
        self._frames[name] = df
        self._columns.pop(name, None)
        self._order[name] = None

    def __delitem__(self, name: str) -> None:
        del self._order[name]
        self._frames.pop(name, None)
        self._columns.pop(name, None)

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._order))

    def __len__(self) -> int:
        return len(self._order)

    def __contains__(self, name: object) -> bool:
        return name in self._order


class FlightLog:
    """Tables of one flight (ArduPilot message names and columns) plus its context.

    The constructor stores the tables as given: they must already be canonical (quantised and
    typed, as made by ``from_buffers``, ``read``, ``read_bin`` or ``quantise_frame``).

    Attributes:
        tables: message name → DataFrame (non-empty tables only; see ``table``).
        schemas: message name → MessageSchema of every table.
        params: ArduPilot parameter name → value (dict) or None.
        params_changed: parameters that differ from their declared defaults (all parameters
            when no defaults are known), or None.
        mission: the mission (any JSON-able object; plain JSON after ``read``).
        faults: fault records (Eq. 4: type, label, start/end TimeUS, start/end lat, lon, alt,
            parameters set), as dicts.
        meta: free-form flight metadata (seed, duration, tlm version, ...).
    """

    def __init__(
        self,
        tables: Mapping[str, pd.DataFrame],
        *,
        params: Any = None,
        mission: Any = None,
        faults: Iterable[Mapping[str, Any]] = (),
        meta: Mapping[str, Any] | None = None,
        schemas: Mapping[str, MessageSchema] | None = None,
        params_changed: Mapping[str, Any] | None = None,
    ) -> None:
        self.schemas: dict[str, MessageSchema] = {}
        for name in tables:
            schema = (schemas or {}).get(name) or SCHEMAS.get(name)
            if schema is None:
                raise KeyError(f"no schema for table {name!r}: pass schemas={{...}}")
            self.schemas[name] = schema
        self.tables: MutableMapping[str, pd.DataFrame]
        if isinstance(tables, LazyTables):
            self.tables = tables
        else:
            self.tables = dict(tables)
        self.params: dict[str, Any] | None = _params_dict(params)
        self.params_changed: dict[str, Any] | None = (
            dict(params_changed) if params_changed is not None else _params_changed(params)
        )
        self.mission = mission
        self.faults: list[dict[str, Any]] = [
            to_jsonable(f) if not isinstance(f, dict) else dict(f) for f in faults
        ]
        self.meta: dict[str, Any] = dict(meta or {})

    # --- construction -----------------------------------------------------------------------
    @classmethod
    def from_buffers(
        cls,
        buffers: Mapping[str, np.ndarray] | Sequence[np.ndarray],
        counts: Mapping[str, int] | Sequence[int] | np.ndarray,
        *,
        params: Any = None,
        mission: Any = None,
        faults: Iterable[Mapping[str, Any]] = (),
        meta: Mapping[str, Any] | None = None,
    ) -> FlightLog:
        """Build a FlightLog from the simulator's float64 log buffers (see module docstring).

        Args:
            buffers: name → array ``[max_rows, len(SCHEMAS[name].columns)]``, or a sequence
                in ``LOGGED_MESSAGES`` order.
            counts: name → rows filled (or a sequence/array in ``LOGGED_MESSAGES`` order).
            params, mission, faults, meta: stored as given (see class docstring).
        Returns:
            a FlightLog whose tables are quantised, typed and sorted stably by TimeUS; tables
            with 0 rows are left out.
        """
        bufs = _as_named(buffers, "buffers")
        cnts = _as_named(counts, "counts")
        tables = LazyTables(SCHEMAS)
        for name, buf in bufs.items():
            if name not in SCHEMAS:
                raise KeyError(f"unknown message {name!r}")
            schema = SCHEMAS[name]
            if name not in cnts:
                raise KeyError(f"no row count for {name}")
            n = int(cnts[name])
            buf = np.asarray(buf)
            if buf.ndim != 2 or buf.shape[1] != len(schema.columns):
                raise ValueError(
                    f"{name}: buffer shape {buf.shape}, expected (rows, {len(schema.columns)})"
                )
            if not 0 <= n <= buf.shape[0]:
                raise ValueError(f"{name}: count {n} outside 0..{buf.shape[0]}")
            if n == 0:
                continue
            rows = buf[:n]
            t = quantise_column(rows[:, 0], schema.fmt[0])
            if n < 2 or bool(np.all(t[1:] >= t[:-1])):  # logged in time order (the usual)
                by_col = rows.T  # by_col[k] = column k in TimeUS order
            else:
                order = np.argsort(t, kind="stable")
                t = t[order]
                by_col = rows[order].T  # one gather
            out = {schema.columns[0]: t}
            for char, idx in _format_groups(schema):
                if FORMAT_CHARS[char].kind in ("str", "array"):
                    for k in idx:
                        out[schema.columns[k]] = quantise_column(by_col[k], char)
                else:  # elementwise: the columns of one format character in one call
                    block = quantise_column(by_col[list(idx)], char)  # a C-ordered copy
                    for j, k in enumerate(idx):
                        out[schema.columns[k]] = block[j]
            tables.add_columns(name, {c: out[c] for c in schema.columns})
        return cls(tables, params=params, mission=mission, faults=faults, meta=meta)

    @classmethod
    def from_bin(cls, path: str | os.PathLike, types: Iterable[str] | None = None) -> FlightLog:
        """FlightLog of a DataFlash ``.bin`` log, read in one pass (``binreader.read_log``).

        Tables as ``read_bin`` (all types when ``types`` is None), parameters at log start from
        PARM, the mission as CMD items (``mission_from_cmd``), the fault records of the sidecar
        beside the log, else of the log itself (``sidecar.log_faults``: ``<log>.json``, tlm
        fly's ``faults.json``, tlm's fault MSG lines or SIM_* parameter changes; where from in
        ``meta["faults_source"]``), and in ``meta`` the source path and what the reader found
        (size, message counts, skipped or damaged bytes).
        """
        from .binreader import read_log
        from .sidecar import log_faults

        log = read_log(path, None if types is None else list(types))
        tables = {n: df for n, df in log.tables.items() if len(df)}
        faults, source = log_faults(path, log.messages, log.param_changes)
        return cls(tables, params=log.params, mission=log.mission, faults=faults,
                   schemas={n: log.schemas[n] for n in tables},
                   meta={"source": os.fspath(path), **log.info, "faults_source": source})

    # --- access -------------------------------------------------------------------------------
    def columns(self, name: str) -> Mapping[str, np.ndarray]:
        """Table ``name`` as column name -> numpy array, without building its DataFrame when
        it has not been built yet (``from_buffers``); KeyError if the flight logged none."""
        if isinstance(self.tables, LazyTables):
            cols = self.tables.columns(name)
            if cols is not None:
                return cols
        df = self.tables[name]
        return {c: df[c].to_numpy() for c in df.columns}

    def n_rows(self, name: str) -> int:
        """Rows of table ``name`` (0 if the flight logged none)."""
        if name not in self.tables:
            return 0
        if isinstance(self.tables, LazyTables):
            cols = self.tables.columns(name)
            if cols is not None:
                return len(next(iter(cols.values()))) if cols else 0
        return len(self.tables[name])

    def table(self, name: str) -> pd.DataFrame:
        """Table ``name``; an empty, correctly typed table if the flight logged none."""
        if name in self.tables:
            return self.tables[name]
        schema = self.schemas.get(name) or SCHEMAS.get(name)
        if schema is None:
            raise KeyError(f"unknown message {name!r}")
        return quantise_frame(pd.DataFrame({c: [] for c in schema.columns}), schema)

    def __contains__(self, name: object) -> bool:
        return name in self.tables

    def __repr__(self) -> str:
        rows = ", ".join(f"{n}={self.n_rows(n)}" for n in self.tables)
        return f"FlightLog({rows}; faults={len(self.faults)})"

    def summary(self) -> dict[str, Any]:
        """Row counts, per-instance rates, time span, faults and meta, as a dict."""
        tables: dict[str, dict[str, Any]] = {}
        t0, t1 = None, None
        for name, df in self.tables.items():
            info, span = table_summary(df, self.schemas[name])
            if span is not None:
                t0 = span[0] if t0 is None else min(t0, span[0])
                t1 = span[1] if t1 is None else max(t1, span[1])
            tables[name] = info
        return {
            "tables": tables,
            "time_us": [t0, t1],
            "duration_s": (t1 - t0) * 1e-6 if t0 is not None else 0.0,
            "faults": [
                {k: f.get(k) for k in ("type", "label", "start_time_us", "end_time_us")}
                for f in self.faults
            ],
            "params": None if self.params is None else len(self.params),
            "meta": dict(self.meta),
        }

    def equals(self, other: FlightLog) -> bool:
        """True when tables (values and dtypes), params, mission, faults and meta are equal."""
        if self.tables.keys() != other.tables.keys():
            return False
        for n, df in self.tables.items():
            o = other.tables[n]
            if list(df.columns) != list(o.columns) or not df.dtypes.equals(o.dtypes):
                return False
            if not df.reset_index(drop=True).equals(o.reset_index(drop=True)):
                return False
        return all(
            _json_equal(to_jsonable(a), to_jsonable(b))
            for a, b in (
                (self.params, other.params),
                (self.params_changed, other.params_changed),
                (self.mission, other.mission),
                (self.faults, other.faults),
                (self.meta, other.meta),
            )
        )

    # --- files --------------------------------------------------------------------------------
    def write(self, out_dir: str | os.PathLike, formats: Iterable[str] = _FORMATS) -> Path:
        """Write ``DIR/<NAME>.csv`` / ``.parquet`` per non-empty table and ``DIR/meta.json``.

        Args:
            out_dir: folder (created if missing). Existing files of the same names are
                overwritten.
            formats: any of "csv", "parquet", "bin" (``DIR/flight.bin``).
        Returns:
            the folder.
        Raises:
            ValueError: an unknown format, or a table name that is not a safe file name
                (``is_safe_table_name``: it could write outside ``out_dir``); nothing is
                written then.
        """
        formats = tuple(formats)
        bad = [f for f in formats if f not in _FORMATS]
        if bad or not formats:
            raise ValueError(f"unknown formats {bad or formats}; use any of {', '.join(_FORMATS)}")
        unsafe = [n for n in self.tables if not is_safe_table_name(n)]
        if unsafe:
            raise ValueError(f"table name(s) {', '.join(map(repr, unsafe))} are not safe file "
                             "names (letters, digits, '_', '-'); nothing written")
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        rows = {}
        for name, df in self.tables.items():
            if len(df) == 0:
                continue
            write_table(out, name, df, self.schemas[name], formats)
            rows[name] = len(df)
        if "bin" in formats:
            self.write_bin(out / BIN_NAME)
        self.write_meta(out, rows)
        return out

    def write_meta(self, out: Path, rows: Mapping[str, int],
                   schemas: Mapping[str, MessageSchema] | None = None) -> Path:
        """Write ``out/meta.json`` (what ``read`` needs besides the table files).

        Args:
            out: the folder (exists).
            rows: name → rows of each table file written.
            schemas: the tables' schemas (default ``self.schemas``); those not in the registry,
                or differing from it, are stored.
        Returns:
            the meta.json path.
        """
        extra = {
            n: {"fmt": s.fmt, "columns": list(s.columns), "units": s.units, "mults": s.mults}
            for n, s in (self.schemas if schemas is None else schemas).items()
            if n in rows and SCHEMAS.get(n) != s
        }
        doc = {
            "format": FORMAT_NAME,
            "format_version": FORMAT_VERSION,
            "meta": to_jsonable(self.meta),
            "faults": to_jsonable(self.faults),
            "params": self.params,
            "params_changed": self.params_changed,
            "mission": to_jsonable(self.mission),
            "tables": dict(rows),
            "schemas": extra,
        }
        path = out / "meta.json"
        path.write_text(json.dumps(doc, indent=1) + "\n")
        return path

    def write_bin(self, path: str | os.PathLike) -> Path:
        """Write the flight as an ArduPilot DataFlash ``.bin`` (see ``binwriter``)."""
        from .binwriter import write_bin

        return write_bin(self, path)

    @classmethod
    def read(cls, in_dir: str | os.PathLike) -> FlightLog:
        """Read a folder written by ``write`` (Parquet preferred, CSV where no Parquet, the
        tables of ``flight.bin`` when the folder holds neither)."""
        d = Path(in_dir)
        if not d.is_dir():
            raise FileNotFoundError(f"no such flight-log folder: {d}")
        meta_path = d / "meta.json"
        doc: dict[str, Any] = json.loads(meta_path.read_text()) if meta_path.exists() else {}
        schemas = dict(SCHEMAS)
        for n, s in (doc.get("schemas") or {}).items():
            schemas[n] = schema_from_fmt(n, s["fmt"], tuple(s["columns"]), s["units"],
                                         s["mults"])
        names = sorted({p.stem for p in d.glob("*.parquet")} | {p.stem for p in d.glob("*.csv")})
        order = list(doc.get("tables") or {})
        names = [n for n in order if n in names] + [n for n in names if n not in order]
        tables = {}
        if not names and (d / BIN_NAME).exists():
            from .binreader import read_bin

            wanted = list(doc.get("tables") or LOGGED_MESSAGES)
            tables = {n: df for n, df in read_bin(d / BIN_NAME, wanted).items() if len(df)}
        for n in names:
            if n not in schemas:
                continue  # not a table of ours
            pq_path, csv_path = d / f"{n}.parquet", d / f"{n}.csv"
            if pq_path.exists():
                tables[n] = read_parquet(pq_path, schemas[n])
            else:
                tables[n] = read_csv(csv_path, schemas[n])
        return cls(
            tables,
            params=doc.get("params"),
            params_changed=doc.get("params_changed"),
            mission=doc.get("mission"),
            faults=doc.get("faults") or (),
            meta=doc.get("meta"),
            schemas={n: schemas[n] for n in tables},
        )
