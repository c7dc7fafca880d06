"""The error type of ``tlm generate``: a user mistake or an unusable dataset, in one line."""

from __future__ import annotations

import re

__all__ = ["ExecutorLost", "GenerateError"]


class GenerateError(ValueError):
    """Bad generation settings, an unusable output folder or dataset, an unreachable Dask
    scheduler. The message is one line (``tlm generate`` prints it after ``tlm: error:``)."""

    def __init__(self, message: str) -> None:
        super().__init__(re.sub(r"\s*\n\s*", " ", str(message)).strip())


class ExecutorLost(GenerateError):
    """The executor can no longer run flights (the Dask scheduler is gone or does not answer).
    ``generate`` closes the data set (state ``incomplete``) and re-raises it as a
    :class:`GenerateError` that says how many flights were written."""
