"""Numba options shared by every per-tick function (dynamics, sensors, control, logging).

``cache`` and ``nogil`` as everywhere in tlm. ``error_model="numpy"``: a float division by
zero gives inf/nan instead of raising, which removes an exception branch from every division.
``_nrt=False``: no reference counting of the array arguments. These functions never allocate,
so they need no runtime; the atomic increments/decrements the runtime would add around every
array passed between functions cost about a third of a physics tick. ``_nrt`` is an
underscore option of numba's CPU target (present since numba 0.4x); should a numba release
drop it, the functions compile with reference counting, only slower.
"""

from __future__ import annotations

from typing import Any

from numba import njit


def _tick_options() -> dict[str, Any]:
    opts: dict[str, Any] = {"cache": True, "nogil": True, "error_model": "numpy"}
    try:
        from numba.core.options import DefaultOptions

        if hasattr(DefaultOptions, "_nrt"):
            opts["_nrt"] = False
    except ImportError:  # pragma: no cover - numba internals moved
        pass
    return opts


#: keyword arguments of ``numba.njit`` for the per-tick functions
TICK_OPTIONS: dict[str, Any] = _tick_options()

#: decorator for the per-tick functions: ``@tick_jit``
tick_jit = njit(**TICK_OPTIONS)
