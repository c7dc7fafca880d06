"""``tlm convert LOG.bin --out DIR``: a DataFlash log to per-message CSV/Parquet files or a
Mission Planner text log (:func:`tlm_process.binlog.convert`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from tlm_process.binlog import (
    CONVERT_FORMATS,
    check_format,
    check_types,
    open_log,
    write_tables,
)
from tlm_process.cliutil import UsageError, add_overwrite, folder, prepare_out

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``convert`` to ``tlm``'s subcommands; returns its parser."""
    c = sub.add_parser(
        "convert", help="convert a DataFlash log to CSV, Parquet or Mission Planner text",
        description="Convert an ArduPilot DataFlash .bin (SITL, a vehicle, or tlm's flight.bin) "
                    "or a DataFlash text .log "
                    "to one file per message type: DIR/GPS.csv, DIR/IMU.csv, ... (every "
                    "message of that type; ArduPilot column names; lat/lon in degrees, "
                    "altitudes in metres, HDop 1.21, as pymavlink and Mission Planner show "
                    "them; instances as rows with their I/IMU/C column) plus meta.json, or "
                    "with --format log to Mission Planner's text log DIR/<name>.log. Logs of "
                    "older firmware come out in 4.x's layout: TimeUS (from TimeMS) on every "
                    "table, IMU2/IMU3 as IMU rows with I 1/2 (docs/log-messages.md).")
    c.add_argument("log", help="the .bin or text .log file")
    c.add_argument("--out", type=folder, required=True, help="output folder")
    c.add_argument("--format", default="csv", metavar="csv|parquet|log",
                   help="csv (default), parquet, or log (Mission Planner text log)")
    c.add_argument("--types", metavar="GPS,IMU,...",
                   help="only these message types (default all)")
    add_overwrite(c)
    c.set_defaults(func=run)
    return c


def run(args: argparse.Namespace) -> int:
    """Convert one .bin log to per-message CSV/Parquet files or a Mission Planner text log."""
    fmt = args.format.lower()
    if fmt not in CONVERT_FORMATS:
        raise UsageError(f"--format: {args.format!r}; choose one of {', '.join(CONVERT_FORMATS)}")
    types = [t.strip().upper() for t in args.types.split(",") if t.strip()] if args.types else None
    log, tables, damage = open_log(args.log)
    names = check_types(log, types)
    check_format(log, fmt)
    # only once the log is known to be readable
    out = prepare_out(args.out, "convert", args.overwrite, inputs=[args.log])
    files, rows = write_tables(log, tables, names, out, fmt, Path(args.log).stem, damage)
    print(f"converted          {args.log} -> {out}/ ({len(files)} files, {fmt}, "
          f"{len(rows)} message types, {sum(rows.values())} messages)")
    for d in damage:
        print(f"damage             {d}")
    return 0
