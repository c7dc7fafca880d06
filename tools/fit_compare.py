"""Fit-and-compare on one real log (issue 40's check): ``tlm fit`` on the first half of a steady
segment, then tlm flying the fitted vehicle (new seeds) against the segment's second half.

    python tools/fit_compare.py LOG [--segment START:END] [--seeds 4] [--iterations 10]
        [--fit-seed 1]

Without ``--segment`` it takes the steady hover ``tlm fit`` would find.

Prints a markdown table (statistic, log first half, log second half, how the halves differ,
tlm, tlm against each half, within 30 % of the second) and writes the fitted parameters
with ``--out``. The steering's blind check on held-back vehicles runs the same script.
Measured on log171.bin (199.5-216.5 s, the hover ``tlm fit`` finds, and 197.5-216.5 s with
LOITER's brake): docs/noise.md.
"""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

import numpy as np

from tlm_process.fit.fit import ALT_HOLD, fit_vehicle, fly_hover_stats, log_battery
from tlm_process.fit.segment import LEVEL_MODES, parse_segment, segment_mode, steady_segments
from tlm_process.fit.stats import segment_stats
from tlm_process.logread import read_log_tables

#: the statistics issue 40 asks within 30 % of the log (VIBE: Copter 3.3 logs have none)
JUDGED = ("hover_thr", "roll_std_deg", "pitch_std_deg", "acc_x_std", "acc_y_std", "acc_z_std",
          "gyr_x_std_dps", "gyr_y_std_dps", "gyr_z_std_dps", "rate_roll_err_std_dps",
          "rate_pitch_err_std_dps")
TOLERANCE = 0.30


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log")
    ap.add_argument("--segment", metavar="START:END", help="seconds of log time (default: the "
                    "steady segment tlm fit finds)")
    ap.add_argument("--seeds", type=int, default=4, help="tlm flights compared (default 4)")
    ap.add_argument("--iterations", type=int, default=10)
    ap.add_argument("--fit-seed", type=int, default=1, help="first seed of the fit's hovers "
                    "(default 1; the fit's flights scatter, so its result does too)")
    ap.add_argument("--out", metavar="vehicle.parm", help="write the fitted parameters")
    args = ap.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lt = read_log_tables(args.log)
        segments = [parse_segment(args.segment)] if args.segment else steady_segments(lt.tables)
        if not segments:
            raise SystemExit("fit_compare: the log has no steady segment; give --segment")
        t0, t1 = segments[0]
        mid = 0.5 * (t0 + t1)
        first = segment_stats(lt.tables, t0, mid)
        second = segment_stats(lt.tables, mid, t1)
        # a segment flown in STABILIZE or ALT_HOLD is fitted and compared with ALT_HOLD
        # hovers (tlm fit)
        mode = ALT_HOLD if segment_mode(lt.tables, t0) in LEVEL_MODES else None
        fit = fit_vehicle(first, lt.params, args.iterations, seed=args.fit_seed,
                          battery=log_battery(lt.tables, lt.params), mode=mode)
        runs = [fly_hover_stats(fit.params, seed=101 + k, mode=mode)
                for k in range(args.seeds)]
    tlm = {k: float(np.mean([r[k] for r in runs])) for k in runs[0]}
    spread = {k: float(np.std([r[k] for r in runs])) for k in runs[0]}
    print(f"{Path(args.log).name}: fitted on {t0 * 1e-6:.1f}-{mid * 1e-6:.1f} s, compared "
          f"with {mid * 1e-6:.1f}-{t1 * 1e-6:.1f} s; tlm: mean (std) of {args.seeds} hovers, "
          "seeds 101+\n")
    print("| statistic | log, first half (fitted) | log, second half | second half vs first | "
          "tlm, fitted vehicle | tlm vs first half | tlm vs second half | within 30 % |")
    print("|---|---|---|---|---|---|---|---|")
    n_ok = n = n_fit = n_log = 0
    for k in first:
        a, b, t = first[k], second[k], tlm[k]
        if not (math.isfinite(a) and a and math.isfinite(b) and b):
            print(f"| {k} | {_n(a)} | {_n(b)} | - | {_n(t)} ({_n(spread[k])}) | - | - | - |")
            continue
        d, d_fit, d_log = t / b - 1.0, t / a - 1.0, b / a - 1.0
        ok = abs(d) <= TOLERANCE
        if k in JUDGED:
            n += 1
            n_ok += ok
            n_fit += abs(d_fit) <= TOLERANCE
            n_log += abs(d_log) > TOLERANCE
        verdict = ("yes" if ok else "**no**") if k in JUDGED else "-"
        print(f"| {k} | {_n(a)} | {_n(b)} | {d_log:+.0%} | {_n(t)} ({_n(spread[k])}) | "
              f"{d_fit:+.0%} | {d:+.0%} | {verdict} |")
    print(f"\n{n_ok} of {n} judged statistics within {TOLERANCE:.0%} of the second half "
          f"({n_fit} of the first half, the one fitted; the log's halves differ by more than "
          f"{TOLERANCE:.0%} on {n_log})")
    if args.out:
        from tlm_sim.params import Params

        Path(args.out).write_text(Params(fit.params).to_parm_text(only_changed=True))
        print(f"written {args.out}")
    return 0


def _n(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:.3g}"


if __name__ == "__main__":
    raise SystemExit(main())
