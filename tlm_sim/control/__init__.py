"""ArduCopter-style control: rate/attitude/position controllers, waypoint navigation, modes."""

from tlm_sim.control.config import build_control_config

__all__ = ["build_control_config"]
