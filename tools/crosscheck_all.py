"""Cross-check every reference SITL log and write docs/crosscheck.md (+ overlay PNGs).

    python tools/crosscheck_all.py [--reference ../shared/reference/sitl] [--out docs]

Each log's scenario is rebuilt from the log and its sidecar and flown in tlm
(``tlm crosscheck``); the table lists every metric for every log, tlm vs SITL.
``tests/test_crosscheck.py`` pins the key metrics to the tolerances stated here.
"""

from __future__ import annotations

import argparse
import math
import shutil
import tempfile
from pathlib import Path

from tlm_process.crosscheck.command import crosscheck, plot, to_json

LOGS = ("normal_s11", "gps_s12", "accel_s13", "engine_s14", "rc_s15", "combined_s21")

HEADER = """# Cross-check: every reference SITL log vs tlm flying the same scenario

Regenerate with `python tools/crosscheck_all.py` (about a minute). One log by hand:
`tlm crosscheck ../shared/reference/sitl/gps_s12.bin --out DIR --json R.json`.

Each scenario is rebuilt from the SITL log (mission and faults from its sidecar, parameters from
PARM), flown in tlm with the sidecar's seed, and aligned at arming. Definitions of the metrics:
`tlm_process/crosscheck/metrics.py`. Targets of the cross-check issue: flight time within 10 %
and trajectory RMS <= 3 m on the normal and combined flights.

"""


def _v(x: object) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return f"{x:.3g}" if isinstance(x, float) else str(x)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = Path(__file__).resolve().parents[1]
    ap.add_argument("--reference", default=str(here.parent / "shared" / "reference" / "sitl"))
    ap.add_argument("--out", default=str(here / "docs"))
    args = ap.parse_args()
    out = Path(args.out)
    img = out / "img"
    img.mkdir(parents=True, exist_ok=True)
    results = {}
    for name in LOGS:
        r = crosscheck(Path(args.reference) / f"{name}.bin")
        tmp = Path(tempfile.mkdtemp())
        for f in plot(r, tmp)[:2]:
            shutil.copy(f, img / f"crosscheck_{name}_{f.name}")
        results[name] = to_json(r)
        print(f"{name}: trajectory RMS {results[name]['trajectory_rms_m']:.2f} m")
    lines = ["| metric | " + " | ".join(LOGS) + " |", "|---|" + "---|" * len(LOGS)]
    first = results[LOGS[0]]
    for k, v in first.items():
        if k in ("faults", "scenario"):
            continue
        if isinstance(v, dict):
            cells = [f"{_v(results[n][k]['tlm'])} / {_v(results[n][k]['sitl'])}" for n in LOGS]
            lines.append(f"| {k} (tlm / SITL) | " + " | ".join(cells) + " |")
        else:
            lines.append(f"| {k} | " + " | ".join(_v(results[n][k]) for n in LOGS) + " |")
    faults = ["", "## Fault signatures (tlm / SITL)", ""]
    for name in LOGS:
        for f in results[name]["faults"]:
            faults += [f"### {name}: {f['type']}", "", "| signature | tlm | SITL |",
                       "|---|---|---|"]
            faults += [f"| {k} | {_v(f['tlm'].get(k))} | {_v(f['sitl'].get(k))} |"
                       for k in f["sitl"]]
            faults.append("")
    plots = ["", "## Overlays", ""]
    for name in LOGS:
        plots += [f"### {name}", "", f"![](img/crosscheck_{name}_trajectory.png) "
                  f"![](img/crosscheck_{name}_profiles.png)", ""]
    (out / "crosscheck.md").write_text(HEADER + "\n".join(lines + faults + plots) + "\n")
    print(f"wrote {out / 'crosscheck.md'}")


if __name__ == "__main__":
    main()
