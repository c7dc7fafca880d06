"""``tlm fly``: fly one mission (built-in or a QGC WPL file), or a pilot's stick script
(``--sticks``), optionally with a fault schedule, and write its log tables, faults.json and
summary.json."""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from tlm_process.cliutil import UsageError, add_overwrite, folder, parse_param_args, prepare_out

if TYPE_CHECKING:  # tlm_sim takes seconds to import: only where a command needs it
    from tlm_sim.faults import FaultSchedule, Trigger
    from tlm_sim.flightlog import FlightLog
    from tlm_sim.mission import Mission
    from tlm_sim.params import Params

__all__ = ["FAULTS_HELP", "FORMATS", "add_parser", "fault_lines", "run", "write_faults"]

FORMATS = ("csv", "parquet", "bin")

#: A time trigger applied more than this after its time [s] is reported as late (the loop
#: applies a change at its first tick at or after the time, well within this).
LATE_S = 0.1

FAULTS_HELP = """\
faults (paper labels: gps 1, accel 2, engine 3, rc 4):
  --fault TYPE:START-END   START/END are seconds since boot (log TimeUS / 1e6) or
                           waypoints wpN (the moment waypoint N is reached)
  --fault TYPE:START-      held until the flight ends (also TYPE:START)
  --fault TYPE:START+DUR   held DUR seconds
  e.g. --fault gps:60-110 --fault accel:wp40-wp48 --fault rc:200-
  --faults FILE.json|.yaml|.yml holds the same as a list, in the order they happen:
    {"faults": [{"fault": "gps", "start": 60, "end": 110},
                {"fault": "accel", "start": "wp40", "end": "wp48"}]}
  A fault that ends at a waypoint the vehicle cannot reach while it holds (an engine
  cut on the ground) lasts to the end of the flight: tlm warns; end it by time instead.
  optional per fault: params_start / params_end (NAME: value, SITL parameters).
  Faults must not overlap; a schedule is checked against the mission before flying.
  DIR/faults.json gets one record per fault (paper Eq. 4: type, label, start/end
  TimeUS and position, parameters); an empty list when no schedule is given.
"""


def _parse_formats(text: str) -> tuple[str, ...]:
    fmts = tuple(f.strip().lower() for f in text.split(",") if f.strip())
    bad = [f for f in fmts if f not in FORMATS]
    if bad or not fmts:
        raise UsageError(f"--format: unknown format(s) {bad or text!r}; choose from "
                         f"{', '.join(FORMATS)}")
    return fmts


def _frame_params(name: str | None, extra: dict[str, float]) -> dict[str, float]:
    """FRAME_CLASS / FRAME_TYPE of ``--frame NAME`` (empty without it); a --param that sets
    either to another value is a UsageError."""
    if name is None:
        return {}
    from tlm_sim.frames import FRAMES

    key = name.strip().lower()
    if key not in FRAMES:
        raise UsageError(f"--frame: unknown frame {name!r}; choose from {', '.join(FRAMES)}")
    f = FRAMES[key]
    out = {"FRAME_CLASS": float(f.frame_class), "FRAME_TYPE": float(f.frame_type)}
    for k, v in out.items():
        if k in extra and extra[k] != v:
            raise UsageError(f"--frame {key} sets {k} {v:g}, but --param sets {k}={extra[k]:g}; "
                             "give one of them")
    return out


def _load_params(args: argparse.Namespace):
    from tlm_sim.params import Params

    p = Params.from_parm(args.params) if args.params else Params()
    extra = parse_param_args(args.param or [])
    extra.update(_frame_params(getattr(args, "frame", None), extra))
    return p.updated(extra) if extra else p


def _check_profile(name: str) -> str:
    """The --profile name, if tlm_sim.profiles knows it."""
    from tlm_sim.profiles import PROFILES

    if name not in PROFILES:
        raise UsageError(f"--profile: unknown profile {name!r}; choose from {', '.join(PROFILES)}")
    return name


def _load_mission(args: argparse.Namespace):
    from tlm_sim.mission import builtin_mission, read_wpl

    if args.mission_file:
        return read_wpl(args.mission_file)
    return builtin_mission(args.mission)


def _parse_changes(items: Sequence[str], max_time_s: float) -> list[tuple[float, str, float]]:
    """``--set TIME_S:NAME=VALUE`` changes, each at a time within the flight (0 to
    ``max_time_s``, the longest it can last) and of a parameter that may change in flight."""
    from tlm_sim.flight import BOOT_ONLY_PARAMS

    out = []
    for it in items:
        try:
            t, rest = it.split(":", 1)
            name, val = rest.split("=", 1)
            change = (float(t), name.strip().upper(), float(val))
        except ValueError:
            raise UsageError(f"--set expects TIME_S:NAME=VALUE, got {it!r}") from None
        if not 0.0 <= change[0] <= max_time_s:  # also refuses nan
            raise UsageError(f"--set {it!r}: the time must be between 0 and {max_time_s:g} s, "
                             f"the longest this flight can last")
        if change[1] in BOOT_ONLY_PARAMS:
            raise UsageError(f"--set {it!r}: {change[1]} cannot change in flight (ArduPilot "
                             f"reads it at boot); give it with --param")
        out.append(change)
    return out


def _split_specs(items: Sequence[str]) -> list[str]:
    """``--fault`` values, each possibly holding several specs separated by commas/spaces."""
    return [s for it in items for s in it.replace(",", " ").split()]


def _load_schedule(args: argparse.Namespace, mission: Mission | None,
                   params: Params, max_time_s: float | None = None) -> FaultSchedule | None:
    """The flight's FaultSchedule (None when neither --faults nor --fault is given), checked
    against the mission's waypoint count and the longest the flight can last, before flying.

    ``params``: the flight's parameters with the profile applied (they size the flight);
    ``mission`` None: a pilot-flown flight of at most ``max_time_s`` (no waypoints).
    """
    from tlm_sim.faults import FaultSchedule, FaultScheduleError
    from tlm_sim.flight import max_duration_s

    if args.faults is not None and args.fault:
        raise UsageError("--faults and --fault are exclusive: give a schedule (paper or a file) "
                         "or shorthand specs, not both")
    lam = getattr(args, "lam", None)
    if args.faults is None and not args.fault:
        if lam is not None:
            raise UsageError("--lambda needs a fault schedule (--faults or --fault)")
        return None
    if args.set:
        raise UsageError("--set cannot be combined with --faults/--fault (a flight takes a fault "
                         "schedule or raw parameter changes); put extra parameter values in a "
                         "schedule file's params_start/params_end")
    # whole seconds, rounded down: readable in messages and never past fly()'s own bound
    if mission is None:  # flown from sticks: no waypoints (require_times below)
        bounds = {"n_waypoints": None, "max_time_s": float(math.floor(max_time_s or 0.0))}
    else:
        bounds = {"n_waypoints": mission.n_waypoints,
                  "max_time_s": float(math.floor(max_duration_s(mission, params)))}
    option = "--fault" if args.fault else "--faults"
    try:
        if args.fault:
            schedule = FaultSchedule.from_shorthand(_split_specs(args.fault), **bounds)
        elif args.faults.strip().lower() == "paper":
            if mission is None:
                raise UsageError("--faults paper places its faults on a mission's waypoints; "
                                 "with --sticks give the faults by time")
            schedule = FaultSchedule.paper(args.seed)
            schedule.validate(**bounds)
        else:
            schedule = FaultSchedule.from_file(args.faults, **bounds)
        if mission is None:
            schedule.require_times()
    except FaultScheduleError as e:
        raise UsageError(f"{option}: {e}") from None
    if lam is None:
        return schedule
    try:
        return schedule.stretched(lam, **bounds)
    except FaultScheduleError as e:
        raise UsageError(f"--lambda: {e}") from None


def fault_warnings(log: FlightLog, schedule: FaultSchedule | None) -> list[str]:
    """``tlm: warning:`` lines for faults that did not happen as asked: one meant to end at a
    waypoint the vehicle never reached while it held (it lasted to the end of the log), and
    one that lasted 0 s (its end came before or with its start)."""
    if schedule is None:
        return []
    started = {int(c["fault"]) for c in log.meta.get("param_changes", [])
               if c.get("edge") == "start" and c.get("time_us") is not None}
    records = iter(log.faults)
    out = []
    for i, fault in enumerate(schedule):
        if i not in started:
            continue
        r = next(records)
        name = f"fault {i + 1} ({r['type']})"
        if fault.end is not None and fault.end.kind == "wp" and r["end_by"] == "flight end":
            out.append(f"tlm: warning: {name} was to end at waypoint {fault.end.value:g}, "
                       f"which the vehicle never reached while the fault held: it lasted "
                       f"{r['duration_s']:.1f} s, to the end of the log; end it by time")
        elif r["duration_s"] <= 0.0:
            out.append(f"tlm: warning: {name} lasted 0 s: its end came with its start "
                       "(mixed time and waypoint boundaries?); it has no fault rows")
    return out


def fault_lines(log: FlightLog, schedule: FaultSchedule | None) -> list[str]:
    """One line per scheduled fault: type, label, start/end (log TimeUS in s), duration; or
    why it has no record (the flight ended before it started)."""
    if schedule is None:
        return []
    started = {int(c["fault"]) for c in log.meta.get("param_changes", [])
               if c.get("edge") == "start" and c.get("time_us") is not None}
    records = iter(log.faults)
    lines = []
    for i, fault in enumerate(schedule):
        if i not in started:
            lines.append(f"fault {i + 1} {fault.type:<6} label {fault.label}  never started "
                         "(the flight ended first)")
            continue
        r = next(records)
        late = [f"{edge} due {trig.value:g} s"
                for edge, trig in (("start", fault.start), ("end", fault.end))
                if (edge == "start" or r["end_by"] == "schedule")
                and _late(trig, r[f"{edge}_time_us"])]
        notes = [f"late: {', '.join(late)}; waited for the boundaries before it"] if late else []
        if r["end_by"] == "flight end":
            notes.append("held to the end of the log")
        note = f" ({'; '.join(notes)})" if notes else ""
        lines.append(f"fault {i + 1} {r['type']:<6} label {r['label']}  "
                     f"start {r['start_time_us'] * 1e-6:7.1f} s  "
                     f"end {r['end_time_us'] * 1e-6:7.1f} s  "
                     f"duration {r['duration_s']:5.1f} s{note}")
    return lines


def _late(trigger: Trigger | None, applied_us: int) -> bool:
    """Whether a time trigger took effect well after its time [s]: it waited for an earlier
    waypoint boundary of the schedule (time and waypoint boundaries are not comparable before
    flying). Waypoint triggers and missing ends are never late."""
    return (trigger is not None and trigger.kind == "time"
            and applied_us * 1e-6 - trigger.value > LATE_S)


def write_faults(out: Path, log: FlightLog) -> Path:
    """``OUT/faults.json``: ``{"faults": [...]}``, the flight's Eq. 4 fault records."""
    from tlm_sim.flightlog.flightlog import to_jsonable

    path = out / "faults.json"
    path.write_text(json.dumps({"faults": to_jsonable(log.faults)}, indent=1) + "\n")
    return path


def _take_defaults(args: argparse.Namespace) -> None:
    """Refuse options that do nothing here, then fill in the defaults of --mission, --seed
    and --profile (``None`` until now, so that --from-manifest can refuse them when given)."""
    if args.flight is not None:
        raise UsageError("--flight N picks a flight of --from-manifest DS; give both")
    if args.mission is not None and args.mission_file:
        raise UsageError("--mission and --mission-file are exclusive: give one")
    args.mission = 1 if args.mission is None else args.mission
    args.seed = 0 if args.seed is None else args.seed
    args.profile = "current" if args.profile is None else args.profile


def _from_manifest(args: argparse.Namespace):
    """(mission, schedule, params, seed, profile, sticks) of ``--from-manifest DS --flight
    N``."""
    from tlm_process.generate.manifest import scenario_from_manifest

    if args.flight is None:
        raise UsageError("--from-manifest needs --flight N")
    clash = [opt for opt, v in (("--mission-file", args.mission_file), ("--faults", args.faults),
                                ("--fault", args.fault), ("--set", args.set),
                                ("--param", args.param), ("--params", args.params),
                                ("--frame", args.frame), ("--lambda", args.lam),
                                ("--mission", args.mission is not None),
                                ("--seed", args.seed is not None),
                                ("--profile", args.profile is not None)) if v]
    if clash:
        raise UsageError(f"--from-manifest flies the data set's own scenario: drop "
                         f"{', '.join(clash)}")
    return scenario_from_manifest(args.from_manifest, args.flight)


def _pilot_scenario(args: argparse.Namespace):
    """(None, the stick script, schedule, params, seed, profile, changes) of ``--sticks FILE``:
    no mission (a pilot flies), faults and --set changes by time within the script's flight."""
    from tlm_sim.flight import PILOT_TAIL_S, rc_table_us
    from tlm_sim.mission.sticks import StickScript, StickScriptError
    from tlm_sim.profiles import profile_params

    if args.mission is not None or args.mission_file:
        raise UsageError("--sticks flies a pilot's script instead of a mission: drop "
                         "--mission / --mission-file")
    try:
        script = StickScript.from_file(args.sticks)
    except StickScriptError as e:
        raise UsageError(f"--sticks: {e}") from None
    args.seed = 0 if args.seed is None else args.seed
    profile = _check_profile("current" if args.profile is None else args.profile)
    params = _load_params(args)
    flown = profile_params(profile, params)
    try:
        table = rc_table_us(script, flown)
    except StickScriptError as e:
        raise UsageError(f"--sticks: {e}") from None
    longest = float(table[-1, 0]) * 1e-6 + PILOT_TAIL_S
    changes = _parse_changes(args.set or [], math.floor(longest))
    schedule = _load_schedule(args, None, flown, longest)
    return None, script, schedule, params, args.seed, profile, changes


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``fly`` to ``tlm``'s subcommands; returns its parser."""
    f = sub.add_parser("fly", help="fly one mission and write its log tables",
                       description="Fly one mission (built-in 1-4 or a QGC WPL file), optionally "
                                   "with faults, and write DIR/GPS.csv, DIR/IMU.csv, ... (and "
                                   "their Parquet twins), meta.json, summary.json and "
                                   "faults.json.",
                       epilog=FAULTS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    f.add_argument("--mission", type=int, default=None, choices=(1, 2, 3, 4),
                   help="built-in mission number (default 1)")
    f.add_argument("--mission-file",
                   help="QGC WPL 110 mission file instead of a built-in one: waypoints (with "
                        "hold times), LOITER_TIME, DO_CHANGE_SPEED, TAKEOFF, RTL or a final "
                        "LAND; anything else is refused (docs/missions.md)")
    f.add_argument("--sticks", metavar="FILE",
                   help="fly a pilot's stick script (.yaml/.json/.csv: time, roll, pitch, "
                        "throttle or the pilot's hand on it (hold, land, height), yaw, mode) "
                        "instead of a mission: STABILIZE, ACRO, ALT_HOLD, LOITER, POSHOLD from "
                        "the sticks, arming by the rudder gesture (docs/pilot.md)")
    f.add_argument("--seed", type=int, default=None,
                   help="random seed of the flight and of --faults paper (default 0)")
    f.add_argument("--out", type=folder, required=True, help="output folder")
    f.add_argument("--format", default="csv,parquet",
                   help="any of csv,parquet,bin (default csv,parquet); bin writes the flight as "
                        "an ArduPilot DataFlash log DIR/flight.bin")
    f.add_argument("--params", help="ArduPilot .parm file applied on top of the defaults")
    f.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="set one parameter (repeatable), e.g. --param WPNAV_SPEED=500")
    f.add_argument("--frame", metavar="NAME",
                   help="airframe: + (default), x, hexa, hexax or octa; sets FRAME_CLASS and "
                        "FRAME_TYPE (as --param FRAME_TYPE=1 for x; over a --params file's)")
    f.add_argument("--profile", default=None, metavar="current|paper",
                   help="ArduPilot semantics: current (as the reference SITL logs, default) or "
                        "paper (the paper's ArduPilot 4.1/4.2)")
    f.add_argument("--faults", metavar="paper|FILE",
                   help="fault schedule: 'paper' (the paper's GPS, accel, engine, RC sequence "
                        "drawn with --seed) or a .json/.yaml/.yml schedule file (see below)")
    f.add_argument("--fault", action="append", metavar="SPEC",
                   help="one fault in shorthand (repeatable, in the order they happen), e.g. "
                        "--fault gps:60-110 --fault accel:wp40-wp48 (see below)")
    f.add_argument("--lambda", dest="lam", type=float, metavar="LAMBDA",
                   help="stretch every fault window by LAMBDA (paper Eq. 5: longer faults in "
                        "the flight); later faults move so the gaps keep their length")
    f.add_argument("--set", action="append", metavar="TIME_S:NAME=VALUE",
                   help="raw parameter change in flight (repeatable), e.g. "
                        "120:SIM_GPS1_ENABLE=0; not with --faults/--fault, and no fault records")
    f.add_argument("--from-manifest", metavar="DS",
                   help="fly flight --flight N of a `tlm generate` data set again, alone "
                        "(its mission, faults, parameters and seed; identical tables)")
    f.add_argument("--flight", type=int, metavar="N", help="flight number for --from-manifest")
    f.add_argument("--no-plot", action="store_true", help="skip trajectory.png")
    add_overwrite(f)
    f.set_defaults(func=run)
    return f


def run(args: argparse.Namespace) -> int:
    """Fly one mission (with an optional fault schedule) and write its tables and faults.json."""
    from tlm_process.summary import flight_summary, format_summary, plot_trajectory
    from tlm_sim import fly
    from tlm_sim.flight import max_duration_s
    from tlm_sim.profiles import profile_params

    fmts = _parse_formats(args.format)
    sticks = None
    if args.from_manifest is not None:
        if args.sticks:
            raise UsageError("--from-manifest flies the data set's own scenario: drop --sticks")
        mission, schedule, params, seed, profile, sticks = _from_manifest(args)
        changes = []
    elif args.sticks:
        mission, sticks, schedule, params, seed, profile, changes = _pilot_scenario(args)
    else:
        _take_defaults(args)
        params = _load_params(args)
        mission = _load_mission(args)
        profile = _check_profile(args.profile)
        flown = profile_params(profile, params)  # what sizes the flight
        changes = _parse_changes(args.set or [],
                                 float(math.floor(max_duration_s(mission, flown))))
        schedule = _load_schedule(args, mission, flown)
        seed = args.seed
    out = prepare_out(args.out, "fly", args.overwrite,
                      inputs=[args.mission_file, args.params, args.faults, args.from_manifest])
    t0 = time.perf_counter()
    faults = schedule if schedule is not None else (changes or None)
    log = fly(mission, faults=faults, params=params, seed=seed, profile=profile, sticks=sticks)
    wall = time.perf_counter() - t0
    log.write(out, formats=fmts)
    write_faults(out, log)
    if not args.no_plot:
        name = "stick script" if sticks is not None else mission.name
        plot_trajectory(log, out / "trajectory.png", f"{name}, seed {seed}")
    s = flight_summary(log)
    (out / "summary.json").write_text(json.dumps(s, indent=1))
    print(format_summary(s))
    for line in fault_lines(log, schedule):
        print(line)
    for line in fault_warnings(log, schedule):
        print(line, file=sys.stderr)
    print(f"wall time          {wall:.2f} s ({s['duration_s'] / max(wall, 1e-9):.0f}x real time, "
          "incl. compile on first run)")
    extra = "" if args.no_plot else ", trajectory.png"
    print(f"written            {out}/ ({', '.join(fmts)}, faults.json{extra})")
    return 0
