"""``tlm process INPUT... --out DS``: the TLM pipeline (:mod:`tlm_process.pipeline`) on the
command line.

``run`` reports user mistakes itself (one line on stderr, exit code 2).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path

from tlm_process.cliutil import (
    UsageError,
    add_overwrite,
    folder,
    fraction,
    is_one_of,
    positive_number,
    prepare_out,
    whole_number,
)

__all__ = ["add_parser", "report_user_errors", "run"]

DESCRIPTION = """\
Turn flights into labelled, feature-processed, scaled data tables (the paper's Time Line
Modeling pipeline): anchor each fault's window (Eq. 4), label every row (0 normal, 1 GPS,
2 accelerometer, 3 engine, 4 RC), drop time-related and non-universal columns (Algorithm 2),
merge flights per table, and min-max scale (Eq. 6) with a scaler fitted on training flights.
"""

EPILOG = """\
INPUT is any of:
  a tlm fly output folder        DIR/meta.json + DIR/GPS.parquet|csv ... (faults in meta.json)
  a DataFlash log with sidecar   X.bin + X.json beside it ({"faults": [...]}, as the SITL logs)
  a folder of per-message CSVs   DIR/GPS.csv, DIR/IMU.csv, ... + DIR/faults.json
  a multi-flight dataset         DS/GPS.parquet ... with a 'flight' column + DS/faults.parquet
  a folder holding any of these  (expanded one level)

writes:
  DS/GPS.parquet DS/IMU.parquet DS/RATE.parquet DS/VIBE.parquet
      flight, split, TimeUS, label + the feature columns (scaled unless --no-scale)
  DS/scaler.json     min/max per feature, fitted on the training flights only
  DS/report.json     features per table, counts per table and label, fault share,
                     split, windows per flight, anchoring disagreement
  DS/label_shares.png, DS/plots/<flight>_trajectory.png, DS/plots/<flight>_fault<i>_<type>.png

anchoring: --anchor auto uses the recorded log times when every fault record has them
(tlm and the SITL sidecars do) and the paper's position method otherwise.

RC labels: --rc-label window (default) labels an RC fault as the paper does, while the radio
is lost; --rc-label failsafe also labels the RTL the radio failsafe started (MODE reason 3)
as RC until it lands (EV 18), is disarmed or leaves that mode, but never into the next
fault's window. report.json records the choice.

examples:
  tlm process ../shared/reference/sitl --out ds-sitl
  tlm process flight1 flight2 combined_s21.bin --out ds --test-flight 'combined_*'
  tlm process runs/ --out ds --test-frac 0.25 --target-fault-ratio 0.54
  tlm process ../shared/reference/sitl/rc_s15.bin --out ds-rc --rc-label failsafe
"""


_fraction = fraction(zero=True)


def _ratio(text: str) -> float:
    v = _fraction(text)
    if v == 0:
        raise argparse.ArgumentTypeError("must be > 0")
    return v


def _instance(text: str) -> int | None:
    if text.strip().lower() == "all":
        return None
    if text.strip() in ("0", "1"):
        return int(text)
    raise argparse.ArgumentTypeError(f"{text!r}: use 0, 1 or all")


def add_parser(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``process`` subcommand to ``tlm``'s subparsers; returns its parser."""
    p = subparsers.add_parser(
        "process", help="label, feature-process and scale flights into a data set",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="flight folders, .bin or text .log logs with sidecars, CSV folders, "
                        "datasets")
    p.add_argument("--out", type=folder, required=True, metavar="DS", help="output folder")
    p.add_argument("--anchor", choices=("auto", "time", "position"), default="auto",
                   help="fault window anchoring (default auto: recorded times when present)")
    p.add_argument("--max-match-m", type=positive_number, default=None, metavar="M",
                   help="position anchoring: a recorded position farther than M metres from "
                        "every GPS row matches nowhere (default 25)")
    p.add_argument("--rc-label", choices=("window", "failsafe"), default="window",
                   help="RC fault rows: window (default, the paper's: while the radio is "
                        "lost) or failsafe (also the radio failsafe's RTL, until it lands)")
    p.add_argument("--phase", choices=("armed", "all"), default="armed",
                   help="rows kept: from arming to disarming (default, as a log with "
                        "LOG_DISARMED=0) or all")
    p.add_argument("--instance", type=_instance, default=0, metavar="0|1|all",
                   help="IMU/VIBE instance kept (default 0, as the paper's row counts imply)")
    p.add_argument("--tables", default="GPS,IMU,RATE,VIBE",
                   help="data tables to write (default GPS,IMU,RATE,VIBE)")
    p.add_argument("--test-flight", action="append", default=[], metavar="PATTERN",
                   help="flights whose id matches this glob are test flights (repeatable)")
    p.add_argument("--test-frac", type=_fraction, default=0.0, metavar="F",
                   help="else: fraction of flights (rounded down) drawn as test flights "
                        "(default 0)")
    p.add_argument("--seed", type=whole_number, default=0, help="seed of the --test-frac draw")
    p.add_argument("--no-scale", action="store_true",
                   help="write raw feature values (scaler.json is still written)")
    p.add_argument("--target-fault-ratio", type=_ratio, default=None, metavar="GAMMA",
                   help="also report the window stretching factor lambda = gamma / alpha "
                        "per table (Eq. 5)")
    p.add_argument("--plots", type=whole_number, default=5, metavar="N",
                   help="trajectory and per-fault plots for the first N flights (default 5; "
                        "0 for none)")
    p.add_argument("--partial", action="store_true",
                   help="read a tlm generate data set that is not complete (killed, "
                        "interrupted, failed flights) anyway: its finished flights only "
                        "(recorded in report.json)")
    p.add_argument("--quiet", action="store_true", help="no per-flight lines")
    add_overwrite(p)
    p.set_defaults(func=run)
    return p


def report_user_errors(body: Callable[[argparse.Namespace], int],
                       args: argparse.Namespace) -> int:
    """``body(args)``, turning a PipelineError (and its subclasses), a UsageError or an OSError
    into one line on stderr and exit code 2 (shared by ``tlm process``, ``evaluate``, ``train``
    and ``detect``). A closed stdout (``BrokenPipeError``, ``| head``) is not a user error: it
    goes on to ``tlm``'s ``main``, which ends quietly."""
    from tlm_process.pipeline.errors import PipelineError

    try:
        return body(args)
    except (PipelineError, UsageError) as e:
        msg = str(e)
    except BrokenPipeError:
        raise
    except OSError as e:
        msg = f"{e.filename or ''}: {e.strerror or e}".lstrip(": ")
    print(f"tlm: error: {msg}", file=sys.stderr)
    return 2


def run(args: argparse.Namespace) -> int:
    """Run ``tlm process``; 0 on success, 2 on a user error (one line on stderr)."""
    return report_user_errors(_run, args)


def _make_plots(p, plots_dir: Path) -> list[str]:
    from tlm_process.pipeline.plots import plot_fault_traces, plot_trajectory

    plots_dir.mkdir(parents=True, exist_ok=True)
    fid = p.flight.id.replace("/", "_").replace(":", "_")
    out = [plot_trajectory(p.labelled, p.windows, plots_dir / f"{fid}_trajectory.png",
                           f"{p.flight.id}: GPS track, fault segments coloured",
                           p.flight.records, p.home_alt)]
    for w in p.windows:
        out.append(plot_fault_traces(p.labelled, w, plots_dir / f"{fid}_fault{w.index + 1}_"
                                     f"{w.type}.png", f"{p.flight.id}: {w.name}, label "
                                     f"{w.label}, window shaded"))
    return [str(x) for x in out]


def _warn_partial(info: dict) -> None:
    """One stderr line for a generated data set read partially or with lines skipped."""
    notes = []
    if info["state"] != "complete":
        notes.append(f"state {info['state']}: reading its {info['committed']} finished of "
                     f"{info['flights']} flights only (--partial)")
    if info["skipped_journal_lines"]:
        notes.append(f"{info['skipped_journal_lines']} journal line(s) cut short by a kill "
                     "skipped")
    if notes:
        print(f"tlm: warning: {info['path']}: {'; '.join(notes)}", file=sys.stderr)


def _command_line() -> str:
    """``tlm process ...`` as typed, when this process is the tlm command ("" otherwise)."""
    import shlex

    argv = sys.argv[1:]
    return "tlm " + " ".join(shlex.quote(a) for a in argv) if argv[:1] == ["process"] else ""


def _run(args: argparse.Namespace) -> int:
    from tlm_process.pipeline.anchoring import DEFAULT_MAX_MATCH_M
    from tlm_process.pipeline.card import dataset_card
    from tlm_process.pipeline.errors import PipelineError
    from tlm_process.pipeline.ingest import expand_inputs, read_dataset, read_flight, unique_ids
    from tlm_process.pipeline.plots import plot_label_shares
    from tlm_process.pipeline.process import (
        ProcessOptions,
        build_dataset,
        process_flight,
        write_dataset,
    )
    from tlm_process.pipeline.report import flight_lines, stretching_report
    from tlm_process.pipeline.stretching import fault_share, format_counts

    tables = tuple(t.strip().upper() for t in args.tables.split(",") if t.strip())
    options = ProcessOptions(
        method=args.anchor, phase=args.phase, instance=args.instance, tables=tables,
        rc_label=args.rc_label,
        max_match_m=args.max_match_m if args.max_match_m is not None else DEFAULT_MAX_MATCH_M)
    out = Path(args.out)
    sources = expand_inputs(args.inputs)
    if is_one_of(out, (p for _, p in sources)):
        raise PipelineError("the output folder is one of the inputs", source=str(out))
    t0 = time.perf_counter()
    prepare_out(out, "process", getattr(args, "overwrite", False),
                inputs=[p for _, p in sources])
    processed = []
    plots: list[str] = []
    seen: dict[str, int] = {}
    generated: list[dict] = []
    for k, (kind, path) in enumerate(sources, 1):
        if kind == "dataset":
            found, info = read_dataset(path, partial=args.partial)
            if info is not None:
                generated.append(info)
                _warn_partial(info)
        else:
            found = read_flight(kind, path)
        flights = unique_ids(found, seen)
        for fl in flights:
            p = process_flight(fl, options)
            processed.append(p)
            if not args.quiet:
                faults = ", ".join(w.type for w in p.windows) or "no faults"
                rows = ", ".join(f"{n} {len(df)}" for n, df in p.features.items())
                print(f"[{k}/{len(sources)}] {fl.id} ({kind}): {faults}; rows {rows} "
                      f"(phase {p.phase})")
                for line in flight_lines(p):
                    print(line)
            if len(processed) <= args.plots:
                plots.extend(_make_plots(p, out / "plots"))
            p.release()
    ds = build_dataset(processed, test_frac=args.test_frac, seed=args.seed,
                       test_patterns=args.test_flight, scale=not args.no_scale,
                       options=options)
    extra: dict = {"inputs": {"partial": bool(args.partial), "generated": generated}}
    if args.target_fault_ratio is not None:
        extra["stretching"] = stretching_report(fault_share(ds.counts).to_dict(),
                                                args.target_fault_ratio)
    plots.append(str(plot_label_shares(ds.counts, out / "label_shares.png",
                                       f"share of each label ({len(processed)} flight"
                                       f"{'s' * (len(processed) != 1)})")))
    extra["plots"] = [str(Path(x).relative_to(out)) for x in plots]
    report = write_dataset(ds, out, extra)
    (out / "README.md").write_text(dataset_card(report, _command_line()))
    n = len(processed)
    print(format_counts(ds.counts, f"rows per class ({n} flight{'s' * (n != 1)}; "
                                   f"train {len(ds.train)}, test {len(ds.test)})"))
    if "stretching" in extra:
        lam = extra["stretching"]["lambda"]
        print(f"lambda for fault share {args.target_fault_ratio:g} (Eq. 5, gamma/alpha): "
              + ", ".join(f"{t} {v:.3f}" if v is not None else f"{t} -" for t, v in
                          lam.items()))
    flat = ds.scaler.constant_features() if ds.scaler else {}
    if flat:
        names = [f"{t} {c}" for t, cs in flat.items() for c in cs]
        print(f"tlm: warning: {len(names)} feature(s) hold one value in every training flight "
              f"and scale to 0 everywhere (report.json scaling.constant_features): "
              f"{', '.join(names[:8])}{', ...' if len(names) > 8 else ''}", file=sys.stderr)
    print(f"written {out}/ ({', '.join(f'{t}.parquet' for t in ds.tables)}, scaler.json, "
          f"report.json, {len(plots)} plots) in {time.perf_counter() - t0:.1f} s")
    return 0

