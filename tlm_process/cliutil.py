"""What the ``tlm`` subcommands share: the user-mistake error, argparse ``type=`` converters and
the output folder (``--out``).

A leaf module: it imports nothing else of tlm_process (and nothing heavy), so every subcommand
module and the data set writer can use it without an import cycle or a slow ``tlm --help``.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

__all__ = ["OUT_MARK", "UsageError", "WRITE_PROBE", "add_overwrite", "check_writable_file",
           "clear_folder", "foreign_entries",
           "fraction", "int_at_least", "is_one_of", "number", "positive_number", "prepare_out",
           "show_param_warnings", "strict_json", "whole_number"]

#: the empty file written and removed to check that an output folder can be written
WRITE_PROBE = ".tlm-write-test"
#: the file by which a folder says that a tlm command wrote it (its text: the command)
OUT_MARK = ".tlm-out"


class UsageError(Exception):
    """A user mistake: ``tlm`` reports it as one line on stderr, exit code 2."""


# ------------------------------------------------------------------ argument types -------
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


def positive_number(text: str) -> float:
    """A float > 0."""
    v = number(text)
    if not v > 0:
        raise argparse.ArgumentTypeError("must be > 0")
    return v


def folder(text: str) -> str:
    """An output folder's path, not empty: an empty ``--out "$DIR"`` (DIR unset) would
    otherwise mean the current folder."""
    if not text.strip():
        raise argparse.ArgumentTypeError("an empty path (give a folder)")
    return text


def int_at_least(low: int) -> Callable[[str], int]:
    """A converter to a whole number >= ``low`` (``low`` >= 1)."""
    def convert(text: str) -> int:
        v = whole_number(text)
        if v < low:
            raise argparse.ArgumentTypeError(f"must be >= {low}")
        return v

    convert.__name__ = f"int_at_least_{low}"
    return convert


def fraction(*, zero: bool) -> Callable[[str], float]:
    """A converter to a share below 1: in [0, 1) with ``zero``, else in (0, 1)."""
    def convert(text: str) -> float:
        v = number(text)
        if not (0 <= v < 1 if zero else 0 < v < 1):
            raise argparse.ArgumentTypeError(f"{text} is not in {'[' if zero else '('}0, 1)")
        return v

    convert.__name__ = "fraction"
    return convert


# ------------------------------------------------------------------ output folder --------
def prepare_out(out: str | os.PathLike, command: str | None = None,
                overwrite: bool = False,
                inputs: Iterable[str | os.PathLike | None] = ()) -> Path:
    """Create output folder ``out`` (and its parents) and check that a file can be written
    in it (an empty probe file, removed at once).

    ``inputs``: the command's input files and folders (``None`` and paths that do not exist
    are skipped). An output folder that is one of them or holds one is refused before
    anything is written or removed: ``--overwrite`` would delete the input first.

    With ``command`` (the subcommand's name) the folder is that command's alone: a folder
    that holds anything (hidden entries aside) is refused unless ``overwrite``, and then only
    if a tlm command wrote it (its :data:`OUT_MARK` file): its whole content is removed
    first, so two runs never mix. The folder is marked as ``command``'s. Call it before the
    command's work, so a refused folder costs nothing.

    Raises:
        UsageError: ``cannot write to output folder OUT: REASON``, or a non-empty folder
            without ``overwrite``, or one that tlm did not write.
    """
    d = Path(out)
    held_input = input_inside(d, inputs)
    if held_input is not None:
        raise UsageError(f"output folder {d} holds an input of this command ({held_input}); "
                         f"choose another folder")
    if command is not None and d.exists():
        if not d.is_dir():
            raise UsageError(f"output folder {d} is a file")
        held = foreign_entries(d)
        if held and not overwrite:
            raise UsageError(
                f"output folder {d} is not empty ({len(held)} entries: "
                f"{', '.join(held[:3])}{', ...' if len(held) > 3 else ''}); choose a new "
                f"folder, or pass --overwrite to replace what tlm wrote there")
        if held:
            if not (d / OUT_MARK).is_file():
                raise UsageError(f"--overwrite: {d} was not written by tlm (no {OUT_MARK} "
                                 f"file), so tlm will not delete it; choose another folder")
            clear_folder(d)
    try:
        d.mkdir(parents=True, exist_ok=True)
        probe = d / WRITE_PROBE
        probe.write_bytes(b"")
        probe.unlink()
        if command is not None:
            (d / OUT_MARK).write_text(command + "\n")
    except OSError as e:
        raise UsageError(f"cannot write to output folder {d}: {e.strerror or e}") from None
    return d


def clear_folder(d: Path, ignore_errors: bool = False) -> None:
    """Remove everything in folder ``d`` (a folder tlm wrote), keeping ``d`` itself;
    ``ignore_errors``: leave what cannot be removed (a clean-up on an error path)."""
    import shutil

    for p in d.iterdir():
        try:
            if p.is_dir() and not p.is_symlink():
                shutil.rmtree(p)
            else:
                p.unlink()
        except OSError:
            if not ignore_errors:
                raise


def check_writable_file(path: str | os.PathLike, option: str) -> None:
    """Raise UsageError unless file ``path`` can be written (it is writable, or it does not
    exist and its folder is writable): checked before a command's work, not after it."""
    p = Path(path)
    if p.is_dir():
        raise UsageError(f"{option} {p}: is a folder")
    parent = p.parent if str(p.parent) else Path(".")
    if p.exists():
        ok = os.access(p, os.W_OK)
    else:
        ok = parent.is_dir() and os.access(parent, os.W_OK | os.X_OK)
    if not ok:
        why = "no such folder" if not parent.is_dir() else "permission denied"
        raise UsageError(f"{option} {p}: cannot be written ({why})")


def add_overwrite(parser: argparse.ArgumentParser) -> None:
    """The ``--overwrite`` flag of a command that writes a folder (see :func:`prepare_out`)."""
    parser.add_argument("--overwrite", action="store_true",
                        help="replace the output folder whole if an earlier tlm run wrote it "
                             "and it holds none of this command's inputs (default: refuse a "
                             "folder that is not empty)")


def foreign_entries(d: Path) -> list[str]:
    """Sorted names of what folder ``d`` holds, hidden entries (``.name``) left out: a folder
    with any is not empty for a command that refuses to mix its output with other files."""
    return sorted(p.name for p in d.iterdir() if not p.name.startswith("."))


def input_inside(out: str | os.PathLike,
                 paths: Iterable[str | os.PathLike | None]) -> str | None:
    """The first of ``paths`` (existing ones; compared resolved) that is folder ``out`` or lies
    inside it, else ``None``."""
    target = Path(out).resolve()
    for p in paths:
        if p is None or not Path(p).exists():
            continue
        rp = Path(p).resolve()
        if rp == target or target in rp.parents:
            return str(p)
    return None


def is_one_of(out: str | os.PathLike, paths: Iterable[str | os.PathLike]) -> bool:
    """Whether output folder ``out`` is one of ``paths`` (compared resolved)."""
    target = Path(out).resolve()
    return any(Path(p).resolve() == target for p in paths)


def show_param_warnings() -> None:
    """Print tlm's own warnings as one ``tlm: warning: ...`` line each on stderr (no file name,
    line number or source line): ``UnmodelledParamWarning`` (a loaded parameter set changes
    parameters tlm does not model), ``BinLogWarning`` (a .bin log was damaged or cut off: how
    much was read, what was skipped) and ``SidecarWarning`` (a sidecar beside a log is not
    fault records); other warnings as Python shows them."""
    from tlm_sim.flightlog.binscan import BinLogWarning
    from tlm_sim.flightlog.sidecar import SidecarWarning
    from tlm_sim.params import UnmodelledParamWarning

    ours = (UnmodelledParamWarning, BinLogWarning, SidecarWarning)
    previous = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001
        if issubclass(category, ours):
            print(f"tlm: warning: {message}", file=sys.stderr)
        else:
            previous(message, category, filename, lineno, file, line)

    warnings.showwarning = show


def parse_param_args(items: Sequence[str]) -> dict[str, float]:
    """``--param NAME=VALUE`` arguments as {NAME (upper case): value}; a malformed one is a
    :class:`UsageError` naming it."""
    out: dict[str, float] = {}
    for it in items:
        name, sep, value = it.partition("=")
        try:
            if not sep or not name.strip():
                raise ValueError
            out[name.strip().upper()] = float(value)
        except ValueError:
            raise UsageError(f"--param expects NAME=VALUE with a number, got {it!r}") from None
    return out


def strict_json(x: object) -> object:
    """``x`` as strict JSON (``json.dumps`` without NaN): dicts (keys as strings), lists and
    tuples recursively, numpy scalars as Python numbers, NaN and infinities as null."""
    import math

    import numpy as np

    if isinstance(x, dict):
        return {str(k): strict_json(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [strict_json(v) for v in x]
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
