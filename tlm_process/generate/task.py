"""The work of one flight, as an executor runs it: sample the scenario, fly, encode the parts.

:func:`fly_job` is a plain module-level function of a small JSON-like job, so any executor can
run it: a local process or thread pool, or a Dask worker (which needs tlm installed, nothing
else: the result carries the encoded Parquet parts back, so no shared file system is needed).
It never raises for a failing flight: the error comes back in the result (``status``
``"failed"``) and the run goes on.
"""

from __future__ import annotations

import json
import os
import resource
import socket
import time
import traceback
from collections.abc import Mapping
from functools import lru_cache
from typing import Any

import numpy as np

from tlm_process.generate.parts import fault_table, table_part, to_parquet_bytes
from tlm_process.generate.scenario import Scenario, ScenarioConfig, sample_scenario

__all__ = ["fly_job", "gps_fault_rows", "make_job", "peak_rss_mb"]

_FIRST = {"done": False}


def make_job(flight: int, run_seed: int, config: ScenarioConfig, *, tables: list[str] | None,
             bin_log: bool, pilot: bool = False) -> dict[str, Any]:
    """The job of flight ``flight``: everything :func:`fly_job` needs, as plain data.

    ``tables``: message tables to keep (None: all the flight logged); ``bin_log``: also encode
    the DataFlash ``.bin``; ``pilot``: fly only to measure the fault share (no parts)."""
    return {"flight": int(flight), "run_seed": int(run_seed),
            "config": json.dumps(config.to_dict(), sort_keys=True),
            "tables": None if tables is None else list(tables), "bin": bool(bin_log),
            "pilot": bool(pilot)}


@lru_cache(maxsize=8)
def _config(text: str) -> ScenarioConfig:
    return ScenarioConfig.from_dict(json.loads(text))


def gps_fault_rows(gps_time_us: np.ndarray, records: list[dict[str, Any]]) -> int:
    """GPS rows inside a fault window (start_time_us <= TimeUS < end_time_us of any record)."""
    inside = np.zeros(len(gps_time_us), dtype=bool)
    for r in records:
        t0, t1 = r.get("start_time_us"), r.get("end_time_us")
        if t0 is not None and t1 is not None:
            inside |= (gps_time_us >= t0) & (gps_time_us < t1)
    return int(inside.sum())


def peak_rss_mb() -> float:
    """Peak resident memory of this process [MB]: ``VmHWM`` (Linux; reset by exec, so a
    spawned worker does not inherit its parent's peak as ``ru_maxrss`` does), else
    ``ru_maxrss``."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _worker_info() -> dict[str, Any]:
    return {"host": socket.gethostname(), "pid": os.getpid(), "peak_rss_mb": peak_rss_mb(),
            "numba_cache": os.environ.get("NUMBA_CACHE_DIR")}


def fly_job(job: Mapping[str, Any]) -> dict[str, Any]:
    """Sample, fly and encode flight ``job["flight"]``; see the module docstring.

    Returns a dict: ``flight``, ``status`` ("ok" or "failed"), ``scenario`` (dict, None if
    sampling failed), ``error`` / ``traceback`` (failed), ``summary`` (simulated duration,
    waypoints, landing, why it ended (``end_reason``), fault types recorded, GPS rows and GPS
    rows in fault windows),
    ``timing`` (s: sample, fly, encode, total; ``first`` = the first job of this process, which
    pays numba's cache load or compile), ``parts`` (table name -> Parquet bytes, ``faults``
    included), ``bin`` (bytes or None), ``worker`` (host, pid, peak RSS, numba cache folder).
    """
    from tlm_sim import fly

    t0 = time.perf_counter()
    first = not _FIRST["done"]
    _FIRST["done"] = True
    flight = int(job["flight"])
    out: dict[str, Any] = {"flight": flight, "status": "failed", "scenario": None,
                           "error": None, "traceback": None, "summary": {}, "parts": {},
                           "bin": None}
    timing = {"sample_s": 0.0, "fly_s": 0.0, "encode_s": 0.0, "first": first}
    try:
        scenario: Scenario = sample_scenario(int(job["run_seed"]), flight, _config(job["config"]))
        out["scenario"] = scenario.to_dict()
        spec = scenario.realise()
        t1 = time.perf_counter()
        timing["sample_s"] = t1 - t0
        log = fly(spec.mission, faults=spec.schedule, params=spec.params, seed=spec.seed,
                  profile=spec.profile, sticks=spec.sticks)
        t2 = time.perf_counter()
        timing["fly_s"] = t2 - t1
        gps_t = log.columns("GPS")["TimeUS"] if log.n_rows("GPS") else np.zeros(0)
        out["summary"] = {
            "duration_s": float(log.meta["duration_s"]),
            "waypoints_reached": int(log.meta["waypoints_reached"]),
            "n_waypoints": int(log.meta["n_waypoints"]),
            "landed": bool(log.meta["landed"]),
            "final_mode": int(log.meta["final_mode"]),
            "end_reason": str(log.meta["end_reason"]),
            "faults": [r["type"] for r in log.faults],
            "gps_rows": len(gps_t),
            "gps_fault_rows": gps_fault_rows(gps_t, log.faults),
        }
        if not job.get("pilot"):
            wanted = job.get("tables")
            names = [n for n in log.tables if wanted is None or n in wanted]
            parts = {n: to_parquet_bytes(table_part(log.columns(n), log.schemas[n], flight))
                     for n in names if log.n_rows(n)}
            parts["faults"] = to_parquet_bytes(fault_table(log.faults, flight))
            out["parts"] = parts
            if job.get("bin"):
                from tlm_sim.flightlog.binwriter import encode_bin

                out["bin"] = encode_bin(log)
            out["summary"]["rows"] = {n: log.n_rows(n) for n in names}
        timing["encode_s"] = time.perf_counter() - t2
        out["status"] = "ok"
    except Exception as exc:  # noqa: BLE001 - a failed flight is recorded, the run goes on
        out["error"] = f"{type(exc).__name__}: {exc}".splitlines()[0][:500]
        out["traceback"] = "".join(traceback.format_exception(exc)[-6:])[-4000:]
        out["parts"], out["bin"] = {}, None
    timing["total_s"] = time.perf_counter() - t0
    out["timing"] = timing
    out["worker"] = _worker_info()
    return out
