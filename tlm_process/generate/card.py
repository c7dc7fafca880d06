"""The data set card of a generated data set: ``DS/README.md`` (issue 22), so the folder says
by itself how it was made, what its flights are (kinds, frames, wind, vibration, faults, how they
ended), what each table and column is (ArduPilot's message, units as ArduPilot logs them) and
what the labels mean. Rewritten whenever a run closes the data set (:func:`generate_card`
from the header and ``manifest.parquet``'s frame).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable, Mapping
from typing import Any

import pandas as pd

__all__ = ["generate_card"]


def _counts(values: Iterable[Any]) -> str:
    c = Counter(str(v) for v in values if v is not None and str(v) not in ("", "nan", "None"))
    return ", ".join(f"{k} {n}" for k, n in sorted(c.items(), key=lambda kv: -kv[1])) or "-"


def _label_rows() -> list[str]:
    from tlm_process.labels import class_name
    from tlm_sim.faults import FAULT_TYPES

    rows = ["| label | fault type | class | what happens |", "|---|---|---|---|",
            "| 0 | - | Normal | no fault |"]
    for name, ft in sorted(FAULT_TYPES.items(), key=lambda kv: kv[1].label):
        rows.append(f"| {ft.label} | `{name}` | {class_name(ft.label)} | {ft.description} |")
    return rows


def _table_rows(name: str) -> list[str]:
    from tlm_sim.flightlog.schema import SCHEMAS

    schema = SCHEMAS.get(name)
    if schema is None:
        return [f"### `{name}.parquet/`", ""]
    rows = [f"### `{name}.parquet/`", "", schema.description, "",
            "| column | unit |", "|---|---|", "| `flight` | flight number (manifest) |"]
    rows += [f"| `{c}` | {schema.unit(c)} |" for c in schema.columns]
    return [*rows, ""]


def generate_card(header: Mapping[str, Any], manifest: pd.DataFrame,
                  tables: Iterable[str]) -> str:
    """Markdown of ``DS/README.md`` for a generated data set: its ``header`` (manifest.json),
    ``manifest`` (manifest.parquet's frame, one row per flight) and the table folders it
    holds."""
    ok = manifest[manifest["status"] == "ok"] if "status" in manifest else manifest
    settings = header.get("settings") or {}
    scenario = settings.get("scenario") or {}
    faults = [f for cell in ok.get("faults", pd.Series(dtype=str)).fillna("")
              for f in str(cell).split(",") if f.strip()]
    lines = [
        "# tlm generated data set",
        "",
        f"Flights simulated by tlm {header.get('tlm_version', '?')} (`tlm generate`): "
        "ArduPilot log tables per flight, with the faults' Eq. 4 records; label the rows with "
        "`tlm process DS --out DS-tlm` (which writes its own card). `manifest.json` holds the "
        "settings, `manifest.parquet` one row per flight (its scenario, frame, wind, faults, "
        "how it ended); `docs/generate.md` in tlm's repository explains both.",
        "",
        "## How it was made",
        "",
        f"* flights: {header.get('flights', len(manifest))} asked, {len(ok)} written "
        f"({header.get('state', '?')}); run seed {header.get('seed', '?')}",
        f"* kinds: {_counts(ok.get('kind', []))}",
        f"* missions: {_counts(str(m).split('-')[0] for m in ok.get('mission', []))}",
        f"* frames: {_counts(ok.get('frame', []))}",
    ]
    pilot = [str(m) for m in ok.get("mission", []) if str(m).startswith("pilot-")]
    if pilot:
        lines.append(f"* pilot-flown (stick scripts, docs/pilot.md): modes "
                     f"{_counts(m.split('-')[1] for m in pilot)}; patterns "
                     f"{_counts('-'.join(m.split('-')[2:]) for m in pilot)}")
    if "vibration" in ok:
        vib = ok["vibration"].fillna("-")
        lines.append(f"* vibration: {int((vib == 'real').sum())} with a real copter's vibration "
                     f"and noise, {int((vib == 'quiet').sum())} SITL-quiet (docs/noise.md)")
    if "calm" in ok:
        windy = ok[~ok["calm"].fillna(False).astype(bool)]
        speeds = windy["wind_spd"] if len(windy) else pd.Series(dtype=float)
        lines.append(f"* wind: {int(ok['calm'].fillna(False).astype(bool).sum())} calm, "
                     f"{len(windy)} windy" + (f" ({speeds.min():.1f}-{speeds.max():.1f} m/s, "
                                              f"turbulence {windy['wind_turb'].min():.1f}-"
                                              f"{windy['wind_turb'].max():.1f} m/s)"
                                              if len(windy) else ""))
    lines += [
        f"* faults flown: {_counts(faults)}",
        f"* lambda (fault windows stretched, Eq. 5): {header.get('lambda', scenario.get('lam'))}",
        f"* profile: {scenario.get('profile', 'current')}; tables: "
        f"{', '.join(tables) or '-'}",
        f"* how the flights ended: {_counts(ok.get('end_reason', []))}",
        "",
        "## Labels",
        "",
        "Fault types and the labels `tlm process` gives their rows:",
        "",
        *_label_rows(),
        "",
        "## Tables",
        "",
        "One folder per ArduPilot message, one Parquet file per flight (or blocks after "
        "`--compact`); values as ArduPilot logs them (not scaled), with the flight number in "
        "`flight`. `faults.parquet/` holds the Eq. 4 records.",
        "",
    ]
    for t in tables:
        lines += _table_rows(t)
    return "\n".join(lines).rstrip() + "\n"
