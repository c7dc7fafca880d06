"""Benchmark: the whole tlm chain on a standard data set, and detection scores beside the paper's.

Runs, through the ``tlm`` command line, in one temporary folder:

1. ``tlm generate --flights N`` with its defaults (every fault type, drawn wind and noise, both
   quad frames; ``--paper``: paper-style flights only, ``--kinds paper=1``; ``--no-env``: as
   the paper flew them, no wind, no extra sensor noise, "+" frame);
2. ``tlm process DS --test-frac 0.25`` (anchoring, labels, Algorithm 2, min-max scaling);
3. ``tlm evaluate DS-tlm --table all --models M --split flight`` (and ``--test-on`` every
   reference SITL log when they are beside the checkout);

and prints the wall time of each step and, per table and model: accuracy and macro-F1 on the
tlm test flights; on the SITL logs (transfer) macro-F1 over every label and over the paper's
five classes (Normal, GPS, Acc, Engine, RC: the mean F1 of those classes in the full
confusion matrix, so a row given another class counts against them); false alarms per hour
of Normal flight (test flights / SITL logs); and how many of the SITL logs' fault events the
model detected in their own class (1 s persistence, ``tlm_process.evaluate.events``), with
the paper's figures for comparison (§5.4: RandomForest 84.08 % on GPS; CNN 85.63 % GPS,
75.32 % RATE, 73.03 % IMU, 63.15 % VIBE).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_detection.py --flights 200 --jobs 2
    PYTHONPATH=. .venv/bin/python benchmarks/bench_detection.py --flights 60 \\
        --models RandomForest,J48,CNN,WindowHGB
    PYTHONPATH=. .venv/bin/python benchmarks/bench_detection.py --flights 200 --jobs 2 \\
        --models WindowHGB60,CentredHGB --evaluate '--booster sklearn'
"""

from __future__ import annotations

import argparse
import json
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

PAPER = {"GPS": {"RandomForest": 84.08, "CNN": 85.63}, "RATE": {"CNN": 75.32},
         "IMU": {"CNN": 73.03}, "VIBE": {"CNN": 63.15}}
PAPER_LABELS = (0, 1, 2, 3, 4)
HERE = Path(__file__).resolve().parents[1]
SITL = HERE.parent / "shared" / "reference" / "sitl"


def macro_f1_of(m: dict[str, Any], labels: tuple[int, ...], order: list[int] | None
                ) -> float | None:
    """Mean F1 of ``labels`` (those with rows or predictions) in result ``m``'s confusion
    matrix (``m["confusion"]``, rows and columns in label ``order``, the model's
    ``labels``): ``2 C[k, k] / (n_k + p_k)``."""
    cm = np.asarray(m.get("confusion") or [], dtype=float)
    if order is None or not cm.size:
        return None
    f1 = []
    for k in labels:
        if k in order:
            i = order.index(k)
            n, p = cm[i].sum(), cm[:, i].sum()
            if n + p > 0:
                f1.append(2 * cm[i, i] / (n + p))
    return float(np.mean(f1)) if f1 else None


def detected(m: dict[str, Any]) -> str:
    """``detected/events`` over every fault class of result ``m``'s ``detection``."""
    det = (m.get("detection") or {}).values()
    return f"{sum(d.get('detected', 0) for d in det)}/{sum(d.get('events', 0) for d in det)}"


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
    ap.add_argument("--paper", action="store_true",
                    help="paper-style flights only (tlm generate --kinds paper=1)")
    ap.add_argument("--tables", default="all", help="tables to evaluate (default all)")
    ap.add_argument("--generate", default="", metavar="ARGS",
                    help="more tlm generate options, one string (e.g. '--calm-share 0.6')")
    ap.add_argument("--evaluate", default="", metavar="ARGS",
                    help="more tlm evaluate options, one string (e.g. '--booster sklearn')")
    ap.add_argument("--no-env", action="store_true",
                    help="fly as the paper and the reference SITL logs did: '+' frame, no "
                         "wind, no extra sensor noise (tlm generate --no-env --frame +)")
    args = ap.parse_args()
    work = Path(args.out or tempfile.mkdtemp(prefix="tlm-bench-"))
    ds, dsp, rj = work / "ds", work / "ds-tlm", work / "results.json"
    times = {
        "generate": _tlm("generate", "--flights", str(args.flights), "--out", str(ds),
                         "--seed", str(args.seed),
                         *(["--kinds", "paper=1"] if args.paper else []),
                         *(["--no-env", "--frame", "+"] if args.no_env else []),
                         *shlex.split(args.generate)),
        "process": _tlm("process", str(ds), "--out", str(dsp), "--test-frac", "0.25",
                        "--seed", str(args.seed), "--quiet"),
    }
    test_on = sorted(str(p) for p in SITL.glob("*.bin")) if SITL.is_dir() else []
    # progress on stderr
    ev = ["evaluate", str(dsp), "--table", args.tables, "--models", args.models,
          "--split", "flight", "--seed", "0", "--json", str(rj), "--jobs", str(args.jobs),
          *shlex.split(args.evaluate)]
    times["evaluate"] = _tlm(*ev, *(["--test-on", *test_on] if test_on else []))
    res = json.loads(rj.read_text())
    env = "no wind or extra noise (--no-env)" if args.no_env else "drawn wind and noise"
    kinds = "paper-style" if args.paper else "tlm generate default"
    print(f"{args.flights} {kinds} flights, {env}, seed {args.seed}"
          + (f", generate {args.generate}" if args.generate else "")
          + f"; {len(test_on)} SITL logs; work folder {work}")
    print(" ".join(f"{k} {v:.1f} s;" for k, v in times.items()))
    print("| table | model | accuracy % | macro-F1 | transfer macro-F1, all labels | "
          "transfer macro-F1, paper's 5 classes | transfer macro-F1, classes the table sees "
          "| false alarms/h test / SITL | SITL faults detected | paper accuracy % |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for table, models in res.items():
        for name, m in models.items():
            tr = m.get("transfer") or {}
            paper = PAPER.get(table, {}).get(name)
            five = macro_f1_of(tr, PAPER_LABELS, m.get("labels"))
            print(f"| {table} | {name} | {100 * m['accuracy']:.2f} | {m['macro_f1']:.3f} | "
                  f"{_f(tr.get('macro_f1'))} | {_f(five)} | "
                  f"{_f((tr.get('visible') or {}).get('macro_f1'))} | "
                  f"{_f(m.get('false_alarms_per_hour'), '.1f')} / "
                  f"{_f(tr.get('false_alarms_per_hour'), '.1f')} | "
                  f"{detected(tr) if tr else '-'} | {'' if paper is None else paper} |")


def _f(v: float | None, spec: str = ".3f") -> str:
    return "-" if v is None else format(v, spec)


if __name__ == "__main__":
    main()
