"""Profile: where the numba flight loop spends its time, per jitted function (Linux ``perf``).

Runs itself under ``perf record`` with an empty numba cache (so the loop is compiled in the
process and the address of every jitted function is known), flies ``--flights`` flights of
mission 1 after a warm-up, writes the ``/tmp/perf-PID.map`` that perf reads for JIT code, and
prints each jitted function's share of the samples that fell in jitted code (self time: small
functions LLVM inlined count in their caller). It profiles the loop as numba links it by
default (``LoopLibrary.privatize = False``, see :mod:`tlm_sim._jit`): the default build makes
the callees private to the loop, where LLVM inlines most of them and perf can no longer tell
them apart. Needs ``perf`` on PATH; ~1 minute (compile).

    PYTHONPATH=. .venv/bin/python benchmarks/profile_fly.py [--flights 20] [--split-inline] \\
        [--paper]

``--paper`` flies ``tlm generate``'s paper-style scenarios (run seed 0) instead of mission 1.

``--split-inline`` compiles the named sections that numba otherwise inlines into their caller
(``inline_jit``: the flight loop's ``_read_sensors``, ``_estimate``, ``_log_tick``, ...) as
functions of their own, so that their time is not counted as ``run_flight``'s. After the table
of functions a second table sums the shares per subsystem (:data:`SUBSYSTEMS`).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from collections import Counter


def _short(symbol: str) -> str:
    """``tlm_sim.dynamics.body.physics_step`` from numba's mangled name
    ``_ZN7tlm_sim8dynamics4body12physics_stepB3v37B52...``."""
    if not symbol.startswith("_ZN"):
        return symbol
    parts, pos = [], 3
    while (n := re.match(r"\d+", symbol[pos:])) is not None:
        k, start = int(n.group()), pos + n.end()
        parts.append(symbol[start:start + k])
        pos = start + k
    return ".".join(parts) or symbol


#: subsystem of a jitted function, by the first prefix of its qualified name that matches
SUBSYSTEMS: tuple[tuple[str, str], ...] = (
    ("tlm_sim.flight._physics_tick", "physics (1200 Hz: body, motors, wind, battery)"),
    ("tlm_sim.sensors.imu.imu_sample", "IMU sampling (1200 Hz)"),
    ("tlm_sim.sensors.imu._", "IMU sampling (1200 Hz)"),
    ("tlm_sim.rng", "IMU sampling (1200 Hz)"),
    ("tlm_sim.dynamics.log", "logging"),
    ("tlm_sim.dynamics", "physics (1200 Hz: body, motors, wind, battery)"),
    ("tlm_sim.rotation", "physics (1200 Hz: body, motors, wind, battery)"),
    ("tlm_sim.sensors.log", "logging"),
    ("tlm_sim.sensors", "sensors (400 Hz: IMU deltas, GPS, baro, compass, RC)"),
    ("tlm_sim.flight._read_sensors", "sensors (400 Hz: IMU deltas, GPS, baro, compass, RC)"),
    ("tlm_sim.ekf.gsf", "EKF yaw estimators (GSF)"),
    ("tlm_sim.ekf.log", "logging"),
    ("tlm_sim.ekf.core.predict_covariance", "EKF covariance prediction (every 12 ms)"),
    ("tlm_sim.ekf.core._mirror_and_add_noise", "EKF covariance prediction (every 12 ms)"),
    ("tlm_sim.ekf.core.propagate", "EKF state propagation + output observer (every tick)"),
    ("tlm_sim.ekf.core.quat_to_rot", "EKF state propagation + output observer (every tick)"),
    ("tlm_sim.ekf.core.output_track", "EKF state propagation + output observer (every tick)"),
    ("tlm_sim.ekf.core.buffer_push", "EKF state propagation + output observer (every tick)"),
    ("tlm_sim.ekf", "EKF other (lane driver, fusion, selection, outputs)"),
    ("tlm_sim.flight._estimate", "EKF other (lane driver, fusion, selection, outputs)"),
    ("tlm_sim.control.dcm", "DCM"),
    ("tlm_sim.control.log", "logging"),
    ("tlm_sim.control.events", "logging"),
    ("tlm_sim.logger", "logging"),
    ("tlm_sim.flight._log_tick", "logging"),
    ("tlm_sim.control.arming", "arming / boot texts"),
    ("tlm_sim.control", "control (modes, navigation, position, attitude, mixer, failsafes)"),
    ("tlm_sim.flight", "flight loop itself (+ callees LLVM inlined)"),
)


def subsystem(name: str) -> str:
    """The :data:`SUBSYSTEMS` group of a jitted function's qualified name."""
    for prefix, group in SUBSYSTEMS:
        if name.startswith(prefix):
            return group
    return "other"


def _flights(flights: int, paper: bool) -> list[dict]:
    """The ``fly`` keyword arguments of the profiled flights: mission 1 (seeds 1..flights),
    or ``tlm generate``'s paper-style scenarios (run seed 0, flights 0..flights-1)."""
    if not paper:
        return [{"mission": 1, "seed": k + 1} for k in range(flights)]
    from tlm_process.generate.scenario import ScenarioConfig, sample_scenario

    out = []
    for k in range(flights):
        spec = sample_scenario(0, k, ScenarioConfig(kinds={"paper": 1.0})).realise()
        out.append({"mission": spec.mission, "faults": spec.schedule, "params": spec.params,
                    "seed": spec.seed, "profile": spec.profile})
    return out


def child(flights: int, split_inline: bool, paper: bool = False) -> None:
    """Fly (under perf), then write the perf map of the loop's jitted functions."""
    if split_inline:  # before any jitted module imports the decorator, so before the
        # package's __init__ (which imports them all) runs
        import importlib.util

        spec = importlib.util.find_spec("tlm_sim")
        assert spec is not None and spec.loader is not None
        pkg = importlib.util.module_from_spec(spec)
        sys.modules["tlm_sim"] = pkg
        from tlm_sim import _jit

        _jit.inline_jit = _jit.tick_jit
        spec.loader.exec_module(pkg)
    from tlm_sim._jit_fast import LoopLibrary

    # keep the callees' exported names (the perf map needs their addresses); the loop is then
    # ~20 % slower than the default build, whose callees are private (tlm_sim._jit_fast)
    LoopLibrary.privatize = False
    from tlm_sim import fly
    from tlm_sim.flight import run_flight

    kwargs = _flights(flights, paper)
    fly(**kwargs[0])  # compile (the profile counts jitted code only)
    for kw in kwargs:
        fly(**kw)
    addrs = []
    for cres in run_flight.overloads.values():
        lib = cres.library
        for f in lib._final_module.functions:  # numba internals: the linked loop module
            if not f.is_declaration:
                a = lib.get_pointer_to_function(f.name)
                if a:
                    addrs.append((a, f.name))
    addrs.sort()
    with open(f"/tmp/perf-{os.getpid()}.map", "w", encoding="ascii") as fh:
        for i, (a, name) in enumerate(addrs):
            size = addrs[i + 1][0] - a if i + 1 < len(addrs) else 0x10000
            fh.write(f"{a:x} {size:x} {name}\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--flights", type=int, default=20)
    ap.add_argument("--split-inline", action="store_true",
                    help="compile the inline_jit sections as functions of their own")
    ap.add_argument("--paper", action="store_true",
                    help="fly tlm generate's paper-style scenarios (faults, drawn wind and "
                         "noise) instead of mission 1")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.flights, args.split_inline, args.paper)
        return
    if shutil.which("perf") is None:
        sys.exit("profile_fly: needs Linux perf on PATH")
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "perf.data")
        env = {**os.environ, "NUMBA_CACHE_DIR": os.path.join(tmp, "numba")}
        subprocess.run(["perf", "record", "-q", "-F", "2000", "-o", data, sys.executable,
                        __file__, "--child", "--flights", str(args.flights)]
                       + (["--split-inline"] if args.split_inline else [])
                       + (["--paper"] if args.paper else []),
                       check=True, env=env)
        rep = subprocess.run(["perf", "report", "-i", data, "-n", "--no-children",
                              "--sort", "sym", "--stdio"], capture_output=True, text=True,
                             check=True).stdout
    samples: Counter[str] = Counter()
    for line in rep.splitlines():
        f = line.split()
        if len(f) >= 4 and f[0].endswith("%") and f[3].startswith("_ZN"):
            name = _short(f[3])
            if name.startswith("tlm_sim."):
                samples[name] += int(f[1])
    total = sum(samples.values())
    if not total:
        sys.exit("profile_fly: no samples in jitted code (perf map not read?)")
    what = "paper-style generate flights" if args.paper else "mission 1"
    print(f"{total} samples in the jitted flight loop ({args.flights} flights of {what})")
    print("| function | share |\n|---|---|")
    for name, n in samples.most_common():
        if n / total >= 0.005:
            print(f"| `{name}` | {100 * n / total:.1f} % |")
    groups: Counter[str] = Counter()
    for name, n in samples.items():
        groups[subsystem(name)] += n
    print("\n| subsystem | share |\n|---|---|")
    for group, n in groups.most_common():
        print(f"| {group} | {100 * n / total:.1f} % |")


if __name__ == "__main__":
    main()
