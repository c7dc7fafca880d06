"""How tlm's per-tick functions and flight loops are compiled: the ``fast`` or the ``plain``
build, chosen once per process.

* ``fast`` (default): :mod:`tlm_sim._jit_fast`, numba options and compiler extensions that use
  numba's private internals (no reference counting, no cfunc wrappers, one compilation per
  function, callees private to the flight loop's module).
* ``plain``: :mod:`tlm_sim._jit_plain`, ``numba.njit`` with public options only.

``TLM_JIT=plain`` in the environment selects the plain build (numba's cache keeps it apart,
:mod:`tlm_sim._cache`). If the installed numba lacks a private piece the fast build needs, tlm
uses the plain build and says so once (a ``RuntimeWarning``), instead of failing. :data:`MODE`
is the build in use. Every jitted module imports its decorators from here::

    from tlm_sim._jit import inline_jit, loop_jit, tick_jit
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from typing import Any

__all__ = ["JIT_MODES", "MODE", "inline_jit", "loop_jit", "requested_mode", "tick_jit"]

#: the builds ``TLM_JIT`` selects
JIT_MODES: tuple[str, ...] = ("fast", "plain")


def requested_mode() -> str:
    """The build ``TLM_JIT`` asks for (``fast`` when unset; an unknown value warns and gives
    ``fast``)."""
    raw = os.environ.get("TLM_JIT", "").strip().lower()
    if not raw:
        return "fast"
    if raw not in JIT_MODES:
        warnings.warn(f"TLM_JIT={raw!r} is not one of {', '.join(JIT_MODES)}; using fast",
                      RuntimeWarning, stacklevel=2)
        return "fast"
    return raw


def _select() -> tuple[str, Callable[..., Any], Callable[..., Any], Callable[..., Any]]:
    if requested_mode() == "fast":
        try:
            from tlm_sim import _jit_fast
        except (ImportError, AttributeError) as exc:
            import numba

            warnings.warn(f"tlm: numba {numba.__version__} lacks an internal of tlm's fast build "
                          f"({exc}); using the plain build (slower)", RuntimeWarning,
                          stacklevel=3)
        else:
            return "fast", _jit_fast.tick_jit, _jit_fast.loop_jit, _jit_fast.inline_jit
    from tlm_sim import _jit_plain

    return "plain", _jit_plain.tick_jit, _jit_plain.loop_jit, _jit_plain.inline_jit


#: ``tick_jit``: per-tick functions; ``loop_jit``: the loops over them; ``inline_jit``: named
#: sections of a long per-tick function, inlined into their one caller by numba
MODE, tick_jit, loop_jit, inline_jit = _select()
