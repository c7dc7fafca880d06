"""Benchmark: writing a flight as a DataFlash .bin and as Mission Planner text, and reading back.

Flies built-in mission 1 with the paper's fault sequence once, then times (best of --repeat):
``encode_bin`` (FlightLog -> bytes), ``write_bin`` (to disk), ``read_bin`` of the written file
(all types), ``write_mp_log`` and ``read_mp_log``, and prints MB/s and messages/s for each and
the ratio of the .bin writer to the text writer measured in the same run.

    python benchmarks/bench_binwrite.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from _timing import best_of  # benchmarks/_timing.py (scripts run from this folder)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule
    from tlm_sim.flightlog import read_bin
    from tlm_sim.flightlog.binwriter import encode_bin
    from tlm_sim.flightlog.mplog import read_mp_log, write_mp_log

    log = fly(1, faults=FaultSchedule.paper(1), seed=1)
    n_msgs = sum(len(df) for df in log.tables.values())
    tmp = Path(tempfile.mkdtemp())
    bin_path, log_path = tmp / "f.bin", tmp / "f.log"
    t_enc = best_of(lambda: encode_bin(log), args.repeat)
    t_wbin = best_of(lambda: log.write_bin(bin_path), args.repeat)
    t_rbin = best_of(lambda: read_bin(bin_path), args.repeat)
    t_wtxt = best_of(lambda: write_mp_log(log, log_path), max(1, args.repeat // 2))
    t_rtxt = best_of(lambda: read_mp_log(log_path), max(1, args.repeat // 2))
    mb_bin = bin_path.stat().st_size / 1e6
    mb_txt = log_path.stat().st_size / 1e6
    print(f"flight: {log.meta['duration_s']:.0f} s simulated, {n_msgs} data messages, "
          f".bin {mb_bin:.2f} MB, .log {mb_txt:.2f} MB")
    rows = [
        ("encode_bin (tables -> bytes)", t_enc, mb_bin),
        ("write_bin (to disk)", t_wbin, mb_bin),
        ("read_bin (all types)", t_rbin, mb_bin),
        ("write_mp_log (text)", t_wtxt, mb_txt),
        ("read_mp_log (text)", t_rtxt, mb_txt),
    ]
    print(f"{'step':32s} {'best s':>8s} {'MB/s':>8s} {'msg/s':>11s}")
    for name, t, mb in rows:
        print(f"{name:32s} {t:8.3f} {mb / t:8.1f} {n_msgs / t:11.0f}")
    print(f"write_bin is {t_wtxt / t_wbin:.0f}x faster than write_mp_log for the same flight")


if __name__ == "__main__":
    main()
