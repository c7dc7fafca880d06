"""The ``tlm`` command line: one entry point with subcommands.

Errors a user can cause (bad parameter, bad mission, bad path) print one line and exit 2.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

FORMATS = ("csv", "parquet")


class UsageError(Exception):
    """A user mistake: reported as one line, exit code 2."""


def _parse_formats(text: str) -> tuple[str, ...]:
    fmts = tuple(f.strip().lower() for f in text.split(",") if f.strip())
    bad = [f for f in fmts if f not in FORMATS]
    if bad or not fmts:
        raise UsageError(f"--format: unknown format(s) {bad or text!r}; choose from "
                         f"{', '.join(FORMATS)}")
    return fmts


def _parse_param_args(items: Sequence[str]) -> dict[str, float]:
    out: dict[str, float] = {}
    for it in items:
        if "=" not in it:
            raise UsageError(f"--param expects NAME=VALUE, got {it!r}")
        k, v = it.split("=", 1)
        try:
            out[k.strip().upper()] = float(v)
        except ValueError:
            raise UsageError(f"--param {k}: {v!r} is not a number") from None
    return out


def _load_params(args: argparse.Namespace):
    from tlm_sim.params import Params

    p = Params.from_parm(args.params) if args.params else Params()
    extra = _parse_param_args(args.param or [])
    return p.updated(extra) if extra else p


def _load_mission(args: argparse.Namespace):
    from tlm_sim.mission import builtin_mission, read_wpl

    if args.mission_file:
        return read_wpl(args.mission_file)
    return builtin_mission(args.mission)


def _parse_changes(items: Sequence[str]) -> list[tuple[float, str, float]]:
    out = []
    for it in items:
        try:
            t, rest = it.split(":", 1)
            name, val = rest.split("=", 1)
            out.append((float(t), name.strip().upper(), float(val)))
        except ValueError:
            raise UsageError(f"--set expects TIME_S:NAME=VALUE, got {it!r}") from None
    return out


def _prepare_out(out: str) -> Path:
    d = Path(out)
    try:
        d.mkdir(parents=True, exist_ok=True)
        probe = d / ".tlm-write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as e:
        raise UsageError(f"cannot write to output folder {d}: {e.strerror or e}") from None
    return d


def cmd_fly(args: argparse.Namespace) -> int:
    """Fly one mission and write its tables."""
    from tlm_process.summary import flight_summary, format_summary, plot_trajectory
    from tlm_sim import fly

    fmts = _parse_formats(args.format)
    params = _load_params(args)
    mission = _load_mission(args)
    changes = _parse_changes(args.set or [])
    out = _prepare_out(args.out)
    t0 = time.perf_counter()
    log = fly(mission, faults=changes or None, params=params, seed=args.seed)
    wall = time.perf_counter() - t0
    log.write(out, formats=fmts)
    if not args.no_plot:
        plot_trajectory(log, out / "trajectory.png", f"{mission.name}, seed {args.seed}")
    s = flight_summary(log)
    (out / "summary.json").write_text(json.dumps(s, indent=1))
    print(format_summary(s))
    print(f"wall time          {wall:.2f} s ({s['duration_s'] / max(wall, 1e-9):.0f}x real time, "
          "incl. compile on first run)")
    extra = "" if args.no_plot else ", trajectory.png"
    print(f"written            {out}/ ({', '.join(fmts)}{extra})")
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    """Fly a paper-style mission with a GPS loss and show where the outputs are."""
    from tlm_process.summary import flight_summary, format_summary, plot_trajectory
    from tlm_sim import fly

    out = _prepare_out(args.out)
    changes = [(100.0, "SIM_GPS1_ENABLE", 0.0), (130.0, "SIM_GPS1_ENABLE", 1.0)]
    print("flying built-in mission 1 (paper-style, ~90 waypoints) with a GPS loss 100-130 s ...")
    t0 = time.perf_counter()
    log = fly(1, faults=changes, seed=args.seed)
    wall = time.perf_counter() - t0
    log.write(out, formats=FORMATS)
    plot_trajectory(log, out / "trajectory.png", "demo: mission 1, GPS loss 100-130 s")
    s = flight_summary(log)
    print(format_summary(s))
    print(f"wall time          {wall:.2f} s (includes numba compile on the first run)")
    print(f"outputs            {out.resolve()}/ (GPS.csv, IMU.csv, RATE.csv, VIBE.csv, ... "
          "+ .parquet, trajectory.png)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argparse tree of ``tlm``."""
    ap = argparse.ArgumentParser(prog="tlm", description=__doc__.splitlines()[0])
    ap.add_argument("--version", action="version", version="tlm 0.1.0")
    sub = ap.add_subparsers(dest="command", required=True)

    f = sub.add_parser("fly", help="fly one mission and write its log tables",
                       description="Fly one mission (built-in 1-4 or a QGC WPL file) and write "
                                   "DIR/GPS.csv, DIR/IMU.csv, ... and their Parquet twins.")
    f.add_argument("--mission", type=int, default=1, choices=(1, 2, 3, 4),
                   help="built-in mission number (default 1)")
    f.add_argument("--mission-file", help="QGC WPL 110 mission file instead of a built-in one")
    f.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    f.add_argument("--out", required=True, help="output folder")
    f.add_argument("--format", default="csv,parquet", help="csv,parquet (default both)")
    f.add_argument("--params", help="ArduPilot .parm file applied on top of the defaults")
    f.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="set one parameter (repeatable), e.g. --param WPNAV_SPEED=500")
    f.add_argument("--set", action="append", metavar="TIME_S:NAME=VALUE",
                   help="change a parameter in flight (repeatable), e.g. 120:SIM_GPS1_ENABLE=0")
    f.add_argument("--no-plot", action="store_true", help="skip trajectory.png")
    f.set_defaults(func=cmd_fly)

    d = sub.add_parser("demo", help="fly a demo mission with a fault and write its outputs")
    d.add_argument("--out", default="demo-out", help="output folder (default demo-out)")
    d.add_argument("--seed", type=int, default=1)
    d.set_defaults(func=cmd_demo)
    return ap


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``tlm`` console script."""
    from tlm_sim.mission import MissionError
    from tlm_sim.params import ParamError

    ap = build_parser()
    args = ap.parse_args(argv)
    if getattr(args, "seed", 0) is not None and getattr(args, "seed", 0) < 0:
        print("tlm: error: --seed must be >= 0", file=sys.stderr)
        return 2
    try:
        return args.func(args)
    except (UsageError, ParamError, MissionError) as e:
        print(f"tlm: error: {e}", file=sys.stderr)
        return 2
    except FileNotFoundError as e:
        print(f"tlm: error: file not found: {e.filename}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("tlm: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
