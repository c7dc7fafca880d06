"""``tlm fit LOG --out vehicle.parm``: the vehicle of one ArduCopter log, for tlm to fly (issue 40).

Finds the log's steady hover (or takes ``--segment START:END``), measures it
(:mod:`tlm_process.fit.stats`), and fits tlm's vehicle to it by flying hovers
(:mod:`tlm_process.fit.fit`): the log's own parameters tlm models, the hover thrust, and the
vibration per axis of the accelerometers and gyros. Prints each statistic, log against the
fitted tlm flight; writes the parameter file and a comparison plot. ``tlm fly --params
vehicle.parm`` and ``tlm generate --params vehicle.parm`` then fly that vehicle.

``--replay DIR`` then re-flies a pilot-flown log from its RCIN with the fitted vehicle
(:mod:`tlm_process.pilot.replay`) and compares it with the log: the fitted statistics over the
same segment of the replay, and the per-stick-segment report and overlay in DIR.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from tlm_process.cliutil import UsageError, check_writable_file

__all__ = ["add_parser", "run"]


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``fit`` to ``tlm``'s subcommands; returns its parser."""
    p = sub.add_parser(
        "fit", help="fit tlm's vehicle (noise, vibration, hover) to one real ArduCopter log",
        description="Measure a steady hover of an ArduCopter log (hover throttle, attitude "
                    "noise, IMU accel and gyro noise per axis, rate-tracking error, VIBE) and "
                    "fit tlm's vehicle to it by flying hovers (ALT_HOLD ones for a STABILIZE "
                    "or ALT_HOLD segment): the log's parameters tlm models, the hover thrust, "
                    "the vibration per axis, the rotor frequency (from VIBE), the gusts, the "
                    "rotors' thrust fluctuation and the airframe's balance. Writes a .parm "
                    "file that tlm fly / tlm generate take with --params.")
    p.add_argument("log", help="the ArduCopter log (.bin or text .log; Copter 3.x to 4.x)")
    p.add_argument("--out", required=True, metavar="vehicle.parm", help="the fitted parameters")
    p.add_argument("--segment", metavar="START:END",
                   help="the segment to fit, seconds of log time (default: the log's longest "
                        "steady hover, from 3 s after the pilot's last stick movement; a "
                        "cruise only when more than four times longer)")
    p.add_argument("--iterations", type=int, default=10,
                   help="fitting steps, each two hover flights (default 10)")
    p.add_argument("--seed", type=int, default=1, help="first seed of tlm's hovers (default 1)")
    p.add_argument("--plot", metavar="PNG",
                   help="comparison plot (default: beside --out, with .png)")
    p.add_argument("--replay", metavar="DIR",
                   help="then re-fly the log from its RCIN (the pilot's sticks) with the "
                        "fitted vehicle and compare: the segment's statistics in the replay, "
                        "DIR/report.md and DIR/overlay.png per stick segment")
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Run ``tlm fit``."""
    import warnings

    from tqdm import tqdm

    from tlm_process.fit.fit import (
        ALT_HOLD,
        FIT_SEEDS,
        FitError,
        fit_steps,
        fit_vehicle,
        log_battery,
    )
    from tlm_process.fit.segment import (
        LEVEL_MODES,
        parse_segment,
        segment_mode,
        steady_segments,
    )
    from tlm_process.fit.spectrum import format_spectra
    from tlm_process.fit.stats import StatsError, motor_asymmetry, segment_stats
    from tlm_process.logread import LogReadError, read_log_tables, warn_damage

    if not Path(args.log).is_file():
        raise FileNotFoundError(2, "no such log", args.log)
    if args.iterations < 1:
        raise UsageError(f"--iterations must be at least 1 (got {args.iterations})")
    check_writable_file(args.out, "--out")
    plot = Path(args.plot) if args.plot else Path(args.out).with_suffix(".png")
    check_writable_file(plot, "--plot")
    try:
        lt = read_log_tables(args.log)
    except LogReadError as exc:
        raise UsageError(str(exc)) from None
    warn_damage(lt)
    try:
        if args.segment:
            t0, t1 = parse_segment(args.segment)
        else:
            segs = steady_segments(lt.tables)
            if not segs:
                raise StatsError("the log has no steady segment (airborne, upright, one mode, "
                                 "steady attitude and altitude for 6 s); give --segment")
            t0, t1 = segs[0]
        target = {**segment_stats(lt.tables, t0, t1),
                  **motor_asymmetry(lt.tables, t0, t1, lt.params)}
    except StatsError as exc:
        raise UsageError(str(exc)) from None
    print(f"segment            {t0 * 1e-6:.1f}-{t1 * 1e-6:.1f} s of {args.log}")
    mode = segment_mode(lt.tables, t0)
    hover_mode = ALT_HOLD if mode in LEVEL_MODES else None
    with tqdm(total=FIT_SEEDS * fit_steps(args.iterations), desc="fit", unit="hover") as bar, \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            r = fit_vehicle(target, lt.params, args.iterations, args.seed,
                            progress=lambda k: bar.update(FIT_SEEDS * k - bar.n),
                            battery=log_battery(lt.tables, lt.params), mode=hover_mode)
        except FitError as exc:
            raise UsageError(f"the fit stopped: {exc}; the segment "
                             f"{t0 * 1e-6:.1f}-{t1 * 1e-6:.1f} s may not be a steady hover "
                             f"(give --segment)") from None
    print(format_table(r.log, r.tlm))
    spectra = _spectra(lt.tables, (t0, t1), r.params, args.seed, hover_mode)
    print(format_spectra(*spectra))
    for name, why in r.dropped.items():
        print(f"note: the log's {name} is not flown: {why}")
    for note in segment_notes(lt.tables, (t0, t1), mode, hover_mode):
        print(f"note: {note}")
    from tlm_sim.params import Params

    p = Params(r.params)
    header = (f"tlm fit {Path(args.log).name} segment {t0 * 1e-6:.1f}-{t1 * 1e-6:.1f} s: "
              "the log's parameters tlm models, the hover thrust, the vibration per axis, the "
              "gusts, the rotors' fluctuation and the airframe's balance")
    Path(args.out).write_text(p.to_parm_text(only_changed=True, header=header))
    plot_fit(r.log, r.tlm, plot, f"{Path(args.log).name} {t0 * 1e-6:.0f}-{t1 * 1e-6:.0f} s",
             spectra)
    print(f"written            {args.out} (+ {plot})")
    if args.replay:
        _replay(args, r.params, target, (t0, t1))
    return 0


def segment_notes(tables: Any, segment: tuple[float, float], mode: int | None,
                  hover_mode: int | None) -> list[str]:
    """What the fit's hovers could not match of the segment: a cruise (the fit flies hovers),
    a mode without position hold (``mode``; the fit's hovers fly ``hover_mode``, ALT_HOLD for
    STABILIZE and ALT_HOLD, else AUTO)."""
    from tlm_process.fit.fit import ALT_HOLD
    from tlm_process.fit.segment import POSITION_MODES, is_hover, segment_speed

    out = []
    if not is_hover(tables, *segment):
        out.append(f"the segment is a cruise (mean ground speed "
                   f"{segment_speed(tables, *segment):.1f} m/s): tlm's fitting flights hover, "
                   "so a cruise's drag, lean and motor commands are compared with a hover's; "
                   "give --segment for a hover")
    if mode is None or mode in POSITION_MODES:
        return out
    from tlm_sim.ardupilot import MODE_NAMES

    name = MODE_NAMES.get(mode, mode)
    if hover_mode == ALT_HOLD:
        out.append(f"the segment was flown in {name}: tlm's fitting hovers flew ALT_HOLD (sticks "
                   "centred; it levels the copter as STABILIZE does and holds the height a "
                   "hovering pilot holds), and the gusts, which do not lean a copter that holds "
                   "no position, were not fitted (SIM_WIND_TURB 0; tlm generate draws its own "
                   "wind)")
    else:
        out.append(f"the segment was flown in {name}, which does not hold the position; tlm's "
                   "fitting hovers hold theirs and lean against the gusts, so their "
                   "roll_std_deg and pitch_std_deg (compared, not fitted) run higher than the "
                   "log's")
    return out


def _spectra(tables: Any, segment: tuple[float, float], fitted: dict[str, float], seed: int,
             mode: int | None = None) -> tuple[dict[str, Any], dict[str, Any]]:
    """The spectra of the log's IMU rows over the segment and of a hover of the fitted
    vehicle (one more flight, seed ``seed`` + 100, in ``mode`` as the fit's)."""
    from tlm_process.fit.fit import fly_hover
    from tlm_process.fit.spectrum import imu_spectra

    log, h0, h1 = fly_hover(fitted, seed + 100, mode=mode)
    return imu_spectra(tables, *segment), imu_spectra(log.tables, h0, h1)


def _replay(args: argparse.Namespace, fitted: dict[str, float], target: dict[str, float],
            segment: tuple[float, float]) -> None:
    """``--replay DIR``: the log re-flown from its RCIN with the fitted vehicle; the segment's
    statistics in it against the log's, and the replay's report in DIR."""
    import warnings

    from tlm_process.fit.stats import StatsError, motor_asymmetry, segment_stats
    from tlm_process.pilot.replay import format_report, plot, replay, summary_lines

    out = Path(args.replay)
    out.mkdir(parents=True, exist_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            rr = replay(args.log, params=fitted)
        except (ValueError, KeyError) as exc:
            raise UsageError(f"--replay: cannot re-fly {args.log} from its RCIN: {exc}") from None
    for line in summary_lines(rr):
        print(line)
    tables = {n: rr["_log"].tables[n] for n in rr["_log"].tables}
    try:
        stats = {**segment_stats(tables, *segment),
                 **motor_asymmetry(tables, *segment, rr["_log"].params)}
        print(f"the segment {segment[0] * 1e-6:.1f}-{segment[1] * 1e-6:.1f} s in the replay:")
        print(format_table(target, stats))
    except StatsError as exc:
        print(f"note: the replay has no statistics over the segment ({exc})")
    plot(rr, out)
    (out / "report.md").write_text(format_report(rr))
    print(f"written            {out}/report.md (+ overlay.png)")


def format_table(log: dict[str, float], tlm: dict[str, float]) -> str:
    """statistic | log | tlm | tlm / log - 1, one line each."""
    from tlm_process.fit.fit import fitted_stats
    from tlm_process.fit.stats import ASYM_NAMES

    fitted = (*fitted_stats(log), *ASYM_NAMES)
    lines = [f"{'statistic':<24} {'log':>9} {'tlm':>9} {'diff':>7}  fitted"]
    for k, v in log.items():
        t = tlm.get(k, math.nan)
        d = f"{t / v - 1:+.0%}" if math.isfinite(v) and v and math.isfinite(t) else "-"
        lines.append(f"{k:<24} {_n(v):>9} {_n(t):>9} {d:>7}  {'yes' if k in fitted else ''}")
    return "\n".join(lines)


def _n(v: float) -> str:
    return "-" if not math.isfinite(v) else f"{v:.3g}"


def plot_fit(log: dict[str, float], tlm: dict[str, float], path: Path, title: str,
             spectra: tuple[dict[str, Any], dict[str, Any]] | None = None) -> None:
    """Bars per statistic (magnitudes): the log's and the fitted tlm flight's; with
    ``spectra`` (the log's and tlm's :func:`~tlm_process.fit.spectrum.imu_spectra`) below them
    the gyro spectra."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    keys = [k for k in log if math.isfinite(log[k]) or math.isfinite(tlm[k])]
    x = np.arange(len(keys))
    gyros = [n for n in ("gyr_x", "gyr_y", "gyr_z") if spectra and n in spectra[0]]
    if gyros:
        fig = plt.figure(figsize=(10, 7))
        ax = fig.add_subplot(2, 1, 1)
        for i, n in enumerate(gyros):
            sx = fig.add_subplot(2, len(gyros), len(gyros) + 1 + i)
            for which, style in ((0, "-"), (1, "--")):
                s = spectra[which].get(n)
                if s is not None:
                    sx.semilogy(s.freq_hz[1:], s.psd[1:], style,
                                label=("log" if which == 0 else "tlm, fitted"))
            sx.set_title(f"{n} spectrum", fontsize=9)
            sx.set_xlabel("Hz (the rows' own rate)", fontsize=8)
            if i == 0:
                sx.set_ylabel("(deg/s)^2 / Hz", fontsize=8)
                sx.legend(fontsize=7)
    else:
        fig, ax = plt.subplots(figsize=(10, 4))
    # magnitudes on the log scale (the motor asymmetries may be negative)
    ax.bar(x - 0.2, [abs(log[k]) for k in keys], 0.4, label="log")
    ax.bar(x + 0.2, [abs(tlm[k]) for k in keys], 0.4, label="tlm, fitted")
    ax.set_ylabel("|value|", fontsize=8)
    ax.set_xticks(x, keys, rotation=40, ha="right", fontsize=8)
    ax.set_yscale("log")
    ax.set_title(f"tlm fit: {title}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
