"""Index an ArduPilot DataFlash ``.bin``: the byte offset and type of every message.

A ``.bin`` is a plain concatenation of messages ``0xA3 0x95 <type> <payload>``; the length of
each type (header included) comes from the FMT message that defines it (type 128, length 89,
layout ``BBnNZ``: Type, Length, Name, Format, Columns). ``scan_bin`` walks the file once in
numba, as pymavlink's indexer does, reading FMT messages as it meets them, and returns a
``BinIndex``. On well-formed logs its offsets equal pymavlink's (``tests/test_binreader.py``
checks that on the reference SITL logs); on damaged files it is defined where pymavlink is not:

* bytes that do not start a message (no ``A3 95`` header, or a type no valid FMT defined
  before) are skipped one at a time until the next message header (pymavlink stops indexing
  at the first unknown type);
* an FMT whose length disagrees with its format characters, with an unknown format
  character, or with a column count unlike its format is rejected (its type stays undefined);
* a second FMT for an already defined type with different content is ignored (the first
  wins; pymavlink lets the last win);
* a message that runs past the end of the file ends the walk (as in pymavlink). Right after
  a complete message it is an incomplete final message, dropped and reported as
  ``tail_bytes`` (every reference SITL log ends with one); after skipped bytes, the rest of
  the file counts as skipped. Bytes after the last message that start no message count as
  skipped too.

The walk always advances, so it ends on any input (at most one pass over the bytes). Nothing
is printed; ``BinIndex.issues`` describes what was skipped, and the readers turn that into
``BinLogWarning`` s.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from .schema import FORMAT_CHARS

__all__ = [
    "FMT_TYPE",
    "FMT_LENGTH",
    "BinLogError",
    "BinLogWarning",
    "LogFormat",
    "BinIndex",
    "scan_bin",
]

HEAD1 = 0xA3
HEAD2 = 0x95
#: type id and length of FMT (fixed in every ArduPilot log and assumed by pymavlink)
FMT_TYPE = 128
FMT_LENGTH = 89
_FMT_FORMAT = "BBnNZ"
_FMT_COLUMNS = ("Type", "Length", "Name", "Format", "Columns")
# byte offsets inside an FMT message (header included)
_F_TYPE, _F_LEN, _F_NAME, _F_FORMAT, _F_COLUMNS = 3, 4, 5, 9, 25


class BinLogError(ValueError):
    """A file that cannot be read as an ArduPilot DataFlash log (message names the file)."""


class BinLogWarning(UserWarning):
    """Part of a DataFlash log was damaged and skipped; the rest was read."""


#: payload bytes of each format character, indexed by its ASCII code (0 = not a format char)
_CHAR_SIZES = np.zeros(256, dtype=np.int64)
for _c, _fc in FORMAT_CHARS.items():
    _CHAR_SIZES[ord(_c)] = _fc.size


@njit(cache=True, nogil=True)
def _fmt_ok(data: np.ndarray, i: int, sizes: np.ndarray) -> bool:
    """Whether the FMT message at ``i`` is self-consistent (length, format chars, columns)."""
    if data[i + _F_NAME] == 0 or data[i + _F_COLUMNS] == 0:
        return False
    size = 0
    nfmt = 0
    for k in range(16):
        c = data[i + _F_FORMAT + k]
        if c == 0:
            break
        s = sizes[c]
        if s == 0:
            return False
        size += s
        nfmt += 1
    if nfmt == 0 or data[i + _F_LEN] != size + 3:
        return False
    ncol = 1
    for k in range(64):
        c = data[i + _F_COLUMNS + k]
        if c == 0:
            break
        if c == 44:  # ','
            ncol += 1
    if ncol != nfmt:
        return False
    if data[i + _F_TYPE] == FMT_TYPE and data[i + _F_LEN] != FMT_LENGTH:
        return False
    return True


@njit(cache=True, nogil=True)
def _same_fmt(data: np.ndarray, a: int, b: int) -> bool:
    for k in range(3, FMT_LENGTH):
        if data[a + k] != data[b + k]:
            return False
    return True


@njit(cache=True, nogil=True)
def _scan(data: np.ndarray, sizes: np.ndarray):  # noqa: ANN202 - numba tuple
    """Walk the messages of ``data`` (uint8). See the module docstring for the rules.

    Returns (offsets int64[n], types uint8[n], fmt_at int64[256] (offset of the FMT that
    defined each type, -1 if none), stats int64[8]):
    stats = skipped bytes, skipped runs, first skipped offset (-1), rejected FMTs,
    first rejected FMT offset (-1), conflicting FMTs, first conflicting FMT offset (-1),
    bytes of the incomplete final message (0 if none).
    """
    n = data.size
    lengths = np.zeros(256, dtype=np.int64)
    lengths[FMT_TYPE] = FMT_LENGTH
    fmt_at = np.full(256, -1, dtype=np.int64)
    cap = max(1024, n // 32)
    offsets = np.empty(cap, dtype=np.int64)
    types = np.empty(cap, dtype=np.uint8)
    count = 0
    stats = np.zeros(8, dtype=np.int64)
    stats[2] = -1
    stats[4] = -1
    stats[6] = -1
    run_start = -1  # start of the current run of skipped bytes
    i = 0
    while i + 3 <= n:
        if data[i] == HEAD1 and data[i + 1] == HEAD2:
            t = data[i + 2]
            length = lengths[t]
            if length > 0 and i + length <= n:
                if t == FMT_TYPE:
                    if not _fmt_ok(data, i, sizes):
                        stats[3] += 1
                        if stats[4] < 0:
                            stats[4] = i
                    else:
                        ft = data[i + _F_TYPE]
                        if fmt_at[ft] < 0:
                            lengths[ft] = data[i + _F_LEN]
                            fmt_at[ft] = i
                        elif not _same_fmt(data, fmt_at[ft], i):
                            stats[5] += 1
                            if stats[6] < 0:
                                stats[6] = i
                if run_start >= 0:
                    stats[0] += i - run_start
                    stats[1] += 1
                    if stats[2] < 0:
                        stats[2] = run_start
                    run_start = -1
                if count == offsets.size:
                    grown = np.empty(2 * count, dtype=np.int64)
                    grown[:count] = offsets
                    offsets = grown
                    grown_t = np.empty(2 * count, dtype=np.uint8)
                    grown_t[:count] = types
                    types = grown_t
                offsets[count] = i
                types[count] = t
                count += 1
                i += length
                continue
            if length > 0:  # a message cut by the end of the file: stop, as pymavlink
                break
        if run_start < 0:
            run_start = i
        i += 1
    if run_start >= 0:  # trailing bytes that are not messages
        stats[0] += n - run_start
        stats[1] += 1
        if stats[2] < 0:
            stats[2] = run_start
    elif i < n:  # an incomplete final message (or 1-2 bytes of a header)
        stats[7] = n - i
    return offsets[:count].copy(), types[:count].copy(), fmt_at, stats


@dataclass(frozen=True)
class LogFormat:
    """One message type as its FMT message defines it.

    Attributes:
        type: type id (0-255).
        name: message name, e.g. "GPS".
        length: bytes per message including the 3 header bytes.
        format: ArduPilot format characters.
        columns: field names.
    """

    type: int
    name: str
    length: int
    format: str
    columns: tuple[str, ...]


@dataclass
class BinIndex:
    """A DataFlash file's bytes, its message types and where each message is.

    Attributes:
        path: the file.
        data: the whole file as uint8.
        formats: type id → LogFormat of every valid FMT (FMT itself included).
        by_name: name → LogFormat (if two types claim a name, the one defined first).
        offsets: type id → int64 offsets (message start, header included), file order.
        skipped_bytes, skipped_runs, first_skipped: bytes that were not part of any message.
        rejected_fmt, conflicting_fmt: FMT messages ignored (inconsistent / redefinitions).
        tail_bytes: bytes of an incomplete final message (dropped; 0 if none).
    """

    path: Path
    data: np.ndarray
    formats: dict[int, LogFormat]
    by_name: dict[str, LogFormat]
    offsets: dict[int, np.ndarray]
    skipped_bytes: int = 0
    skipped_runs: int = 0
    first_skipped: int = -1
    rejected_fmt: int = 0
    conflicting_fmt: int = 0
    tail_bytes: int = 0
    issues: list[str] = field(default_factory=list)

    @property
    def size(self) -> int:
        """File size in bytes."""
        return int(self.data.size)

    def count(self, name: str) -> int:
        """Number of complete messages of type ``name`` (0 when the log has no such type)."""
        f = self.by_name.get(name)
        return 0 if f is None else int(self.offsets.get(f.type, np.zeros(0)).size)


def _cstr(b: bytes) -> str:
    b = b.split(b"\0", 1)[0]
    try:
        return b.decode("ascii")
    except UnicodeDecodeError:
        return b.decode("latin-1")


def _parse_fmt(raw: bytes) -> LogFormat | None:
    """LogFormat of one FMT payload (86 bytes) or None if its text is not usable."""
    ftype, flen = raw[0], raw[1]
    name = _cstr(raw[2:6])
    fmt = _cstr(raw[6:22])
    cols = tuple(_cstr(raw[22:86]).split(","))
    ok = (
        name.isascii() and name.isprintable() and name.strip() == name and name != ""
        and all(c.isascii() and c.isprintable() and c != "" for c in cols)
        and len(set(cols)) == len(cols) == len(fmt)
    )
    return LogFormat(ftype, name, flen, fmt, cols) if ok else None


def read_bytes(path: str | os.PathLike) -> tuple[Path, np.ndarray]:
    """The file's bytes (uint8); FileNotFoundError / BinLogError when there is nothing to read."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"no such log: {p}")
    data = np.fromfile(p, dtype=np.uint8)
    if data.size == 0:
        raise BinLogError(f"{p}: empty file, not an ArduPilot DataFlash log")
    return p, data


def scan_bin(path: str | os.PathLike) -> BinIndex:
    """Index a DataFlash file (one pass; see the module docstring for damaged input).

    Raises:
        FileNotFoundError: no such file.
        BinLogError: empty file, or no valid FMT message (not a DataFlash log).
    """
    p, data = read_bytes(path)
    offs, types, fmt_at, stats = _scan(data, _CHAR_SIZES)
    formats: dict[int, LogFormat] = {
        FMT_TYPE: LogFormat(FMT_TYPE, "FMT", FMT_LENGTH, _FMT_FORMAT, _FMT_COLUMNS)
    }
    issues: list[str] = []
    bad_text = 0
    for t in np.flatnonzero(fmt_at >= 0):
        if t == FMT_TYPE:
            continue
        o = int(fmt_at[t])
        f = _parse_fmt(data[o + 3 : o + FMT_LENGTH].tobytes())
        if f is None:
            bad_text += 1
        else:
            formats[int(t)] = f
    if len(formats) == 1 and fmt_at[FMT_TYPE] < 0:
        what = "no FMT message" if not np.any(types == FMT_TYPE) else "no valid FMT message"
        raise BinLogError(f"{p}: not an ArduPilot DataFlash log ({what})")
    by_name: dict[str, LogFormat] = {}
    for t in sorted(formats, key=lambda t: (fmt_at[t], t)):
        f = formats[t]
        if f.name in by_name:
            issues.append(f"{p.name}: FMT types {by_name[f.name].type} and {t} are both "
                          f"named {f.name!r}; kept type {by_name[f.name].type}")
            del formats[t]
        else:
            by_name[f.name] = f
    order = np.argsort(types, kind="stable")
    sorted_types = types[order]
    bounds = np.searchsorted(sorted_types, np.arange(257))
    offsets: dict[int, np.ndarray] = {}
    for t in range(256):
        a, b = bounds[t], bounds[t + 1]
        if b > a and t in formats:
            offsets[t] = offs[order[a:b]]
    undecodable = int(sum(bounds[t + 1] - bounds[t] for t in range(256) if t not in formats))
    skipped, runs, first, rejected, _, conflicts, first_conflict, tail = (int(x) for x in stats)
    if skipped:
        issues.append(
            f"{p.name}: skipped {skipped} bytes that are not messages "
            f"({runs} place{'s' if runs != 1 else ''}, first at byte {first})"
        )
    if rejected or bad_text:
        issues.append(f"{p.name}: ignored {rejected + bad_text} damaged FMT message(s)")
    if conflicts:
        issues.append(
            f"{p.name}: ignored {conflicts} FMT message(s) redefining a type differently "
            f"(first at byte {first_conflict}); kept the first definition"
        )
    if undecodable:
        issues.append(f"{p.name}: dropped {undecodable} message(s) of types with unusable FMT")
    return BinIndex(
        path=p, data=data, formats=formats, by_name=by_name, offsets=offsets, skipped_bytes=skipped,
        skipped_runs=runs, first_skipped=first, rejected_fmt=rejected + bad_text,
        conflicting_fmt=conflicts, tail_bytes=tail, issues=issues,
    )
