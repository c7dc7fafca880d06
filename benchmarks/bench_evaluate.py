"""Benchmark ``tlm evaluate``: per table and model, fit and predict time, rows, memory, score.

Uses a ``tlm process`` data set given with ``--data``, or makes one in ``--work`` (default
``TMP/tlm-bench-evaluate-<N>f-s<S>``; reused when it is already there): ``tlm generate
--flights N --seed S`` (its defaults: every fault type, wind, both quad frames) then
``tlm process --test-frac 0.25 --seed S``. Transfer logs (``--test-on``;
default: two reference SITL logs, ``combined_s21`` and ``normal_s11``, when they are beside
the checkout) are read with the data set's options and scaler, as ``tlm evaluate --test-on``
does.

Each table is evaluated by one call of ``tlm_process.evaluate.evaluate`` with every model asked
for (as ``tlm evaluate`` runs them), and the table prints, per table and model:

* ``train Hz``: the rate the model's training rows were thinned to (``all``: every row;
  ``5 (N 1)``: 5 Hz with the Normal rows at 1 Hz, ``--normal-hz``);
* ``fit s``, ``pred s``: wall seconds of fitting and predicting (the runner's own figures,
  summed over folds; ``pred s`` includes the transfer rows), ``wall s`` the model's whole
  turn, and ``cpu s``: this process's CPU seconds (all threads; not SMO's worker
  processes) over it, which a shared machine disturbs less than wall time (but OpenMP
  threads that wait for a busy core spin and count);
* ``rows fit`` / ``rows test``: training rows the model was fitted on, test rows predicted;
* ``peak MiB``: the largest resident-set growth over the level before the model (``/proc``
  sampled every 10 ms: numpy, scikit-learn and torch allocations alike);
* ``macro-F1`` on the test flights and, with transfer logs, on them.

The ``[table]`` row is the table's preparation (features, windows, folds) before its first
model. With two or more threads the one-core models (``runner.SINGLE_CORE_MODELS``: NaiveBayes,
AdaBoost, OneR, ZeroR, J48, RandomTree) are fitted side by side before the others; their
shared ``wall s`` and ``cpu s`` go to the first of them in the table, the rest show about 0
(their ``fit s`` and ``pred s`` are their own).
``--profile DIR`` runs every table under cProfile, writes ``DIR/<TABLE>.prof`` and
prints the 25 functions with the most cumulative time (profile one model at a time:
``--models WindowHGB60 --profile prof``).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_evaluate.py --flights 20 --tables GPS
    PYTHONPATH=. .venv/bin/python benchmarks/bench_evaluate.py --data /tmp/ds60 --tables GPS \\
        --models WindowHGB60,RandomForest,CNN --json bench.json
    PYTHONPATH=. .venv/bin/python benchmarks/bench_evaluate.py --data /tmp/ds60 \\
        --models RandomForest --profile prof
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

from tlm_process.commands.evaluate import BOOSTER_NAMES
from tlm_process.evaluate.metrics import train_rate_label

HERE = Path(__file__).resolve().parents[1]
SITL = HERE.parent / "shared" / "reference" / "sitl"
DEFAULT_TEST_ON = ("combined_s21.bin", "normal_s11.bin")
_PAGE = os.sysconf("SC_PAGE_SIZE")
_MODEL_DONE = re.compile(r"^\[(\w+)\] (\w+): accuracy")


def _rss() -> int:
    """Resident set size of this process [bytes]."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * _PAGE


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class PeakSampler:
    """Samples the RSS every ``dt`` seconds in a thread; :meth:`mark` returns the peak growth
    since the previous mark [bytes] and starts a new interval."""

    def __init__(self, dt: float = 0.01) -> None:
        self.dt = dt
        self._base = self._peak = _rss()
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.dt):
            r = _rss()
            with self._lock:
                self._peak = max(self._peak, r)

    def mark(self) -> int:
        r = _rss()
        with self._lock:
            grow = max(self._peak, r) - self._base
            self._base = self._peak = r
        return grow

    def close(self) -> None:
        self._stop.set()
        self._thread.join()


def _tlm(*args: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tlm_process.cli", *args], check=True, cwd=HERE,
                   stdout=subprocess.DEVNULL, env={**os.environ, "PYTHONPATH": str(HERE)})
    return time.perf_counter() - t0


def make_dataset(work: Path, flights: int, seed: int) -> Path:
    """``WORK/ds``: ``tlm generate`` defaults + ``tlm process --test-frac 0.25`` (kept when it
    is already there)."""
    gen, ds = work / "gen", work / "ds"
    if (ds / "report.json").exists():
        print(f"reusing {ds}", file=sys.stderr)
        return ds
    work.mkdir(parents=True, exist_ok=True)
    tg = _tlm("generate", "--flights", str(flights), "--out", str(gen), "--seed", str(seed),
              "--no-progress")
    tp = _tlm("process", str(gen), "--out", str(ds), "--test-frac", "0.25", "--seed",
              str(seed), "--quiet", "--overwrite")
    print(f"made {ds}: generate {tg:.1f} s, process {tp:.1f} s", file=sys.stderr)
    return ds


def bench_table(ds: Any, table: str, models: list[str], transfer: Any, args: argparse.Namespace
                ) -> list[dict[str, Any]]:
    """Evaluate ``table`` with every model in one runner call; one record per model (and one
    for the table's preparation)."""
    from tlm_process.evaluate import evaluate

    sampler = PeakSampler()
    rows: list[dict[str, Any]] = []
    clock = {"t": time.perf_counter(), "cpu": _cpu()}

    def lap() -> tuple[float, float]:
        t, c = time.perf_counter(), _cpu()
        out = (t - clock["t"], c - clock["cpu"])
        clock["t"], clock["cpu"] = t, c
        return out

    def progress(msg: str) -> None:
        if args.verbose:
            print(msg, file=sys.stderr, flush=True)
        if msg.startswith(f"[{table}] ") and " rows, " in msg and not rows:
            wall, cpu = lap()
            rows.append({"table": table, "model": "[table]", "wall_s": wall, "cpu_s": cpu,
                         "peak_mib": sampler.mark() / 2**20})
            return
        m = _MODEL_DONE.match(msg)
        if m and m.group(1) == table:
            wall, cpu = lap()
            rows.append({"table": table, "model": m.group(2), "wall_s": wall, "cpu_s": cpu,
                         "peak_mib": sampler.mark() / 2**20})

    kw = {"tables": [table], "models": models, "split": "flight", "seed": args.seed,
          "transfer": transfer, "progress": progress}
    if args.jobs is not None:
        kw["n_jobs"] = args.jobs
    if args.train_hz is not None:
        kw["train_hz"] = args.train_hz
    if args.normal_hz is not None:
        kw["normal_hz"] = args.normal_hz
    if args.max_rows is not None:
        kw["max_rows"] = args.max_rows
    if args.booster is not None:
        kw["booster"] = args.booster
    try:
        if args.profile:
            import cProfile
            import pstats

            prof = cProfile.Profile()
            res = prof.runcall(evaluate, ds, **kw)
            Path(args.profile).mkdir(parents=True, exist_ok=True)
            prof.dump_stats(Path(args.profile) / f"{table}.prof")
            print(f"--- cProfile, {table}: 25 functions by cumulative time", file=sys.stderr)
            pstats.Stats(prof, stream=sys.stderr).sort_stats("cumulative").print_stats(25)
        else:
            res = evaluate(ds, **kw)
    finally:
        sampler.close()
    for r in rows[1:]:
        m = res[table][r["model"]]
        tr = m.get("transfer") or {}
        r.update(fit_s=m["fit_seconds"] + m.get("transfer_fit_seconds", 0.0),
                 predict_s=m["predict_seconds"] + m.get("transfer_predict_seconds", 0.0),
                 train_hz=m.get("train_hz"), normal_hz=m.get("normal_hz"),
                 n_fit=m.get("n_fit", m["n_train"]),
                 n_test=m["n_test"],
                 macro_f1=m["macro_f1"], transfer_macro_f1=tr.get("macro_f1"))
    return rows


def _fmt(v: Any, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def print_table(records: list[dict[str, Any]]) -> None:
    head = ("| table | model | train Hz | fit s | pred s | wall s | cpu s | rows fit | "
            "rows test | peak MiB | macro-F1 | transfer macro-F1 |")
    print(head)
    print("|---" * 12 + "|")
    for r in records:
        print(f"| {r['table']} | {r['model']} | "
              f"{train_rate_label(r.get('train_hz'), r.get('normal_hz'))} | "
              f"{_fmt(r.get('fit_s'), '.2f')} | "
              f"{_fmt(r.get('predict_s'), '.2f')} | {r['wall_s']:.2f} | {r['cpu_s']:.2f} | "
              f"{_fmt(r.get('n_fit'), ',')} | {_fmt(r.get('n_test'), ',')} | "
              f"{r['peak_mib']:.0f} | {_fmt(r.get('macro_f1'), '.4f')} | "
              f"{_fmt(r.get('transfer_macro_f1'), '.4f')} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n".join(__doc__.splitlines()[1:]))
    ap.add_argument("--data", help="an existing 'tlm process' data set (else one is made)")
    ap.add_argument("--work", help="folder of the generated data set (default: "
                                   "TMP/tlm-bench-evaluate-<flights>f-s<seed>)")
    ap.add_argument("--flights", type=int, default=20, help="flights to generate (default 20)")
    ap.add_argument("--seed", type=int, default=0, help="generate/process/evaluate seed")
    ap.add_argument("--tables", default="GPS", help="comma list or all (default GPS)")
    ap.add_argument("--models", default="all", help="all or a comma list (default all)")
    ap.add_argument("--test-on", nargs="*", default=None, metavar="LOG",
                    help="transfer logs (default: combined_s21.bin normal_s11.bin of the "
                         "reference SITL logs when present; none: --test-on with no LOG)")
    ap.add_argument("--jobs", type=int, default=None, help="threads (default: the runner's)")
    ap.add_argument("--train-hz", type=float, default=None,
                    help="training-row rate for every model (default: the runner's)")
    ap.add_argument("--normal-hz", type=float, default=None,
                    help="Normal training-row rate of the weighted models (default: the "
                         "runner's)")
    ap.add_argument("--max-rows", type=int, default=None,
                    help="row budget per fit for every model (default: the runner's)")
    ap.add_argument("--booster", choices=BOOSTER_NAMES, default=None,
                    help="the window models' booster (default: the runner's, xgboost)")
    ap.add_argument("--json", help="write the records as JSON here")
    ap.add_argument("--profile", metavar="DIR", help="cProfile each table into DIR")
    ap.add_argument("--verbose", action="store_true", help="show the runner's progress lines")
    args = ap.parse_args()

    import numpy as np

    from tlm_process.evaluate import load_dataset, load_transfer
    from tlm_process.evaluate.runner import resolve_models

    np.seterr(all="ignore")
    work = Path(args.work or Path(tempfile.gettempdir())
                / f"tlm-bench-evaluate-{args.flights}f-s{args.seed}")
    ds_path = Path(args.data) if args.data else make_dataset(work, args.flights, args.seed)
    tables = (["GPS", "IMU", "RATE", "VIBE"] if args.tables.lower() == "all"
              else [t.strip().upper() for t in args.tables.split(",")])
    models = resolve_models(args.models)
    test_on = (args.test_on if args.test_on is not None else
               [str(SITL / n) for n in DEFAULT_TEST_ON if (SITL / n).exists()])
    t0 = time.perf_counter()
    ds = load_dataset(ds_path, tables)
    transfer = load_transfer(test_on, ds, tables) if test_on else None
    t_load = time.perf_counter() - t0
    print(f"data set {ds_path}: " + ", ".join(f"{t} {len(ds.tables[t]):,} rows"
                                              for t in tables)
          + f"; transfer {', '.join(Path(p).name for p in test_on) or 'none'}; "
            f"loaded in {t_load:.1f} s; load average {os.getloadavg()[0]:.1f}")
    records: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for t in tables:
        records += bench_table(ds, t, models, transfer, args)
    total = time.perf_counter() - t0
    print_table(records)
    print(f"evaluate total {total:.1f} s wall; load average {os.getloadavg()[0]:.1f}")
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"data": str(ds_path), "test_on": test_on, "load_seconds": t_load,
             "evaluate_seconds": total, "records": records}, indent=1) + "\n")


if __name__ == "__main__":
    main()
