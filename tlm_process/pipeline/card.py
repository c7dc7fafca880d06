"""The data set card: ``DS/README.md`` beside a ``tlm process`` output (issue 22), so a data
set says by itself what it holds: how it was made, what each table and column is (units as
ArduPilot logs them, before min-max scaling), what each label means and how many rows of each
there are.

:func:`dataset_card` renders it from ``report.json``'s content (what :func:`write_dataset`
returns); ``tlm process`` writes it last.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["dataset_card"]

#: what the columns beside the features are
_NON_FEATURE_DOC = {
    "flight": "flight id (the input folder / log name, or DS:N for flight N of a generated "
              "data set)",
    "split": "train or test (whole flights; the scaler was fitted on train only)",
    "TimeUS": "time since the flight's boot [µs] (not a feature)",
    "label": "class of the row (table below); 0 = normal",
}


#: the card's words for ProcessOptions.rc_label
_RC_LABEL_TEXT = {"window": "while the radio is lost (the paper's)",
                  "failsafe": "while the radio is lost and through the radio failsafe's RTL "
                              "until it lands (--rc-label failsafe)"}

def _label_rows(report: Mapping[str, Any]) -> list[str]:
    from tlm_process.labels import class_name
    from tlm_sim.faults import FAULT_TYPES

    by_label = {ft.label: ft for ft in FAULT_TYPES.values()}
    counts = report.get("counts") or {}
    tables = list(report.get("tables") or counts)
    labels = sorted({int(k) for c in counts.values() for k in c if k != "total"} | {0})
    rows = ["| label | class | meaning | " + " | ".join(f"{t} rows" for t in tables) + " |",
            "|---|---|---|" + "---|" * len(tables)]
    for k in labels:
        meaning = ("no fault" if k == 0 else
                   by_label[k].description if k in by_label else "?")
        cells = [f"{int((counts.get(t) or {}).get(str(k), 0)):,}" for t in tables]
        rows.append(f"| {k} | {class_name(k)} | {meaning} | " + " | ".join(cells) + " |")
    totals = [f"{int((counts.get(t) or {}).get('total', 0)):,}" for t in tables]
    rows.append("| | all | | " + " | ".join(totals) + " |")
    return rows


def _column_rows(table: str, features: list[str], scaled: bool) -> list[str]:
    from tlm_sim.flightlog.schema import SCHEMAS

    schema = SCHEMAS.get(table)
    rows = ["| column | unit in the log | what it is |", "|---|---|---|"]
    for c in ("flight", "split", "TimeUS", "label"):
        rows.append(f"| `{c}` | {'µs' if c == 'TimeUS' else ''} | {_NON_FEATURE_DOC[c]} |")
    for c in features:
        unit = ""
        if schema is not None and c in schema.columns:
            unit = schema.unit(c)
        note = "min-max scaled to 0..1 (scaler.json)" if scaled else "raw value"
        rows.append(f"| `{c}` | {unit} | feature, {note} |")
    return rows


def dataset_card(report: Mapping[str, Any], command: str = "") -> str:
    """``DS/README.md`` of a processed data set from its report (``report.json``'s content).
    ``command``: the command line that made it, shown as is."""
    from tlm_sim.flightlog.schema import SCHEMAS

    scaling = report.get("scaling") or {}
    scaled = bool(scaling.get("applied", True))
    split = report.get("split") or {}
    opts = report.get("options") or {}
    inputs = report.get("inputs") or {}
    lines = [
        "# tlm data set",
        "",
        "Labelled ArduPilot log tables for fault detection, made by tlm's Time Line Modeling "
        "pipeline (`tlm process`: fault windows anchored by Eq. 4, time and place columns "
        "dropped by Algorithm 2, min-max scaled by Eq. 6). `report.json` holds all of this as "
        "data.",
        "",
        "## How it was made",
        "",
    ]
    if command:
        lines += [f"    {command}", ""]
    lines += [
        f"* flights: {len(split.get('train') or [])} for training, "
        f"{len(split.get('test') or [])} for testing (whole flights)",
        f"* anchoring: {opts.get('anchoring', '?')}; rows kept: {opts.get('phase', '?')} "
        f"phase; IMU instance {opts.get('instance', 0)}; RC labels: "
        f"{_RC_LABEL_TEXT.get(opts.get('rc_label', 'window'), opts.get('rc_label'))}",
        f"* scaling: {scaling.get('method', 'min-max')}, fitted on the training flights, "
        f"{'applied' if scaled else 'not applied (raw values)'}",
    ]
    generated = [str(g.get("path", g)) if isinstance(g, Mapping) else str(g)
                 for g in inputs.get("generated") or []]
    if generated:
        lines.append(f"* generated data sets read: {', '.join(generated)}")
    flat = scaling.get("constant_features") or {}
    if flat:
        names = ", ".join(f"{t}.{c}" for t, cs in flat.items() for c in cs)
        lines.append(f"* constant in every training flight (0 after scaling): {names}")
    lines += ["", "## Labels", "", *_label_rows(report), ""]
    lines += ["## Tables", ""]
    for t in report.get("tables") or []:
        feats = list((report.get("features") or {}).get(t) or [])
        desc = SCHEMAS[t].description if t in SCHEMAS else ""
        lines += [f"### `{t}.parquet`", "", desc, "", *_column_rows(t, feats, scaled), ""]
    return "\n".join(lines).rstrip() + "\n"
