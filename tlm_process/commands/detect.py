"""``tlm detect MODEL LOG... --out DIR``: run a saved detector on ArduPilot logs
(:mod:`tlm_process.detect.run`).

``run`` reports user mistakes itself (one line on stderr, exit code 2).
"""

from __future__ import annotations

import argparse
import sys

from tlm_process.cliutil import add_overwrite, folder, prepare_out
from tlm_process.commands.process import report_user_errors

__all__ = ["add_parser", "run"]

DESCRIPTION = """\
Run a detector saved by 'tlm train' on ArduPilot logs: tlm's, SITL's or a real vehicle's,
.bin or text .log, Copter 3.x to 4.7, with or without a fault sidecar. Each log is read
from arming (EV 10, ARM, or the first motor output above idle for a log that starts at
arming) to disarming, on the detector's 10 Hz grid; every row gets a probability per class.
A fault is reported when one class is predicted for at least 1 s; runs less than 5 s apart
are one fault, named by the class predicted on most of its rows. A per-table model (tlm train
--models) predicts every row of its table instead, the log processed as its data set's
flights were.
"""

EPILOG = """\
outputs:
  DIR/summary.csv              one row per fault found: log, class, label, start_s, end_s
                               (log time, s since boot), peak_p, also (other classes
                               predicted briefly within it); class 'none' for a log where
                               nothing was found
  DIR/<log>/predictions.parquet  TimeUS, p_<class> per class, label (the most probable),
                               fault (the class of the fault reported over the row, 0
                               outside them); true_label when the log has a sidecar
  DIR/<log>/timeline.png       class probabilities over time, the faults reported, the log's
                               MODE/ERR/EV marks, and the true fault windows when known

a log lacking a column the model reads is refused with one line naming it and the
--drop-features to train without it (or run with --allow-missing: those channels are
then missing values throughout, and the columns are listed). Other logs are still run;
the exit code is 2 if any log was refused.

examples:
  tlm detect model flight.bin --out found
  tlm detect model ../shared/reference/sitl/*.bin --out found-sitl
"""


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``detect`` to ``tlm``'s subcommands; returns its parser."""
    p = subparsers.add_parser(
        "detect", help="find faults in ArduPilot logs with a detector from tlm train",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("model", metavar="MODEL", help="a model folder written by tlm train")
    p.add_argument("logs", nargs="+", metavar="LOG", help=".bin or .log files")
    p.add_argument("--out", type=folder, required=True, metavar="DIR",
                   help="output folder (summary.csv, one folder per log)")
    p.add_argument("--allow-missing", action="store_true",
                   help="run on logs that lack columns the model reads (listed), instead of "
                        "refusing them")
    p.add_argument("--no-plots", action="store_true", help="skip timeline.png")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_overwrite(p)
    p.set_defaults(func=run)
    return p


def _run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from tqdm import tqdm

    from tlm_process.detect.model import load_detector
    from tlm_process.detect.run import run_detect

    det = load_detector(args.model)
    out = prepare_out(args.out, "detect", args.overwrite, inputs=[args.model, *args.logs])

    def bar(paths):  # noqa: ANN001, ANN202
        return tqdm(paths, desc="detecting", unit=" logs", disable=args.quiet,
                    file=sys.stderr)

    results, errors = run_detect(det, [Path(p) for p in args.logs], out,
                                 allow_missing=args.allow_missing, plots=not args.no_plots,
                                 progress=bar)
    for res in results:
        found = ", ".join(f"{f.name} {f.start_s:.1f}-{f.end_s:.1f} s (p {f.peak:.2f})"
                          for f in res.findings) or "none"
        print(f"{res.log.source}: {found}")
        if res.missing:
            print(f"  not used (the log lacks them): {', '.join(res.missing)}")
        if res.log.arming != "EV 10":
            print(f"  armed span from {res.log.arming}")
        if res.scores:
            sc = res.scores
            marks = ", ".join(f"{f['class']} at {f['start_s']:.1f} s "
                              f"{'found' if f['found'] else 'MISSED'}"
                              + (f" ({f['delay_s']:+.1f} s)" if f["found"] else "")
                              for f in sc["faults"]) or "no faults"
            print(f"  sidecar: {marks}; row macro-F1 {sc['macro_f1']:.3f}")
    print(f"summary            {out / 'summary.csv'}")
    for e in errors:
        print(f"tlm: error: {e}", file=sys.stderr)
    return 2 if errors else 0


def run(args: argparse.Namespace) -> int:
    """Run ``tlm detect``; 0 on success, 2 on a user error (one line on stderr)."""
    return report_user_errors(_run, args)
