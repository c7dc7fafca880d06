"""benchmarks/profile_compile.py: its phase clock charges time exclusively, and every phase it
wraps exists in the installed numba."""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path

import pytest

_PATH = Path(__file__).resolve().parents[1] / "benchmarks" / "profile_compile.py"


@pytest.fixture(scope="module")
def pc():
    spec = importlib.util.spec_from_file_location("profile_compile", _PATH)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _spin(seconds: float) -> None:
    t0 = time.process_time()
    while time.process_time() - t0 < seconds:
        pass


def test_every_phase_resolves(pc):
    for _, target in pc.PHASES:
        cls, meth = pc.resolve(target)
        assert callable(getattr(cls, meth))


def test_nested_phases_are_charged_exclusively(pc):
    class Compiler:
        def outer(self):
            _spin(0.05)
            self.inner()
            _spin(0.05)

        def inner(self):
            _spin(0.1)

    clock = pc.PhaseClock()
    clock.wrap_method("outer", Compiler, "outer")
    clock.wrap_method("inner", Compiler, "inner")
    Compiler().outer()
    clock.switch()
    assert clock.total["inner"] == pytest.approx(0.1, abs=0.03)
    assert clock.total["outer"] == pytest.approx(0.1, abs=0.03)
