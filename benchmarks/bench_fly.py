"""Benchmark: real-time factor of one paper-length flight (full stack) on one core.

Prints the first-flight time (a cold compile when the numba cache is empty: set
NUMBA_CACHE_DIR to an empty folder for a truly cold number) with the CPU time it took in this
process and in the compile workers (tlm_sim.precompile), the warm real-time factor (simulated
seconds per wall second) over several flights, and the peak memory.

    python benchmarks/bench_fly.py [--flights 5] [--mission 1] [--frame x] [--boot]
                                   [--compile-procs N]
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
    ap.add_argument("--frame", default=None,
                    help="frame of tlm_sim.frames (+, x, hexa, hexax, octa; default: +)")
    ap.add_argument("--boot", action="store_true",
                    help="fly SITL's boot phase (TLM_BOOT_PHASE 1: arming at ~40 s, not 10 s)")
    ap.add_argument("--compile-procs", type=int, default=None,
                    help="processes for a cold compile (TLM_COMPILE_PROCS; default: CPU count)")
    args = ap.parse_args()
    if args.compile_procs is not None:
        os.environ["TLM_COMPILE_PROCS"] = str(args.compile_procs)

    t0 = time.perf_counter()
    from tlm_sim import fly
    from tlm_sim.flight import run_flight

    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    params = {"TLM_BOOT_PHASE": 1} if args.boot else None
    log = fly(args.mission, seed=0, frame=args.frame, params=params)
    t_first = time.perf_counter() - t0
    sim_first = log.meta["duration_s"]
    cpu = [resource.getrusage(who) for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)]
    procs = os.environ.get("TLM_COMPILE_PROCS") or "CPU count"
    print(f"import {t_import:.2f} s; first flight (compile or cache load + fly) {t_first:.2f} s "
          f"for {sim_first:.0f} s simulated; compiled signatures: {len(run_flight.signatures)}")
    print(f"  CPU so far: {cpu[0].ru_utime + cpu[0].ru_stime:.1f} s here, "
          f"{cpu[1].ru_utime + cpu[1].ru_stime:.1f} s in compile workers "
          f"(TLM_COMPILE_PROCS: {procs}; os.cpu_count() {os.cpu_count()})")

    from tlm_sim import flight as F

    orig = F.run_flight
    loop_walls: list[float] = []

    def timed(*a):
        t = time.perf_counter()
        r = orig(*a)
        loop_walls.append(time.perf_counter() - t)
        return r

    sims: list[float] = []
    walls: list[float] = []
    F.run_flight = timed
    try:
        for k in range(args.flights):
            t = time.perf_counter()
            log = fly(args.mission, seed=k + 1, frame=args.frame, params=params)
            walls.append(time.perf_counter() - t)
            sims.append(log.meta["duration_s"])
    finally:
        F.run_flight = orig
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    sim_total = sum(sims)
    boot = ", boot phase" if args.boot else ""
    print(f"{args.flights} flights of mission {args.mission} ({log.meta['frame']} frame{boot}): "
          f"{sim_total:.0f} s simulated "
          "(real-time factor = simulated s / wall s; mean over all flights, and best flight)")
    for label, w in (("numba loop only ", loop_walls), ("fly() end to end", walls)):
        best = max(s / x for s, x in zip(sims, w, strict=True))
        print(f"  {label}: mean {sim_total / sum(w):6.0f} x, best {best:6.0f} x real time "
              f"({sum(w) / len(w) * 1e3:.0f} ms per flight)")
    print(f"  peak RSS        : {peak_mb:.0f} MB")
    print(f"  rows per flight : GPS {len(log.tables['GPS'])}, IMU {len(log.tables['IMU'])}, "
          f"RATE {len(log.tables['RATE'])}, VIBE {len(log.tables['VIBE'])}")


if __name__ == "__main__":
    main()
