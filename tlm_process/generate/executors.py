"""Where flights run: a local process or thread pool, or a Dask distributed cluster.

All three are ``concurrent.futures`` executors (Dask through ``Client.get_executor``), so the
generator submits, waits and cancels the same way whichever runs the flights:

* ``auto`` (default): ``thread`` for up to :data:`AUTO_THREADS_MAX` workers, ``process`` above.
  On the project's 2-core machine threads were faster (no worker start-up, no result
  pickling: 0.20-0.22 CPU s per paper-style flight against 0.24, and 25-50 % more flights per
  minute in interleaved 300-flight runs); about a fifth of a flight holds the GIL, so threads
  stop scaling at a few cores, where processes take over.
* ``process``: ``ProcessPoolExecutor`` with the ``spawn`` start method, one flight per
  task. Workers ignore SIGINT (the parent handles Ctrl-C and lets running flights finish) and
  import tlm_sim on start (~2.6 s of CPU), which points them at the same on-disk numba cache as
  the parent (``NUMBA_CACHE_DIR`` is inherited), so a worker loads the compiled flight instead
  of compiling it. A worker that dies (a crash in native code) does not stop the run.
* ``thread``: ``ThreadPoolExecutor``; the flight loop is compiled with ``nogil=True``, but
  building the pandas tables, the fault records and the Arrow tables need the GIL.
* ``dask``: ``--scheduler tcp://HOST:PORT`` connects a ``distributed.Client`` to a running
  cluster; ``--dask-local N`` starts a ``LocalCluster`` of N single-threaded worker processes.
  Workers need tlm installed; results (the encoded Parquet parts) come back to this process,
  which writes them, so workers need no shared file system.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import os
import signal
from dataclasses import dataclass, field
from typing import Any

from tlm_process.generate.errors import GenerateError

__all__ = ["AUTO_THREADS_MAX", "EXECUTORS", "ExecutorHandle", "open_executor"]

#: Local executor kinds.
EXECUTORS: tuple[str, ...] = ("auto", "process", "thread")
#: ``auto`` runs up to this many workers as threads, more as processes.
AUTO_THREADS_MAX = 4


def _init_process_worker() -> None:
    """Process pool initializer: Ctrl-C is the parent's business; load tlm_sim once."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    import tlm_sim  # noqa: F401 - sets NUMBA_CACHE_DIR (inherited) and imports the jitted code


@dataclass
class ExecutorHandle:
    """A running executor: ``pool`` (a ``concurrent.futures.Executor``), a one-line
    ``description``, the number of flights it runs at once (``slots``) and how to close it."""

    kind: str
    pool: cf.Executor
    slots: int
    description: str
    _client: Any = None
    _cluster: Any = None
    _workers: int = 0
    restarts: int = field(default=0)

    def restart(self) -> None:
        """A fresh process pool after a worker process died (BrokenProcessPool)."""
        if self.kind != "process":
            raise RuntimeError("only a process pool is restarted")
        self.pool.shutdown(wait=False, cancel_futures=True)
        self.pool = _process_pool(self._workers)
        self.restarts += 1

    def close(self, cancel: bool = False) -> None:
        """Shut the executor down; ``cancel`` drops flights not started yet."""
        try:
            if self.kind == "dask":
                self.pool.shutdown(wait=not cancel)
            else:
                self.pool.shutdown(wait=True, cancel_futures=cancel)
        finally:
            if self._client is not None:
                self._client.close()
            if self._cluster is not None:
                self._cluster.close()


def _process_pool(workers: int) -> cf.ProcessPoolExecutor:
    return cf.ProcessPoolExecutor(max_workers=workers,
                                  mp_context=multiprocessing.get_context("spawn"),
                                  initializer=_init_process_worker)


def _check_workers(n: Any, what: str) -> int:
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise GenerateError(f"{what} must be a whole number >= 1, got {n!r}")
    return n


def default_workers() -> int:
    """All cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def open_executor(kind: str = "auto", workers: int | None = None, *,
                  scheduler: str | None = None, dask_local: int | None = None,
                  timeout_s: float = 10.0) -> ExecutorHandle:
    """Start the executor flights run on.

    Args:
        kind: ``auto``, ``process`` or ``thread`` (local); ignored when ``scheduler`` or
            ``dask_local`` is given.
        workers: local workers (default: all cores).
        scheduler: address of a running Dask scheduler (``tcp://HOST:PORT``).
        dask_local: start a Dask ``LocalCluster`` with this many single-threaded workers.
        timeout_s: how long to try to reach the scheduler.

    Raises:
        GenerateError: bad arguments, or the scheduler cannot be reached.
    """
    if scheduler is not None and dask_local is not None:
        raise GenerateError("--scheduler and --dask-local are exclusive")
    if scheduler is not None or dask_local is not None:
        return _open_dask(scheduler, dask_local, timeout_s)
    if kind not in EXECUTORS:
        raise GenerateError(f"unknown executor {kind!r}; choose from {', '.join(EXECUTORS)}")
    n = default_workers() if workers is None else _check_workers(workers, "--workers")
    if kind == "auto":
        kind = "thread" if n <= AUTO_THREADS_MAX else "process"
    if kind == "process":
        return ExecutorHandle("process", _process_pool(n), n, f"{n} local processes",
                              _workers=n)
    pool = cf.ThreadPoolExecutor(max_workers=n, thread_name_prefix="tlm-flight")
    return ExecutorHandle("thread", pool, n, f"{n} local threads", _workers=n)


def _open_dask(scheduler: str | None, dask_local: int | None,
               timeout_s: float) -> ExecutorHandle:
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - a dependency of tlm
        raise GenerateError("Dask is not installed: pip install 'dask[distributed]'") from None
    import tlm_sim  # noqa: F401 - NUMBA_CACHE_DIR is set before local workers start

    cluster = None
    try:
        if dask_local is not None:
            n = _check_workers(dask_local, "--dask-local")
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            client = Client(cluster, timeout=f"{timeout_s}s")
        else:
            assert scheduler is not None
            client = Client(scheduler, timeout=f"{timeout_s}s")
    except GenerateError:
        raise
    except (OSError, TimeoutError, ValueError) as exc:
        if cluster is not None:
            cluster.close()
        where = f"the Dask scheduler at {scheduler}" if scheduler else "a Dask LocalCluster"
        raise GenerateError(f"cannot reach {where}: {exc}") from None
    info = client.scheduler_info()
    workers = info.get("workers", {})
    slots = sum(int(w.get("nthreads", 1)) for w in workers.values()) or 1
    what = f"Dask LocalCluster ({len(workers)} workers)" if cluster is not None else (
        f"Dask cluster {scheduler} ({len(workers)} workers, {slots} threads)")
    return ExecutorHandle("dask", client.get_executor(pure=False), slots, what,
                          _client=client, _cluster=cluster, _workers=len(workers))
