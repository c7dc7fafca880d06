"""Profile: where a cold compile of the flight loop spends its CPU time, by compiler phase.

Compiles the flight loop in this one process on an empty numba cache (``TLM_COMPILE_PROCS=1``,
a private temporary ``NUMBA_CACHE_DIR``), flies mission 1 once, and prints the CPU time of each
phase of numba's compiler, each counted exclusively (a phase's time excludes the phases it
calls: type inference compiles every callee it meets, and that callee's time is charged to the
callee's phases):

* numba's own Python: the front end and untyped passes, IR inlining of the ``inline_jit``
  sections, type inference, lowering to LLVM IR, cache writes;
* LLVM: function passes on each function's own module, module passes on a function's module
  with its callees linked in, machine code.

numba links every callee's code into its caller's module and optimises and emits the whole
module again (``tlm_sim._jit_fast`` explains why tlm keeps it that way), so LLVM's work grows
with the depth of the call tree. Two more tables: the functions whose type inference and
lowering took longest (an ``inline_jit`` section counts in its caller), and the code libraries
with the most LLVM time, with the number of functions each one's final module defines. Plain
numba hooks, no ``perf``; ~2-3 minutes on the 2-core VM. The phases wrap numba's private
methods: a numba that renamed one fails loudly here (``tests/test_profile_compile.py`` checks
them), nothing else changes.

    PYTHONPATH=. .venv/bin/python benchmarks/profile_compile.py [--top 15]
"""

from __future__ import annotations

import argparse
import functools
import os
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

#: compiler phases: (label, "module:Class.method")
PHASES: tuple[tuple[str, str], ...] = (
    ("numba: dispatcher, front end, untyped passes",
     "numba.core.dispatcher:_FunctionCompiler._compile_core"),
    ("numba: IR inlining (inline_jit sections)",
     "numba.core.inline_closurecall:InlineWorker.inline_ir"),
    ("numba: type inference", "numba.core.typed_passes:NopythonTypeInference.run_pass"),
    ("numba: lowering to LLVM IR", "numba.core.typed_passes:NativeLowering.run_pass"),
    ("numba: cache writes", "numba.core.caching:Cache.save_overload"),
    ("LLVM: function passes", "numba.core.codegen:CPUCodeLibrary._optimize_functions"),
    ("LLVM: module passes (callees linked in)",
     "numba.core.codegen:CPUCodeLibrary._optimize_final_module"),
    ("LLVM: machine code", "numba.core.codegen:JITCodeLibrary._finalize_specific"),
)
LLVM_PHASES = [label for label, _ in PHASES if label.startswith("LLVM")]
#: numba phases also summed per function compiled (an inline_jit section counts in its caller)
PER_FUNCTION = ["numba: type inference", "numba: lowering to LLVM IR"]


def resolve(target: str) -> tuple[type, str]:
    """(class, method name) of ``module:Class.method``; AttributeError when numba lacks it."""
    import importlib

    module, qual = target.split(":")
    cls_name, meth = qual.split(".")
    cls = getattr(importlib.import_module(module), cls_name)
    getattr(cls, meth)
    return cls, meth


class PhaseClock:
    """Exclusive CPU time per phase: a stack of the active phases, the time between two
    switches charged to the phase on top (``outside`` when none is active)."""

    def __init__(self) -> None:
        self.total: dict[str, float] = defaultdict(float)
        #: phase times by name: the code library's (LLVM phases) or the function's (PER_FUNCTION)
        self.by_name: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))
        self.functions: dict[str, int] = {}
        self._stack: list[tuple[str, str | None]] = [("outside", None)]
        self._t = time.process_time()

    def switch(self) -> None:
        """Charge the time since the last switch to the phase on top (call once at the end)."""
        now = time.process_time()
        label, library = self._stack[-1]
        self.total[label] += now - self._t
        if library is not None:
            self.by_name[library][label] += now - self._t
        self._t = now

    def wrap(self, label: str, target: str) -> None:
        """Charge the method ``module:Class.method`` to ``label`` while it runs."""
        self.wrap_method(label, *resolve(target))

    def wrap_method(self, label: str, cls: type, meth: str) -> None:
        """Charge ``cls.meth`` to ``label`` while it runs (replaces the class attribute)."""
        orig: Callable[..., Any] = getattr(cls, meth)
        clock = self

        @functools.wraps(orig)
        def timed(obj: Any, *args: Any, **kwargs: Any) -> Any:
            if label in LLVM_PHASES:
                library = obj.name
            elif label in PER_FUNCTION:  # a compiler pass: run_pass(self, state)
                library = args[0].func_id.func_qualname
            else:
                library = None
            clock.switch()
            clock._stack.append((label, library))
            try:
                return orig(obj, *args, **kwargs)
            finally:
                clock.switch()
                clock._stack.pop()
                if label == LLVM_PHASES[1] and library is not None:
                    clock.functions[library] = sum(
                        1 for f in obj._final_module.functions if not f.is_declaration)

        setattr(cls, meth, timed)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--top", type=int, default=15,
                    help="rows of the per-function and per-library tables (default 15)")
    args = ap.parse_args()
    os.environ["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="tlm-profile-compile-")
    os.environ["TLM_COMPILE_PROCS"] = "1"

    clock = PhaseClock()
    for label, target in PHASES:
        clock.wrap(label, target)
    t0, w0 = time.process_time(), time.perf_counter()
    from tlm_sim import fly

    log = fly(1, seed=0)
    clock.switch()
    cpu, wall = time.process_time() - t0, time.perf_counter() - w0
    print(f"import + cold compile + one flight of mission 1 ({log.meta['duration_s']:.0f} s "
          f"simulated), one process: {cpu:.1f} CPU s, {wall:.1f} s wall, "
          f"{len(clock.functions)} code libraries")
    print(f"{'phase':48s} {'CPU s':>7s} {'share':>6s}")
    for label in [lbl for lbl, _ in PHASES] + ["outside"]:
        name = "outside the compiler (imports, the flight, tables)" if label == "outside" \
            else label
        print(f"{name:48s} {clock.total[label]:7.1f} {clock.total[label] / cpu:6.1%}")
    llvm = sum(clock.total[p] for p in LLVM_PHASES)
    numba = sum(clock.total[lbl] for lbl, _ in PHASES if lbl.startswith("numba"))
    print(f"{'numba in all':48s} {numba:7.1f} {numba / cpu:6.1%}")
    print(f"{'LLVM in all':48s} {llvm:7.1f} {llvm / cpu:6.1%}")

    funcs = sorted(clock.by_name.items(),
                   key=lambda kv: -sum(kv[1][p] for p in PER_FUNCTION))
    print(f"\nnumba's type inference and lowering by function compiled, top {args.top}")
    print(f"{'function':32s} {'typing':>7s} {'lower':>7s}")
    for name, t in funcs[:args.top]:
        print(f"{name[:32]:32s} {t[PER_FUNCTION[0]]:7.2f} {t[PER_FUNCTION[1]]:7.2f}")

    libs = sorted(clock.by_name.items(),
                  key=lambda kv: -sum(kv[1][p] for p in LLVM_PHASES))
    print(f"\nLLVM time by code library, top {args.top} (fn: function passes, mod: module "
          "passes, mc: machine code; defs: functions its final module defines)")
    print(f"{'library':32s} {'fn':>6s} {'mod':>6s} {'mc':>6s} {'defs':>5s}")
    for name, t in libs[:args.top]:
        print(f"{name[:32]:32s} {t[LLVM_PHASES[0]]:6.2f} {t[LLVM_PHASES[1]]:6.2f} "
              f"{t[LLVM_PHASES[2]]:6.2f} {clock.functions.get(name, 0):5d}")
    below = sum(t[p] for n, t in libs if n != "run_flight" for p in LLVM_PHASES[1:])
    print(f"module passes + machine code in libraries other than run_flight's (their callees' "
          f"code again at every level): {below:.1f} CPU s")


if __name__ == "__main__":
    main()
