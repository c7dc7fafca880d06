"""``tlm info LOG``: the summary of a DataFlash log (:func:`tlm_process.binlog.log_info`)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from tlm_process.binlog import format_info, log_info
from tlm_process.cliutil import check_writable_file

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``info`` to ``tlm``'s subcommands; returns its parser."""
    i = sub.add_parser(
        "info", help="summarise a DataFlash log: messages, modes, changes, faults",
        description="Summarise an ArduPilot DataFlash .bin or text .log: time span, armed "
                    "time and how it was found (EV 10, ARM, or the motor outputs of a log "
                    "that starts at arming), firmware, each message type's count, instances "
                    "and rate (messages logged regularly over at least 1 s), flight modes "
                    "with reasons, parameters changed in flight, and faults found (SIM_* "
                    "parameter changes, tlm fault MSG lines, a sidecar LOG.json). Logs of "
                    "older firmware are normalised first (TimeMS, IMU2/IMU3: "
                    "docs/log-messages.md).")
    i.add_argument("log", help="the .bin or text .log file")
    i.add_argument("--json", metavar="R.json", help="also write the summary as JSON")
    i.add_argument("--all-params", action="store_true",
                   help="list housekeeping parameter changes too (STAT_*, MIS_TOTAL, ...)")
    i.set_defaults(func=run)
    return i


def run(args: argparse.Namespace) -> int:
    """Print the summary of one log (and optionally write it as JSON)."""
    if args.json:
        check_writable_file(args.json, "--json")
    info = log_info(args.log, all_params=args.all_params)
    print(format_info(info))
    if args.json:
        Path(args.json).write_text(json.dumps(info, indent=1) + "\n")
    return 0
