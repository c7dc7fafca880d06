"""Cross-check tlm against real ArduPilot SITL logs: rebuild a log's scenario, fly it, compare."""

from tlm_process.crosscheck.command import crosscheck, gate
from tlm_process.crosscheck.scenario import SitlScenario, mission_from_cmd, reconstruct

__all__ = ["SitlScenario", "crosscheck", "gate", "mission_from_cmd", "reconstruct"]
