"""Rehearse issue 42's blind replay check on tlm's own pilot flights: every pilot mode on three
frames, in wind, a motor weakened, each re-flown from its RCIN with other seeds.

tlm flies the reference pilot script's steps (pitch forward, roll right, yaw right, pitch back;
ACRO: 1 s rate pulses) in STABILIZE and ACRO (the pilot's hand on the throttle), ALT_HOLD,
LOITER and POSHOLD, on the X, hexa and octa frames, in 5 m/s wind with ``SIM_WIND_TURB`` 1 and
motor 2 at ``SIM_ENGINE_MUL`` 0.85; writes each ``.bin`` (no sidecar: RCIN's segments) and
re-flies it as ``tlm crosscheck`` does (:func:`tlm_process.pilot.replay.replay`: seed 0, ten
draws of the gusts). Prints one line per flight and the measures outside::

    PYTHONPATH=. .venv/bin/python tools/replay_rehearsal.py --out /tmp/rehearsal [--jobs 2]

docs/pilot.md ("Every mode on three frames, in wind") gives the last result.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

MODES = ("STABILIZE", "ACRO", "ALT_HOLD", "LOITER", "POSHOLD")
FRAMES = {"x": (1, 1), "hexa": (2, 0), "octa": (3, 0)}
WEATHER = {"SIM_WIND_SPD": 5, "SIM_WIND_DIR": 60, "SIM_WIND_TURB": 1}
WEAK_MOTOR = {"SIM_ENGINE_FAIL": 2, "SIM_ENGINE_MUL": 0.85}  # motor 2 (bit 1)
FLIGHT_SEED = 7


def script(mode: str) -> dict[str, Any]:
    """The stick script: the rudder gesture, a climb, the four steps, a descent and landing."""
    hand = mode in ("STABILIZE", "ACRO")
    stick, leg = (0.15, 1) if mode == "ACRO" else (0.4, 8)
    rows: list[dict[str, Any]] = [{"t": 0, "mode": "STABILIZE" if hand else mode},
                                  {"t": 20, "yaw": 1, "ramp": 0}, {"t": 23.5, "yaw": 0, "ramp": 0}]
    rows += ([{"t": 24, "height": 10}] if hand else
             [{"t": 24, "throttle": 0.8, "ramp": 0}, {"t": 33, "throttle": 0.5}])
    if mode == "ACRO":
        rows.append({"t": 38, "mode": "ACRO"})
    t = 45.0
    for axis, v, length in (("pitch", stick, leg), ("roll", stick, leg), ("yaw", 0.3, 4),
                            ("pitch", -stick, leg)):
        rows += [{"t": t, axis: v}, {"t": t + length, axis: 0.0}]
        t += length + 9
    if hand:
        rows.append({"t": t, "throttle": "land"})
    else:
        rows += [{"t": t, "throttle": 0.15}, {"t": t + 14, "throttle": 0.0, "ramp": 0},
                 {"t": t + 15, "yaw": -1, "ramp": 0}, {"t": t + 18.5, "yaw": 0, "ramp": 0}]
    return {"sticks": rows}


def one(job: tuple[str, str, str]) -> str:
    """Fly, write and re-fly one (mode, frame); the report lines."""
    from tlm_process.pilot.replay import replay
    from tlm_sim import ardupilot as AP
    from tlm_sim import fly
    from tlm_sim.mission.sticks import StickScript
    from tlm_sim.params import Params

    mode, frame, out = job
    numbers = {v: k for k, v in AP.MODE_NAMES.items()}
    fc, ft = FRAMES[frame]
    params = {"FRAME_CLASS": fc, "FRAME_TYPE": ft, "FLTMODE2": AP.MODE_ACRO, **WEATHER,
              **WEAK_MOTOR,
              "FLTMODE1": AP.MODE_STABILIZE if mode == "ACRO" else numbers[mode]}
    log = fly(None, params=Params(params), sticks=StickScript.from_dict(script(mode)),
              seed=FLIGHT_SEED)
    path = Path(out) / f"{mode}_{frame}.bin"
    log.write_bin(path)
    r = replay(path)
    j = r["judged"]
    lines = [f"{mode:9s} {frame:4s} {log.meta['end_reason']:7s} {int(j['pass'].sum())}/{len(j)}"
             f" measures, flight time {'pass' if r['checks']['flight_time']['pass'] else 'FAIL'}"]
    bad = j[~j["pass"]]
    lines += [f"    outside: {b.segment} {b.measure}: log {b.log:.3f}, tlm {b.tlm_min:.3f}.."
              f"{b.tlm_max:.3f} (tolerance {b.tol:.3f})" for b in bad.itertuples()]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="folder for the flights' .bin")
    ap.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    jobs = [(m, f, str(args.out)) for m in MODES for f in FRAMES]
    with ProcessPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        for text in pool.map(one, jobs):
            print(text, flush=True)


if __name__ == "__main__":
    main()
