"""Simulated sensors: two IMUs, GPS, barometer, compass, RC receiver (ArduPilot SITL semantics)."""

from tlm_sim.sensors.config import build_sensor_config

__all__ = ["build_sensor_config"]
