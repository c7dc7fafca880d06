"""``generate()``: fly many sampled flights on an executor and write them into a data set.

The calling thread samples nothing and flies nothing: it hands out small jobs (flight index,
run seed, settings), keeps about two jobs per worker in flight, writes each finished flight
(:class:`~tlm_process.generate.writer.DatasetWriter`) and shows progress. Flight ``i`` is a
pure function of the run seed, ``i`` and the settings, so the tables do not depend on the
executor, the worker count or the order flights finish in.

Re-running with the same settings continues a data set: flights the journal lists as ok are
skipped, failed ones are flown again. Ctrl-C stops handing out flights, lets the running ones
finish (a second Ctrl-C drops them), and closes the data set consistently. A Dask scheduler
that is gone, or silent for ``scheduler_grace_s`` while no flight finishes, stops the run the
same way and raises a one-line :class:`GenerateError`.

``target_fault_ratio`` (γ): λ = γ / α (:func:`tlm_process.pipeline.stretching.lambda_for_target`,
the paper's Eq. 5), with α the fault share of GPS rows measured on pilot flights (the first
``pilot_flights`` scenarios flown with λ = 1, nothing written), then corrected in up to
``pilot_rounds - 1`` more pilot rounds flown at the current λ (the share is not linear in λ:
an engine fault or the RC failsafe ends a mission early). λ and the rounds are stored in the
manifest and reused when the data set is continued.
"""

from __future__ import annotations

import concurrent.futures as cf
import difflib
import json
import math
import sys
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from tlm_process.cliutil import clear_folder
from tlm_process.generate.errors import ExecutorLost, GenerateError
from tlm_process.generate.executors import (
    ExecutorHandle,
    check_executor_options,
    local_kind,
    open_executor,
)
from tlm_process.generate.manifest import FORMAT, FORMAT_VERSION, HEADER, sim_fingerprint
from tlm_process.generate.scenario import ScenarioConfig, flight_conditions, sample_scenario
from tlm_process.generate.task import fly_job, make_job, peak_rss_mb
from tlm_process.generate.writer import DatasetWriter
from tlm_sim.faults.types import BUILTIN_TYPES
from tlm_sim.flight import END_NOT_ARMED, END_TIME_CAP
from tlm_sim.frames import FRAMES

__all__ = ["GenerateOptions", "GenerateReport", "generate"]

#: Jobs kept in flight per executor slot (the parent writes one while the workers fly).
JOBS_PER_SLOT = 2
#: How long running flights may take to finish after Ctrl-C [s].
DRAIN_TIMEOUT_S = 60.0
#: Most flights a data set can hold: part and block file names carry 8-digit flight numbers
#: (``flight-00000000.parquet`` .. ``flight-99999999.parquet``), so names sort by flight.
MAX_FLIGHTS = 10**8
#: On Dask, how often the wait for finished flights looks at the connection [s].
DASK_POLL_S = 1.0
#: Frames in table order (the report lists its counts so)
_FRAME_ORDER = {name: i for i, name in enumerate(FRAMES)}


@dataclass
class GenerateOptions:
    """Settings of a ``tlm generate`` run (see :func:`generate`)."""

    out: Path
    flights: int
    seed: int = 0
    config: ScenarioConfig = field(default_factory=ScenarioConfig)
    target_fault_ratio: float | None = None
    tables: Sequence[str] | None = None
    bin_log: bool = False
    executor: str = "auto"
    workers: int | None = None
    scheduler: str | None = None
    dask_local: int | None = None
    progress: bool | None = None
    pilot_flights: int = 16
    pilot_rounds: int = 3
    compact: bool = False
    connect_timeout_s: float = 10.0
    #: Dask: the run stops when no flight finished and the scheduler did not answer for this
    #: long [s] (``None``: ``connect_timeout_s``)
    scheduler_grace_s: float | None = None

    @property
    def grace_s(self) -> float:
        """How long a silent Dask scheduler counts as still there [s]."""
        return float(self.connect_timeout_s if self.scheduler_grace_s is None
                     else self.scheduler_grace_s)


@dataclass
class GenerateReport:
    """What a run did (all times wall-clock seconds unless named ``sim``)."""

    out: Path
    flights: int
    skipped: int = 0
    #: flights the data set holds: the most any run on it asked for (>= ``flights``)
    dataset_flights: int = 0
    ok: int = 0
    failed: int = 0
    interrupted: bool = False
    state: str = ""
    executor: str = ""
    slots: int = 0
    wall_s: float = 0.0
    sim_s: float = 0.0
    fly_s: float = 0.0
    encode_s: float = 0.0
    first_flight_s: float = 0.0
    bytes_written: int = 0
    lam: float = 1.0
    alpha_pilot: float | None = None
    target_fault_ratio: float | None = None
    gps_rows: int = 0
    gps_fault_rows: int = 0
    peak_rss_mb: dict[str, float] = field(default_factory=dict)
    parent_peak_rss_mb: float = 0.0
    restarts: int = 0
    compacted_parts: int = 0
    compact_s: float = 0.0
    errors: list[str] = field(default_factory=list)
    #: flights of this run (status ok) still armed at the simulator's time cap: cut off
    capped: list[int] = field(default_factory=list)
    not_armed: list[int] = field(default_factory=list)
    #: flights of this run (status ok) by frame name
    frames: dict[str, int] = field(default_factory=dict)
    #: flights of this run (status ok) in calm air (no wind, no turbulence) and in wind
    calm: int = 0
    windy: int = 0

    @property
    def ran(self) -> int:
        """Flights finished in this run (ok or failed)."""
        return self.ok + self.failed

    @property
    def flights_per_min(self) -> float:
        """Finished flights per wall-clock minute of this run."""
        return 60.0 * self.ran / self.wall_s if self.wall_s > 0 else math.nan

    @property
    def fault_share(self) -> float:
        """Share of GPS rows inside fault windows, flights of this run."""
        return self.gps_fault_rows / self.gps_rows if self.gps_rows else math.nan

    def lines(self) -> list[str]:
        """Human-readable summary."""
        out = [f"data set           {self.out} ({self.state})",
               f"flights            {self.ok} ok, {self.failed} failed this run"
               + (f", {self.skipped} already done" if self.skipped else "")
               + (" (interrupted: run the same command again to continue)"
                  if self.interrupted else "")]
        if self.dataset_flights > self.flights and self.state != "complete":
            out.append(f"note               an earlier run asked for {self.dataset_flights} "
                       f"flights: the data set is complete once flights 0.."
                       f"{self.dataset_flights - 1} are flown (--flights "
                       f"{self.dataset_flights})")
        if self.ran:
            rt = self.sim_s / self.wall_s if self.wall_s > 0 else math.nan
            out.append(f"wall time          {self.wall_s:.1f} s on {self.executor}: "
                       f"{self.flights_per_min:.0f} flights/min, {rt:.0f}x real time overall")
            if self.ok:
                out.append(f"per flight         {self.sim_s / self.ok:.0f} s simulated, "
                           f"fly {self.fly_s / self.ok:.3f} s + encode "
                           f"{self.encode_s / self.ok:.3f} s of worker time")
            out.append(f"written            {self.bytes_written / 1e6:.1f} MB")
            if self.peak_rss_mb:
                out.append(f"peak memory        {max(self.peak_rss_mb.values()):.0f} MB per "
                           f"worker process (largest of {len(self.peak_rss_mb)})")
        if self.compacted_parts:
            out.append(f"compacted          {self.compacted_parts} per-flight parts into block "
                       f"files in {self.compact_s:.1f} s")
        lam = f"lambda             {self.lam:g}"
        if self.alpha_pilot is not None:
            lam += f" (pilot fault share alpha {100 * self.alpha_pilot:.1f} %)"
        out.append(lam)
        if self.frames:
            frames = ", ".join(f"{n} {c}" for n, c in self.frames.items())
            out.append(f"frames, wind       {frames}; {self.calm} calm, {self.windy} windy")
        if self.gps_rows:
            target = ("" if self.target_fault_ratio is None
                      else f" (target {100 * self.target_fault_ratio:.1f} %)")
            out.append(f"fault share        {100 * self.fault_share:.1f} % of GPS rows{target}")
        if self.capped:
            shown, more, pl = _flight_list(self.capped)
            out.append(f"capped             {len(self.capped)} flight{pl} still armed at the "
                       f"time cap, cut off (flight{pl} {shown}{more}): see end_reason in "
                       "manifest.parquet")
        if self.not_armed:
            shown, more, pl = _flight_list(self.not_armed)
            out.append(f"not armed          {len(self.not_armed)} flight{pl} never armed: the "
                       f"pre-arm checks failed (flight{pl} {shown}{more}): see end_reason in "
                       "manifest.parquet and the Arm: texts")
        if self.restarts:
            out.append(f"worker pool        restarted {self.restarts} time(s): a worker process "
                       "died")
        out += [f"failed             {e}" for e in self.errors[:5]]
        if len(self.errors) > 5:
            out.append(f"                   ... {len(self.errors) - 5} more in the manifest")
        return out


def _check_tables(tables: Sequence[str] | None) -> list[str] | None:
    from tlm_sim.flightlog import LOGGED_MESSAGES

    if tables is None:
        return None
    out = []
    for t in tables:
        name = str(t).strip().upper()
        if name not in LOGGED_MESSAGES:
            close = difflib.get_close_matches(name, LOGGED_MESSAGES, n=1)
            hint = f" (did you mean {close[0]}?)" if close else ""
            raise GenerateError(f"--tables: tlm logs no table {t!r}{hint}; tables: "
                                f"{', '.join(LOGGED_MESSAGES)}")
        if name not in out:
            out.append(name)
    if not out:
        raise GenerateError("--tables: name at least one table")
    return sorted(out)


def _flight_list(flights: Iterable[int]) -> tuple[str, str, str]:
    """(the first ten flight numbers, ", ..." when there are more, the plural "s")."""
    fs = sorted(flights)
    return (", ".join(str(f) for f in fs[:10]), ", ..." if len(fs) > 10 else "",
            "s" if len(fs) > 1 else "")


def _open(opts: GenerateOptions) -> ExecutorHandle:
    return open_executor(opts.executor, opts.workers, scheduler=opts.scheduler,
                         dask_local=opts.dask_local, timeout_s=opts.connect_timeout_s)


def _check(opts: GenerateOptions) -> list[str] | None:
    for what, v, lo in (("--flights", opts.flights, 1), ("--seed", opts.seed, 0),
                        ("pilot flights", opts.pilot_flights, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < lo:
            raise GenerateError(f"{what} must be a whole number >= {lo}, got {v!r}")
    check_executor_options(opts.executor, opts.workers, scheduler=opts.scheduler,
                           dask_local=opts.dask_local)
    _check_registered_types(opts)
    if opts.flights > MAX_FLIGHTS:
        raise GenerateError(f"--flights must be at most {MAX_FLIGHTS:_} (file names hold "
                            f"8-digit flight numbers), got {opts.flights:_}")
    g = opts.target_fault_ratio
    if g is not None:
        if isinstance(g, bool) or not isinstance(g, int | float) or not 0 < g < 1:
            raise GenerateError(f"--target-fault-ratio must be a number in (0, 1), got {g!r}")
        if opts.config.lam != 1.0:
            raise GenerateError("give --lambda or --target-fault-ratio, not both")
    return _check_tables(opts.tables)


def _check_registered_types(opts: GenerateOptions) -> None:
    """GenerateError when the settings draw a fault type registered in this process (not a
    built-in one) and the flights would run in other processes (a process pool, Dask), whose
    fresh interpreters know the built-in types only."""
    extra = sorted(t for t in opts.config.drawn_types() if t not in BUILTIN_TYPES)
    if not extra:
        return
    local = opts.scheduler is None and opts.dask_local is None
    if local and local_kind(opts.executor, opts.workers) == "thread":
        return
    raise GenerateError(f"fault type {extra[0]!r} is registered in this process only, and "
                        "worker processes know the built-in types: run its flights on threads "
                        "(executor='thread', --executor thread)")


def _settings(opts: GenerateOptions, tables: list[str] | None) -> dict[str, Any]:
    scenario = opts.config.to_dict()
    lam = scenario.pop("lam")
    return {"scenario": scenario,
            "lambda": None if opts.target_fault_ratio is not None else lam,
            "target_fault_ratio": opts.target_fault_ratio,
            "tables": tables, "bin": bool(opts.bin_log)}


class _Run:
    """One run's loop: hand out jobs (``window`` in flight), collect results, pass them on.

    A worker process that dies breaks its whole pool (every job in it is lost, and which one
    killed it is unknown): the pool is restarted and the lost jobs are flown again one at a
    time, so a job that breaks the pool while flying alone is the culprit and is recorded as
    failed; the others come out as usual.

    On Dask, a job the client cancelled (it lost and regained the scheduler) is handed out
    again, and a scheduler that is gone, or has not answered while no flight finished for
    ``grace_s`` seconds, stops the run with :class:`ExecutorLost`."""

    def __init__(self, handle: ExecutorHandle, jobs: Iterator[dict[str, Any]], window: int,
                 on_result: Callable[[Mapping[str, Any]], None], grace_s: float = 10.0) -> None:
        self.handle = handle
        self.jobs = jobs
        self.window = max(1, window)
        self.on_result = on_result
        self.grace_s = grace_s
        self.pending: dict[cf.Future, tuple[int, dict[str, Any]]] = {}
        self.retry: deque[tuple[int, dict[str, Any]]] = deque()
        self.again: deque[tuple[int, dict[str, Any]]] = deque()
        self.exhausted = False
        self.draining = False
        self.heard_at = time.monotonic()  # when the executor last showed it works

    @property
    def busy(self) -> bool:
        """Jobs are handed out, waiting to be retried, or still to come."""
        return bool(self.pending or self.retry or self.again
                    or not (self.exhausted or self.draining))

    def _submit(self, job: dict[str, Any], tries: int) -> None:
        try:
            fut = self.handle.pool.submit(fly_job, job)
        except BrokenProcessPool:
            self._broken([])
            self.retry.appendleft((tries, job))
            return
        except Exception as exc:  # a Dask client that gave up on its scheduler
            if self.handle.kind != "dask":
                raise
            raise self.handle.mark_lost(f"{type(exc).__name__}: {exc}".splitlines()[0][:200]
                                        ) from None
        self.pending[fut] = (tries, job)

    def fill(self) -> None:
        """Hand out jobs up to the window (a retried job only when nothing else runs)."""
        while not self.draining:
            if self.again and len(self.pending) < self.window:
                tries, job = self.again.popleft()
                self._submit(job, tries)
                continue
            if self.retry:
                if not self.pending:
                    tries, job = self.retry.popleft()
                    self._submit(job, tries)
                return
            if self.exhausted or len(self.pending) >= self.window:
                return
            job = next(self.jobs, None)
            if job is None:
                self.exhausted = True
                return
            self._submit(job, 0)

    def step(self, timeout: float | None = None) -> int:
        """Fill, then wait up to ``timeout`` for finished jobs and pass their results on;
        returns how many finished."""
        self.fill()
        if not self.pending:
            return 0
        done = self._wait(timeout)
        n = 0
        for fut in sorted(done, key=lambda f: self.pending.get(f, (0, {"flight": -1}))[1][
                "flight"]):
            if fut not in self.pending:
                continue  # lost with a broken pool, already queued again
            tries, job = self.pending.pop(fut)
            if fut.cancelled():
                if not self.draining:  # not by us: Dask lost the scheduler for a while
                    self.again.append((tries, job))
                continue
            try:
                res = fut.result()
            except BrokenProcessPool:
                self._broken([(tries, job)])
                continue
            except Exception as exc:  # noqa: BLE001 - e.g. a Dask worker lost
                res = _failed(job, f"{type(exc).__name__}: {exc}".splitlines()[0][:500])
            self.on_result(_with_scenario(res, job))
            n += 1
        return n

    def _wait(self, timeout: float | None) -> set[cf.Future]:
        """The jobs that finish within ``timeout`` seconds (``None``: until one does). On Dask
        the wait is cut into :data:`DASK_POLL_S` slices and the scheduler checked after each
        empty one (:meth:`_check_scheduler`)."""
        if self.handle.kind != "dask":
            return cf.wait(list(self.pending), timeout=timeout,
                           return_when=cf.FIRST_COMPLETED)[0]
        end = None if timeout is None else time.monotonic() + timeout
        while True:
            left = DASK_POLL_S if end is None else min(DASK_POLL_S, end - time.monotonic())
            done = cf.wait(list(self.pending), timeout=max(0.0, left),
                           return_when=cf.FIRST_COMPLETED)[0]
            if done:
                self.heard_at = time.monotonic()
                return done
            self._check_scheduler()
            if end is not None and time.monotonic() >= end:
                return done

    def _check_scheduler(self) -> None:
        """Raise :class:`ExecutorLost` when the Dask client has closed (it gave up
        reconnecting), or when nothing was heard for ``grace_s`` and the scheduler does not
        answer within ``grace_s`` either."""
        if self.handle.kind != "dask":
            return
        status = getattr(self.handle._client, "status", "running")
        if status in ("closing", "closed"):
            raise self.handle.mark_lost("the client closed the connection")
        if time.monotonic() - self.heard_at < self.grace_s:
            return
        why = self.handle.unreachable(self.grace_s)
        if why is not None:
            raise self.handle.mark_lost(why)
        self.heard_at = time.monotonic()

    def _broken(self, first: list[tuple[int, dict[str, Any]]]) -> None:
        lost = first + list(self.pending.values())
        self.pending.clear()
        if self.draining:  # stopping anyway: the lost jobs stay missing, flown next run
            return
        self.handle.restart()
        for tries, job in sorted(lost, key=lambda x: x[1]["flight"]):
            if tries >= 1 and len(lost) == 1:  # it ran alone: it killed the worker
                res = _failed(job, "the worker process died while flying it")
                self.on_result(_with_scenario(res, job))
            else:
                self.retry.append((tries + 1, job))

    def stop(self) -> None:
        """Hand out nothing more and cancel the jobs that have not started."""
        self.draining = True
        self.retry.clear()
        self.again.clear()
        for fut in list(self.pending):
            if fut.cancel():
                self.pending.pop(fut)


def _failed(job: Mapping[str, Any], error: str) -> dict[str, Any]:
    """The result of a job that produced none (the executor raised)."""
    return {"flight": job["flight"], "status": "failed", "error": error, "traceback": None,
            "scenario": None, "summary": {}, "timing": {}, "parts": {}, "bin": None,
            "worker": None}


def _with_scenario(res: dict[str, Any], job: Mapping[str, Any]) -> dict[str, Any]:
    """A failed result without its scenario gets it here, so the manifest says what the
    flight was (unless drawing it fails here too)."""
    if res.get("status") != "ok" and res.get("scenario") is None:
        try:
            config = ScenarioConfig.from_dict(json.loads(job["config"]))
            res["scenario"] = sample_scenario(int(job["run_seed"]), int(job["flight"]),
                                              config).to_dict()
        except Exception:  # noqa: BLE001 - the recorded error is what counts
            pass
    return res


def _pilot_share(opts: GenerateOptions, handle: ExecutorHandle, lam: float,
                 progress: bool | None) -> float:
    """Fault share of GPS rows of the pilot flights (the first ``pilot_flights`` scenarios,
    nothing written) flown with window factor ``lam``.

    Stratified by flight kind: the mean fault rows and rows per flight of each kind are
    weighted by the kind's configured share (``ScenarioConfig.kinds``), so a pilot set whose
    mix of no-fault, single-fault and paper-style flights happens to differ from the
    configured one (16 flights draw it coarsely) does not bias the estimate. Falls back to
    the plain ratio when a kind with a share has no finished pilot flight."""
    k = opts.pilot_flights
    config = opts.config.with_lambda(lam)
    per_kind: dict[str, list[int]] = {}  # kind -> [fault rows, rows, flights]
    errors: list[str] = []

    def take(res: Mapping[str, Any]) -> None:
        if res.get("status") == "ok":
            acc = per_kind.setdefault(str((res.get("scenario") or {}).get("kind")), [0, 0, 0])
            acc[0] += int(res["summary"]["gps_fault_rows"])
            acc[1] += int(res["summary"]["gps_rows"])
            acc[2] += 1
        else:
            errors.append(f"flight {res['flight']}: {res.get('error')}")

    jobs = (make_job(i, opts.seed, config, tables=None, bin_log=False, pilot=True)
            for i in range(k))
    run = _Run(handle, jobs, JOBS_PER_SLOT * handle.slots, take, opts.grace_s)
    bar = _bar(k, f"pilot flights (lambda {lam:.3g})", progress)
    try:
        while run.busy:
            bar.update(run.step())
    finally:
        bar.close()
    fault_rows = sum(v[0] for v in per_kind.values())
    rows = sum(v[1] for v in per_kind.values())
    if rows == 0:
        why = f" ({errors[0]})" if errors else ""
        raise GenerateError(f"--target-fault-ratio: no pilot flight finished{why}")
    shares = {kind: p for kind, p in opts.config.kinds.items() if p > 0}
    if all(kind in per_kind for kind in shares):
        fault_rows = sum(p * per_kind[kd][0] / per_kind[kd][2] for kd, p in shares.items())
        rows = sum(p * per_kind[kd][1] / per_kind[kd][2] for kd, p in shares.items())
    return fault_rows / rows


#: a pilot round within this relative distance of the target share ends the search
PILOT_TOLERANCE = 0.02


def _next_lambda(points: Sequence[tuple[float, float]], gamma: float) -> float:
    """The window factor expected to give share ``gamma``, from the last two measured
    (lambda, share) points: the secant of log share over log lambda (share = c lambda^b; b = 1
    is Eq. 5), falling back to Eq. 5 from the last point when the slope is not usable."""
    (l1, s1), (l2, s2) = points[-2], points[-1]
    lam = l2 * gamma / s2 if s2 > 0 else l2 * 2.0
    if s1 > 0 and s2 > 0 and l1 != l2:
        b = math.log(s2 / s1) / math.log(l2 / l1)
        if math.isfinite(b) and b > 0.05:
            lam = l2 * (gamma / s2) ** (1.0 / b)
    return min(max(lam, l2 / 4.0), l2 * 4.0)


#: the longest stretch --target-fault-ratio may choose (Eq. 5's lambda)
MAX_LAMBDA = 10.0


def _pilot_lambda(opts: GenerateOptions, handle: ExecutorHandle, gamma: float,
                  progress: bool | None) -> tuple[float, float, list[tuple[float, float]]]:
    """λ for the target fault share γ from pilot flights (see the module docstring).

    Round 1 flies the pilots at λ = 1 and takes Eq. 5, λ = γ / α. Each further round (up to
    ``pilot_rounds``) flies them at the current λ and corrects it by the secant
    (:func:`_next_lambda`), because Eq. 5 assumes flights keep their length, which engine
    faults and the RC failsafe do not quite do. Returns (λ, α, [(λ, share) measured])."""
    from tlm_process.pipeline.stretching import lambda_for_target

    alpha = _pilot_share(opts, handle, 1.0, progress)
    if alpha <= 0:
        raise GenerateError("--target-fault-ratio: the pilot flights have no fault rows (do "
                            "the kinds give any faults?)")
    try:
        lam = lambda_for_target(alpha, gamma)
    except ValueError as exc:
        raise GenerateError(f"--target-fault-ratio: {exc}") from None
    points = [(1.0, alpha)]
    for _ in range(max(opts.pilot_rounds, 1) - 1):
        share = _pilot_share(opts, handle, lam, progress)
        points.append((lam, share))
        if abs(share - gamma) <= PILOT_TOLERANCE * gamma:
            break
        lam = _next_lambda(points, gamma)
    if lam > MAX_LAMBDA:
        raise GenerateError(
            f"--target-fault-ratio {gamma:g} needs lambda = {lam:.1f} (every fault held "
            f"{lam:.1f} times as long; the pilot flights' fault share is {alpha:.3f}), more "
            f"than the {MAX_LAMBDA:g} tlm allows: faults that long stop looking like the "
            f"paper's. Ask for at most about {alpha * MAX_LAMBDA:.2f}, or put more faults in "
            f"each flight (--kinds paper=1 / sequence=...)")
    return float(lam), float(alpha), points


def _bar(total: int, desc: str, progress: bool | None) -> Any:
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="flight", dynamic_ncols=True, smoothing=0.05,
                file=sys.stderr, disable=None if progress is None else not progress)


def generate(opts: GenerateOptions) -> GenerateReport:
    """Generate (or continue) the data set ``opts.out``; see the module docstring.

    With the default ``process`` executor, call it under ``if __name__ == "__main__":`` in a
    script: worker processes are started with ``spawn`` and import the main module.

    Raises:
        GenerateError: bad settings, an unwritable or foreign output folder, a data set made
            with other settings or another tlm, an unreachable Dask scheduler, or one lost
            during the run (raised after the data set was closed, state ``incomplete``).
    """
    t_start = time.perf_counter()
    tables = _check(opts)
    settings = _settings(opts, tables)
    wanted = {"format": FORMAT, "format_version": FORMAT_VERSION, **sim_fingerprint(),
              "seed": opts.seed, "flights": opts.flights, "settings": settings}
    # a Dask scheduler is reached before the data set is touched: one that cannot be reached
    # leaves no manifest behind to refuse the corrected command
    handle = _open(opts) if opts.scheduler is not None else None
    existed = Path(opts.out).exists()
    fresh = not existed or not (Path(opts.out) / HEADER).exists()
    writer = DatasetWriter(opts.out)
    try:
        status = writer.open(wanted)
    except BaseException:
        if handle is not None:
            handle.close(cancel=True)
        raise
    report = GenerateReport(Path(opts.out), opts.flights,
                            target_fault_ratio=opts.target_fault_ratio)
    done = {f for f, st in status.items() if st == "ok"}
    report.skipped = sum(1 for f in done if f < opts.flights)
    n_todo = opts.flights - report.skipped
    report.dataset_flights = int(writer.header.get("flights", opts.flights))
    lost: ExecutorLost | None = None
    failure: BaseException | None = None
    run_info: dict[str, Any] = {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    try:
        config = opts.config
        gamma = opts.target_fault_ratio
        need_pilot = gamma is not None and writer.header.get("lambda") is None
        if (n_todo or need_pilot) and handle is None:
            handle = _open(opts)
        if handle is not None:
            report.executor, report.slots = handle.description, handle.slots
            run_info.update(executor=handle.description, slots=handle.slots)
        if gamma is not None:
            if need_pilot:
                assert handle is not None
                lam, alpha, rounds = _pilot_lambda(opts, handle, gamma, opts.progress)
                writer.header["lambda"] = lam
                writer.header["pilot"] = {"flights": opts.pilot_flights, "alpha": alpha,
                                          "rounds": [list(p) for p in rounds]}
                report.alpha_pilot = alpha
            else:
                report.alpha_pilot = (writer.header.get("pilot") or {}).get("alpha")
            config = config.with_lambda(float(writer.header["lambda"]))
        else:
            writer.header["lambda"] = config.lam
        report.lam = config.lam
        if n_todo:
            assert handle is not None
            todo = (i for i in range(opts.flights) if i not in done)  # lazily: N may be large
            _fly_all(opts, handle, writer, report, config, tables, todo, n_todo, t_start)
    except KeyboardInterrupt:
        report.interrupted = True
    except ExecutorLost as exc:
        report.interrupted, lost = True, exc
        run_info["lost"] = str(exc)
    except BaseException as exc:
        failure = exc
        raise
    finally:
        try:
            if handle is not None:
                report.restarts = handle.restarts
                handle.close(cancel=True)
        finally:
            report.wall_s = time.perf_counter() - t_start
            report.parent_peak_rss_mb = peak_rss_mb()
            run_info.update(wall_s=round(report.wall_s, 3), ok=report.ok,
                            failed=report.failed, capped=len(report.capped),
                            interrupted=report.interrupted)
            report.state = _close(writer, run_info, failure or lost)
            if failure is not None and fresh and report.ok == 0 and report.failed == 0:
                _discard(Path(opts.out), existed)  # refused before any flight: leave nothing
    if lost is not None:
        raise GenerateError(f"{lost}; {writer.header.get('counts', {}).get('ok', report.ok)} of "
                            f"{opts.flights} flights written (data set {report.state}), run the "
                            "same command again to continue")
    if opts.compact and not report.interrupted:
        _compact(opts.out, writer, report)
    return report


def _discard(out: Path, existed: bool) -> None:
    """Remove a data set this run created and never wrote a flight to (a run refused after
    the folder was opened, e.g. an impossible --target-fault-ratio), so the corrected command
    is not refused as "made with other settings"; a folder that existed (empty) stays."""
    import shutil

    if not existed:
        shutil.rmtree(out, ignore_errors=True)
        return
    clear_folder(out, ignore_errors=True)


def _close(writer: DatasetWriter, run_info: Mapping[str, Any],
           failure: BaseException | None) -> str:
    """Close the data set (its manifest gets the counts and state); returns the state.

    Raises GenerateError when it cannot be closed: the message adds that to ``failure`` (a
    GenerateError already on its way, e.g. a full disk while writing a flight)."""
    try:
        return str(writer.close(run_info).get("state", ""))
    except GenerateError as exc:
        if isinstance(failure, GenerateError):
            raise GenerateError(f"{failure}; then: {exc}") from None
        raise


def _compact(out: Path, writer: DatasetWriter, report: GenerateReport) -> None:
    """``--compact``: merge the parts of the finished flights into block files."""
    from tlm_process.generate.compact import compact_dataset

    t0 = time.perf_counter()
    try:
        report.compacted_parts = compact_dataset(
            out, {f for f, st in writer.status.items() if st == "ok"})
    except OSError as exc:
        where = f" ({exc.filename})" if exc.filename else ""
        raise GenerateError(f"compacting {out} stopped: {exc.strerror or exc}{where}; the data "
                            "set is whole; free space and run the same command again to "
                            "finish compacting") from None
    report.compact_s = time.perf_counter() - t0


def _count_conditions(report: GenerateReport, scenario: Any) -> None:
    """Count a finished flight's frame and calm / windy air in the report."""
    if not isinstance(scenario, Mapping) or not isinstance(scenario.get("params"), Mapping):
        return
    cond = flight_conditions(scenario["params"])
    name = str(cond["frame"])
    report.frames = dict(sorted({**report.frames, name: report.frames.get(name, 0) + 1}.items(),
                                key=lambda kv: _FRAME_ORDER.get(kv[0], len(_FRAME_ORDER))))
    if cond["calm"]:
        report.calm += 1
    else:
        report.windy += 1


def _fly_all(opts: GenerateOptions, handle: ExecutorHandle, writer: DatasetWriter,
             report: GenerateReport, config: ScenarioConfig, tables: list[str] | None,
             todo: Iterable[int], n_todo: int, t_start: float) -> None:
    """Fly the ``n_todo`` flights ``todo`` and write them (the body of :func:`generate`)."""
    bar = _bar(n_todo, "flights", opts.progress)

    def take(res: Mapping[str, Any]) -> None:
        entry = writer.put(res)
        report.bytes_written += int(entry.get("bytes", 0))
        tm = res.get("timing") or {}
        if entry["status"] == "ok":
            report.ok += 1
            sm = res["summary"]
            report.sim_s += float(sm.get("duration_s", 0.0))
            report.gps_rows += int(sm.get("gps_rows", 0))
            report.gps_fault_rows += int(sm.get("gps_fault_rows", 0))
            report.fly_s += float(tm.get("fly_s", 0.0))
            report.encode_s += float(tm.get("encode_s", 0.0))
            if sm.get("end_reason") == END_TIME_CAP:
                report.capped.append(int(res["flight"]))
            elif sm.get("end_reason") == END_NOT_ARMED:
                report.not_armed.append(int(res["flight"]))
            _count_conditions(report, res.get("scenario"))
        else:
            report.failed += 1
            report.errors.append(f"flight {res['flight']}: {res.get('error')}")
            bar.set_postfix(failed=report.failed, refresh=False)
        if tm.get("first"):
            report.first_flight_s = max(report.first_flight_s, float(tm.get("total_s", 0.0)))
        w = res.get("worker")
        if w:
            key = f"{w.get('host')}:{w.get('pid')}"
            report.peak_rss_mb[key] = max(report.peak_rss_mb.get(key, 0.0),
                                          float(w.get("peak_rss_mb", 0.0)))
        bar.update(1)

    jobs = (make_job(i, opts.seed, config, tables=tables, bin_log=opts.bin_log) for i in todo)
    run = _Run(handle, jobs, JOBS_PER_SLOT * handle.slots, take, opts.grace_s)
    try:
        while run.busy:
            run.step()
    except KeyboardInterrupt:
        report.interrupted = True
        run.stop()
        bar.set_description("finishing running flights (Ctrl-C again to drop them)")
        deadline = time.perf_counter() + DRAIN_TIMEOUT_S
        try:
            while run.pending and time.perf_counter() < deadline:
                run.step(max(0.0, deadline - time.perf_counter()))
        except KeyboardInterrupt:
            pass
    finally:
        bar.close()
