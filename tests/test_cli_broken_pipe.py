"""``tlm ... | head``: a command whose stdout reader goes away ends quietly (no traceback),
with exit status 141 (128 + SIGPIPE), as ``tlm_process.cli.main`` documents."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import pytest

TLM = [sys.executable, "-m", "tlm_process.cli"]


def _run_into_closed_pipe(*argv: str) -> subprocess.CompletedProcess:
    """Run ``tlm ARGV`` with stdout a pipe whose reader has already gone."""
    r, w = os.pipe()
    os.close(r)
    try:
        return subprocess.run([*TLM, *argv], stdout=w, stderr=subprocess.PIPE, text=True,
                              timeout=120)
    finally:
        os.close(w)


def test_a_reader_that_stops_after_one_line_ends_tlm_quietly():
    """``tlm params | head -1``. tlm params writes ~170 kB in one write, more than a pipe
    holds; whether that write then fails depends on the kernel (one that takes a write
    blocked when the reader leaves as done reports nothing), so the exit status is 141 or 0,
    and stderr is empty either way."""
    p = subprocess.Popen([*TLM, "params"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    assert p.stdout.readline().startswith("NAME")
    p.stdout.close()
    err = p.stderr.read()
    p.stderr.close()
    assert p.wait(timeout=120) in (141, 0)
    assert err == ""


def test_stdout_closed_before_the_first_line():
    """The reader is gone before tlm writes: the first write fails on every kernel."""
    p = _run_into_closed_pipe("params")
    assert p.returncode == 141
    assert p.stderr == ""


@pytest.mark.parametrize("argv", [["--help"], ["evaluate", "--help"]])
def test_help_into_a_closed_pipe_is_quiet(argv):
    """argparse ignores a failed write of the help (exit 0); nothing may surface at exit."""
    p = _run_into_closed_pipe(*argv)
    assert p.returncode in (0, 141)
    assert p.stderr == ""


def test_evaluate_passes_a_closed_stdout_past_its_user_errors(monkeypatch):
    """tlm evaluate turns OSErrors into one-line user errors; a closed stdout is not one."""
    from tlm_process.commands import evaluate

    def closed(args):
        raise BrokenPipeError(32, "Broken pipe")

    monkeypatch.setattr(evaluate, "_run", closed)
    with pytest.raises(BrokenPipeError):
        evaluate.run(argparse.Namespace())
