"""The four built-in missions near CMAC (paper §3.2: "four simple flight paths")."""

from __future__ import annotations

from functools import cache

import numpy as np

from tlm_sim.geo import HOME_CMAC
from tlm_sim.mission._builtin_data import BUILTIN_DATA
from tlm_sim.mission.errors import MissionError
from tlm_sim.mission.generate import interpolate_waypoints, smooth_altitudes
from tlm_sim.mission.mission import Mission

__all__ = ["BUILTIN_IDS", "builtin_mission"]

#: valid arguments of :func:`builtin_mission`
BUILTIN_IDS: tuple[int, ...] = tuple(sorted(BUILTIN_DATA))


@cache
def builtin_mission(k: int) -> Mission:
    """Built-in mission ``k`` (1-4): home at CMAC, ~90 waypoints, 1.1-1.3 km loop.

    Made from literal raw points and raw altitudes (``_builtin_data.py``) with
    :func:`interpolate_waypoints` (n = 90) and :func:`smooth_altitudes` (21, 3, 0.01 m).
    The returned Mission is immutable and cached.

    Raises:
        MissionError: ``k`` is not one of :data:`BUILTIN_IDS`.
    """
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or int(k) not in BUILTIN_DATA:
        raise MissionError(f"no built-in mission {k!r}; choose one of {list(BUILTIN_IDS)}")
    seed, raw, alts = BUILTIN_DATA[int(k)]
    raw_arr = np.asarray(raw, dtype=np.float64)
    alt_raw = np.asarray(alts, dtype=np.float64)
    latlon = interpolate_waypoints(raw_arr, 90)
    if len(latlon) != len(alt_raw):  # pragma: no cover - guards the literal data
        raise MissionError(f"built-in mission {k}: {len(latlon)} waypoints, {len(alt_raw)} alts")
    alt = smooth_altitudes(alt_raw, 21, 3)
    return Mission(
        waypoints=np.column_stack([latlon, alt]),
        home=HOME_CMAC,
        raw_waypoints=raw_arr,
        altitudes_raw=alt_raw,
        name=f"builtin-{int(k)}",
        seed=seed,
        savgol=(21, 3),
    )
