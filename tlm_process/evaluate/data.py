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
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from tlm_process.pipeline.errors import PipelineError

__all__ = ["TABLES", "EvalDataset", "EvaluateError", "load_dataset", "load_transfer"]

#: The data tables (paper Table 5), in the paper's order.
TABLES: tuple[str, ...] = ("GPS", "IMU", "RATE", "VIBE")


class EvaluateError(PipelineError):
    """A bad data set, transfer log or request for ``tlm evaluate``: one line, exit code 2."""


@dataclass
class EvalDataset:
    """A loaded data set: ``tables`` (name -> DataFrame), ``features`` (name -> feature
    columns), the scaler (``tlm_process.pipeline.scaling.MinMaxScaler``) and the report."""

    path: Path
    tables: dict[str, pd.DataFrame]
    features: dict[str, list[str]]
    scaler: Any
    report: dict[str, Any] = field(default_factory=dict)

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


def load_transfer(paths: Iterable[str | Path], ds: EvalDataset,
                  tables: Sequence[str] | None = None) -> dict[str, pd.DataFrame]:
    """The transfer logs ``paths`` as tables like the data set's (``flight``, ``TimeUS``,
    ``label``, scaled features), processed with the data set's options (``rc_label``
    included: the transfer rows are labelled as the data set's were) and scaler."""
    from tlm_process.pipeline.anchoring import DEFAULT_MAX_MATCH_M
    from tlm_process.pipeline.ingest import read_flights
    from tlm_process.pipeline.process import ProcessOptions, process_flight

    tables = list(tables) if tables is not None else list(ds.tables)
    if ds.scaler is None:
        raise EvaluateError("the data set has no scaler.json: transfer logs cannot be "
                            "scaled like its flights", source=str(ds.path))
    opt = ds.options
    options = ProcessOptions(
        method=opt.get("anchoring", "auto"), phase=opt.get("phase", "armed"),
        instance=opt.get("instance", 0),
        max_match_m=opt.get("max_match_m") or DEFAULT_MAX_MATCH_M,
        tables=tuple(tables), rc_label=opt.get("rc_label") or "window")
    flights = read_flights(list(paths))
    frames: dict[str, list[pd.DataFrame]] = {t: [] for t in tables}
    for fl in flights:
        p = process_flight(fl, options)
        for t in tables:
            df = p.features[t]
            lack = [c for c in ds.features[t] if c not in df.columns]
            if lack:
                raise EvaluateError(f"{t} lacks the data set's feature(s) {', '.join(lack)}",
                                    source=fl.source)
            frames[t].append(df)
        p.release()
    scaled = bool((ds.report.get("scaling") or {}).get("applied", True))
    out = {}
    for t in tables:
        df = pd.concat(frames[t], ignore_index=True)
        out[t] = ds.scaler.transform_table(t, df) if scaled else df
    return out
