"""``tlm params``: every parameter tlm knows, with unit, range, default, whether tlm models it
and its meaning (what Mission Planner's full parameter list shows, plus the "modelled" column).

A parameter that is not modelled is refused when set explicitly (``--param``, ``--set``, a fault
schedule, ``tlm generate`` ranges); a whole ``.parm`` file or a SITL log's PARM set may change
it: it is then carried, listed in one warning and in ``meta.json`` ``unmodelled_params``.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

__all__ = ["add_parser", "format_rows", "run"]


def _number(v: float | None) -> str:
    """A number as the ``.parm`` files write it; "-" for none."""
    if v is None:
        return "-"
    return str(int(v)) if float(v).is_integer() and abs(v) < 1e16 else repr(float(v))


def format_rows(rows: list[dict[str, Any]]) -> str:
    """The text table of ``tlm params``: one line per parameter."""
    lines = [f"{'NAME':<16} {'DEFAULT':>12} {'UNIT':<9} {'RANGE':<22} {'MODELLED':<8} "
             "DESCRIPTION"]
    for r in rows:
        rng = "-" if r["min"] is None else f"{_number(r['min'])} .. {_number(r['max'])}"
        desc = r["description"] or "ArduPilot parameter carried from the default set"
        if r["aliases"]:
            desc += f" (also read as {', '.join(r['aliases'])})"
        lines.append(f"{r['name']:<16} {_number(r['default']):>12} {r['unit'] or '-':<9} "
                     f"{rng:<22} {'yes' if r['modelled'] else 'no':<8} {desc}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """List the parameters (all, or those named), as a table or as JSON."""
    from tlm_sim.params import parameter_list

    rows = parameter_list(args.names or ())
    if args.modelled:
        rows = [r for r in rows if r["modelled"]]
    elif args.unmodelled:
        rows = [r for r in rows if not r["modelled"]]
    text = json.dumps(rows, indent=1) if args.json else format_rows(rows)
    sys.stdout.write(text + "\n")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``params`` to ``tlm``'s subcommands; returns its parser."""
    p = sub.add_parser(
        "params", help="list tlm's parameters: unit, range, default, modelled, description",
        description="List every parameter tlm knows (ArduPilot names and units, plus TLM_* "
                    "model constants): default, unit, accepted range, whether tlm models it, "
                    "and its meaning. A parameter that is not modelled is refused by --param, "
                    "--set and fault schedules; a whole .parm file or a SITL log may change it "
                    "(it is then listed in a warning and in meta.json, and ignored).")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="parameter names or patterns such as 'EK3_*' (default: all)")
    p.add_argument("--json", action="store_true", help="print a JSON list instead of a table")
    which = p.add_mutually_exclusive_group()
    which.add_argument("--modelled", action="store_true", help="only parameters tlm models")
    which.add_argument("--unmodelled", action="store_true",
                       help="only parameters tlm does not model")
    p.set_defaults(func=run)
    return p
