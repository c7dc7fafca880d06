"""``tlm generate`` under hostile conditions: the parent SIGKILLed (no worker process may stay
behind), SIGTERM (stops like Ctrl-C), and a Dask scheduler that dies or stops answering (the
run stops with one line and a resumable data set). Every interrupted data set is then
continued and must hold the same bytes as one made in a single run.

The command runs as a subprocess in its own session, so every process it starts (workers,
the multiprocessing resource tracker, Dask workers) shares its session id; a test looks for
processes of that session in /proc and kills stragglers, so a failing test leaves none.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

from tests.test_generate import SEED, SHORT, _parts
from tlm_process.generate import GenerateError, GenerateOptions, generate, read_header, runner
from tlm_process.generate.executors import ExecutorHandle

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

FLIGHTS = 12
#: ``--connect-timeout`` against a real scheduler [s]: short, so a lost scheduler is noticed
#: quickly, but long enough for a scheduler short of CPU on a loaded 2-core machine (a worker
#: loading or compiling, the other test process flying): with 2 s, one CI run's ``tlm
#: generate`` gave up before its first flight
CONNECT_TIMEOUT_S = 6
TLM = [sys.executable, "-c", "import sys; from tlm_process.cli import main; sys.exit(main())"]


def _gen(out: Path, n: int = FLIGHTS, **kw) -> object:
    opts = {"executor": "thread", "workers": 2, **kw}
    return generate(GenerateOptions(out=out, flights=n, seed=SEED, config=SHORT, progress=False,
                                    **opts))


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> dict[str, bytes]:
    """The parts of FLIGHTS flights written in one uninterrupted run."""
    ds = tmp_path_factory.mktemp("ref") / "ds"
    rep = _gen(ds)
    assert rep.state == "complete"
    return _parts(ds)


@pytest.fixture(scope="module")
def config_file(tmp_path_factory) -> Path:
    """SHORT as a ``--config`` file."""
    path = tmp_path_factory.mktemp("cfg") / "short.json"
    path.write_text(json.dumps(SHORT.to_dict()))
    return path


def _command(out: Path, config: Path, *extra: str) -> list[str]:
    return [*TLM, "generate", "--flights", str(FLIGHTS), "--seed", str(SEED), "--out", str(out),
            "--config", str(config), "--no-progress", *extra]


def _session(sid: int) -> list[int]:
    """Live (not zombie) processes of session ``sid``."""
    pids = []
    for name in os.listdir("/proc"):
        if not name.isdigit():
            continue
        try:
            if os.getsid(int(name)) != sid:
                continue
            state = Path(f"/proc/{name}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue  # gone meanwhile
        if state != "Z":
            pids.append(int(name))
    return pids


def _left_after(sid: int, deadline_s: float) -> list[int]:
    """Processes of session ``sid`` still alive after up to ``deadline_s`` seconds."""
    end = time.monotonic() + deadline_s
    while (left := _session(sid)) and time.monotonic() < end:
        time.sleep(0.2)
    return left


def _kill_session(sid: int) -> None:
    for pid in _session(sid):
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass


def _wait_for_flights(out: Path, proc: subprocess.Popen, n: int = 1,
                      timeout_s: float = 180.0) -> None:
    """Until the journal lists ``n`` flights (workers are flying), or fail."""
    journal = out / "flights.jsonl"
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if journal.exists() and journal.read_text().count("\n") >= n:
            return
        if proc.poll() is not None:
            err = proc.stderr.read() if proc.stderr is not None else ""
            pytest.fail(f"tlm generate ended early ({proc.returncode}): {err[-2000:]}")
        time.sleep(0.1)
    pytest.fail(f"no flight in the journal after {timeout_s} s")


@pytest.mark.parametrize("executor", [["--executor", "process", "--workers", "2"],
                                      ["--dask-local", "2"]], ids=["process", "dask-local"])
def test_sigkill_leaves_no_process_and_the_data_set_resumes(reference, config_file, tmp_path,
                                                            executor):
    out = tmp_path / "ds"
    cmd = _command(out, config_file, *executor)
    proc = subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    try:
        _wait_for_flights(out, proc)
        assert len(_session(proc.pid)) >= 3  # the parent and its workers
        proc.kill()
        proc.wait()
        left = _left_after(proc.pid, 15.0)
        assert not left, "left behind: " + "; ".join(
            Path(f"/proc/{p}/cmdline").read_text().replace("\0", " ")[:120] for p in left)
    finally:
        proc.kill()
        proc.wait()
        _kill_session(proc.pid)
    assert read_header(out)["state"] == "running"  # nobody closed it
    if executor[0] == "--executor":  # the same command continues it
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
    else:
        _gen(out)
    assert read_header(out)["state"] == "complete"
    assert _parts(out) == reference


def test_sigterm_to_the_process_group_stops_like_ctrl_c(reference, config_file, tmp_path):
    """As ``timeout`` or systemd send it: to the parent and its workers at once."""
    out = tmp_path / "ds"
    proc = subprocess.Popen(_command(out, config_file, "--executor", "process", "--workers", "2"),
                            start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        _wait_for_flights(out, proc)
        os.killpg(proc.pid, signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=120)
        assert not _left_after(proc.pid, 15.0)
    finally:
        proc.kill()
        proc.communicate()
        _kill_session(proc.pid)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "Error" not in stderr, stderr
    assert "interrupted: run the same command again to continue" in stdout
    assert "restarted" not in stdout  # the workers let their flights finish
    header = read_header(out)
    assert header["state"] == "incomplete" and header["runs"][-1]["interrupted"]
    _gen(out)
    assert _parts(out) == reference


class _StallingPool(cf.Executor):
    """Runs the first ``ok`` jobs on threads; every later one never finishes."""

    def __init__(self, ok: int) -> None:
        self.inner = cf.ThreadPoolExecutor(ok)
        self.ok = ok
        self.futures: list[cf.Future] = []

    def submit(self, fn, /, *args, **kwargs) -> cf.Future:
        if len(self.futures) < self.ok:
            fut = self.inner.submit(fn, *args, **kwargs)
        else:
            fut = cf.Future()
        self.futures.append(fut)
        return fut

    @property
    def gone(self) -> bool:
        """The scheduler is gone once the jobs that finish have finished."""
        return len(self.futures) > self.ok and all(f.done() for f in self.futures[:self.ok])

    def shutdown(self, wait: bool = True, **kwargs) -> None:
        raise AssertionError("a lost scheduler's executor is not shut down (it would hang)")


class _DisconnectedClient:
    """A distributed.Client whose scheduler stops answering when ``pool.gone``."""

    def __init__(self, pool: _StallingPool) -> None:
        self.pool = pool
        self.scheduler = SimpleNamespace(identity=None, address="tcp://10.9.8.7:8786")
        self.closed_with: list[object] = []

    @property
    def status(self) -> str:
        return "connecting" if self.pool.gone else "running"

    def sync(self, func, *args, callback_timeout=None, **kwargs) -> dict:
        assert callback_timeout is not None  # the probe itself cannot hang
        if self.pool.gone:
            raise OSError("Timed out trying to connect to tcp://10.9.8.7:8786")
        return {}

    def close(self, timeout=None) -> None:
        self.closed_with.append(timeout)


def test_a_lost_dask_scheduler_stops_the_run_with_one_line(reference, tmp_path, monkeypatch):
    pool = _StallingPool(ok=2)
    client = _DisconnectedClient(pool)
    handle = ExecutorHandle("dask", pool, 2, "fake Dask cluster", _client=client,
                            address=client.scheduler.address)
    monkeypatch.setattr(runner, "open_executor", lambda *a, **k: handle)
    monkeypatch.setattr(runner, "DASK_POLL_S", 0.05)
    out = tmp_path / "ds"
    t0 = time.monotonic()
    with pytest.raises(GenerateError) as err:
        _gen(out, n=6, scheduler_grace_s=0.3)
    assert time.monotonic() - t0 < 30
    msg = str(err.value)
    assert "\n" not in msg
    assert msg.startswith("lost the Dask scheduler at tcp://10.9.8.7:8786 (unreachable: ")
    assert msg.endswith("; 2 of 6 flights written (data set incomplete), run the same command "
                        "again to continue")
    assert client.closed_with and client.closed_with[0] is not None  # closed, not waited on
    pool.inner.shutdown()
    header = read_header(out)
    assert header["state"] == "incomplete" and header["counts"]["ok"] == 2
    assert header["runs"][-1]["lost"].startswith("lost the Dask scheduler")
    monkeypatch.undo()
    _gen(out, n=6)  # continued on another executor
    assert read_header(out)["state"] == "complete"
    assert _parts(out) == {k: v for k, v in reference.items()
                           if int(k.split("flight-")[1][:8]) < 6}


@pytest.mark.parametrize("how", ["killed", "stopped"])
def test_a_real_scheduler_that_dies_or_hangs_stops_the_run(reference, config_file, tmp_path,
                                                           how):
    """A scheduler and one worker in subprocesses; the scheduler is SIGKILLed (its
    connections close) or SIGSTOPped (they stay open and nothing answers: the old hang)."""
    sched_file = tmp_path / "scheduler.json"
    py = sys.executable
    sched = subprocess.Popen([py, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                              "--port", "0", "--no-dashboard", "--scheduler-file",
                              str(sched_file)], start_new_session=True,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    procs = [sched]
    out = tmp_path / "ds"
    try:
        end = time.monotonic() + 60
        while not sched_file.exists() or not sched_file.read_text().strip():
            assert time.monotonic() < end and sched.poll() is None, "no scheduler"
            time.sleep(0.1)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen(
            [py, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
             "--no-nanny", "--no-dashboard"], start_new_session=True,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        gen = subprocess.Popen(_command(out, config_file, "--scheduler", address,
                                        "--connect-timeout", str(CONNECT_TIMEOUT_S)),
                               start_new_session=True, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
        procs.append(gen)
        _wait_for_flights(out, gen)
        sched.send_signal(signal.SIGKILL if how == "killed" else signal.SIGSTOP)
        t0 = time.monotonic()
        stdout, stderr = gen.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        for p in procs:
            p.kill()
            p.wait()
            _kill_session(p.pid)
    assert gen.returncode == 2, stderr
    assert took < 4 * CONNECT_TIMEOUT_S  # silent for one timeout, no answer within another
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith(f"tlm: error: lost the Dask scheduler at {address} (")
    assert lines[0].endswith("run the same command again to continue")
    assert read_header(out)["state"] == "incomplete"
    _gen(out)
    assert _parts(out) == reference
