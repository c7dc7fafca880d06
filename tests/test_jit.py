"""tlm_sim._jit: loop entries keep their callees' code private to their own module."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from llvmlite import binding as ll
from numba import config

from tlm_sim import fly
from tlm_sim._jit import LoopLibrary, loop_jit, tick_jit

pytestmark = pytest.mark.skipif(config.DISABLE_JIT, reason="needs numba's compiler")


@tick_jit
def _bump(a, i, by):
    a[i] += by


def test_loop_library_makes_linked_callees_private_and_keeps_its_own_exported():
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
            _, done = path_update(c, g, path, 2, pos, vel, 0.0, True)
            pos[:] = c[C.PXY_POS_T], c[C.PXY_POS_T + 1], c[C.PZ_POS_T]
        print(pos[0])
    """)
    for _ in range(2):  # the first run caches the callees' own code, the second loads it
        out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                             timeout=300)
        assert out.returncode == 0, out.stderr[-2000:]
        assert float(out.stdout.split()[-1]) == pytest.approx(30.0, abs=0.02)
