"""Benchmark: the whole tlm chain on a standard data set, and detection scores beside the paper's.

Runs, through the ``tlm`` command line, in one temporary folder:

1. ``tlm generate --flights N --kinds paper=1`` (paper-style flights: GPS, accel, engine, RC;
   with ``--no-env`` as the paper flew them: no wind, no extra sensor noise);
2. ``tlm process DS --test-frac 0.25`` (anchoring, labels, Algorithm 2, min-max scaling);
3. ``tlm evaluate DS-tlm --table all --models M --split flight`` (and ``--test-on`` the
   reference SITL logs when they are beside the checkout);

and prints the wall time of each step and, per table, accuracy and macro-F1 of every model
(transfer macro-F1 when SITL logs were used), with the paper's figures for comparison (§5.4:
RandomForest 84.08 % on GPS; CNN 85.63 % GPS, 75.32 % RATE, 73.03 % IMU, 63.15 % VIBE).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_detection.py --flights 200 --jobs 2
    PYTHONPATH=. .venv/bin/python benchmarks/bench_detection.py --flights 60 \\
        --models RandomForest,J48,CNN,WindowHGB
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

PAPER = {"GPS": {"RandomForest": 84.08, "CNN": 85.63}, "RATE": {"CNN": 75.32},
         "IMU": {"CNN": 73.03}, "VIBE": {"CNN": 63.15}}
HERE = Path(__file__).resolve().parents[1]
SITL = HERE.parent / "shared" / "reference" / "sitl"


def _tlm(*args: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tlm_process.cli", *args], check=True, cwd=HERE,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--models", default="all")
    ap.add_argument("--out", help="working folder (default: a temporary one)")
    ap.add_argument("--jobs", type=int, default=1, help="threads for the models (default 1)")
    ap.add_argument("--no-env", action="store_true",
                    help="fly as the paper and the reference SITL logs did: '+' frame, no "
                         "wind, no extra sensor noise (tlm generate --no-env --frame +)")
    args = ap.parse_args()
    work = Path(args.out or tempfile.mkdtemp(prefix="tlm-bench-"))
    ds, dsp, rj = work / "ds", work / "ds-tlm", work / "results.json"
    times = {
        "generate": _tlm("generate", "--flights", str(args.flights), "--out", str(ds),
                         "--seed", str(args.seed), "--kinds", "paper=1",
                         *(["--no-env", "--frame", "+"] if args.no_env else [])),
        "process": _tlm("process", str(ds), "--out", str(dsp), "--test-frac", "0.25",
                        "--seed", str(args.seed), "--quiet"),
    }
    test_on = sorted(str(p) for p in SITL.glob("*.bin")) if SITL.is_dir() else []
    ev = ["evaluate", str(dsp), "--table", "all", "--models", args.models, "--split", "flight",
          "--seed", "0", "--json", str(rj), "--jobs", str(args.jobs)]  # progress on stderr
    times["evaluate"] = _tlm(*ev, *(["--test-on", *test_on] if test_on else []))
    res = json.loads(rj.read_text())
    env = "no wind or extra noise (--no-env)" if args.no_env else "drawn wind and noise"
    print(f"{args.flights} paper-style flights, {env}, seed {args.seed}; work folder {work}")
    print(" ".join(f"{k} {v:.1f} s;" for k, v in times.items()))
    print("| table | model | accuracy % | macro-F1 | transfer macro-F1 (SITL logs) | paper "
          "accuracy % |")
    print("|---|---|---|---|---|---|")
    for table, models in res.items():
        for name, m in models.items():
            tr = m.get("transfer") or {}
            tf = tr.get("macro_f1")
            paper = PAPER.get(table, {}).get(name)
            print(f"| {table} | {name} | {100 * m['accuracy']:.2f} | {m['macro_f1']:.3f} | "
                  f"{'-' if tf is None else f'{tf:.3f}'} | {'' if paper is None else paper} |")


if __name__ == "__main__":
    main()
