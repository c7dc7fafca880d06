"""Cross-check tlm against real ArduPilot SITL logs: rebuild a log's scenario, fly it, compare.

Names are imported lazily (``tlm_process._lazy``) so that ``tlm --help`` stays fast.
"""

from __future__ import annotations

from tlm_process._lazy import lazy_exports

_EXPORTS: dict[str, str] = {
    "compare": "crosscheck gate",
    "scenario": "SitlScenario mission_from_cmd reconstruct",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
