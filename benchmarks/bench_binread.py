"""Benchmark: DataFlash .bin reading speed (MB/s) on the reference SITL logs, per stage.

For each log: the offset scan (``binscan.scan_bin``, numba), the bulk numpy decode of every
type, ``read_bin`` end to end (both stages, all types), and, measured in the same run,
``read_bin(method="messages")`` (pymavlink ``recv_match``) and pymavlink's own index pass
(``DFReader_binary``: its C indexer ``dfindexer``, and its pure-Python indexer with
PYMAVLINK_FAST_INDEX=0). Times are the best of ``--repeat`` runs (the slow pymavlink paths
run once). The first scan of the process includes numba's compile or cache load; it is
printed separately.

    PYTHONPATH=. python benchmarks/bench_binread.py [--repeat 5] [--no-messages] [LOG.bin ...]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import time
from pathlib import Path

from _timing import best_of  # benchmarks/_timing.py (scripts run from this folder)

REFERENCE = Path(__file__).resolve().parents[2] / "shared" / "reference" / "sitl"


def _pymavlink_index(path: Path, fast: bool) -> float:
    from pymavlink import DFReader

    old = os.environ.get("PYMAVLINK_FAST_INDEX")
    os.environ["PYMAVLINK_FAST_INDEX"] = "1" if fast else "0"
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            t0 = time.perf_counter()
            r = DFReader.DFReader_binary(str(path))
            dt = time.perf_counter() - t0
        r.data_map.close()
        r.filehandle.close()
        return dt
    finally:
        if old is None:
            del os.environ["PYMAVLINK_FAST_INDEX"]
        else:
            os.environ["PYMAVLINK_FAST_INDEX"] = old


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("logs", nargs="*", type=Path, help="logs (default: the reference SITL logs)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-messages", action="store_true",
                    help="skip read_bin(method='messages') and pymavlink's Python indexer")
    args = ap.parse_args()
    logs = args.logs or sorted(REFERENCE.glob("*.bin"))
    if not logs:
        raise SystemExit(f"no logs given and none found in {REFERENCE}")

    t0 = time.perf_counter()
    from tlm_sim.flightlog import binreader
    from tlm_sim.flightlog.binscan import scan_bin

    t_import = time.perf_counter() - t0
    t0 = time.perf_counter()
    scan_bin(logs[0])
    t_first = time.perf_counter() - t0
    print(f"import {t_import:.2f} s; first scan (numba compile or cache load + scan) "
          f"{t_first:.2f} s")
    head = (f"{'log':<18}{'MB':>6}{'msgs':>9}{'scan':>9}{'decode':>9}{'read_bin':>10}"
            f"{'MB/s':>8}{'pmv C idx':>11}{'pmv py idx':>12}{'messages':>10}{'ratio':>8}")
    print(head)
    print("-" * len(head))
    tot_mb = tot_read = tot_msgs_t = 0.0
    for path in logs:
        mb = path.stat().st_size / 1e6
        ix = scan_bin(path)
        n_msgs = sum(o.size for o in ix.offsets.values())
        names = binreader._present(ix)
        t_scan = best_of(lambda p=path: scan_bin(p), args.repeat)
        t_dec = best_of(lambda i=ix, n=names: binreader._decode_types(i, n), args.repeat)
        t_read = best_of(lambda p=path: binreader.read_bin(p), args.repeat)
        t_c = min(_pymavlink_index(path, fast=True) for _ in range(args.repeat))
        line = (f"{path.name:<18}{mb:>6.1f}{n_msgs:>9}{t_scan * 1e3:>7.1f}ms"
                f"{t_dec * 1e3:>7.0f}ms{t_read * 1e3:>8.0f}ms{mb / t_read:>8.0f}"
                f"{t_c * 1e3:>9.1f}ms")
        if not args.no_messages:
            t_py = _pymavlink_index(path, fast=False)
            t0 = time.perf_counter()
            binreader.read_bin(path, method="messages")
            t_msgs = time.perf_counter() - t0
            tot_msgs_t += t_msgs
            line += f"{t_py:>11.2f}s{t_msgs:>9.2f}s{t_msgs / t_read:>7.0f}x"
        tot_mb += mb
        tot_read += t_read
        print(line)
    print(f"all logs: {tot_mb:.1f} MB, read_bin (all types) {tot_mb / tot_read:.0f} MB/s", end="")
    if tot_msgs_t:
        print(f", method='messages' {tot_mb / tot_msgs_t:.1f} MB/s "
              f"({tot_msgs_t / tot_read:.0f}x slower)")
    else:
        print()


if __name__ == "__main__":
    main()
