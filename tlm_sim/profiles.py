"""Compatibility profiles: where the paper's ArduPilot (4.1/4.2) and today's differ.

A profile is a set of parameter values applied under the user's own (reference §6):

* ``current`` (default): ArduPilot 2598e9d4 as in the reference SITL logs: SIM_ENGINE_FAIL is
  a bit mask (1 = motor 1, set in tlm's defaults), RC_FS_TIMEOUT 1 s, today's rotor yaw-torque
  model, GPS.NSats exactly as SITL reports it (10 / 3).
* ``paper``: the paper's era: SIM_ENGINE_FAIL is the index of one motor (0 = motor 1, so
  SIM_ENGINE_MUL 0 alone cuts motor 1), the radio failsafe's fixed 0.5 s timeout, the
  radians(40) yaw-torque model (TLM_PROFILE 1), and the paper's Eq. 3 satellite-count jitter
  on GPS.NSats (TLM_SAT_JITTER, its mu).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from tlm_sim.params import Params

PROFILES: Mapping[str, Mapping[str, float]] = MappingProxyType({
    "current": MappingProxyType({}),
    "paper": MappingProxyType({
        "TLM_PROFILE": 1.0,
        "SIM_ENGINE_FAIL": 0.0,
        "RC_FS_TIMEOUT": 0.5,
        "TLM_SAT_JITTER": 1.5,
    }),
})


def profile_params(profile: str, params: Params | Mapping[str, float] | None = None) -> Params:
    """Parameters of ``profile`` with ``params`` on top (a Params instance contributes the
    values it changed from the defaults)."""
    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r}; known: {', '.join(PROFILES)}")
    if isinstance(params, Params):  # already validated; a loaded set keeps its carried values
        own = params.changed()
        return params.updated({k: v for k, v in PROFILES[profile].items() if k not in own})
    base = Params(PROFILES[profile])
    return base if params is None else base.updated(params)
