"""``tlm demo``: fly built-in mission 1 with the paper's fault sequence, write its log and run
the TLM pipeline (``tlm process``) on it."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from tlm_process.cliutil import OUT_MARK, add_overwrite, folder, prepare_out
from tlm_process.commands import process
from tlm_process.commands.fly import FORMATS, fault_lines, write_faults

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``demo`` to ``tlm``'s subcommands; returns its parser."""
    d = sub.add_parser("demo", help="fly mission 1 with the paper's fault sequence, write its "
                                    "log and run the TLM pipeline on it")
    d.add_argument("--out", type=folder, default="demo-out",
                   help="output folder (default demo-out)")
    d.add_argument("--seed", type=int, default=1,
                   help="seed of the flight and of its fault sequence (default 1)")
    add_overwrite(d)
    d.set_defaults(func=run)
    return d


def _process_args(argv: list[str]) -> argparse.Namespace:
    """``tlm process ARGV``'s arguments, with that command's defaults."""
    ap = argparse.ArgumentParser(prog="tlm")
    process.add_parser(ap.add_subparsers(dest="command", required=True))
    return ap.parse_args(["process", *argv])


def run(args: argparse.Namespace) -> int:
    """Fly built-in mission 1 with the paper's fault sequence, write its log (tables and .bin)
    and run the TLM pipeline on it (anchoring, labels, features, scaling)."""
    from tlm_process.summary import flight_summary, format_summary, plot_trajectory
    from tlm_sim import fly
    from tlm_sim.faults import FaultSchedule

    mark = Path(args.out) / OUT_MARK
    again = mark.is_file() and mark.read_text().strip() == "demo"  # an earlier demo's folder
    out = prepare_out(args.out, "demo", overwrite=again or args.overwrite)
    schedule = FaultSchedule.paper(args.seed)
    print(f"flying built-in mission 1 (paper-style, ~90 waypoints) with the paper's fault "
          f"sequence GPS, accel, engine, RC (seed {args.seed}) ...")
    t0 = time.perf_counter()
    log = fly(1, faults=schedule, seed=args.seed)
    wall = time.perf_counter() - t0
    log.write(out, formats=FORMATS)
    write_faults(out, log)
    plot_trajectory(log, out / "trajectory.png",
                    f"demo: mission 1, paper fault sequence, seed {args.seed}")
    s = flight_summary(log)
    print(format_summary(s))
    for line in fault_lines(log, schedule):
        print(line)
    print(f"wall time          {wall:.2f} s (includes numba compile on the first run)")
    print("\nrunning the TLM pipeline (anchoring, labelling, feature processing, scaling) ...")
    rc = process.run(_process_args([str(out), "--out", str(out / "tlm")]))
    if rc != 0:
        return rc
    print(f"\noutputs            {out.resolve()}/")
    print("  flight log       GPS.csv, IMU.csv, RATE.csv, VIBE.csv, ... (+ .parquet), "
          "flight.bin (open it in Mission Planner or `tlm info`), faults.json, trajectory.png")
    print("  TLM data set     tlm/GPS.parquet, tlm/IMU.parquet, tlm/RATE.parquet, "
          "tlm/VIBE.parquet (labelled, scaled), tlm/report.json, tlm/label_shares.png, "
          "tlm/plots/")
    return 0
