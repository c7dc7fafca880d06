"""Read a ``tlm process`` data set, and turn transfer logs into its features and scale.

A data set is the folder ``tlm process ... --out DS`` writes: ``DS/report.json`` (format
``tlm.process``: feature columns per table, processing options), ``DS/scaler.json`` and
``DS/<TABLE>.parquet`` (``flight``, ``split``, ``TimeUS``, ``label``, features).

Transfer logs (``tlm evaluate --test-on``) are any inputs ``tlm process`` reads (``.bin`` +
sidecar, tlm flight folders, ...). They are processed exactly as the data set's flights were
(the options in its report: anchoring, phase, sensor instance, RC labelling; a report without
``rc_label``, from a tlm before it, had the paper's "window") and scaled with the data set's
own scaler (fitted on its training flights), so a model trained on the data set sees them as
it would see a new flight of its own.

A transfer log must say which faults it holds: a ``.bin`` with neither a sidecar (``LOG.json``
or ``faults.json`` beside it) nor fault records of its own (tlm's fault MSG lines, a SITL
log's SIM_* parameter changes) is refused, unless the caller says such logs are normal
flights (``assume_normal``; ``tlm evaluate --assume-normal``): scoring a damaged propeller's
log as a normal flight would report a detector that never fires as perfect. A log whose
labels say "no faults" (a sidecar with an empty list) is labelled.

:func:`drop_features` takes features out of a data set (``tlm evaluate --drop-features``),
e.g. those an older firmware's logs lack (``RATE.AOutSlew``: Copter 4.0/4.1), so that a
model trained on it can be tested on them.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from tlm_process.pipeline.errors import PipelineError

__all__ = ["TABLES", "EvalDataset", "EvaluateError", "drop_features", "load_dataset",
           "load_transfer", "parse_drop_features"]

#: The data tables (paper Table 5), in the paper's order.
TABLES: tuple[str, ...] = ("GPS", "IMU", "RATE", "VIBE")


class EvaluateError(PipelineError):
    """A bad data set, transfer log or request for ``tlm evaluate``: one line, exit code 2."""


@dataclass
class EvalDataset:
    """A loaded data set: ``tables`` (name -> DataFrame), ``features`` (name -> feature
    columns), the scaler (``tlm_process.pipeline.scaling.MinMaxScaler``), the report and the
    features :func:`drop_features` took out (``dropped``: table -> columns)."""

    path: Path
    tables: dict[str, pd.DataFrame]
    features: dict[str, list[str]]
    scaler: Any
    report: dict[str, Any] = field(default_factory=dict)
    dropped: dict[str, list[str]] = field(default_factory=dict)

    @property
    def options(self) -> dict[str, Any]:
        return dict(self.report.get("options") or {})


def load_dataset(path: str | Path, tables: Sequence[str] | None = None) -> EvalDataset:
    """Load ``tables`` (default: every table the data set has) of the data set at ``path``.
    Raises :class:`EvaluateError` for a missing folder, a folder that is not a ``tlm process``
    output, a missing table or column."""
    from tlm_process.pipeline.report import REPORT_FORMAT, REPORT_VERSION
    from tlm_process.pipeline.scaling import MinMaxScaler

    p = Path(path)
    if not p.exists():
        raise EvaluateError("no such data set folder", source=str(p))
    if not p.is_dir():
        raise EvaluateError("not a folder (expected a 'tlm process' output folder)",
                            source=str(p))
    rep_path = p / "report.json"
    if not rep_path.exists():
        raise EvaluateError("no report.json: not a 'tlm process' output folder (run tlm "
                            "process INPUT... --out DS first)", source=str(p))
    try:
        report = json.loads(rep_path.read_text())
    except (OSError, ValueError) as exc:
        raise EvaluateError(f"cannot read report.json: {exc}", source=str(p)) from None
    if not isinstance(report, dict) or report.get("format") != REPORT_FORMAT:
        raise EvaluateError(f"report.json is not a 'tlm process' report (format "
                            f"{REPORT_FORMAT!r} expected)", source=str(p))
    version = report.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version > REPORT_VERSION:
        raise EvaluateError(f"report.json has data set version {version!r}; this tlm reads "
                            f"versions up to {REPORT_VERSION} (a newer tlm wrote it: update "
                            f"tlm)", source=str(p))
    feats = report.get("features")
    if not isinstance(feats, dict) or not feats:
        raise EvaluateError("report.json lists no features", source=str(p))
    have = [t for t in TABLES if t in feats] + [t for t in feats if t not in TABLES]
    want = list(tables) if tables is not None else have
    missing = [t for t in want if t not in feats]
    if missing:
        raise EvaluateError(f"no table {', '.join(missing)} in the data set (it has "
                            f"{', '.join(have)})", source=str(p))
    scaler = None
    if (p / "scaler.json").exists():
        scaler = MinMaxScaler.load(p / "scaler.json")
    out: dict[str, pd.DataFrame] = {}
    for t in want:
        f = p / f"{t}.parquet"
        if not f.exists():
            raise EvaluateError(f"{t}.parquet is missing", source=str(p))
        try:
            df = pd.read_parquet(f)
        except Exception as exc:  # pyarrow raises several types for a bad file
            raise EvaluateError(f"cannot read {t}.parquet: {exc}", source=str(p)) from None
        need = ["flight", "label", "TimeUS", *feats[t]]
        lack = [c for c in need if c not in df.columns]
        if lack:
            raise EvaluateError(f"{t}.parquet lacks column(s) {', '.join(lack)}",
                                source=str(p))
        if not len(df):
            raise EvaluateError(f"{t}.parquet has no rows", source=str(p))
        out[t] = df.reset_index(drop=True)
    return EvalDataset(p, out, {t: list(feats[t]) for t in want}, scaler, report)


def parse_drop_features(spec: str | Sequence[str], ds: EvalDataset) -> dict[str, list[str]]:
    """Table -> columns of ``--drop-features`` ``TABLE.COL[,TABLE.COL...]`` (a string, or a
    list of them), checked against the data set's report (every table it has, loaded or
    not; tables case-insensitive, columns as ArduPilot names them). Raises
    :class:`EvaluateError` (one line) for an item that is not ``TABLE.COL`` or names no
    feature of the data set."""
    items = [x.strip() for part in ([spec] if isinstance(spec, str) else spec)
             for x in str(part).split(",") if x.strip()]
    feats = ds.report.get("features") or ds.features
    out: dict[str, list[str]] = {}
    for item in items:
        table, dot, col = item.partition(".")
        table, col = table.strip().upper(), col.strip()
        if not dot or not table or not col:
            raise EvaluateError(f"--drop-features: {item!r} is not TABLE.COL (e.g. "
                                f"RATE.AOutSlew)")
        if table not in feats:
            raise EvaluateError(f"--drop-features: unknown feature {item!r}: the data set has "
                                f"no table {table} (it has {', '.join(feats)})")
        if col not in feats[table]:
            raise EvaluateError(f"--drop-features: unknown feature {item!r}: {table}'s "
                                f"features are {', '.join(feats[table])}")
        if col not in out.setdefault(table, []):
            out[table].append(col)
    return out


def drop_features(ds: EvalDataset, drop: dict[str, list[str]]) -> EvalDataset:
    """``ds`` without the features ``drop`` (table -> columns; :func:`parse_drop_features`):
    gone from its loaded tables, its feature lists and its scaler, and recorded in
    ``dropped``. Tables ``drop`` names that are not loaded are left as they are. Raises
    :class:`EvaluateError` when a table would be left without features."""
    import copy

    drop = {t: list(cols) for t, cols in drop.items() if t in ds.tables and cols}
    if not drop:
        return ds
    features = {t: [c for c in f if c not in drop.get(t, ())] for t, f in ds.features.items()}
    empty = [t for t, f in features.items() if not f]
    if empty:
        raise EvaluateError(f"--drop-features leaves table {empty[0]} without features")
    tables = {t: df.drop(columns=drop[t]) if t in drop else df for t, df in ds.tables.items()}
    scaler = ds.scaler
    if scaler is not None:
        scaler = copy.copy(scaler)
        scaler.ranges = {t: {c: r for c, r in rng.items() if c not in drop.get(t, ())}
                         for t, rng in ds.scaler.ranges.items()}
    dropped = {t: list(c) for t, c in ds.dropped.items()}
    for t, cols in drop.items():
        dropped[t] = list(dict.fromkeys([*dropped.get(t, []), *cols]))
    return EvalDataset(ds.path, tables, features, scaler, ds.report, dropped)


#: why a transfer log without labels is refused, after its name
NO_LABELS = ("no fault labels found (no sidecar {json}, no faults.json beside it, no fault "
             "records in the log: tlm's fault MSG lines or SIM_* parameter changes); label it, "
             "or add --assume-normal if it is a normal flight")


def load_transfer(paths: Iterable[str | Path], ds: EvalDataset,
                  tables: Sequence[str] | None = None, *, assume_normal: bool = False,
                  progress: Callable[[str], None] | None = None) -> dict[str, pd.DataFrame]:
    """The transfer logs ``paths`` as tables like the data set's (``flight``, ``TimeUS``,
    ``label``, scaled features), processed with the data set's options (``rc_label``
    included: the transfer rows are labelled as the data set's were) and scaler; the
    features ``ds`` dropped (:func:`drop_features`) are dropped from them too.

    A log without fault labels (see the module docstring) raises :class:`EvaluateError`
    naming it, unless ``assume_normal``: then it is a normal flight and ``progress`` (if
    given) gets a line naming the logs so taken. A log that lacks a feature of the data set
    raises :class:`EvaluateError` naming the ``--drop-features`` that avoids it."""
    from tlm_process.pipeline.ingest import read_flights
    from tlm_process.pipeline.process import ProcessOptions, process_flight

    tables = list(tables) if tables is not None else list(ds.tables)
    if ds.scaler is None:
        raise EvaluateError("the data set has no scaler.json: transfer logs cannot be "
                            "scaled like its flights", source=str(ds.path))
    options = ProcessOptions.from_recorded(ds.options, tables)
    flights = read_flights(list(paths))
    bare = [fl for fl in flights if fl.unlabelled]
    if bare and not assume_normal:
        src = Path(bare[0].source)
        more = f" ({len(bare) - 1} more log(s) without labels)" if len(bare) > 1 else ""
        raise EvaluateError(NO_LABELS.format(json=src.with_suffix(".json").name) + more,
                            source=str(src))
    if bare and progress is not None:
        progress(f"{len(bare)} transfer log(s) without fault labels taken as normal flights "
                 f"(--assume-normal): {', '.join(fl.source for fl in bare)}")
    frames: dict[str, list[pd.DataFrame]] = {t: [] for t in tables}
    for fl in flights:
        p = process_flight(fl, options)
        lack = {t: [c for c in ds.features[t] if c not in p.features[t].columns]
                for t in tables}
        lack = {t: cols for t, cols in lack.items() if cols}
        if lack:
            raise EvaluateError(
                "; ".join(f"{t} lacks the data set's feature(s) {', '.join(cols)}"
                          for t, cols in lack.items())
                + " (older firmware may not log "
                + ("it" if sum(map(len, lack.values())) == 1 else "them")
                + "): add --drop-features "
                + ",".join(f"{t}.{c}" for t, cols in lack.items() for c in cols),
                source=fl.source)
        for t in tables:
            df = p.features[t]
            gone = [c for c in ds.dropped.get(t, ()) if c in df.columns]
            frames[t].append(df.drop(columns=gone) if gone else df)
        p.release()
    scaled = bool((ds.report.get("scaling") or {}).get("applied", True))
    out = {}
    for t in tables:
        df = pd.concat(frames[t], ignore_index=True)
        out[t] = ds.scaler.transform_table(t, df) if scaled else df
    return out
