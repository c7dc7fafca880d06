"""The ``tlm`` command line: one entry point with subcommands.

This module only routes: :data:`COMMANDS` names the module of each subcommand
(``tlm_process.commands.<name>``), which exports ``add_parser(subparsers)`` and ``run(args) ->
exit code``. Errors a user can cause (bad parameter, bad mission, bad path) print one line and
exit 2.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
from collections.abc import Sequence
from types import ModuleType

from tlm_process.cliutil import UsageError, show_param_warnings
from tlm_process.commands.fly import fault_lines as _fault_lines  # noqa: F401 (old imports)

__all__ = ["COMMANDS", "UsageError", "build_parser", "command_module", "main"]

#: subcommand -> its module, in the order ``tlm --help`` lists them
COMMANDS: dict[str, str] = {name: f"tlm_process.commands.{name}" for name in (
    "fly", "demo", "convert", "info", "generate", "process", "evaluate", "train", "detect",
    "crosscheck", "fit", "params")}


def command_module(name: str) -> ModuleType:
    """The module of subcommand ``name`` (imports only what its parser needs)."""
    return importlib.import_module(COMMANDS[name])


def build_parser() -> argparse.ArgumentParser:
    """The argparse tree of ``tlm``."""
    ap = argparse.ArgumentParser(
        prog="tlm", description="Labelled UAV fault flights without ArduPilot: fly a simulated "
        "ArduCopter with SITL's faults, write ArduPilot logs, and run the Time Line Modeling "
        "pipeline on them.", epilog="'tlm COMMAND --help' describes each command.")
    ap.add_argument("--version", action="version", version="tlm 0.1.0")
    sub = ap.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        command_module(name).add_parser(sub)
    return ap


def _show_compile_notices() -> None:
    """Print tlm_sim.precompile's notices ("compiling the flight loop ...", "compiled in 20 s")
    on stderr: a cold numba cache makes the first flight after an install take seconds."""
    lg = logging.getLogger("tlm_sim.precompile")
    if not lg.handlers:
        h = logging.StreamHandler(sys.stderr)
        h.setFormatter(logging.Formatter("tlm: %(message)s"))
        lg.addHandler(h)
        lg.setLevel(logging.INFO)


def _main_body(argv: Sequence[str] | None) -> int:
    """:func:`main` but for a closed stdout."""
    ap = build_parser()
    args = ap.parse_args(argv)  # before importing tlm_sim (seconds): --help stays instant
    from tlm_process.binlog import LogError
    from tlm_process.generate.errors import GenerateError
    from tlm_sim.faults import FaultScheduleError
    from tlm_sim.flightlog.binscan import BinLogError
    from tlm_sim.mission import MissionError
    from tlm_sim.params import ParamError

    _show_compile_notices()
    show_param_warnings()
    if getattr(args, "seed", 0) is not None and getattr(args, "seed", 0) < 0:
        print("tlm: error: --seed must be >= 0", file=sys.stderr)
        return 2
    try:
        return command_module(args.command).run(args)
    except (UsageError, ParamError, MissionError, FaultScheduleError, LogError,
            GenerateError, BinLogError) as e:
        print(f"tlm: error: {e}", file=sys.stderr)
        return 2
    except FileNotFoundError as e:
        print(f"tlm: error: file not found: {e.filename}", file=sys.stderr)
        return 2
    except UnicodeDecodeError as e:  # a reader that does not name its file yet
        print(f"tlm: error: a file given is not UTF-8 text ({e.reason} at byte {e.start})",
              file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tlm: interrupted", file=sys.stderr)
        return 130


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``tlm`` console script.

    When stdout's reader goes away (``tlm params | head -5``, a closed pager), the command
    stops quietly: no traceback, stdout is pointed at /dev/null so that the flush at exit
    cannot fail again, and the exit status is 141, what a shell reports for a program ended by
    SIGPIPE (128 + 13), so a pipeline under ``set -o pipefail`` sees it as cut short.
    SIGPIPE itself keeps Python's disposition (ignored): a Dask worker's lost socket must stay
    an exception, not end the process.
    """
    try:
        try:
            return _main_body(argv)
        finally:  # a closed pipe surfaces here (and for --help), not in the flush at exit
            sys.stdout.flush()
    except BrokenPipeError:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 141


if __name__ == "__main__":
    sys.exit(main())
