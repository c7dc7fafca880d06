"""Feature processing (paper Algorithm 2): drop time-related and non-universal columns.

For each data table the columns below are deleted, each for a reason; what is left is the
table's feature set. ``flight``, ``label`` and ``TimeUS`` stay as non-feature columns
(``TimeUS`` for plots and checks only, never a feature).

Instances. IMU and VIBE log one row per IMU (instances 0 and 1, 25 Hz and 10 Hz each); GPS
logs instance 0 only. The pipeline keeps **instance 0 only** and drops the instance column,
because the paper's tables were built that way: Table 7 has 12,773 IMU rows for 2,555 GPS rows
(5.00x, IMU 25 Hz / GPS 5 Hz: one instance) and 5,109 VIBE rows for 5,109 RATE rows (1.00x,
both 10 Hz: one instance); with both instances they would be 10x and 2x. Both IMUs fail together
in the accelerometer fault and read the same constant, so the second adds little. Keeping both
instances as rows (with the instance as a feature) would mix two sensors with different noise
in one column; splitting them into IMU0/IMU1 tables would double the tables. ``instance=None``
keeps every row and the instance column (as a non-feature column) for experiments.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import MappingProxyType

import numpy as np
import pandas as pd

from tlm_process.pipeline.errors import PipelineError

__all__ = [
    "DROP",
    "INSTANCE_COLUMN",
    "NON_FEATURE",
    "TIME_COLUMNS",
    "feature_columns",
    "feature_table",
    "merge_tables",
    "trim_to_span",
]

#: Columns kept beside the features; never features.
NON_FEATURE: tuple[str, ...] = ("flight", "TimeUS", "label")

#: Time-related columns of any table (deleted wherever they appear; TimeUS is kept as a
#: non-feature column).
TIME_COLUMNS: Mapping[str, str] = MappingProxyType({
    "timestamp": "wall-clock time (mavlogdump CSV): only marks when the row was written",
    "TimeMS": "milliseconds since boot (older logs): marks where the row is in the log",
})

#: Instance column per table (one row per sensor instance).
INSTANCE_COLUMN: Mapping[str, str] = MappingProxyType({"GPS": "I", "IMU": "I", "VIBE": "IMU"})

#: Per-table columns deleted by Algorithm 2, with the reason (time-related or not universal).
DROP: Mapping[str, Mapping[str, str]] = MappingProxyType({
    "GPS": MappingProxyType({
        "I": "instance number: the log has one GPS (always 0)",
        "GMS": "time-related: GPS milliseconds of the week, a clock",
        "GWk": "time-related: GPS week number, a calendar date",
        "Lat": "not universal: where the vehicle is (paper 4.4: a UAV does not fail because "
               "it reached a latitude)",
        "Lng": "not universal: where the vehicle is (longitude)",
        "Alt": "not universal: altitude above mean sea level = the site's elevation (584 m at "
               "the SITL home) plus the height flown",
        "Yaw": "not universal: heading from a dual-antenna (moving-baseline) receiver, 0 with "
               "a single antenna: a property of the receiver",
        "U": "not universal: whether this receiver is the one in use, a configuration flag",
    }),
    "IMU": MappingProxyType({
        "I": "instance number: instance 0 kept only (see the module docstring)",
        "EG": "time-related: gyro error count, cumulative since boot",
        "EA": "time-related: accelerometer error count, cumulative since boot",
        "T": "time-related / not universal: IMU temperature follows the board's warm-up after "
             "boot and the weather, not the flight",
        "GHz": "not universal: the gyro's sample rate, a property of the sensor chip",
        "AHz": "not universal: the accelerometer's sample rate, a property of the sensor chip",
    }),
    "RATE": MappingProxyType({}),
    "VIBE": MappingProxyType({
        "IMU": "instance number: instance 0 kept only (see the module docstring)",
        "Clip": "time-related: clipping count, cumulative since boot (a crash early in the "
                "flight would mark every later normal row)",
    }),
})


def trim_to_span(tables: Mapping[str, pd.DataFrame],
                 span: tuple[int, int] | None) -> dict[str, pd.DataFrame]:
    """Rows with ``span[0] <= TimeUS <= span[1]`` of every table (all rows for None)."""
    if span is None:
        return dict(tables)
    return {n: df[(df["TimeUS"] >= span[0]) & (df["TimeUS"] <= span[1])].reset_index(drop=True)
            for n, df in tables.items()}


def feature_columns(name: str, columns: Sequence[str]) -> list[str]:
    """The feature columns of table ``name`` with the given columns: all but the non-feature,
    time-related and ``DROP[name]`` columns (the instance column is not a feature either
    way)."""
    if name not in DROP:
        raise PipelineError(f"no feature list for table {name!r}; known: {', '.join(DROP)}")
    skip = set(NON_FEATURE) | set(TIME_COLUMNS) | set(DROP[name])
    inst = INSTANCE_COLUMN.get(name)
    if inst is not None:
        skip.add(inst)
    return [c for c in columns if c not in skip]


def feature_table(name: str, df: pd.DataFrame, flight_id: str,
                  instance: int | None = 0) -> pd.DataFrame:
    """One flight's table as ``flight, TimeUS, label, <features...>`` (Algorithm 2).

    ``df`` needs ``TimeUS`` and ``label``. ``instance``: keep rows of this sensor instance only
    (default 0, see the module docstring); None keeps all rows and the instance column (as a
    non-feature column right after ``label``)."""
    for col in ("TimeUS", "label"):
        if col not in df.columns:
            raise PipelineError(f"{name} has no {col!r} column", source=flight_id)
    inst = INSTANCE_COLUMN.get(name)
    if inst is not None and inst in df.columns and instance is not None:
        df = df[df[inst] == instance]
    feats = feature_columns(name, list(df.columns))
    bad = [c for c in feats if not pd.api.types.is_numeric_dtype(df[c])]
    if bad:
        raise PipelineError(f"{name} column(s) {', '.join(bad)} are not numeric; features "
                            "must be numbers", source=flight_id)
    cols: dict[str, object] = {
        "flight": pd.Series(flight_id, index=df.index, dtype="string"),
        "TimeUS": df["TimeUS"].astype(np.int64),
        "label": df["label"].astype(np.int8),
    }
    if inst is not None and instance is None and inst in df.columns:
        cols[inst] = df[inst].astype(np.int8)
    for c in feats:
        cols[c] = df[c].astype(np.float64)
    return pd.DataFrame(cols).reset_index(drop=True)


def merge_tables(per_flight: Sequence[Mapping[str, pd.DataFrame]]) -> dict[str, pd.DataFrame]:
    """Merge flights per table (rows of flight 1, then flight 2, ...). Every flight must have
    the same columns in each table; a difference is an error naming the flight."""
    out: dict[str, pd.DataFrame] = {}
    names = list(dict.fromkeys(n for tables in per_flight for n in tables))
    for name in names:
        frames = []
        ref_cols: list[str] | None = None
        ref_flight = ""
        for tables in per_flight:
            df = tables.get(name)
            if df is None:
                continue
            fid = str(df["flight"].iloc[0]) if len(df) else "?"
            if ref_cols is None:
                ref_cols, ref_flight = list(df.columns), fid
            elif list(df.columns) != ref_cols:
                extra = sorted(set(df.columns) - set(ref_cols))
                missing = sorted(set(ref_cols) - set(df.columns))
                raise PipelineError(
                    f"{name} columns differ from flight {ref_flight}'s (extra: "
                    f"{', '.join(extra) or '-'}; missing: {', '.join(missing) or '-'})",
                    source=fid)
            frames.append(df)
        out[name] = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    return out
