"""Benchmark: real-time factor of one paper-length flight (full stack) on one core.

Prints the cold compile time (first call in a fresh process with an empty numba cache is not
guaranteed here: run `find . -name "*.nbi" -delete` first for a truly cold number), the warm
real-time factor (simulated seconds per wall second) over several flights, and the peak memory.

    python benchmarks/bench_fly.py [--flights 5] [--mission 1]
"""

from __future__ import annotations

import argparse
import os
import resource
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=5)
    ap.add_argument("--mission", type=int, default=1)
    args = ap.parse_args()

    t0 = time.perf_counter()
    from tlm_sim import fly
    from tlm_sim.flight import run_flight

    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    log = fly(args.mission, seed=0)
    t_first = time.perf_counter() - t0
    sim_first = log.meta["duration_s"]
    print(f"import {t_import:.2f} s; first flight (compile or cache load + fly) {t_first:.2f} s "
          f"for {sim_first:.0f} s simulated; compiled signatures: {len(run_flight.signatures)}")

    sim_total = 0.0
    loop_wall = 0.0
    total_wall = 0.0
    import numpy as np

    from tlm_sim import flight as F

    orig = F.run_flight

    def timed(*a):
        nonlocal loop_wall
        t = time.perf_counter()
        r = orig(*a)
        loop_wall += time.perf_counter() - t
        return r

    F.run_flight = timed
    try:
        for k in range(args.flights):
            t = time.perf_counter()
            log = fly(args.mission, seed=k + 1)
            total_wall += time.perf_counter() - t
            sim_total += log.meta["duration_s"]
    finally:
        F.run_flight = orig
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(f"{args.flights} flights of mission {args.mission}: {sim_total:.0f} s simulated")
    print(f"  numba loop only : {sim_total / loop_wall:8.0f} x real time "
          f"({loop_wall / args.flights * 1e3:.0f} ms per flight)")
    print(f"  fly() end to end: {sim_total / total_wall:8.0f} x real time "
          f"({total_wall / args.flights * 1e3:.0f} ms per flight, incl. building the tables)")
    print(f"  peak RSS        : {peak_mb:.0f} MB")
    print(f"  rows per flight : GPS {len(log.tables['GPS'])}, IMU {len(log.tables['IMU'])}, "
          f"RATE {len(log.tables['RATE'])}, VIBE {len(log.tables['VIBE'])}")
    _ = np


if __name__ == "__main__":
    main()
