"""The error type of the TLM pipeline: one-line messages a user can act on."""

from __future__ import annotations

import re

__all__ = ["AnchorError", "IngestError", "PipelineError"]


class PipelineError(ValueError):
    """A bad input or an impossible request in the TLM pipeline.

    The message is one line (newlines are folded), starting with the source it concerns when
    known: ``SOURCE: reason``. ``tlm process`` prints it and exits with code 2.
    """

    def __init__(self, reason: str, *, source: str | None = None) -> None:
        self.reason = re.sub(r"\s*\n\s*", " ", str(reason)).strip()
        self.source = source
        super().__init__(f"{source}: {self.reason}" if source else self.reason)


class IngestError(PipelineError):
    """An input that cannot be read as a flight (missing sidecar, table or fault record)."""


class AnchorError(PipelineError):
    """Fault windows that cannot be anchored: overlapping windows, a record that matches
    nowhere in the log, a log without GPS."""
