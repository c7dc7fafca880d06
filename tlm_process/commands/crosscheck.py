"""``tlm crosscheck SITL.bin``: fly a SITL log's scenario in tlm and report how far apart they are
(:mod:`tlm_process.crosscheck`). A pilot-flown log (RCIN, no AUTO; or ``--replay``) is re-flown
from its RCIN instead (:mod:`tlm_process.pilot.replay`): per stick segment, issue 42's
measures; exit code 1 when one is outside its tolerance.

Writes ``DIR/report.md`` with overlay plots (trajectory, altitude and speed, IMU spectrum), the
re-flown flight as ``DIR/tlm_flight.bin`` (ArduPilot DataFlash) and ``R.json``;
``--max-flight-time-diff`` and ``--max-trajectory-rms`` turn it into a regression
gate (exit code 1 when exceeded).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from tlm_process.cliutil import (
    UsageError,
    add_overwrite,
    check_writable_file,
    folder,
    parse_param_args,
    prepare_out,
    strict_json,
)
from tlm_process.crosscheck.compare import (
    DEFAULT_MAX_FLIGHT_TIME_DIFF,
    DEFAULT_MAX_TRAJECTORY_RMS_M,
    cell,
)

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``crosscheck`` to ``tlm``'s subcommands; returns its parser."""
    c = sub.add_parser(
        "crosscheck", help="fly a SITL log's scenario in tlm and compare the two",
        description="Rebuild a real ArduPilot SITL flight (mission from CMD, parameters from "
                    "PARM, faults from the sidecar or from SIM_* parameter changes), fly it in "
                    "tlm, align the two at arming and report per channel how far apart they "
                    "are. Exit code 1 when a --max-* threshold is exceeded.")
    c.add_argument("log", help="the SITL .bin")
    c.add_argument("--sidecar", help="fault sidecar JSON (default: LOG.json beside the log)")
    c.add_argument("--seed", type=int, help="tlm seed (default: the sidecar's, else 0; with "
                                             "--seeds the first seed, default 1)")
    c.add_argument("--seeds", type=int, metavar="N",
                   help="re-fly the log with N tlm seeds and report per signature metric tlm's "
                        "10/50/90 %% values and range beside SITL's value (random faults such as "
                        "GPS jamming are judged by distribution)")
    c.add_argument("--param", action="append", metavar="NAME=VALUE",
                   help="fly with this parameter over the log's (repeatable): another frame "
                        "(--param FRAME_TYPE=1), a wind, or SITL's start-up (--param "
                        "TLM_BOOT_PHASE=1: then the pre-arm and EKF start-up texts are compared "
                        "too)")
    c.add_argument("--replay", action="store_true",
                   help="re-fly the log from its RCIN (the pilot's sticks; STABILIZE, ACRO, "
                        "ALT_HOLD, LOITER, POSHOLD) and compare per stick segment; the default "
                        "for a log with RCIN and no AUTO mode (a log flown in random gusts, "
                        "SIM_WIND_TURB > 0, is re-flown with ten draws of them and judged on "
                        "their range)")
    c.add_argument("--json", metavar="R.json", help="write the metrics as JSON")
    c.add_argument("--out", type=folder, metavar="DIR",
                   help="write report.md, overlay PNGs and the re-flown flight (tlm_flight.bin) "
                        "here")
    c.add_argument("--max-flight-time-diff", type=float, default=None, metavar="FRAC",
                   help=f"fail when armed flight time differs by more than FRAC "
                        f"(issue target {DEFAULT_MAX_FLIGHT_TIME_DIFF})")
    c.add_argument("--max-trajectory-rms", type=float, default=None, metavar="M",
                   help=f"fail when the trajectory RMS exceeds M metres (issue target "
                        f"{DEFAULT_MAX_TRAJECTORY_RMS_M})")
    add_overwrite(c)
    c.set_defaults(func=run)
    return c


def run(args: argparse.Namespace) -> int:
    """Run ``tlm crosscheck``."""
    from tlm_process.crosscheck.compare import crosscheck, format_report, gate, plot, to_json
    from tlm_process.crosscheck.scenario import ScenarioError

    if not Path(args.log).is_file():
        raise FileNotFoundError(2, "no such log", args.log)
    overrides = parse_param_args(args.param or [])
    if args.json:
        check_writable_file(args.json, "--json")
    out = prepare_out(args.out, "crosscheck", args.overwrite,
                      inputs=[args.log, args.sidecar]) if args.out else None
    if args.replay or _pilot_flown(args.log):
        return _run_replay(args, overrides, out)
    if args.seeds is not None:
        return _run_seeds(args, overrides, out)
    try:
        r = crosscheck(args.log, args.sidecar, args.seed, params=overrides or None)
    except ScenarioError as e:
        msg = str(e)
        if msg.startswith("the log has no mission"):
            msg += ("; --replay re-flies it from its RCIN instead" if _has_sticks(args.log)
                    else "; nor RCIN with the pilot's sticks to re-fly it from")
        raise UsageError(msg) from None
    text = format_report(r)
    print(text.split("\n| metric")[0])
    ft = r["flight_time_s"]
    print(f"flight time: tlm {ft['tlm']:.1f} s, SITL {ft['sitl']:.1f} s")
    for note in r["scenario"].get("notes") or ():
        print(f"note: {note}")
    for f in r["faults"]:
        keys = list(f["sitl"])[:3]
        print(f"fault {f['type']}: {f.get('passed', 0)}/{f.get('compared', 0)} signature "
              "metrics within 35 %; " + ", ".join(
                  f"{k} tlm {cell(f['tlm'].get(k))} / SITL {cell(f['sitl'].get(k))}"
                  for k in keys))
    c = r["checks"]
    print(f"checks: flight time {'pass' if c['flight_time']['pass'] else 'FAIL'}, trajectory "
          f"RMS {'pass' if c['trajectory_rms']['pass'] else 'FAIL'}, signatures "
          f"{c['signatures']['value']}")
    if out is not None:
        plot(r, out)
        (out / "report.md").write_text(text)
        r["_log"].write_bin(out / "tlm_flight.bin")
        print(f"written            {out}/report.md (+ trajectory.png, profiles.png, imu_psd.png, "
              "tlm_flight.bin)")
    if args.json:
        Path(args.json).write_text(json.dumps(to_json(r), indent=1) + "\n")
    bad = gate(r, args.max_flight_time_diff, args.max_trajectory_rms)
    for b in bad:
        print(f"tlm crosscheck: FAIL: {b}")
    return 1 if bad else 0


def _run_seeds(args: argparse.Namespace, overrides: dict[str, float], out: Path | None) -> int:
    """``tlm crosscheck LOG --seeds N`` (:mod:`tlm_process.crosscheck.seeds`)."""
    from tqdm import tqdm

    from tlm_process.crosscheck.compare import to_json
    from tlm_process.crosscheck.scenario import ScenarioError
    from tlm_process.crosscheck.seeds import (
        DEFAULT_FIRST_SEED,
        crosscheck_seeds,
        format_seeds_report,
        plot_seeds,
    )

    if args.seeds < 2:
        raise UsageError(f"--seeds needs at least 2 seeds (got {args.seeds})")
    if args.max_flight_time_diff is not None or args.max_trajectory_rms is not None:
        raise UsageError("--max-* gates judge one flight; leave them out with --seeds")
    first = DEFAULT_FIRST_SEED if args.seed is None else args.seed
    with tqdm(total=args.seeds, desc="seeds", unit="flight") as bar:
        try:
            d = crosscheck_seeds(args.log, args.sidecar, args.seeds, first,
                                 params=overrides or None,
                                 progress=lambda k: bar.update(k - bar.n))
        except ScenarioError as e:
            raise UsageError(str(e)) from None
    text = format_seeds_report(d)
    print(text.split("\n![")[0])
    if out is not None:
        plot_seeds(d, out)
        (out / "report.md").write_text(text)
        print(f"written            {out}/report.md (+ seeds.png)")
    if args.json:
        Path(args.json).write_text(json.dumps(to_json(d), indent=1) + "\n")
    return 0


def _pilot_flown(path: str) -> bool:
    """Whether the log was flown by a pilot (:func:`tlm_process.pilot.replay.is_pilot_flown`)."""
    from tlm_process.logread import LogReadError, read_log_tables
    from tlm_process.pilot.replay import is_pilot_flown

    try:
        return is_pilot_flown(read_log_tables(path, ["MODE", "RCIN"]).tables)
    except LogReadError:
        return False  # (the mission path reports what is wrong with the file)


def _has_sticks(path: str) -> bool:
    """Whether the log's RCIN holds the pilot's sticks
    (:func:`tlm_process.pilot.replay.has_sticks`)."""
    from tlm_process.logread import LogReadError, read_log_tables
    from tlm_process.pilot.replay import has_sticks

    try:
        return has_sticks(read_log_tables(path, ["RCIN"]).tables)
    except LogReadError:
        return False


def _run_replay(args: argparse.Namespace, overrides: dict[str, float], out: Path | None) -> int:
    """``tlm crosscheck LOG`` for a pilot-flown log: re-fly it from its RCIN."""
    from tlm_process.pilot.replay import format_report, plot, replay, summary_lines

    if args.seeds is not None:
        raise UsageError("--seeds compares fault signatures of mission flights; a replay from "
                         "RCIN judges one flight")
    try:
        r = replay(args.log, args.sidecar, args.seed, params=overrides or None)
    except (ValueError, KeyError) as e:
        raise UsageError(f"cannot replay {args.log} from RCIN: {e}") from None
    for line in summary_lines(r):
        print(line)
    if out is not None:
        plot(r, out)
        (out / "report.md").write_text(format_report(r))
        r["_log"].write_bin(out / "tlm_flight.bin")
        print(f"written            {out}/report.md (+ overlay.png, tlm_flight.bin)")
    if args.json:
        doc = {"scenario": r["scenario"], "checks": r["checks"],
               "flight_time_s": r["flight_time_s"],
               "judged": r["judged"].to_dict("records"),
               "segments": {k: v.to_dict("records") for k, v in r["segments"].items()}}
        Path(args.json).write_text(json.dumps(strict_json(doc), indent=1) + "\n")
    c = r["checks"]
    return 0 if c["segments"]["pass"] and c["flight_time"]["pass"] else 1

