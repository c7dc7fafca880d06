"""The one exception type of the mission package."""

from __future__ import annotations

__all__ = ["MissionError"]


class MissionError(ValueError):
    """A mission, a mission file or a mission-generation request is invalid.

    The message names the culprit (waypoint index, file line, parameter).
    """
