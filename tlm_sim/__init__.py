"""tlm_sim: a numba ArduCopter-style quadcopter that flies missions and logs ArduPilot tables.

``tlm_sim.fly(mission, faults=None, params=None, seed=0) -> FlightLog``.
"""

from tlm_sim._cache import configure_numba_cache

configure_numba_cache()

# ruff: noqa: E402  (the numba cache folder must be set before any jitted module is imported)

from tlm_sim.flight import fly
from tlm_sim.flightlog import FlightLog
from tlm_sim.mission import Mission, builtin_mission
from tlm_sim.params import ParamError, Params

__version__ = "0.1.0"

__all__ = ["FlightLog", "Mission", "ParamError", "Params", "__version__", "builtin_mission", "fly"]
