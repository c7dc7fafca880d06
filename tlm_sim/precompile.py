"""Cold-cache compile of the flight loop, split across processes.

A flight is one numba function, :func:`tlm_sim.flight.run_flight`, calling ~150 jitted
functions. On an empty numba cache they are compiled one after another: tens of seconds of
CPU (``benchmarks/RESULTS.md``), most of it numba's own Python (type inference and lowering) under
its process-wide compiler lock, so more cores do not help within one process. The call tree
below ``run_flight`` splits into independent subtrees (the autopilot's ``vehicle_step``, the
EKF's ``ekf_update``, the rigid body's ``physics_step``, sensors and logging), each cached on
disk under its own name. :func:`precompile` therefore shares them out: worker processes compile
their share into the on-disk cache (``NUMBA_CACHE_DIR``, which :mod:`tlm_sim._cache` sets and
the workers inherit) while this process compiles its own; ``run_flight``, compiled here last,
then loads the workers' subtrees from the cache instead of compiling them again. The machine
code is the same as a one-process compile's; only the wall time of a cold start changes.

A file lock in the cache folder makes concurrent cold starts (``pytest -n 2``, a process pool
of ``tlm generate``) compile once: the others wait, then load the result.

:func:`tlm_sim.fly` calls :func:`ensure_compiled` before its first flight. ``TLM_COMPILE_PROCS``
sets the number of processes (default: the CPU count, at most 4; ``1`` compiles in this process
only, as numba would).

Each job names a function and the exact signature ``run_flight`` calls it with. A job whose
signature went stale would compile an unused variant; ``tests/test_precompile.py`` checks every
job against the signatures in the cache of a real flight.

Run ``python -m tlm_sim.precompile`` to fill the cache ahead of time (e.g. in a container build).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from numba import config
from numba import types as nt

from tlm_sim import bundles as B
from tlm_sim import logger as L

__all__ = ["JOBS", "CompileReport", "ensure_compiled", "job_dispatcher", "precompile"]

log = logging.getLogger(__name__)

#: most processes a cold compile uses (the call tree has three big subtrees)
MAX_PROCS = 4
#: CPU seconds a worker process spends starting (interpreter, numba, tlm_sim imports)
WORKER_START_S = 1.5
#: a worker still compiling after this long [s] is stopped (its share is compiled here)
WORKER_TIMEOUT_S = 900.0

_F1 = nt.float64[::1]
_F2 = nt.float64[:, ::1]
_I1 = nt.int64[::1]
_U1 = nt.uint64[::1]
_U2 = nt.uint64[:, ::1]  # the sensor noise streams (tlm_sim.rng.new_streams)
_f8, _i8, _b1 = nt.float64, nt.int64, nt.boolean
_BUFS = nt.UniTuple(_F2, len(L.LOG_ORDER))
_EVENTS = nt.UniTuple(_F2, 3)  # the event buffers (tlm_sim.logger E_*)
_EV = nt.Tuple((_EVENTS, _I1))  # ... with their row counts, as the vehicle logic takes them
# the flight loop's bundles (tlm_sim.bundles)
_STATE = nt.NamedTuple((_F1, _F1, _F2, _F1, _F1, _F1, _F2, _U2, _U1), B.VehicleState)
_CONFIG = nt.NamedTuple((_F1,) * 4, B.VehicleConfig)
_WORK = nt.NamedTuple((_F2, _F2, _F2, _F1), B.LoopWork)
_LOGS = nt.NamedTuple((_BUFS, _I1, _F2), B.FlightLogs)
_VIN = nt.NamedTuple((_F1,) * 6 + (_f8,) * 3, B.VehicleInputs)
_TICK = nt.NamedTuple((_i8, _i8, _b1, _b1, _b1), B.LoopTick)
_EKF_INPUTS = nt.NamedTuple((_F2, _F2, _F1, _b1, _F1, _F1, _b1, _b1, _f8, _b1, _F1, _b1),
                            B.EkfInputs)
_PLAN = nt.NamedTuple((_F2, _F2, _F2, _F1, _F1, _F1, _F2, _F2), B.FlightPlan)


@dataclass(frozen=True)
class Job:
    """One function to compile: ``module:name``, its argument types, and its cold compile
    cost [CPU s] (including the functions it calls; measured on the 2-core machine) used to
    share the jobs out."""

    target: str
    args: tuple[Any, ...]
    cost_s: float


#: the big subtrees below run_flight (called directly or from its small per-tick helpers:
#: _physics_tick, _read_sensors, _estimate, _log_tick, which run_flight's own compile covers)
#: and fly()'s set-up, with the exact signatures they are called with. No job may call
#: another: a function two jobs share (prepare_path, new_row, ekf_init) is compiled inside
#: each caller's job, where it is needed, instead.
JOBS: tuple[Job, ...] = (
    Job("tlm_sim.control.modes:vehicle_step",
        (_F1, _F1, _i8, _VIN, _F2, _F2, _EV),
        13.1),
    Job("tlm_sim.ekf.lanes:ekf_update",
        (_F2, _F1, _F1, _f8, _EKF_INPUTS), 13.4),
    Job("tlm_sim.dynamics.body:physics_step", (_F1, _F1, _F1, _f8, _f8, _U1), 4.1),
    Job("tlm_sim.control.log:log_control_10hz",
        (_LOGS, _i8, _F1, _F1, _F1, _F1), 1.8),
    Job("tlm_sim.ekf.log:log_ekf_10hz", (_LOGS, _i8, _F2, _F1, _F1, _F1), 1.5),
    Job("tlm_sim.sensors.log:log_sensors_10hz", (_LOGS, _i8, _F1, _f8), 0.8),
    Job("tlm_sim.dynamics.log:log_dynamics_10hz", (_LOGS, _i8, _F1, _F1), 1.0),
    Job("tlm_sim.dynamics.body:init_state", (_F1, _F1, _f8), 0.2),
    Job("tlm_sim.sensors.imu:imu_sample", (_F1, _F1, _F1, _f8, _f8, _F1, _U2), 1.6),
    Job("tlm_sim.sensors.log:log_imu", (_LOGS, _i8, _F1, _F1), 0.8),
    Job("tlm_sim.sensors.log:log_gps", (_LOGS, _i8, _F1, _F1, _F1, _F1, _f8), 0.6),
    Job("tlm_sim.sensors.gps:gps_push_truth", (_F1, _F1, _f8), 0.1),
    Job("tlm_sim.sensors.gps:gps_measure", (_F1, _F1, _f8, _F1, _U1), 0.9),
    Job("tlm_sim.flight:_apply_schedule", (_PLAN, _CONFIG, _i8, _i8, _f8), 0.3),
    Job("tlm_sim.sensors.imu:imu_take_deltas", (_F1, _i8, _f8, _F2, _F2), 0.3),
    Job("tlm_sim.sensors.baro:baro_read", (_F1, _F1, _F1, _U2, _f8), 0.5),
    Job("tlm_sim.sensors.baro:baro_init", (_F1,), 0.1),
    Job("tlm_sim.sensors.mag:mag_sample", (_F1, _F1, _F1, _U1, _f8), 0.8),
    # issue 19's main-loop callees: compiled by run_flight itself they made its serial tail
    # 6.6 s instead of 4.0 s
    Job("tlm_sim.control.battery:battery_monitor", (_F1, _F1, _i8, _f8, _f8, _EV),
        0.6),
    Job("tlm_sim.control.ahrs:ahrs_update", (_F1,) * 7, 0.4),
    Job("tlm_sim.ekf.lanes:ekf_gps_accuracy", (_F2, _F1, _f8, _F1), 0.2),
    Job("tlm_sim.ekf.lanes:ekf_output", (_F2, _F1, _F1), 0.4),  # with ekf_output_nav
    Job("tlm_sim.ekf.log:gps_glitch_check", (_EV, _i8, _F2, _F1), 0.1),
    Job("tlm_sim.ekf.log:log_lane_switch", (_EV, _i8, _F1), 0.1),
    Job("tlm_sim.sensors.gps:gps_init", (_F1, _f8, _f8), 0.1),
    Job("tlm_sim.sensors.rc:rc_update", (_F1, _F1, _f8, _F2, _F1), 0.1),
    Job("tlm_sim.ekf.log:log_ekf_evidence", (_LOGS, _i8, _F2, _F1, _F1), 1.9),
    # issue 21: the arming driver, pre-arm checks and boot texts, the EKF's GPS checks
    Job("tlm_sim.control.arming:arming_step",
        (_F1, _F1, _f8, nt.UniTuple(_F1, 2), _VIN, _F2, _EV), 2.8),
    Job("tlm_sim.control.arming:lifecycle_texts",
        (_F1, _TICK, _F1, _F1, _f8, _F2, _EV), 0.5),
    Job("tlm_sim.control.modes:arm_vehicle", (_F1, _i8, _F1, _EV), 0.1),
    Job("tlm_sim.ekf.lanes:ekf_gps_checks", (_F2, _F1, _f8, _F1), 1.1),
    # issue 21: the DCM estimator and the EKF lanes' yaw estimators, their logs
    Job("tlm_sim.control.dcm:dcm_update", (_F1, _F1, _F1, _EKF_INPUTS, _F1, _i8, _i8), 3.9),
    Job("tlm_sim.ekf.gsf:gsf_update", (_F2, _F2, _F1, _EKF_INPUTS), 2.7),
    Job("tlm_sim.control.log:log_dcm_10hz",
        (_LOGS, _i8, _F1, _F1, nt.UniTuple(_F1, 2), _F1, _F1), 0.7),
    Job("tlm_sim.ekf.log:log_gsf", (_LOGS, _i8, _F2), 0.8),
    # issue 21's evidence messages (ARM, ORGN, LDET, MISE every tick; SIM2 at 50 Hz)
    Job("tlm_sim.control.log:log_vehicle_events",
        (_LOGS, _i8, _F1, _F1, _b1, _F1), 1.5),
    Job("tlm_sim.dynamics.log:log_sim2", (_LOGS, _i8, _F1), 0.4),
)

RUN_FLIGHT = Job(
    "tlm_sim.flight:run_flight",
    (_STATE, _CONFIG, _PLAN, _LOGS, _WORK, _i8), 8.4)


@dataclass
class CompileReport:
    """What :func:`precompile` did: processes used, jobs per process, wall time [s]."""

    processes: int
    shares: list[list[str]] = field(default_factory=list)
    wall_s: float = 0.0
    worker_failures: int = 0
    #: workers' jobs that this process compiled after all (cache misses; should be none)
    misses: list[str] = field(default_factory=list)
    skipped: str = ""


def job_dispatcher(job: Job) -> Any:
    """The numba dispatcher a job names."""
    module, name = job.target.split(":")
    return getattr(importlib.import_module(module), name)


def _compile(job: Job) -> None:
    job_dispatcher(job).compile(job.args)


def share_out(jobs: Sequence[Job], n_procs: int) -> list[list[Job]]:
    """Longest job first to the least loaded process; share 0 is this process's (workers start
    :data:`WORKER_START_S` behind)."""
    load = [0.0] + [WORKER_START_S] * (n_procs - 1)
    shares: list[list[Job]] = [[] for _ in range(n_procs)]
    for job in sorted(jobs, key=lambda j: -j.cost_s):
        k = min(range(n_procs), key=lambda i: load[i])
        shares[k].append(job)
        load[k] += job.cost_s
    return shares


def _n_procs() -> int:
    env = os.environ.get("TLM_COMPILE_PROCS", "").strip()
    if env:
        try:
            return max(1, int(env))
        except ValueError:
            log.warning("TLM_COMPILE_PROCS=%r is not an integer; compiling in one process", env)
            return 1
    return max(1, min(os.cpu_count() or 1, MAX_PROCS))


def _start_worker(jobs: Sequence[Job]) -> subprocess.Popen[bytes]:
    """A ``python -m tlm_sim.precompile --worker`` process compiling ``jobs`` into the cache."""
    env = dict(os.environ)
    root = Path(__file__).resolve().parents[1]
    if root.name not in ("site-packages", "dist-packages"):  # a checkout: import this very one
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(root), env.get("PYTHONPATH")) if p)
    env["TLM_COMPILE_PROCS"] = "1"
    names = [j.target for j in jobs]
    return subprocess.Popen([sys.executable, "-m", "tlm_sim.precompile", "--worker", *names],
                            env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)


def _is_cached(job: Job) -> bool:
    """Whether the on-disk cache already holds the job's function (its index file exists)."""
    disp = job_dispatcher(job)
    if disp.signatures:
        return True
    try:
        return Path(disp._cache._cache_file._index_path).exists()
    except AttributeError:  # numba internals moved: assume cold, compile as numba would
        return False


@contextlib.contextmanager
def _cache_lock() -> Iterator[None]:
    """Exclusive lock on the numba cache folder across processes (no-op where fcntl is
    unavailable)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows
        yield
        return
    folder = Path(config.CACHE_DIR or Path(__file__).resolve().parent / "__pycache__")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fh = open(folder / ".tlm-compile.lock", "a+b")  # noqa: SIM115 - closed below
    except OSError:  # read-only cache folder: numba caches elsewhere or not at all
        yield
        return
    with fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh, fcntl.LOCK_UN)


def precompile(n_procs: int | None = None) -> CompileReport:
    """Compile the flight loop into the numba cache, sharing the work over ``n_procs``
    processes (default ``TLM_COMPILE_PROCS`` or the CPU count, at most :data:`MAX_PROCS`).

    Does nothing when the cache already holds the flight (its first call loads it). A worker
    that fails only costs time: whatever it did not compile, run_flight's compile here does.
    """
    t0 = time.perf_counter()
    n = _n_procs() if n_procs is None else max(1, int(n_procs))
    if _is_cached(RUN_FLIGHT):  # no lock: many warm processes start at once in a pool
        return CompileReport(processes=0, skipped="cached")
    with _cache_lock():
        if _is_cached(RUN_FLIGHT):  # another process compiled it while this one waited
            return CompileReport(processes=0, wall_s=time.perf_counter() - t0,
                                 skipped="compiled by another process")
        log.info("compiling the flight loop into the numba cache with %d process(es) (first "
                 "run after an install or an edit of tlm_sim) ...", n)
        shares = share_out(JOBS, n)
        workers = []
        failures = 0
        try:
            for share in shares[1:]:
                if not share:
                    continue
                try:
                    workers.append(_start_worker(share))
                except OSError as exc:  # no subprocesses here: this process compiles it all
                    log.debug("precompile worker did not start (%s)", exc)
                    shares[0].extend(share)
                    share.clear()
            for job in shares[0]:
                _compile(job)
            for w in workers:
                try:
                    _, err = w.communicate(timeout=WORKER_TIMEOUT_S)
                except subprocess.TimeoutExpired:
                    w.kill()
                    _, err = w.communicate()
                if w.returncode != 0:
                    failures += 1
                    log.warning("a precompile worker failed (exit %s); its share is compiled "
                                "here:\n%s", w.returncode, err.decode(errors="replace")[-2000:])
        finally:  # an error or Ctrl-C here stops the workers too
            for w in workers:
                if w.poll() is None:
                    w.kill()
                    w.wait()
        _compile(RUN_FLIGHT)
        log.info("compiled in %.1f s", time.perf_counter() - t0)
    misses = [j.target for s in shares[1:] for j in s
              if sum(job_dispatcher(j).stats.cache_misses.values())]
    return CompileReport(processes=1 + len(workers), shares=[[j.target for j in s] for s in shares],
                         wall_s=time.perf_counter() - t0, worker_failures=failures, misses=misses)


_ensured = False
_ensure_lock = threading.Lock()


def ensure_compiled() -> None:
    """Before the first flight of this process: compile (or load) the flight loop, in parallel
    on a cold cache. Does nothing with numba's JIT disabled or once done."""
    global _ensured
    if _ensured or config.DISABLE_JIT:
        return
    with _ensure_lock:
        if not _ensured:
            precompile()
            _ensured = True


def _worker(targets: Sequence[str]) -> None:
    by_target = {j.target: j for j in (*JOBS, RUN_FLIGHT)}
    for t in targets:
        _compile(by_target[t])


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m tlm_sim.precompile",
                                 description="Compile tlm's flight loop into the numba cache.")
    ap.add_argument("--procs", type=int, default=None,
                    help=f"processes to use (default: CPU count, at most {MAX_PROCS})")
    ap.add_argument("--worker", nargs="+", metavar="MODULE:NAME", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        _worker(a.worker)
        return 0
    rep = precompile(a.procs)
    if rep.skipped:
        print(f"already compiled ({rep.skipped}) in {config.CACHE_DIR}")
    else:
        print(f"compiled in {rep.wall_s:.1f} s with {rep.processes} process(es) "
              f"into {config.CACHE_DIR}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
