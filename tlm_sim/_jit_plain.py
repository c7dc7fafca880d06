"""The ``plain`` build of tlm's jitted code: ``numba.njit`` with public options only.

``TLM_JIT=plain`` selects it (:mod:`tlm_sim._jit`), and tlm falls back to it when the installed
numba lacks a private internal of the default ``fast`` build (:mod:`tlm_sim._jit_fast`). It
computes the same model with the same floating-point options; it is slower, and its flights may
differ from the fast build's in the last bits, because LLVM inlines (and so fuses multiply-adds)
differently.

Options: ``cache`` (numba's on-disk cache, :mod:`tlm_sim._cache`), ``nogil`` (the ``thread``
executor flies flights in parallel), ``error_model="numpy"`` (a float division by zero gives
inf/nan instead of raising, which removes an exception branch from every division) and two of
LLVM's fast-math flags only: ``contract`` lets a multiply and an add fuse into one FMA
instruction (one rounding instead of two), ``arcp`` lets a division become a multiplication by
the reciprocal (within an ulp or so). No flag that assumes away NaN or infinity (the EKF's
health checks test for them), ignores the sign of zero, or reorders sums. Flights remain a
pure function of their inputs on a given machine; FMA makes their last bits depend on the CPU
having FMA (x86-64 since 2013, every arm64), as libm already makes them depend on the C
library.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numba

__all__ = ["PLAIN_OPTIONS", "inline_jit", "loop_jit", "tick_jit"]

#: keyword arguments of ``numba.njit`` for every per-tick function and loop (public options)
PLAIN_OPTIONS: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy",
                                 "fastmath": {"contract", "arcp"}}


def tick_jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """``numba.njit(**PLAIN_OPTIONS)``."""
    return numba.njit(**PLAIN_OPTIONS)(func)


def inline_jit(func: Callable[..., Any]) -> Callable[..., Any]:
    """``numba.njit(inline="always", **PLAIN_OPTIONS)``: a section of a per-tick function,
    inlined into its caller's numba IR."""
    return numba.njit(inline="always", **PLAIN_OPTIONS)(func)


def loop_jit(func: Callable[..., Any], *, cache: bool = True) -> Callable[..., Any]:
    """``numba.njit(**PLAIN_OPTIONS)``; ``cache=False`` compiles in memory only."""
    return numba.njit(**{**PLAIN_OPTIONS, "cache": cache})(func)
