"""Benchmark: the whole-log detector, from tlm generate to tlm detect on logs it never saw.

Runs, through the ``tlm`` command line, in one work folder:

1. ``tlm generate --flights N --seed S`` with its defaults (every fault type, drawn wind and
   noise, both quad frames), unless ``--data DS`` names one already made;
2. ``tlm train DS --out MODEL`` (timed: issue 38's target is <= 5 minutes for 200 flights on
   2 cores), with ``--holdout F`` when asked (held-out row macro-F1, delays, false alarms
   come from the manifest);
3. ``tlm detect MODEL`` on every reference SITL log *copied without its sidecar* (the
   detector cannot see the labels), then each log's findings are compared with the sidecar's
   fault windows: a fault is *named* when a finding of its class starts within 3 s of it; a
   normal log passes when nothing is found. Row macro-F1 over the labels present is computed
   from the predictions against the sidecar's windows (rows of the armed span, 10 Hz);
4. detection speed: ``tlm detect --no-plots`` on ``--speed-logs`` tlm flights of about ten
   minutes (``tlm fly --mission 4 --format bin --param WPNAV_SPEED=270``), in logs a minute
   and in ten-minute logs a minute (issue 38's target: >= 20).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_detect.py --flights 200 --seed 1
    PYTHONPATH=. .venv/bin/python benchmarks/bench_detect.py --data DS --holdout 0.2
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parents[1]
SITL = HERE.parent / "shared" / "reference" / "sitl"


def _tlm(*args: str, quiet: bool = True) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tlm_process.cli", *args], check=True, cwd=HERE,
                   stdout=subprocess.DEVNULL if quiet else None)
    return time.perf_counter() - t0


def _windows(log: Path) -> list[tuple[int, float, float]]:
    """(label, start s, end s) of the faults of ``log``'s sidecar, anchored as tlm process
    anchors them."""
    from tlm_process.detect.data import read_log

    ws = read_log(log).windows or []
    return [(w.label, w.start_us * 1e-6, w.end_us * 1e-6) for w in ws]


def reference_check(model: Path, work: Path) -> None:
    """tlm detect on the reference SITL logs without their sidecars; a table per log."""
    from sklearn.metrics import f1_score

    from tlm_process.pipeline.anchoring import FaultWindow, label_rows

    blind = work / "sitl-blind"
    if blind.exists():
        shutil.rmtree(blind)
    blind.mkdir(parents=True)
    logs = sorted(SITL.glob("*.bin"))
    for p in logs:
        shutil.copy(p, blind / p.name)
    out = work / "found-sitl"
    t = _tlm("detect", str(model), *[str(blind / p.name) for p in logs], "--out", str(out),
             "--overwrite", "--quiet")
    summary = pd.read_csv(out / "summary.csv")
    print(f"\ntlm detect on {len(logs)} reference SITL logs without sidecars: {t:.1f} s")
    print("| log | true faults | found | named (class, start within 3 s) | row macro-F1 |")
    print("|---|---|---|---|---|")
    ok_all = 0
    f1s = []
    pooled: dict[str, list[np.ndarray]] = {"flight": [], "t": [], "true": [], "pred": []}
    for p in logs:
        truth = _windows(p)
        rows = summary[summary["log"] == str(blind / p.name)]
        found = [(int(r.label), float(r.start_s)) for r in rows.itertuples() if r.label != 0]
        named = [any(lab == t_lab and abs(s - t_s) <= 3.0 for lab, s in found)
                 for t_lab, t_s, _ in truth]
        ok = all(named) if truth else not found
        ok_all += ok
        pred = pd.read_parquet(out / p.stem / "predictions.parquet")
        wins = [FaultWindow(i, "", lab, s * 1e6, e * 1e6, "time")
                for i, (lab, s, e) in enumerate(truth)]
        yt = label_rows(pred["TimeUS"].to_numpy(), wins)
        present = sorted({int(v) for v in np.unique(yt)})
        f1 = f1_score(yt, pred["label"], labels=present, average="macro", zero_division=0)
        f1s.append(f1)
        pooled["flight"].append(np.full(len(yt), p.stem, dtype=object))
        pooled["t"].append(pred["TimeUS"].to_numpy())
        pooled["true"].append(yt)
        pooled["pred"].append(pred["label"].to_numpy())
        tf = ", ".join(f"{lab}@{s:.1f}" for lab, s, _ in truth) or "none"
        ff = ", ".join(f"{lab}@{s:.1f}" for lab, s in found) or "none"
        print(f"| {p.stem} | {tf} | {ff} | {'yes' if ok else 'NO'} | {f1:.3f} |")
    print(f"logs passed: {ok_all}/{len(logs)}; mean row macro-F1 {np.mean(f1s):.3f}")
    _pooled({k: np.concatenate(v) for k, v in pooled.items()})


def _pooled(rows: dict[str, np.ndarray]) -> None:
    """Row macro-F1 over every label present, median detection delay per fault class and
    false alarms per hour of normal flight, over every row of every log
    (:mod:`tlm_process.evaluate.events`: 1 s persistence)."""
    from sklearn.metrics import f1_score

    from tlm_process.evaluate.events import detection_summary

    yt, yp = rows["true"], rows["pred"]
    present = sorted({int(v) for v in np.unique(yt)})
    f1 = f1_score(yt, yp, labels=present, average="macro", zero_division=0)
    ev = detection_summary(rows["flight"], rows["t"], yt, yp)
    print(f"pooled: row macro-F1 {f1:.3f} over {len(present)} labels; false alarms "
          f"{ev['false_alarms']} in {ev['normal_hours']:.2f} h of normal rows "
          f"({ev['false_alarms_per_hour']:.2f}/h)")
    for name, d in ev["detection"].items():
        print(f"  {name:<14} detected {d['detected']}/{d['events']}, median delay "
              f"{d['delay_median_s']:.2f} s")


def speed_check(model: Path, work: Path, n: int) -> None:
    """tlm detect throughput on n ten-minute tlm logs."""
    logs = []
    for i in range(n):
        d = work / f"long{i}"
        if not (d / "flight.bin").exists():
            _tlm("fly", "--mission", "4", "--seed", str(i), "--out", str(d), "--format", "bin",
                 "--param", "WPNAV_SPEED=270", "--overwrite")
        logs.append(next(d.glob("*.bin")))
    from tlm_process.logread import log_end_us, log_start_us, read_log_tables

    lengths = []
    for p in logs:
        tb = read_log_tables(p, ["GPS"]).tables
        lengths.append((log_end_us(tb) - log_start_us(tb)) * 1e-6 / 60)
    t = _tlm("detect", str(model), *map(str, logs), "--out", str(work / "found-speed"),
             "--overwrite", "--quiet", "--no-plots")
    per_min = len(logs) / (t / 60)
    ten = per_min * np.mean(lengths) / 10
    print(f"\ntlm detect speed: {len(logs)} logs of {np.mean(lengths):.1f} min in {t:.1f} s "
          f"(process start included): {per_min:.1f} logs/min, {ten:.1f} ten-minute logs/min")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--data", help="an existing tlm generate data set (skips generate)")
    ap.add_argument("--out", help="work folder (default: a temporary one)")
    ap.add_argument("--holdout", type=float, default=0.0)
    ap.add_argument("--train", default="", help="more tlm train options, one string")
    ap.add_argument("--speed-logs", type=int, default=10)
    args = ap.parse_args()
    work = Path(args.out or tempfile.mkdtemp(prefix="tlm-bench-detect-"))
    work.mkdir(parents=True, exist_ok=True)
    ds = Path(args.data) if args.data else work / "ds"
    if not args.data:
        t = _tlm("generate", "--flights", str(args.flights), "--out", str(ds), "--seed",
                 str(args.seed))
        print(f"generate {args.flights} flights: {t:.1f} s")
    model = work / "model"
    t = _tlm("train", str(ds), "--out", str(model), "--overwrite", "--quiet",
             "--holdout", str(args.holdout), *args.train.split(), quiet=False)
    m = json.loads((model / "manifest.json").read_text())
    print(f"tlm train: {t:.1f} s wall (read {m['times_s']['read_s']} s, fit "
          f"{m['times_s']['fit_s']} s), {m['data']['train_flights']} flights, "
          f"{m['data']['fit_rows']} rows fitted")
    if SITL.is_dir():
        reference_check(model, work)
    if args.speed_logs:
        speed_check(model, work, args.speed_logs)
    print(f"work folder {work}")


if __name__ == "__main__":
    main()
