"""The ``fast`` build of tlm's jitted code, the default (:mod:`tlm_sim._jit` chooses): numba
options and compiler extensions that rely on numba's *private* internals.

Imported only by :mod:`tlm_sim._jit`. Raises ImportError at import when the installed numba
lacks one of the internals it relies on, so tlm falls back to the ``plain`` build
(:mod:`tlm_sim._jit_plain`) with one warning instead of failing mid-compile.

On top of the plain options (``cache``, ``nogil``, ``error_model="numpy"``, ``fastmath``
``contract`` + ``arcp``, see :mod:`tlm_sim._jit_plain`):

* ``_nrt=False`` (an underscore option of numba's CPU target): no reference counting of the
  array arguments. The per-tick functions never allocate, so they need no runtime; the atomic
  increments and decrements around every array passed between functions are a large share of
  a physics tick.
* ``no_cfunc_wrapper``: no C-callable wrapper per function (only ``numba.cfunc`` callbacks and
  first-class function values use one; Python calls go through the CPython wrapper, jitted
  calls call the function itself); saves compile time, flights bit-identical.
* :class:`TickDispatcher`: one compilation per function. numba types an integer constant
  passed from jitted code as ``Literal[int]`` and compiles the callee once per distinct
  constant (``reset_block(e, 3, 3, v)`` and ``reset_block(e, 9, 3, v)`` were two
  compilations). Such calls are typed with plain ``int64`` instead, falling back to the
  literal types only when a function cannot be compiled without them. The constants still
  reach the machine code: the callee is linked into its caller's module, where LLVM inlines
  and folds small functions.
* :class:`LoopLibrary` for loop entries (:func:`loop_jit`: ``run_flight``, ``run_ticks``):
  every function linked in from their callees becomes *private* to the entry's module before
  LLVM's module passes run. numba links a callee's code into its caller as ``linkonce_odr``:
  an exported symbol, whose signature LLVM may not change and whose body it must keep as a
  standalone copy. Private, LLVM may drop unused arguments (each array is 7 machine words:
  meminfo, parent, size, itemsize, data, shape, stride), propagate constant arguments and
  inline a function called from one place whatever its size. Nothing outside the entry refers
  to those copies (each callee's own library keeps its exported version).

What each piece gains, measured, is in ``benchmarks/RESULTS.md``.
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

from tlm_sim._jit_plain import PLAIN_OPTIONS

__all__ = ["TICK_OPTIONS", "LoopLibrary", "TickDispatcher", "inline_jit", "loop_jit", "tick_jit"]


def _check_internals() -> None:
    """ImportError unless numba has every private piece this build uses."""
    from numba.core.options import DefaultOptions

    needed = {"numba.core.options.DefaultOptions._nrt": hasattr(DefaultOptions, "_nrt"),
              "numba.core.options.DefaultOptions.no_cfunc_wrapper":
                  hasattr(DefaultOptions, "no_cfunc_wrapper"),
              "JITCodeLibrary._optimize_final_module":
                  callable(getattr(JITCodeLibrary, "_optimize_final_module", None)),
              "JITCodeLibrary.add_llvm_module":
                  callable(getattr(JITCodeLibrary, "add_llvm_module", None)),
              "CPUDispatcher.get_call_template":
                  callable(getattr(CPUDispatcher, "get_call_template", None)),
              "CPUDispatcher.enable_caching":
                  callable(getattr(CPUDispatcher, "enable_caching", None))}
    missing = [name for name, ok in needed.items() if not ok]
    if missing:
        raise ImportError(f"numba lacks {', '.join(missing)}")


_check_internals()


#: keyword arguments of ``numba.njit`` for the per-tick functions
TICK_OPTIONS: dict[str, Any] = {**PLAIN_OPTIONS, "no_cfunc_wrapper": True, "_nrt": False}


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
                cache: bool = True, inline: bool = False) -> Any:
    """``func`` compiled with :data:`TICK_OPTIONS` by a :class:`TickDispatcher` (``inline``:
    numba inlines it into its jitted callers, ``inline="always"``)."""
    if config.DISABLE_JIT:
        return func
    options = {k: v for k, v in TICK_OPTIONS.items() if k != "cache"}
    if inline:
        options["inline"] = "always"
    tick = TickDispatcher(py_func=func, locals={}, pipeline_class=pipeline_class,
                          targetoptions={"nopython": True, "boundscheck": None, **options})
    if cache:
        tick.enable_caching()
    return tick


def tick_jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator for the per-tick functions: ``numba.njit(**TICK_OPTIONS)`` with
    :class:`TickDispatcher` (see the module docstring)."""
    return _dispatcher(func)


def inline_jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator for a section of a per-tick function (a part of a long function, named and
    called from its one place): :func:`tick_jit` with numba's ``inline="always"``, so the
    section is inlined into its caller's numba IR. It costs no compilation of its own, and
    adds no level of linked LLVM modules: every level re-optimises all the code below it, so
    splitting the flight's long functions into plain tick_jit sections made a cold compile
    about 35 % longer."""
    return _dispatcher(func, inline=True)


def loop_jit(func: Callable[..., Any], *, cache: bool = True) -> Callable[..., Any]:
    """Decorator for a loop over the per-tick functions (the flight, ``run_ticks``):
    :func:`tick_jit`, its callees' code private to its module (:class:`LoopLibrary`).
    ``cache=False`` (tests): compile in memory only."""
    return _dispatcher(func, _LoopCompiler, cache)
