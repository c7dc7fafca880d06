"""Reading a user's text file (parameter, mission, fault schedule, configuration, JSON) with
one-line errors: each reader wraps :class:`TextFileError` in its own error type and prefix."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["TextFileError", "read_text"]


class TextFileError(ValueError):
    """A text file that cannot be read, or is not text in its encoding: the message is the
    reason in one line ("No such file or directory", "not UTF-8 text (invalid start byte at
    byte 3)")."""


def read_text(path: str | os.PathLike, encoding: str = "utf-8") -> str:
    """The text of ``path``; raises :class:`TextFileError` with the reason in one line."""
    try:
        return Path(path).read_text(encoding=encoding)
    except OSError as exc:
        raise TextFileError(str(exc.strerror or exc)) from None
    except UnicodeDecodeError as exc:
        raise TextFileError(f"not UTF-8 text ({exc.reason} at byte {exc.start})") from None
