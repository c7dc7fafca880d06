"""The parallel cold compile (tlm_sim.precompile): its plan matches the flight, and it works."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tlm_sim import precompile as P

REPO = Path(__file__).resolve().parents[1]


def test_every_job_signature_is_the_one_the_flight_compiled(normal_flight):
    """A stale job signature would compile an unused variant in a worker and leave the real one
    to the serial compile: each job's signature must be in its function's cache as flown."""
    assert normal_flight.meta["duration_s"] > 0
    for job in (*P.JOBS, P.RUN_FLIGHT):
        disp = P.job_dispatcher(job)
        if tuple(job.args) in disp.overloads:
            continue
        assert disp._cache.load_overload(job.args, disp.targetctx) is not None, job.target


def test_jobs_are_the_run_flight_callees_and_distinct():
    targets = [j.target for j in P.JOBS]
    assert len(set(targets)) == len(targets)
    assert P.RUN_FLIGHT.target not in targets
    for job in P.JOBS:
        assert job.cost_s > 0
        assert callable(P.job_dispatcher(job).py_func)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 8])
def test_share_out_gives_each_job_to_one_process_and_balances(n):
    shares = P.share_out(P.JOBS, n)
    assert len(shares) == n
    flat = [j.target for s in shares for j in s]
    assert sorted(flat) == sorted(j.target for j in P.JOBS)
    loads = [sum(j.cost_s for j in s) + (P.WORKER_START_S if k else 0.0)
             for k, s in enumerate(shares)]
    biggest = max(j.cost_s for j in P.JOBS)
    # longest-processing-time rule: no process ends more than the biggest job after another
    assert max(loads) - min(loads) <= biggest + P.WORKER_START_S
    if n == 1:
        assert len(shares[0]) == len(P.JOBS)


def test_n_procs_from_environment(monkeypatch):
    monkeypatch.setenv("TLM_COMPILE_PROCS", "3")
    assert P._n_procs() == 3
    monkeypatch.setenv("TLM_COMPILE_PROCS", "0")
    assert P._n_procs() == 1
    monkeypatch.setenv("TLM_COMPILE_PROCS", "many")
    assert P._n_procs() == 1
    monkeypatch.delenv("TLM_COMPILE_PROCS")
    assert 1 <= P._n_procs() <= P.MAX_PROCS


class _FakeWorker:
    """Stands in for a worker process: records its jobs, exits with ``rc``."""

    def __init__(self, jobs, rc):
        self.jobs = [j.target for j in jobs]
        self.returncode = rc

    def communicate(self, timeout=None):
        return b"", b"boom" if self.returncode else b""

    def poll(self):
        return self.returncode


@pytest.mark.parametrize("rc", [0, 1])
def test_precompile_shares_jobs_and_compiles_run_flight_last(monkeypatch, caplog, rc):
    compiled: list[str] = []
    started: list[_FakeWorker] = []
    monkeypatch.setattr(P, "_is_cached", lambda job: False)
    monkeypatch.setattr(P, "_compile", lambda job: compiled.append(job.target))

    def start(jobs):
        started.append(_FakeWorker(jobs, rc))
        return started[-1]

    monkeypatch.setattr(P, "_start_worker", start)
    with caplog.at_level("INFO", logger="tlm_sim.precompile"):
        rep = P.precompile(3)
    assert rep.processes == 3 and len(started) == 2
    assert compiled[-1] == P.RUN_FLIGHT.target
    assert sorted(compiled[:-1] + [t for w in started for t in w.jobs]) == sorted(
        j.target for j in P.JOBS)
    assert rep.worker_failures == (2 if rc else 0)
    assert "compiling the flight loop" in caplog.text
    assert ("precompile worker failed" in caplog.text) == bool(rc)


def test_precompile_without_subprocesses_compiles_everything_here(monkeypatch):
    compiled: list[str] = []
    monkeypatch.setattr(P, "_is_cached", lambda job: False)
    monkeypatch.setattr(P, "_compile", lambda job: compiled.append(job.target))

    def start(jobs):
        raise OSError("no fork here")

    monkeypatch.setattr(P, "_start_worker", start)
    rep = P.precompile(2)
    assert rep.processes == 1
    assert sorted(compiled) == sorted([j.target for j in P.JOBS] + [P.RUN_FLIGHT.target])


def test_precompile_loads_a_cached_flight(monkeypatch):
    compiled: list[str] = []
    monkeypatch.setattr(P, "_is_cached", lambda job: True)
    monkeypatch.setattr(P, "_compile", lambda job: compiled.append(job.target))
    rep = P.precompile(4)
    assert rep.skipped == "cached" and compiled == []


#: the main loop's sensor reads (``tlm_sim.flight._read_sensors``) with the signature
#: ``run_flight`` calls them with, and the jobs below them: a real subtree of the flight that
#: compiles in seconds, so the two-process cold compile runs end to end in every test run
#: (the whole flight's takes minutes of CPU, and each cold CI run does it anyway in its first
#: flight)
_COLD = """
import json
from numba import types as nt
from tlm_sim import precompile as P
F1, F2, I1 = nt.float64[::1], nt.float64[:, ::1], nt.int64[::1]
SUBTREE = ("imu_take_deltas", "gps_push_truth", "gps_measure", "baro_read", "mag_sample")
P.JOBS = tuple(j for j in P.JOBS if j.target.split(":")[1] in SUBTREE)
assert len(P.JOBS) == len(SUBTREE)
P.RUN_FLIGHT = P.Job("tlm_sim.flight:_read_sensors",
                     (P._STATE, F1, P._WORK, nt.int64, P._EV), 1.0)
rep = P.precompile(2)
again = P.precompile(2)
hits = {j.target: sum(P.job_dispatcher(j).stats.cache_hits.values()) for j in P.JOBS}
print(json.dumps({"processes": rep.processes, "misses": rep.misses,
                  "failures": rep.worker_failures, "shares": rep.shares, "hits": hits,
                  "again": again.skipped,
                  "root": len(P.job_dispatcher(P.RUN_FLIGHT).signatures)}))
"""


def test_cold_compile_in_two_processes_loads_the_workers_share(tmp_path):
    """On an empty cache, a worker process compiles its share of a subtree of the flight and
    this process, compiling the subtree's root, loads the worker's functions from the cache
    (a cache hit, no miss for any of them); a second call finds the root cached."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
           "PYTHONPATH": os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH"))
                                         if p)}
    out = subprocess.run([sys.executable, "-c", _COLD], env=env, capture_output=True, text=True,
                         timeout=600, check=False)
    assert out.returncode == 0, out.stderr[-3000:]
    rep = json.loads(out.stdout.strip().splitlines()[-1])
    assert rep["processes"] == 2
    assert rep["failures"] == 0
    assert rep["misses"] == []
    assert rep["shares"][1], "the worker got no jobs"
    assert all(rep["hits"][t] >= 1 for t in rep["shares"][1])  # loaded, not compiled here
    assert rep["again"] == "cached"
    assert rep["root"] == 1
