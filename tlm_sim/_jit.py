"""Numba options and decorator shared by every per-tick function (dynamics, sensors, EKF,
control, logging).

``cache`` and ``nogil`` as everywhere in tlm. ``error_model="numpy"``: a float division by
zero gives inf/nan instead of raising, which removes an exception branch from every division.
``_nrt=False``: no reference counting of the array arguments. These functions never allocate,
so they need no runtime; the atomic increments/decrements the runtime would add around every
array passed between functions cost about a third of a physics tick. ``_nrt`` is an
underscore option of numba's CPU target (present since numba 0.4x); should a numba release
drop it, the functions compile with reference counting, only slower. ``no_cfunc_wrapper``: no
C-callable wrapper per function (only ``numba.cfunc`` callbacks and first-class function
values use it; Python calls go through the CPython wrapper, jitted calls call the function
itself). Building those wrappers took 1.1 s of a cold compile, before their LLVM work
(measured with a timer on numba's ``create_cfunc_wrapper``); flights are bit-identical.
``fastmath={"contract", "arcp"}``, two of LLVM's fast-math flags only: ``contract`` lets a
multiply and an add fuse into one FMA instruction (one rounding instead of two: as accurate
or more), ``arcp`` lets a division become a multiplication by the reciprocal (within an ulp or
so of the quotient). No flag that assumes away NaN or infinity (the EKF's health checks test
for them), the sign of zero, or reorders sums. Measured on the flight loop: ~165 -> ~152 ms per
470 s flight; ``tools/crosscheck_all.py`` against the SITL logs is unchanged but for the
combined flight's trajectory RMS (2.72 -> 2.50 m: a chaotic flight, see docs/crosscheck.md).
Flights remain a pure function of their inputs on a given machine; FMA makes their last bits
depend on the CPU having FMA (x86-64 since 2013, every arm64), as libm already makes them
depend on the C library.

One compilation per function: numba types an integer constant passed from jitted code as
``Literal[int]`` and compiles the callee once per distinct constant (``reset_block(e, 3, 3,
v)`` and ``reset_block(e, 9, 3, v)`` were two compilations, 33 extra of 179 for a flight).
:class:`TickDispatcher` types such calls with plain ``int64`` instead, falling back to the
literal types only when a function cannot be compiled without them. The constants still reach
the machine code: the callee is linked into its caller's module, where LLVM inlines and
folds small functions.

Loop entries (:func:`loop_jit`: ``run_flight``, ``run_ticks``) also make every function linked
in from their callees *private* to the entry's module before LLVM's module passes run
(:class:`LoopLibrary`). numba links a callee's code into its caller as ``linkonce_odr``: an
exported symbol, whose signature LLVM may not change and whose body it must keep as a
standalone copy. Private, LLVM may drop unused arguments (each array is 7 machine words:
meminfo, parent, size, itemsize, data, shape, stride), propagate constant arguments and inline
a function called from one place whatever its size. Nothing outside the entry refers to those
copies (each callee's own library keeps its exported version). Measured on the flight loop:
~205 -> ~165 ms per 470 s flight, flights bit-identical (same SHA-1 of every table of four
flights); ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from numba import config
from numba.core import errors, types
from numba.core.codegen import JITCodeLibrary
from numba.core.compiler import Compiler
from numba.core.compiler_machinery import LoweringPass, register_pass
from numba.core.registry import CPUDispatcher
from numba.core.typed_passes import IRLegalization


def _tick_options() -> dict[str, Any]:
    opts: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy",
                            "no_cfunc_wrapper": True, "fastmath": {"contract", "arcp"}}
    try:
        from numba.core.options import DefaultOptions

        if hasattr(DefaultOptions, "_nrt"):
            opts["_nrt"] = False
    except ImportError:  # pragma: no cover - numba internals moved
        pass
    return opts


#: keyword arguments of ``numba.njit`` for the per-tick functions
TICK_OPTIONS: dict[str, Any] = _tick_options()


class TickDispatcher(CPUDispatcher):
    """numba's CPU dispatcher, typing calls from jitted code without literal arguments."""

    def get_call_template(self, args: Any, kws: Any) -> Any:
        plain = tuple(types.unliteral(a) for a in args)
        plain_kws = {k: types.unliteral(v) for k, v in kws.items()}
        if plain == tuple(args) and plain_kws == dict(kws):
            return super().get_call_template(args, kws)
        try:
            return super().get_call_template(plain, plain_kws)
        except errors.TypingError:  # the function needs the constants at typing time
            return super().get_call_template(args, kws)


class LoopLibrary(JITCodeLibrary):
    """numba code library of a loop entry (:func:`loop_jit`).

    Before LLVM's module passes, every function linked in from a callee's library becomes
    *private* to this module; the functions compiled for the entry itself (its native function
    and its CPython wrapper) stay exported. Private, not internal: an internal function keeps
    its name in the object file's symbol table, and numba's JIT linker then resolved a direct
    Python call of that callee (a test calling ``path_update``) to the entry's copy, whose
    arguments LLVM had changed (a crash). ``privatize = False`` keeps numba's linkage (for
    per-function profiles, ``benchmarks/profile_fly.py``)."""

    privatize: bool = True

    def __init__(self, codegen: Any, name: str) -> None:
        super().__init__(codegen, name)
        self._own_functions: set[str] = set()
        #: names of the linked-in functions made private (for tests and inspection)
        self.privatized: list[str] = []

    def add_llvm_module(self, ll_module: Any) -> None:
        self._own_functions.update(f.name for f in ll_module.functions if not f.is_declaration)
        super().add_llvm_module(ll_module)

    def _optimize_final_module(self) -> None:
        if self.privatize:
            for f in self._final_module.functions:
                if not f.is_declaration and f.name not in self._own_functions:
                    f.linkage = "private"
                    self.privatized.append(f.name)
        super()._optimize_final_module()


@register_pass(mutates_CFG=False, analysis_only=False)
class _UseLoopLibrary(LoweringPass):
    """Compiler pass, placed before lowering: lower the function into a :class:`LoopLibrary`
    (numba's lowering pass creates a plain library only when none is set)."""

    _name = "tlm_use_loop_library"

    def __init__(self) -> None:
        LoweringPass.__init__(self)

    def run_pass(self, state: Any) -> bool:
        if state.library is not None:  # compiled into a library its caller gave
            return False
        state.library = LoopLibrary(state.targetctx.codegen(), state.func_id.func_qualname)
        state.library.enable_object_caching()
        return True


class _LoopCompiler(Compiler):
    """numba's pipelines, the nopython one with :class:`_UseLoopLibrary` before lowering."""

    def define_pipelines(self) -> list[Any]:
        pms = super().define_pipelines()
        for pm in pms:
            if pm.pipeline_name == "nopython":
                pm.add_pass_after(_UseLoopLibrary, IRLegalization)
                pm.finalize()
        return pms


def _dispatcher(func: Callable[..., Any], pipeline_class: type = Compiler,
                cache: bool = True) -> Any:
    """``func`` compiled with :data:`TICK_OPTIONS` by a :class:`TickDispatcher`."""
    if config.DISABLE_JIT:
        return func
    options = {k: v for k, v in TICK_OPTIONS.items() if k != "cache"}
    tick = TickDispatcher(py_func=func, locals={}, pipeline_class=pipeline_class,
                          targetoptions={"nopython": True, "boundscheck": None, **options})
    if cache:
        tick.enable_caching()
    return tick


def tick_jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator for the per-tick functions: ``numba.njit(**TICK_OPTIONS)`` with
    :class:`TickDispatcher` (see the module docstring)."""
    return _dispatcher(func)


def loop_jit(func: Callable[..., Any], *, cache: bool = True) -> Callable[..., Any]:
    """Decorator for a loop over the per-tick functions (the flight, ``run_ticks``):
    :func:`tick_jit`, its callees' code private to its module (:class:`LoopLibrary`).
    ``cache=False`` (tests): compile in memory only."""
    return _dispatcher(func, _LoopCompiler, cache)
