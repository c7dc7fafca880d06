"""argparse ``type=`` converters shared by the ``tlm`` subcommands (one-line usage errors)."""

from __future__ import annotations

import argparse

__all__ = ["number", "whole_number"]


def whole_number(text: str) -> int:
    """An integer >= 0."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v < 0:
        raise argparse.ArgumentTypeError("must be >= 0")
    return v


def number(text: str) -> float:
    """Any float."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
