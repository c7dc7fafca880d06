"""Where flights run: a local process or thread pool, or a Dask distributed cluster.

All three are ``concurrent.futures`` executors (Dask through ``Client.get_executor``), so the
generator submits, waits and cancels the same way whichever runs the flights:

* ``auto`` (default): ``thread`` for up to :data:`AUTO_THREADS_MAX` workers, ``process`` above.
  On a few cores threads are faster (no worker start-up, no result pickling; docs/generate.md
  has the measurements); part of a flight holds the GIL, so threads stop scaling at a few
  cores, where processes take over.
* ``process``: ``ProcessPoolExecutor`` with the ``spawn`` start method, one flight per
  task. Workers ignore SIGINT and SIGTERM (the parent handles both and lets running flights
  finish) and import tlm_sim on start (seconds of CPU), which points them at the same on-disk
  numba cache as the parent (``NUMBA_CACHE_DIR`` is inherited), so a worker loads the
  compiled flight instead of compiling it. A worker that dies (a crash in native code) does
  not stop the run. A worker whose parent dies (even by SIGKILL) exits within
  :data:`PARENT_POLL_S`, and with the last one the multiprocessing resource tracker, so a
  killed run leaves no process behind.
* ``thread``: ``ThreadPoolExecutor``; the flight loop is compiled with ``nogil=True``, but
  building the pandas tables, the fault records and the Arrow tables need the GIL.
* ``dask``: ``--scheduler tcp://HOST:PORT`` connects a ``distributed.Client`` to a running
  cluster; ``--dask-local N`` starts a ``LocalCluster`` of N single-threaded worker processes.
  Workers need tlm installed; results (the encoded Parquet parts) come back to this process,
  which writes them, so workers need no shared file system. LocalCluster workers exit by
  themselves when this process dies (Dask watches its parent). A scheduler that is gone is
  noticed by the generator (``ExecutorHandle.unreachable``), which stops the run.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import multiprocessing
import os
import signal
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from tlm_process.generate.errors import ExecutorLost, GenerateError

__all__ = ["AUTO_THREADS_MAX", "EXECUTORS", "ExecutorHandle", "check_executor_options",
           "local_kind", "open_executor"]

#: Local executor kinds.
EXECUTORS: tuple[str, ...] = ("auto", "process", "thread")
#: ``auto`` runs up to this many workers as threads, more as processes.
AUTO_THREADS_MAX = 4
#: How long closing the client of a lost Dask scheduler may take [s].
DASK_CLOSE_TIMEOUT_S = 2.0
#: The loggers quieted while a Dask client is open: the client logs its lost connection as
#: an error, its batched stream the closed connection with a traceback (seen once in a test).
QUIET_LOGGERS = ("distributed.client", "distributed.batched",
                 # the event loop's log of the client's gather that failed with the scheduler
                 # (CommClosedError "Stream is closed", seen when a scheduler was stopped)
                 "tornado.application")


#: How often a worker process checks that the process that started it is alive [s].
PARENT_POLL_S = 0.5


def _watch_parent(parent_pid: int, poll_s: float = PARENT_POLL_S) -> None:
    """Exit this process at once (``os._exit``) when ``parent_pid`` is no longer its parent.

    A dead parent's children are re-parented (to init or a subreaper), so ``os.getppid()``
    changes for good; this runs in a daemon thread and so also ends a worker whose main thread
    is flying, blocked writing a result to a pipe nobody reads, or waiting on a queue lock.
    """
    while os.getppid() == parent_pid:
        time.sleep(poll_s)
    os._exit(1)


def _init_process_worker(parent_pid: int) -> None:
    """Process pool initializer: exit when the parent ``parent_pid`` dies (even by SIGKILL,
    which leaves it no chance to stop us); Ctrl-C and SIGTERM are the parent's business (sent
    to the whole process group, they let the running flight finish); load tlm_sim once.
    """
    threading.Thread(target=_watch_parent, args=(parent_pid,), name="tlm-parent-watch",
                     daemon=True).start()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
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
    #: the Dask scheduler's address (``kind == "dask"``)
    address: str = ""
    #: why the executor is gone (set by :meth:`mark_lost`), else ``None``
    lost: str | None = None
    #: log levels to restore on close (loggers quieted while the executor is open)
    _log_levels: dict[str, int] = field(default_factory=dict)

    def restart(self) -> None:
        """A fresh process pool after a worker process died (BrokenProcessPool)."""
        if self.kind != "process":
            raise RuntimeError("only a process pool is restarted")
        self.pool.shutdown(wait=False, cancel_futures=True)
        self.pool = _process_pool(self._workers)
        self.restarts += 1

    def close(self, cancel: bool = False) -> None:
        """Shut the executor down; ``cancel`` drops flights not started yet. A Dask client
        whose scheduler is gone is closed without waiting for it (nothing is raised)."""
        try:
            if self.kind != "dask":
                self.pool.shutdown(wait=True, cancel_futures=cancel)
            elif self.lost is None:
                with contextlib.suppress(Exception):  # the scheduler may have just gone
                    self.pool.shutdown(wait=not cancel)
        finally:
            if self._client is not None:
                with contextlib.suppress(Exception):
                    if self.lost is None:
                        self._client.close()
                    else:
                        self._client.close(timeout=DASK_CLOSE_TIMEOUT_S)
            if self._cluster is not None:
                self._cluster.close()
            for name, level in self._log_levels.items():
                logging.getLogger(name).setLevel(level)
            self._log_levels.clear()

    def unreachable(self, timeout_s: float) -> str | None:
        """Why the Dask scheduler cannot run flights now, in a few words; ``None`` when it
        answers a (cheap) identity call within ``timeout_s`` seconds, or for local pools."""
        if self.kind != "dask" or self._client is None:
            return None
        client = self._client
        if client.status in ("closing", "closed"):
            return "the client closed the connection"
        try:
            client.sync(client.scheduler.identity, n_workers=0, callback_timeout=timeout_s)
        except TimeoutError:
            return f"no answer for {timeout_s:g} s"
        except Exception as exc:  # noqa: BLE001 - OSError, CommClosedError, ...
            if client.status in ("closing", "closed"):
                return "the client closed the connection"
            return f"unreachable: {exc}".splitlines()[0][:200]
        return None

    def mark_lost(self, why: str) -> ExecutorLost:
        """Remember the executor is gone (``close`` then waits for nothing) and return the
        error to raise: one line naming the scheduler and ``why``."""
        self.lost = why
        return ExecutorLost(f"lost the Dask scheduler at {self.address or '?'} ({why})")


def _process_pool(workers: int) -> cf.ProcessPoolExecutor:
    return cf.ProcessPoolExecutor(max_workers=workers,
                                  mp_context=multiprocessing.get_context("spawn"),
                                  initializer=_init_process_worker,
                                  initargs=(os.getpid(),))


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


def check_executor_options(kind: str = "auto", workers: int | None = None, *,
                           scheduler: str | None = None, dask_local: int | None = None) -> None:
    """Raise GenerateError for executor options that cannot work (exclusive options, an
    unknown executor, a worker count < 1, a scheduler address without host and port),
    without starting anything: ``tlm generate`` checks them before it writes a data set."""
    if scheduler is not None and dask_local is not None:
        raise GenerateError("--scheduler and --dask-local are exclusive")
    if dask_local is not None:
        _check_workers(dask_local, "--dask-local")
    if scheduler is not None:
        from urllib.parse import urlsplit

        text = str(scheduler)
        parts = urlsplit(text if "://" in text else "tcp://" + text)
        try:
            port = parts.port
        except ValueError:
            port = None
        if not parts.hostname or port is None:
            raise GenerateError(f"--scheduler {text!r}: give the address as tcp://HOST:PORT")
    if scheduler is None and dask_local is None:
        if kind not in EXECUTORS:
            raise GenerateError(f"unknown executor {kind!r}; choose from {', '.join(EXECUTORS)}")
        if workers is not None:
            _check_workers(workers, "--workers")


def local_kind(kind: str, workers: int | None) -> str:
    """``thread`` or ``process``: what a local executor ``kind`` (``auto`` resolved) with
    ``workers`` workers (None: all cores) runs flights in."""
    if kind not in EXECUTORS:
        raise GenerateError(f"unknown executor {kind!r}; choose from {', '.join(EXECUTORS)}")
    if kind == "auto":
        n = default_workers() if workers is None else workers
        return "thread" if n <= AUTO_THREADS_MAX else "process"
    return kind


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
    n = default_workers() if workers is None else _check_workers(workers, "--workers")
    kind = local_kind(kind, n)
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
    # a lost scheduler is reported by generate in one line; the client's own log of its
    # failed reconnection would come first, on stderr
    log_levels = {name: logging.getLogger(name).level for name in QUIET_LOGGERS}
    for name in QUIET_LOGGERS:
        logging.getLogger(name).setLevel(logging.CRITICAL)
    info = client.scheduler_info()
    workers = info.get("workers", {})
    slots = sum(int(w.get("nthreads", 1)) for w in workers.values()) or 1
    what = f"Dask LocalCluster ({len(workers)} workers)" if cluster is not None else (
        f"Dask cluster {scheduler} ({len(workers)} workers, {slots} threads)")
    return ExecutorHandle("dask", client.get_executor(pure=False), slots, what,
                          _client=client, _cluster=cluster, _workers=len(workers),
                          address=str(client.scheduler.address), _log_levels=log_levels)
