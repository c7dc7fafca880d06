"""tlm_sim._jit: the fast build (loop entries keep their callees' code private to their own
module), the plain build (public numba options only) and the choice between them."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from llvmlite import binding as ll
from numba import config

from tlm_sim import _jit, fly
from tlm_sim._jit import loop_jit, tick_jit

pytestmark = pytest.mark.skipif(config.DISABLE_JIT, reason="needs numba's compiler")
fast_only = pytest.mark.skipif(_jit.MODE != "fast", reason="tests the fast build")


@tick_jit
def _bump(a, i, by):
    a[i] += by


@fast_only
def test_loop_library_makes_linked_callees_private_and_keeps_its_own_exported():
    from tlm_sim._jit_fast import LoopLibrary

    def loop(a, n):
        for _ in range(n):
            _bump(a, 0, 1.0)
            _bump(a, 1, 2.0)
        return a[0]

    entry = loop_jit(loop, cache=False)
    a = np.zeros(2)
    assert entry(a, 3) == 3.0
    assert a[1] == 6.0
    (cres,) = entry.overloads.values()
    lib = cres.library
    assert isinstance(lib, LoopLibrary)
    (bump,) = _bump.overloads.values()
    assert bump.fndesc.llvm_func_name in lib.privatized
    own = {cres.fndesc.llvm_func_name, cres.fndesc.llvm_cpython_wrapper_name}
    assert own <= lib._own_functions
    assert not own & set(lib.privatized)
    for f in lib._final_module.functions:  # what LLVM left of the callees stays private
        if not f.is_declaration and f.name not in own:
            assert f.linkage == ll.Linkage.private, f.name
    # the callee called directly still runs its own exported code
    _bump(a, 0, 5.0)
    assert a[0] == 8.0


def test_callees_of_the_flight_loop_run_when_called_directly_after_a_flight():
    """Regression: with internal (not private) copies, a process that loaded the flight loop
    from the cache and then called one of its callees directly got the loop module's copy,
    whose arguments LLVM had changed (SystemError or a crash)."""
    fly(1, seed=0)  # the flight loop is in the cache
    script = textwrap.dedent("""
        import numpy as np
        from tlm_sim import fly
        fly(1, seed=0)  # run_flight from the cache, before any callee's own library
        from tlm_sim.control import layout as C
        from tlm_sim.control.config import build_control_config
        from tlm_sim.control.wpnav import PATH_COLS, path_start, path_update, prepare_path
        from tlm_sim.params import Params
        g = build_control_config(Params())
        path = np.zeros((2, PATH_COLS))
        path[:, :3] = [(0.0, 0.0, -20.0), (30.0, 0.0, -20.0)]
        prepare_path(path, 2, g)
        c = np.zeros(C.N_CONTROL_STATE)
        path_start(c)
        pos = path[0, :3].copy()
        c[C.PXY_POS_T], c[C.PXY_POS_T + 1], c[C.PZ_POS_T] = pos
        done = False
        while not done:  # a perfectly tracking vehicle flies the path to its end
            vel = np.array([c[C.PXY_VEL_FF], c[C.PXY_VEL_FF + 1], c[C.PZ_VEL_FF]])
            _, done = path_update(c, g, path, 2, (pos, vel), 0.0, True)
            pos[:] = c[C.PXY_POS_T], c[C.PXY_POS_T + 1], c[C.PZ_POS_T]
        print(pos[0])
    """)
    for _ in range(2):  # the first run caches the callees' own code, the second loads it
        out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                             timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        assert float(out.stdout.split()[-1]) == pytest.approx(30.0, abs=0.02)


def _run(script: str, **env: str) -> subprocess.CompletedProcess:
    import os

    full = {k: v for k, v in os.environ.items() if k not in ("TLM_JIT", "NUMBA_CACHE_DIR")}
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True,
                          text=True, timeout=600, env={**full, **env})


def test_plain_build_flies_the_same_flight_as_the_fast_build():
    """TLM_JIT=plain: every function is a public numba.njit, its cache is its own, and it flies
    the model the fast build flies (not bit for bit: LLVM inlines, and so fuses multiply-adds,
    differently)."""
    out = _run("""
        import json, numba, tlm_sim
        from tlm_sim import _jit
        from tlm_sim.flight import run_flight
        from tlm_sim.dynamics.body import physics_step
        log = tlm_sim.fly(1, seed=3)
        pos = log.tables["POS"]
        print(json.dumps({"mode": _jit.MODE, "cache": __import__("os").environ["NUMBA_CACHE_DIR"],
                          "plain": all(type(f) is numba.core.registry.CPUDispatcher
                                       for f in (run_flight, physics_step)),
                          "meta": {k: log.meta[k] for k in ("duration_s", "waypoints_reached",
                                                            "landed")},
                          "end": [float(pos["Lat"].iloc[-1]), float(pos["Lng"].iloc[-1])]}))
    """, TLM_JIT="plain")
    assert out.returncode == 0, out.stderr[-3000:]
    import json

    got = json.loads(out.stdout.splitlines()[-1])
    assert got["mode"] == "plain" and got["plain"]
    assert got["cache"].endswith("-plain")
    ref = fly(1, seed=3)
    assert got["meta"]["waypoints_reached"] == ref.meta["waypoints_reached"]
    assert got["meta"]["landed"] == ref.meta["landed"]
    assert got["meta"]["duration_s"] == pytest.approx(ref.meta["duration_s"], abs=0.5)
    pos = ref.tables["POS"]
    assert got["end"][0] == pytest.approx(float(pos["Lat"].iloc[-1]), abs=2e-6)  # ~0.2 m
    assert got["end"][1] == pytest.approx(float(pos["Lng"].iloc[-1]), abs=2e-6)


def test_a_numba_without_a_private_internal_falls_back_to_plain_with_one_warning():
    out = _run("""
        import warnings
        from numba.core.options import DefaultOptions
        del DefaultOptions._nrt  # a numba release without the option
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            from tlm_sim import _jit
        ours = [str(w.message) for w in caught if "tlm" in str(w.message)]
        print(_jit.MODE, len(ours), ours[0] if ours else "")
    """)
    assert out.returncode == 0, out.stderr[-3000:]
    mode, n, message = out.stdout.split(" ", 2)
    assert (mode, n) == ("plain", "1")
    assert "DefaultOptions._nrt" in message and "plain build" in message


def test_tlm_jit_values(monkeypatch):
    monkeypatch.delenv("TLM_JIT", raising=False)
    assert _jit.requested_mode() == "fast"
    monkeypatch.setenv("TLM_JIT", " Plain ")
    assert _jit.requested_mode() == "plain"
    monkeypatch.setenv("TLM_JIT", "turbo")
    with pytest.warns(RuntimeWarning, match="TLM_JIT='turbo'"):
        assert _jit.requested_mode() == "fast"
