"""``tlm evaluate DS``: the paper's classifiers, its CNN and a time-window model on a data set
(:mod:`tlm_process.evaluate`).

``run`` reports user mistakes itself (one line on stderr, exit code 2).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from tlm_process.cliutil import (
    UsageError,
    add_overwrite,
    check_writable_file,
    folder,
    fraction,
    int_at_least,
    number,
    prepare_out,
    whole_number,
)
from tlm_process.commands.process import report_user_errors

__all__ = ["BOOSTER_NAMES", "MODEL_NAMES", "TABLE_NAMES", "add_parser", "run"]

MODEL_NAMES = ("NaiveBayes", "Logistic", "SMO", "KNN", "AdaBoost", "OneR", "ZeroR", "J48",
               "RandomForest", "RandomTree", "CNN", "WindowHGB", "WindowHGB60", "CentredHGB",
               "SeqCNN")
TABLE_NAMES = ("GPS", "IMU", "RATE", "VIBE")
#: the window models' boosters (``tlm_process.evaluate.temporal.WINDOW_BOOSTERS``, written
#: out so that ``--help`` does not import numba)
BOOSTER_NAMES = ("xgboost", "sklearn")

DESCRIPTION = """\
Evaluate fault classifiers on a 'tlm process' data set as the paper's section 5 does, and
more honestly: the ten Weka classifiers of Table 11 (as scikit-learn estimators), the paper's
row-image CNN, WindowHGB, a model that sees the last seconds of each flight, and SeqCNN, a
causal convolutional network on each flight's rows. Prints the
Table 11-style table per data table (Weka's weighted TP rate, FP rate, precision, recall, F1;
'?' where precision is undefined because a class is never predicted) plus macro-F1.
"""

EPILOG = f"""\
models: all, or a comma list of {', '.join(MODEL_NAMES)}

splits:
  --split flight   (default) no flight in both training and test: the data set's own
                   train/test flights (tlm process --test-frac/--test-flight), else grouped
                   k-fold over flights (--folds, default 5)
  --split random   the paper's random row split (stratified; test share as the data set's,
                   or --test-frac); --folds K gives row k-fold CV. Neighbouring rows of one
                   flight then land on both sides: compare with --split flight to see the leak

transfer:
  --test-on LOG... trains on the data set and also tests on these logs (.bin + sidecar as
                   the reference SITL logs, tlm fly folders, ...), processed with the data
                   set's options and scaled with its scaler; adds a 'transfer' entry per model
                   and, with --out, DIR/feature_shift.csv (per feature and class: KS statistic
                   and percentiles of data set vs transfer rows). A log without fault labels
                   (no sidecar LOG.json, no faults.json, no fault records in the log) is
                   refused: a faulty flight would count as normal
  --assume-normal  the logs without fault labels are normal flights (recorded in R.json)
  --drop-features TABLE.COL[,TABLE.COL...]
                   leave these features out of training and the transfer logs, e.g.
                   RATE.AOutSlew, which Copter 4.0/4.1 logs lack

training rows:
  --train-hz HZ    every model is fitted on each training flight's rows thinned to about
                   HZ rows per second (every k-th row, k = round(table rate / HZ); 0: every
                   row; at least 0.001 otherwise); test and transfer rows are never
                   thinned. Default per model, as measured to score within 0.01 macro-F1 of
                   every row (docs/evaluation.md):
                   5 Hz (every GPS row, every 2nd RATE/VIBE row, every 5th IMU row) for
                   NaiveBayes, Logistic, KNN, AdaBoost, OneR, ZeroR, RandomForest and the
                   window models; 1 Hz for SMO; every row for J48, RandomTree, the CNN and
                   SeqCNN
  --normal-hz HZ   the Normal rows (most of every flight) of the models that take sample
                   weights (NaiveBayes, Logistic, ZeroR, RandomForest, RandomTree, the CNN
                   and the window models) are thinned further, to about HZ rows per second,
                   and weighted back so the class balance stays (0: as the other rows).
                   Default 1 Hz for Logistic, RandomForest, WindowHGB60 and CentredHGB, 2 Hz
                   for the CNN, 0 for the others (docs/evaluation.md)
  --max-rows N     a model is fitted on at most about N rows per fold: where its rates
                   keep more, they are lowered evenly in every flight, the Normal rows
                   first for the models that take sample weights, so a fit costs the same
                   on 60 flights or 1,000 (0: no limit). Default 100,000 for Logistic, SMO,
                   KNN, RandomForest, the CNN and WindowHGB, 30,000 for WindowHGB60 and
                   CentredHGB, no limit for the others (docs/evaluation.md "Row budget")
  --jobs N         threads (default: all cores); the results do not depend on it

window models:
  --booster B      the gradient boosting of WindowHGB, WindowHGB60 and CentredHGB: xgboost
                   (default) or sklearn, scikit-learn's HistGradientBoostingClassifier as
                   they had it until 2026-11: three to four times slower, 0.02-0.04 higher
                   test macro-F1 on 200 flights in three table x model cells
                   (docs/evaluation.md "The booster")

outputs:
  stdout           Table 11 per table; per model the false alarms per flight hour and per
                   fault class the median detection delay (1 s persistence; see
                   docs/evaluation.md "Detection delay and false alarms"); confusion matrix
                   and per-class scores (Tables 12-18) of the best model by macro-F1 (all
                   models with --details)
  --json R.json    {{TABLE: {{MODEL: {{accuracy, macro_f1, weighted_precision, weighted_recall,
                   weighted_f1, weighted_tp_rate, weighted_fp_rate, per_class, confusion,
                   detection, false_alarms_per_hour, transfer, ...}}}}}}; undefined values
                   are null
  --out DIR        DIR/<TABLE>_<MODEL>_confusion.png (+ _transfer_confusion.png),
                   DIR/<TABLE>_CNN_training.png (Figs. 20-21), DIR/report.txt

examples:
  tlm evaluate ds --table GPS --models RandomForest,J48,WindowHGB
  tlm evaluate ds --table all --split random --json random.json
  tlm evaluate ds --table GPS --test-on ../shared/reference/sitl/*.bin --out eval-out
"""


#: the lowest positive ``--train-hz`` / ``--normal-hz`` [Hz]: one row in 1000 s, already
#: less than one a flight (a smaller one overflowed the thinning step)
MIN_RATE_HZ = 1e-3


def _rate_hz(text: str) -> float:
    """0 (every row) or a finite rate >= :data:`MIN_RATE_HZ` [Hz] (``--train-hz``,
    ``--normal-hz``)."""
    v = number(text)
    if not (v == 0 or (v >= MIN_RATE_HZ and math.isfinite(v))):
        raise argparse.ArgumentTypeError(f"must be 0 (every row) or a finite rate >= "
                                         f"{MIN_RATE_HZ:g} Hz")
    return v


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``evaluate`` subcommand to ``tlm``'s subparsers; returns its parser."""
    p = subparsers.add_parser(
        "evaluate", help="train and score fault classifiers on a 'tlm process' data set",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("dataset", metavar="DS", help="a 'tlm process' output folder")
    p.add_argument("--table", default="all", metavar="GPS|IMU|RATE|VIBE|all",
                   help="data table(s), comma-separated (default all)")
    p.add_argument("--models", default="all", metavar="all|NAME,NAME",
                   help="models to run (default all; see below)")
    p.add_argument("--split", choices=("flight", "random"), default="flight",
                   help="flight: whole flights (default); random: the paper's row split")
    p.add_argument("--folds", type=int_at_least(2), default=None, metavar="K",
                   help="K-fold cross-validation (over flights, or rows with --split random) "
                        "instead of one hold-out")
    p.add_argument("--test-frac", type=fraction(zero=False), default=None, metavar="F",
                   help="--split random: share of rows tested (default: the data set's test "
                        "share, else 0.25)")
    p.add_argument("--seed", type=whole_number, default=0,
                   help="seed of the splits and models (default 0); same seed, same results")
    p.add_argument("--json", metavar="R.json", help="write the results as JSON")
    p.add_argument("--test-on", nargs="+", action="extend", default=[], metavar="LOG",
                   help="transfer test: also test on these logs (.bin + sidecar, tlm fly "
                        "folders, ...)")
    p.add_argument("--assume-normal", action="store_true",
                   help="--test-on logs without fault labels are normal flights (default: "
                        "refused)")
    p.add_argument("--drop-features", action="append", default=[],
                   metavar="TABLE.COL[,TABLE.COL...]",
                   help="leave these features out of training and the transfer logs (e.g. "
                        "RATE.AOutSlew, which older firmware does not log)")
    p.add_argument("--out", type=folder, metavar="DIR",
                   help="write confusion-matrix PNGs, the CNN's training curves and report.txt "
                        "here")
    p.add_argument("--details", action="store_true",
                   help="print every model's confusion matrix and per-class scores")
    p.add_argument("--jobs", type=int_at_least(1), default=None, metavar="N",
                   help="CPU threads (RandomForest, KNN, SMO, the window models, the CNN; "
                        "default: all cores); results do not depend on it")
    p.add_argument("--train-hz", type=_rate_hz, default=None, metavar="HZ",
                   help="fit every model on each training flight's rows thinned to about HZ "
                        "rows per second (0: every row; default: per model, see below); "
                        "test rows are never thinned")
    p.add_argument("--normal-hz", type=_rate_hz, default=None, metavar="HZ",
                   help="thin the Normal training rows of the models that take sample weights "
                        "further, to about HZ rows per second, weighted back (0: as the "
                        "other rows; default: per model, see below)")
    p.add_argument("--max-rows", type=whole_number, default=None, metavar="N",
                   help="fit every model on at most about N rows per fold, lowering its "
                        "rates evenly in every flight where needed (0: no limit; default: "
                        "per model, see below)")
    p.add_argument("--booster", choices=BOOSTER_NAMES, default="xgboost",
                   help="gradient boosting of the window models (default xgboost; see below)")
    p.add_argument("--cnn-epochs", type=int_at_least(1), default=None, metavar="N",
                   help="CNN training epochs (default 10)")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    add_overwrite(p)
    p.set_defaults(func=run)
    return p


def _tables(text: str) -> list[str]:
    from tlm_process.evaluate.data import EvaluateError

    items = [s.strip().upper() for s in text.split(",") if s.strip()]
    if not items:
        raise EvaluateError("--table: no table given")
    if "ALL" in items:
        return list(TABLE_NAMES)
    bad = [s for s in items if s not in TABLE_NAMES]
    if bad:
        raise EvaluateError(f"--table: unknown table {bad[0]!r}; choose from "
                         f"{', '.join(TABLE_NAMES)} or all")
    return list(dict.fromkeys(items))


def run(args: argparse.Namespace) -> int:
    """Run ``tlm evaluate``; 0 on success, 2 on a user error (one line on stderr)."""
    return report_user_errors(_run, args)


def _best(results: dict, key: str = "macro_f1", transfer: bool = False) -> str | None:
    best, score = None, -1.0
    for m, r in results.items():
        v = (r.get("transfer") or {}).get(key) if transfer else r.get(key)
        if v is not None and v == v and v > score:
            best, score = m, v
    return best


def _check(args: argparse.Namespace, models: list[str]) -> None:
    """Raise EvaluateError for options that exclude each other, a --json folder, or CNN
    without torch: before anything is read."""
    from tlm_process.evaluate.data import EvaluateError

    if args.split != "random" and args.test_frac is not None:
        raise EvaluateError("--test-frac applies to --split random only (the flight split "
                            "uses the data set's test flights or --folds)")
    if args.split == "random" and args.test_frac is not None and args.folds is not None:
        raise EvaluateError("--test-frac and --folds exclude each other")
    if args.assume_normal and not args.test_on:
        raise EvaluateError("--assume-normal applies to --test-on logs only")
    if args.json:
        try:
            check_writable_file(args.json, "--json")
        except UsageError as e:
            raise EvaluateError(str(e)) from None
    if "CNN" in models:
        from tlm_process.evaluate.cnn import require_torch

        try:
            require_torch()
        except ImportError as e:
            raise EvaluateError(str(e)) from None


def _run(args: argparse.Namespace) -> int:
    from tlm_process.evaluate.runner import resolve_models

    tables = _tables(args.table)
    models = resolve_models(args.models)
    _check(args, models)
    import numpy as np

    from tlm_process.evaluate.data import (
        drop_features,
        load_dataset,
        load_transfer,
        parse_drop_features,
    )
    from tlm_process.evaluate.runner import evaluate

    t_start = time.perf_counter()
    quiet = args.quiet

    def say(msg: str) -> None:
        if not quiet:
            print(msg, file=sys.stderr, flush=True)

    out = prepare_out(args.out, "evaluate", args.overwrite,
                      inputs=[args.dataset, *args.test_on]) if args.out else None
    ds = load_dataset(args.dataset, tables)
    if args.drop_features:
        ds = drop_features(ds, parse_drop_features(args.drop_features, ds))
    transfer = None
    if args.test_on:
        say(f"reading {len(args.test_on)} transfer log(s) with the data set's options (RC "
            f"labels: {ds.options.get('rc_label') or 'window'}) and scaler")
        transfer = load_transfer(args.test_on, ds, tables, assume_normal=args.assume_normal,
                                 progress=say)
    np.seterr(all="ignore")
    results = evaluate(ds, tables=tables, models=models, split=args.split, seed=args.seed,
                       folds=args.folds, test_frac=args.test_frac, transfer=transfer,
                       out_dir=out, progress=say, n_jobs=args.jobs,
                       cnn_epochs=args.cnn_epochs, train_hz=args.train_hz,
                       normal_hz=args.normal_hz, max_rows=args.max_rows,
                       bar=False if quiet else None, booster=args.booster)
    if transfer is not None:
        for res in results.values():
            for r in res.values():
                r["assume_normal"] = bool(args.assume_normal)
    lines: list[str] = []
    for t, res in results.items():
        lines += _table_lines(t, res, args, details_of=_shown(res, args.details,
                                                             transfer is not None))
    if transfer is not None:
        lines.append(_shift_text(ds, transfer, out))
    text = "\n".join(lines).rstrip() + "\n"
    print(text, end="")
    _write(text, results, out, args.json)
    say(f"done in {time.perf_counter() - t_start:.1f} s"
        + (f"; wrote {args.json}" if args.json else "")
        + (f"; plots in {out}/" if out is not None else ""))
    return 0


def _shown(res: dict, details: bool, transfer: bool) -> list[str]:
    """Models whose confusion matrix is printed: all with --details, else the best by
    macro-F1 (and the best on the transfer logs, when there are any)."""
    shown = list(res) if details else [m for m in {_best(res)} if m]
    if transfer and not details:
        bt = _best(res, transfer=True)
        if bt and bt not in shown:
            shown.append(bt)
    return shown


def _table_lines(t: str, res: dict, args: argparse.Namespace, details_of: list[str]
                 ) -> list[str]:
    """One table's report: the Table 11-style table, the confusion matrices and per-class
    scores of the models ``details_of``, the models with undefined precision."""
    from tlm_process.evaluate.metrics import (
        format_confusion,
        format_per_class,
        format_results_table,
        format_timing_table,
    )
    from tlm_process.evaluate.runner import default_jobs

    first = next(iter(res.values()))
    how = (f"{args.split} split, {first['folds']} folds" if first["folds"] > 1 else
           f"{args.split} split")
    lines = [format_results_table(
        res, f"{t}: {first['n_test']:,} test rows, {first['n_train'] // first['folds']:,}"
             f" training rows per fold ({how}, seed {args.seed})"
             + (f"; transfer: {first['transfer']['n']:,} rows of "
                f"{len(args.test_on)} log(s)" if "transfer" in first else "")
             + ("; logs without labels taken as normal" if args.assume_normal else "")
             + (f"; dropped {', '.join(first['dropped_features'])}"
                if first.get("dropped_features") else ""),
        transfer="transfer" in first)]
    lines += _event_lines(t, res, "transfer" in first)
    for m in details_of:
        r = res[m]
        lines.append("")
        lines.append(format_confusion(r["confusion"], list(r["per_class"]),
                                      title=f"{t} {m}: confusion matrix "
                                            "(rows true, columns predicted)"))
        lines.append(format_per_class(r, title=f"{t} {m}: per class"))
        if "transfer" in r:
            lines.append(format_confusion(r["transfer"]["confusion"],
                                          list(r["transfer"]["per_class"]),
                                          title=f"{t} {m}: confusion on the transfer logs"))
            lines.append(format_per_class(r["transfer"],
                                          title=f"{t} {m}: per class on the transfer logs"))
    undefined = {m: r["undefined_precision"] for m, r in res.items()
                 if r["undefined_precision"]}
    if undefined:
        lines.append("")
        lines.append("'?': precision undefined (paper: NaN) because the model never "
                     "predicts " + "; ".join(f"{m}: {', '.join(c)}"
                                             for m, c in undefined.items()))
    lines.append("")
    jobs = args.jobs or default_jobs()
    lines.append(format_timing_table(res, f"{t}: time per model (wall seconds, {jobs} "
                                          f"thread(s); training rows thinned to 'train Hz')"))
    lines.append("")
    return lines


def _event_lines(t: str, res: dict, transfer: bool) -> list[str]:
    """The detection-delay and false-alarm tables of the test rows (and transfer rows)."""
    from tlm_process.evaluate.events import PERSISTENCE_S, format_detection_table

    lines = []
    for xfer, where in ((False, "test rows"), (True, "transfer rows")):
        first = next(iter(res.values()))
        if xfer:
            first = first.get("transfer") or {}
        if (xfer and not transfer) or "normal_hours" not in first:
            continue
        text = format_detection_table(
            res, f"{t}: detection delay and false alarms on the {where} (persistence "
                 f"{PERSISTENCE_S:g} s; FA: false alarms in {first['normal_hours']:.2f} h of "
                 f"normal rows; per fault class: median detection delay [s] "
                 f"(detected/events))", transfer=xfer)
        if text:
            lines += ["", text]
    return lines


def _shift_text(ds, transfer: dict, out: Path | None) -> str:
    """The feature-shift table of data set vs transfer rows (also ``OUT/feature_shift.csv``)."""
    from tlm_process.evaluate.shift import feature_shift, format_shift

    scaled = bool((ds.report.get("scaling") or {}).get("applied", True))
    shift = feature_shift(ds.tables, transfer, ds.features, ds.scaler, scaled)
    if out is not None:
        shift.to_csv(out / "feature_shift.csv", index=False, float_format="%.6g")
    return format_shift(shift)


def _write(text: str, results: dict, out: Path | None, json_path: str | None) -> None:
    """``OUT/report.txt`` (with --out) and the results as JSON (with --json)."""
    from tlm_process.evaluate.metrics import to_jsonable

    if out is not None:
        (out / "report.txt").write_text(text)
    if json_path:
        jp = Path(json_path)
        if jp.parent != Path(""):
            jp.parent.mkdir(parents=True, exist_ok=True)
        jp.write_text(json.dumps(to_jsonable(results), indent=1) + "\n")
