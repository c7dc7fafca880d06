"""``tlm generate --flights N --out DS``: a labelled fault data set of many simulated flights
(:func:`tlm_process.generate.generate`).

``run`` reports user mistakes itself (one line on stderr, exit code 2); exit code 1 when some
flights failed (they are in the manifest with their error), 130 after Ctrl-C or SIGTERM, 2
when the Dask scheduler was lost (the data set is closed, incomplete).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import signal
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from tlm_process.cliutil import UsageError, folder, parse_param_args

__all__ = ["add_parser", "build_config", "run"]

DESCRIPTION = """\
Fly many Monte Carlo flights and write them as one labelled data set: missions (the four
built-in shapes and random Algorithm 1 missions, fresh altitude profiles), no-fault,
single-fault, paper-style (GPS, accel, engine, RC in one flight) and sequence flights (several
of SITL's other faults, --faults), fault magnitudes, fault start times and holds (scaled by
lambda), the frame (+ or X quad), calm air or wind, and sensor noise, all drawn from --seed.
Flight i is the same whatever --flights, executor or worker count; re-running the command
continues an interrupted data set.
"""

EPILOG = """\
writes:
  DS/GPS.parquet DS/IMU.parquet ...  one folder per table, one part per flight, column
                                     'flight'; read with tlm_process.generate.
                                     read_dataset_table(DS, 'GPS') (or, once the manifest
                                     says complete, pandas.read_parquet('DS/GPS.parquet'))
  DS/faults.parquet                  Eq. 4 fault records, column 'flight'
  DS/manifest.json                   settings, tlm version, state, runs
  DS/flights.jsonl, DS/manifest.parquet   per flight: scenario, seed, status, timings, error
  DS/bin/flight-00000042.bin         with --bin: ArduPilot DataFlash logs
  DS/GPS.parquet/flights-00000000-00000099.parquet   with --compact: 100 flights per file

defaults: --faults all (kinds none=0.2,single=0.4,paper=0.2,sequence=0.2: single faults
of every type 1-14, the paper sequence, sequences of the new types); missions
builtin=0.5,random=0.5; frames +=0.5,x=0.5 (FRAME_CLASS 1, FRAME_TYPE 0 or 1); wind:
30 % calm (SIM_WIND_SPD 0, SIM_WIND_TURB 0), the others SIM_WIND_SPD 0-8 m/s, SIM_WIND_DIR
0-360 deg, SIM_WIND_TURB 0-2 m/s; noise SIM_GYR1/2_RND 0-0.5 deg/s, SIM_BARO/BAR2_RND
0-0.2 m, SIM_MAG_RND 0-20 mGauss; vibration: 50 % of the flights a real copter's (VIBE
~2-20 m/s/s per axis, gyro noise ~0.5-7 deg/s, rotors lagging and turning apart, gusts
correlated over 0.3-1 s; --real-share), the others SITL-quiet (--no-env: no wind, no noise
and no vibration drawn).
--config FILE (.json/.yaml) sets any scenario setting (docs/generate.md), e.g. the magnitude
ranges of the new faults (magnitudes: {gps_glitch: {offset_m: [20, 60]}, battery: {volt:
[9.9, 10.4]}, ...}), frames: {"+": 0.3, x: 0.7}, wind: {calm: 0.5, speed: [2, 8]}; flags
override it.

examples:
  tlm generate --flights 1000 --out ds --seed 1
  tlm generate --flights 200 --out ds-paper --kinds paper=1 --profile paper --lambda 1.5
  tlm generate --flights 1000 --out ds-all --faults all        # every fault type
  tlm generate --flights 300 --out ds-b --faults battery,motor_partial,vibration
  tlm generate --flights 500 --out ds-x --frame x --calm-share 0 --wind-speed 4:8
  tlm generate --flights 200 --out ds-calm --frame + --no-env   # as the paper flew
  tlm generate --flights 5000 --out ds --scheduler tcp://127.0.0.1:8786   # via an SSH tunnel
  tlm fly --from-manifest ds --flight 123 --out flight123    # one flight again, alone
"""


def _shares(text: str, flag: str) -> dict[str, float]:
    out: dict[str, float] = {}
    for item in (s for s in text.replace(" ", "").split(",") if s):
        name, sep, value = item.partition("=")
        try:
            if not sep:
                raise ValueError
            out[name.lower()] = float(value)
        except ValueError:
            raise UsageError(f"{flag} expects NAME=SHARE,..., got {text!r}") from None
    return out


def _ranges(items: Sequence[str]) -> dict[str, tuple[float, float]]:
    out: dict[str, tuple[float, float]] = {}
    for it in items:
        name, sep, value = it.partition("=")
        lo, sep2, hi = value.partition(":")
        try:
            if not (sep and sep2):
                raise ValueError
            out[name.strip().upper()] = (float(lo), float(hi))
        except ValueError:
            raise UsageError(f"--range expects NAME=LOW:HIGH, got {it!r}") from None
    return out


def _span(text: str | None, flag: str) -> tuple[float, float] | None:
    """``LOW:HIGH`` or one value ``V`` (= ``V:V``) of a wind flag; None when not given."""
    if text is None:
        return None
    lo, sep, hi = text.partition(":")
    try:
        return (float(lo), float(hi)) if sep else (float(lo), float(lo))
    except ValueError:
        raise UsageError(f"{flag} expects LOW:HIGH or one value, got {text!r}") from None


def _frames(text: str) -> list[str] | dict[str, float]:
    """``--frame``: ``x``, ``+,x`` (equal shares) or ``+=0.3,x=0.7``."""
    items = [s for s in text.replace(" ", "").split(",") if s]
    if not items:
        raise UsageError("--frame expects NAME, NAME,NAME,... or NAME=SHARE,..., got "
                         f"{text!r}")
    if not any("=" in it for it in items):
        return [it.lower() for it in items]
    if not all("=" in it for it in items):
        raise UsageError(f"--frame: give every frame a share (+=0.3,x=0.7) or none (+,x), got "
                         f"{text!r}")
    return _shares(text, "--frame")


def _wind_setting(args: argparse.Namespace, d: dict[str, Any],
                  ranges: dict[str, tuple[float, float]],
                  flag_ranges: dict[str, tuple[float, float]]) -> dict[str, Any] | None:
    """The ``wind`` setting of the command line: the file's (or the defaults), with
    ``--calm-share``, ``--wind-speed``, ``--wind-dir``, ``--wind-turb`` and a ``--range`` of
    SIM_WIND_SPD / _DIR / _TURB on top (removed from ``ranges``); None with ``--no-env``."""
    from tlm_process.generate.scenario import WIND_PARAMS

    flags = {"speed": ("--wind-speed", _span(args.wind_speed, "--wind-speed")),
             "direction": ("--wind-dir", _span(args.wind_dir, "--wind-dir")),
             "turbulence": ("--wind-turb", _span(args.wind_turb, "--wind-turb"))}
    given = [f for f, v in flags.values() if v is not None]
    if args.calm_share is not None:
        given.insert(0, "--calm-share")
    wind = None if args.no_env else d.get("wind", {})
    if wind is None:
        if given:
            why = "--no-env" if args.no_env else f"{args.config} (wind: null)"
            raise UsageError(f"{why} draws no wind: drop {', '.join(given)}, or fix the wind "
                             "for every flight with --param SIM_WIND_SPD=V")
        return None
    if not isinstance(wind, dict):
        return wind  # ScenarioConfig says what is wrong with it
    wind = dict(wind)
    if args.calm_share is not None:
        wind["calm"] = args.calm_share
    for key, name in WIND_PARAMS.items():
        flag, span = flags[key]
        if span is not None and name in flag_ranges:
            raise UsageError(f"give {flag} or --range {name}, not both")
        span = span if span is not None else flag_ranges.get(name)
        if span is not None:  # a flag beats the file's wind and ranges
            wind[key] = span
            ranges.pop(name, None)
    return wind


def _config_file(path: str) -> dict[str, Any]:
    import yaml

    p = Path(path)
    from tlm_sim.textfile import TextFileError, read_text

    try:
        text = read_text(p)
    except TextFileError as exc:
        raise UsageError(f"--config: cannot read {p}: {exc}") from None
    try:
        doc = json.loads(text) if p.suffix.lower() == ".json" else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError, RecursionError) as exc:
        msg = str(exc).splitlines()[0]
        raise UsageError(f"--config: {p} is not valid JSON/YAML: {msg}") from None
    if not isinstance(doc, dict):
        raise UsageError(f"--config: {p} must hold a mapping of scenario settings")
    return doc


def _vehicle_params(path: str | None, wind_drawn: bool = False) -> dict[str, float]:
    """The changes a ``--params`` file (e.g. ``tlm fit``'s vehicle) makes that tlm models, as
    fixed parameters of every flight; its frame is --frame's to choose (FRAME_CLASS /
    FRAME_TYPE are left out), and while the wind is drawn (``wind_drawn``) so is its wind:
    the file's SIM_WIND_SPD / _DIR / _TURB (a fit's gusts are its log's air, not the vehicle)
    are left out, with a note on stderr. A vehicle whose motors vibrate without the rotor lag
    (TLM_ROTOR_TC 0) gets a note too."""
    if not path:
        return {}
    import sys
    import warnings

    from tlm_process.generate.scenario import WIND_PARAMS
    from tlm_sim.params import Params, is_modelled

    if not Path(path).is_file():
        raise UsageError(f"--params {path}: no such file")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = Params.from_parm(path)
    out = {k: v for k, v in p.changed().items()
           if is_modelled(k) and k not in ("FRAME_CLASS", "FRAME_TYPE")}
    air = sorted(k for k in out if wind_drawn and k in WIND_PARAMS.values())
    if air:
        for k in air:
            del out[k]
        print(f"tlm generate: --params {path}: {', '.join(air)} left to the drawn wind "
              "(--no-env, or --calm-share 0 with --wind-* ranges, to fly the file's air)",
              file=sys.stderr)
    vibrates = p["SIM_VIB_MOT_MAX"] > 0.0 and max(
        p[f"SIM_{s}{i}_RND"] for s in ("ACC", "GYR") for i in (1, 2)) > 0.0
    if vibrates and p["TLM_ROTOR_TC"] == 0.0:
        print(f"tlm generate: --params {path}: the vehicle's motors vibrate with SITL's rotor "
              "model (TLM_ROTOR_TC 0): strong vibration then goes round the rate loop at its "
              "own frequency and pilot-flown landings may never complete; tlm fit's vehicles "
              "set TLM_ROTOR_TC 0.05 (docs/noise.md)", file=sys.stderr)
    return out


def build_config(args: argparse.Namespace) -> Any:
    """The ScenarioConfig of the command line (``--config`` file, then the flags)."""
    from tlm_process.generate.scenario import ScenarioConfig

    d: dict[str, Any] = _config_file(args.config) if args.config else {}
    if getattr(args, "faults", None):  # the flag's preset beats the file's keys it sets
        from tlm_process.generate.errors import GenerateError
        from tlm_process.generate.scenario import fault_preset

        try:
            d = {**{k: v for k, v in d.items() if k != "faults"}, **fault_preset(args.faults)}
        except GenerateError as exc:
            raise UsageError(f"--faults: {exc}") from None
    if args.kinds:
        d["kinds"] = _shares(args.kinds, "--kinds")
    if args.missions:
        d["missions"] = _shares(args.missions, "--missions")
    if args.profile:
        d["profile"] = args.profile
    if args.lam is not None:
        d["lam"] = args.lam
    if args.frame:
        d["frames"] = _frames(args.frame)
    ranges = dict(ScenarioConfig().ranges if "ranges" not in d else d["ranges"])
    if args.no_env:
        ranges = {}
    flag_ranges = _ranges(args.range or [])
    ranges.update(flag_ranges)
    wind_drawn = not args.no_env and d.get("wind", {}) is not None
    params = {**dict(d.get("params") or {}),
              **_vehicle_params(getattr(args, "params", None), wind_drawn),
              **parse_param_args(args.param or [])}
    for name in params:  # a fixed value replaces a drawn one
        ranges.pop(name, None)
    d["wind"] = _wind_setting(args, d, ranges, flag_ranges)
    d["vibration"] = _vibration_setting(args, d)
    share = getattr(args, "pilot_share", None)
    if share is not None:
        if d.get("pilot", {}) is None:
            raise UsageError(f"{args.config} (pilot: null) draws no pilot-flown flights: drop "
                             "--pilot-share")
        d["pilot"] = {**dict(d.get("pilot") or {}), "share": share}
    d["ranges"], d["params"] = ranges, params
    return ScenarioConfig.from_dict(d)


def _vibration_setting(args: argparse.Namespace, d: dict[str, Any]) -> Any:
    """The ``vibration`` setting of the command line: the file's (or the defaults) with
    ``--real-share`` on top; None with ``--no-env``."""
    share = getattr(args, "real_share", None)
    vib = None if args.no_env else d.get("vibration", {})
    if vib is None:
        if share is not None:
            why = "--no-env" if args.no_env else f"{args.config} (vibration: null)"
            raise UsageError(f"{why} draws no vibration: drop --real-share")
        return None
    if share is not None and isinstance(vib, dict):
        vib = {**vib, "real": share}
    return vib


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``generate`` to ``tlm``'s subcommands; returns its parser."""
    p = subparsers.add_parser(
        "generate", help="fly many sampled flights into one labelled data set",
        description=DESCRIPTION, epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--flights", type=int, required=True,
                   help="number of flights N (0..N-1), at most 100000000")
    p.add_argument("--out", type=folder, required=True,
                   help="data set folder (new, empty, or one to continue)")
    p.add_argument("--seed", type=int, default=0, help="run seed: every draw comes from it "
                                                       "(default 0)")
    ex = p.add_argument_group("where flights run")
    ex.add_argument("--workers", type=int, help="local workers (default: all cores)")
    ex.add_argument("--executor", choices=("auto", "process", "thread"), default="auto",
                    help="local threads or processes; auto (default): threads up to 4 "
                         "workers (faster on few cores), processes above")
    ex.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                    help="run on a Dask distributed cluster (unauthenticated: use only a "
                         "scheduler you started, on loopback / an SSH tunnel or with TLS; see "
                         "docs/generate.md)")
    ex.add_argument("--dask-local", type=int, metavar="N",
                    help="start a Dask LocalCluster of N worker processes")
    ex.add_argument("--connect-timeout", type=float, default=10.0, metavar="S",
                    help="give up reaching the Dask scheduler after S seconds, and stop a "
                         "run whose scheduler is silent that long (default 10)")
    sc = p.add_argument_group("scenarios")
    lam = sc.add_mutually_exclusive_group()
    lam.add_argument("--lambda", dest="lam", type=float, metavar="L",
                     help="fault window factor: every fault is held L times as long "
                          "(Eq. 5; default 1)")
    lam.add_argument("--target-fault-ratio", type=float, metavar="G",
                     help="choose lambda = G / alpha, alpha measured on pilot flights, so about "
                          "a share G of the rows is in fault windows")
    sc.add_argument("--faults", metavar="paper|all|new|single|TYPE,TYPE,...",
                    help="which fault types are drawn: all (the default: every type, "
                         "labels 1-14: single faults, the paper sequence and sequences of new "
                         "faults), paper (the paper's four, labels 1-4), new (labels 5-14), "
                         "single (single faults of every type), or a list of types (single "
                         "faults and sequences of them); --kinds overrides the mix it sets")
    sc.add_argument("--kinds", metavar="none=A,single=B,paper=C,sequence=D",
                    help="shares of no-fault, single-fault, paper-style (all four faults) "
                         "and sequence (several faults of sequence_types) flights")
    sc.add_argument("--missions", metavar="builtin=A,random=B",
                    help="shares of built-in shapes and random Algorithm 1 missions")
    sc.add_argument("--profile", choices=("current", "paper"),
                    help="ArduPilot semantics (default current)")
    sc.add_argument("--frame", metavar="x|+,x|+=A,x=B",
                    help="frames drawn per flight: one name, a list (equal shares) or shares; "
                         "names +, x (quads), hexa, hexax, octa; it sets FRAME_CLASS and "
                         "FRAME_TYPE (default +=0.5,x=0.5)")
    sc.add_argument("--calm-share", type=float, metavar="F",
                    help="share of flights in calm air: no wind, no turbulence (default 0.3)")
    sc.add_argument("--wind-speed", metavar="LOW:HIGH",
                    help="SIM_WIND_SPD of the windy flights, m/s at full-strength height "
                         "(uniform; one value fixes it; default 0:8)")
    sc.add_argument("--wind-dir", metavar="LOW:HIGH",
                    help="SIM_WIND_DIR of the windy flights, deg, where the wind comes from "
                         "(default 0:360)")
    sc.add_argument("--wind-turb", metavar="LOW:HIGH",
                    help="SIM_WIND_TURB of the windy flights, m/s (default 0:2)")
    sc.add_argument("--pilot-share", type=float, metavar="F",
                    help="share of pilot-flown flights (ALT_HOLD, LOITER, POSHOLD from a drawn "
                         "stick script: hover, lines, boxes, yaw turns, freestyle; default 0; "
                         "STABILIZE by a --config's pilot modes), the rest fly missions; "
                         "faults are drawn as for missions (docs/generate.md)")
    sc.add_argument("--real-share", type=float, metavar="F",
                    help="share of flights with a real copter's vibration and noise, the rest "
                         "SITL-quiet (default 0.5; 0 when --params gives the vehicle its own; "
                         "docs/noise.md)")
    sc.add_argument("--params", metavar="F.parm",
                    help="an ArduPilot .parm file whose parameters every flight flies (a "
                         "vehicle from tlm fit; --param beats it; its frame is --frame's)")
    sc.add_argument("--param", action="append", metavar="NAME=VALUE",
                    help="fixed parameter for every flight (repeatable); not FRAME_CLASS / "
                         "FRAME_TYPE (--frame) nor, unless --no-env, the drawn SIM_WIND_SPD / "
                         "_DIR / _TURB (--wind-speed ...)")
    sc.add_argument("--range", action="append", metavar="NAME=LOW:HIGH",
                    help="parameter drawn uniformly per flight (repeatable); a range of "
                         "SIM_WIND_SPD / _DIR / _TURB is the windy flights' (as --wind-speed, "
                         "--wind-dir, --wind-turb)")
    sc.add_argument("--no-env", action="store_true",
                    help="no drawn wind, extra sensor noise or vibration (the reference SITL "
                         "settings; add --frame + for the paper's frame)")
    sc.add_argument("--config", metavar="FILE", help="scenario settings (.json/.yaml)")
    out = p.add_argument_group("output")
    out.add_argument("--tables", metavar="GPS,IMU,...",
                     help="tables to write (default: all the simulator logs)")
    out.add_argument("--bin", action="store_true", help="also write DS/bin/flight-N.bin")
    out.add_argument("--compact", action="store_true",
                     help="at the end, merge each table's per-flight parts into one file per "
                          "100 flights (fewer files, faster reads; also on a finished data set)")
    out.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)
    return p


@contextlib.contextmanager
def _sigterm_as_interrupt(handler: Any) -> Iterator[None]:
    """SIGTERM stops a run like Ctrl-C (main thread only; elsewhere nothing changes)."""
    try:
        old = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _print_line(line: str) -> None:
    """Print ``line`` to stdout, escaping what its encoding cannot hold (the undecodable
    bytes of a non-UTF-8 --out, which Python keeps as lone surrogates)."""
    enc = getattr(sys.stdout, "encoding", None) or "utf-8"
    print(line.encode(enc, "backslashreplace").decode(enc))


def run(args: argparse.Namespace) -> int:
    """Run ``tlm generate``; returns the exit code."""
    from tlm_process.generate.errors import GenerateError
    from tlm_process.generate.runner import GenerateOptions, generate

    def _term(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    try:
        config = build_config(args)
        tables = None if not args.tables else [t for t in args.tables.split(",") if t.strip()]
        opts = GenerateOptions(
            out=Path(args.out), flights=args.flights, seed=args.seed, config=config,
            target_fault_ratio=args.target_fault_ratio, tables=tables, bin_log=args.bin,
            executor=args.executor, workers=args.workers, scheduler=args.scheduler,
            dask_local=args.dask_local, progress=False if args.no_progress else None,
            connect_timeout_s=args.connect_timeout, compact=args.compact)
        with _sigterm_as_interrupt(_term):
            report = generate(opts)
    except (UsageError, GenerateError) as exc:
        print(f"tlm: error: {exc}", file=sys.stderr)
        return 2
    for line in report.lines():
        _print_line(line)
    if report.interrupted:
        return 130
    return 1 if report.failed else 0
