"""``tlm train DS... --out MODEL``: fit the whole-log fault detector and save it
(:mod:`tlm_process.detect`).

``run`` reports user mistakes itself (one line on stderr, exit code 2).
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from tlm_process.cliutil import (
    add_overwrite,
    folder,
    fraction,
    int_at_least,
    positive_number,
    prepare_out,
    whole_number,
)
from tlm_process.commands.process import report_user_errors

if TYPE_CHECKING:
    from tlm_process.detect.train import TrainResult

__all__ = ["add_parser", "run"]

DESCRIPTION = """\
Fit the whole-log fault detector on labelled flights and save it in a model folder that
'tlm detect' runs on any ArduPilot log. The detector reads every table a log carries that
holds evidence (GPS, GPA, IMU and VIBE of both IMUs, RATE, ATT, BARO, MAG, BAT, the EKF's
innovations and test ratios (XKF1/3/4), motor outputs RCOU, RCIN, CTUN, MODE and ERR), aligned
on one 10 Hz grid from arming to disarming, summarised over trailing 2 s and 10 s windows:
causal, each decision uses only rows up to its time. The classifier is XGBoost; the weights
are saved in XGBoost's own UBJSON format (no pickle) beside manifest.json. With --models, one
of tlm evaluate's window models on one table of a 'tlm process' data set instead.
"""

EPILOG = """\
inputs: anything 'tlm process' reads that carries fault labels: a 'tlm generate' data set
  (the usual: tlm generate --flights 200 --out ds), .bin logs with their sidecar JSON, tlm fly
  folders, or folders of these. Fault windows are anchored as 'tlm process' does (recorded
  times; the RC fault while the radio is lost).

outputs: MODEL/manifest.json (tlm version, command, channels with units and the log columns
  they need, feature columns, classes, options, training data summary, held-out scores, the
  weights' SHA-256) and MODEL/booster.ubj.

channels: --list-channels prints them. --drop-features removes channels: a channel
  (IMU1.GyrX), a group (IMU1: IMU instance 1, XKF4L1: EKF lane 1), a table (XKF3) or a log
  column (RATE.AOutSlew: every channel computed from it). Drop what your logs lack, e.g.
  RATE.AOutSlew for Copter 4.0/4.1, IMU1,VIBE1 for one-IMU boards; 'tlm detect' names them.
  --tables keeps only the channels of these tables (e.g. --tables GPS: the paper's GPS-only
  view, as a detector).

examples:
  tlm generate --flights 200 --out ds --seed 1
  tlm process ds --out ds-tlm
  tlm train ds-tlm --models WindowHGB60 --tables GPS --out model-gps
  tlm train ds --out model --holdout 0.2
  tlm train ds --out model-41 --drop-features RATE.AOutSlew
  tlm detect model flight.bin --out found
"""


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``train`` to ``tlm``'s subcommands; returns its parser."""
    p = subparsers.add_parser(
        "train", help="fit the whole-log fault detector on labelled flights and save it",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="*", metavar="DS",
                   help="labelled flights: tlm generate data sets, .bin logs with sidecars, "
                        "tlm fly folders")
    p.add_argument("--out", type=folder, metavar="MODEL", help="the model folder to write")
    p.add_argument("--holdout", type=fraction(zero=True), default=0.0, metavar="F",
                   help="hold out each flight with probability F (a hash of --seed and its "
                        "id) and score the detector on them (default 0: train on all)")
    p.add_argument("--holdout-flight", action="append", default=[], metavar="PATTERN",
                   help="hold out the flights whose id matches PATTERN (fnmatch; repeatable)")
    p.add_argument("--drop-features", action="append", default=[],
                   metavar="NAME[,NAME...]",
                   help="channels, groups, tables or log columns not to use (see below)")
    p.add_argument("--tables", default=None, metavar="TABLE[,TABLE...]",
                   help="use only the channels of these log tables (default: all); with "
                        "--models, the one table of the tlm process data set")
    p.add_argument("--models", default=None, metavar="MODEL",
                   help="instead of the whole-log detector, the paper's per-table view: "
                        "window model WindowHGB, WindowHGB60 or CentredHGB on one table "
                        "(--tables) of a 'tlm process' data set")
    p.add_argument("--rounds", type=int_at_least(1), default=100, metavar="N",
                   help="boosting rounds (default 100)")
    p.add_argument("--min-child-weight", type=positive_number, default=20.0, metavar="W",
                   help="least summed hessian of a leaf (XGBoost's min_child_weight; default "
                        "20: no leaf for a handful of rows of one rare event; a training set "
                        "of a few flights needs 1)")
    p.add_argument("--seed", type=whole_number, default=0,
                   help="seed of the hold-out draw and the booster (default 0)")
    p.add_argument("--jobs", type=int_at_least(1), default=None, metavar="N",
                   help="threads (default: all cores)")
    p.add_argument("--partial", action="store_true",
                   help="read the finished flights of an unfinished tlm generate data set")
    p.add_argument("--list-channels", action="store_true",
                   help="print the channels (name, kind, unit, log columns) and exit")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_overwrite(p)
    p.set_defaults(func=run)
    return p


def _split(items: list[str]) -> list[str]:
    return [x.strip() for item in items for x in item.split(",") if x.strip()]


def _drops(args: argparse.Namespace) -> list[str]:
    """--drop-features, plus every table not in --tables."""
    from tlm_process.detect.channels import CHANNELS
    from tlm_process.detect.data import DetectError

    drop = _split(args.drop_features)
    if args.tables is not None:
        keep = _split([args.tables])
        tables = {n.split(".", 1)[0] for c in CHANNELS for n in c.needs}
        bad = [t for t in keep if t not in tables]
        if bad or not keep:
            raise DetectError(f"--tables: {', '.join(bad) or '(none)'} is not a table the "
                              f"detector reads ({', '.join(sorted(tables))})")
        drop += sorted(tables - set(keep))
    return drop


def _list_channels() -> int:
    from tlm_process.detect.channels import CHANNELS

    w = max(len(c.name) for c in CHANNELS)
    for c in CHANNELS:
        print(f"{c.name:<{w}}  {c.kind:<5}  {c.unit:<9}  {', '.join(c.needs)}")
    return 0


def _run(args: argparse.Namespace) -> int:
    import os

    from tqdm import tqdm

    from tlm_process.cliutil import UsageError
    from tlm_process.detect.train import TrainOptions, check_drop, manifest, train_detector

    if args.list_channels:
        return _list_channels()
    if not args.inputs:
        raise UsageError("tlm train: name the labelled flights (DS...), or --list-channels")
    if not args.out:
        raise UsageError("tlm train: --out MODEL is required")
    if args.models is not None:
        return _run_table(args)
    _refuse_processed(args.inputs)
    opt = TrainOptions(drop=tuple(_drops(args)), holdout=args.holdout,
                       holdout_flights=tuple(args.holdout_flight), seed=args.seed,
                       rounds=args.rounds, min_child_weight=args.min_child_weight,
                       n_jobs=args.jobs or os.cpu_count() or 1,
                       partial=args.partial)
    check_drop(opt.drop)  # before the folder is made
    out = prepare_out(args.out, "train", args.overwrite, inputs=args.inputs)
    bar = tqdm(desc="reading flights", unit=" flights", disable=args.quiet, file=sys.stderr)

    def progress(n: int, fid: str) -> None:
        bar.update(1)

    try:
        res = train_detector(args.inputs, opt, progress)
    finally:
        bar.close()
    res.detector.manifest = manifest(res, opt, [str(Path(p)) for p in args.inputs],
                                     _command())
    res.detector.save(out)
    _print(res, out)
    return 0


def _is_processed(path: str) -> bool:
    from tlm_process.pipeline.ingest import _is_processed as processed

    return Path(path).is_dir() and processed(Path(path))


def _refuse_processed(inputs: list[str]) -> None:
    from tlm_process.detect.data import DetectError

    for p in inputs:
        if _is_processed(p):
            raise DetectError("a 'tlm process' data set holds the paper's four tables only: "
                              "the whole-log detector trains on raw flights (tlm generate "
                              "data sets, logs); for a per-table detector give --models "
                              "WindowHGB60 --tables GPS", source=p)


def _run_table(args: argparse.Namespace) -> int:
    """``--models``: one window model on one table of a ``tlm process`` data set."""
    import os

    from tlm_process.cliutil import UsageError
    from tlm_process.detect.table_model import train_table
    from tlm_process.detect.table_spec import check_table_model
    from tlm_process.detect.train import TrainOptions, manifest

    models = _split([args.models])
    tables = _split([args.tables]) if args.tables else []
    if len(models) != 1 or len(tables) != 1:
        raise UsageError("tlm train --models: one window model and one table (--tables) per "
                         "model folder, e.g. --models WindowHGB60 --tables GPS")
    check_table_model(models[0])  # before the folder is made
    if len(args.inputs) != 1 or not _is_processed(args.inputs[0]):
        raise UsageError("tlm train --models: name one 'tlm process' data set (tlm process "
                         "DS --out DS-tlm)")
    if not args.out:
        raise UsageError("tlm train: --out MODEL is required")
    opt = TrainOptions(drop=tuple(_split(args.drop_features)), holdout=args.holdout,
                       holdout_flights=tuple(args.holdout_flight), seed=args.seed,
                       rounds=args.rounds, min_child_weight=args.min_child_weight,
                       n_jobs=args.jobs or os.cpu_count() or 1)
    out = prepare_out(args.out, "train", args.overwrite, inputs=args.inputs)
    res = train_table(args.inputs[0], tables[0], models[0], opt)
    res.detector.manifest = manifest(res, opt, list(args.inputs), _command())
    res.detector.save(out)
    _print(res, out)
    return 0


def _command() -> str:
    if len(sys.argv) > 1 and sys.argv[1] == "train":
        return "tlm train " + " ".join(shlex.quote(a) for a in sys.argv[2:])
    return "tlm train"


def _print(res: TrainResult, out: Path) -> None:
    from tlm_process.labels import class_name

    det = res.detector
    t = res.times
    print(f"model              {out}")
    print(f"flights            {len(res.train)} trained on, {len(res.held_out)} held out")
    table = det.channels[0].split(".")[0]
    what = "whole-log detector" if det.kind == "whole-log" else f"{det.kind} on {table}"
    print(f"model kind         {what}")
    print(f"channels           {len(det.channels)} ({len(det.features)} features, "
          f"{len(det.columns)} used)")
    print(f"classes            {', '.join(class_name(c) for c in det.classes)}")
    print(f"time               read {t['read_s']:.1f} s, fit {t['fit_s']:.1f} s")
    s = res.scores
    if s:
        ev = s["events"]
        print(f"held out           row macro-F1 {s['macro_f1']:.3f} over {len(s['labels'])} "
              f"labels, accuracy {s['accuracy']:.3f}, false alarms "
              f"{ev['false_alarms_per_hour'] or 0:.2f} per flight hour")
        for name, d in ev["detection"].items():
            med = d["delay_median_s"]
            print(f"  {name:<15} F1 {s['f1'].get(name, float('nan')):.3f}  found "
                  f"{d['detected']}/{d['events']}  median delay "
                  f"{'-' if med is None else f'{med:.1f} s'}")


def run(args: argparse.Namespace) -> int:
    """Run ``tlm train``; 0 on success, 2 on a user error (one line on stderr)."""
    return report_user_errors(_run, args)
