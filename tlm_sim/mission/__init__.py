"""Missions: the paper's Algorithm 1 waypoints with Savitzky-Golay altitudes, QGC WPL files.

Public API::

    Mission, MissionError
    interpolate_waypoints, smooth_altitudes, make_mission, random_loop
    builtin_mission, BUILTIN_IDS
    read_wpl, write_wpl
"""

from tlm_sim.mission.builtin import BUILTIN_IDS, builtin_mission
from tlm_sim.mission.errors import MissionError
from tlm_sim.mission.generate import (
    allocate_intervals,
    interpolate_waypoints,
    make_mission,
    random_loop,
    segment_lengths_m,
    smooth_altitudes,
)
from tlm_sim.mission.mission import Mission, path_length_horizontal_m
from tlm_sim.mission.wpl import read_wpl, write_wpl

__all__ = [
    "BUILTIN_IDS",
    "Mission",
    "MissionError",
    "allocate_intervals",
    "builtin_mission",
    "interpolate_waypoints",
    "make_mission",
    "path_length_horizontal_m",
    "random_loop",
    "read_wpl",
    "segment_lengths_m",
    "smooth_altitudes",
    "write_wpl",
]
