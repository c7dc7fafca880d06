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

One compilation per function: numba types an integer constant passed from jitted code as
``Literal[int]`` and compiles the callee once per distinct constant (``reset_block(e, 3, 3,
v)`` and ``reset_block(e, 9, 3, v)`` were two compilations, 33 extra of 179 for a flight).
:class:`TickDispatcher` types such calls with plain ``int64`` instead, falling back to the
literal types only when a function cannot be compiled without them. The constants still reach
the machine code: the callee is linked into its caller's module, where LLVM inlines and
folds small functions.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from numba import config
from numba.core import errors, types
from numba.core.registry import CPUDispatcher


def _tick_options() -> dict[str, Any]:
    opts: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy",
                            "no_cfunc_wrapper": True}
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


def tick_jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """Decorator for the per-tick functions: ``numba.njit(**TICK_OPTIONS)`` with
    :class:`TickDispatcher` (see the module docstring)."""
    if config.DISABLE_JIT:
        return func
    options = {k: v for k, v in TICK_OPTIONS.items() if k != "cache"}
    tick = TickDispatcher(py_func=func, locals={},
                          targetoptions={"nopython": True, "boundscheck": None, **options})
    tick.enable_caching()
    return tick
