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
* a type whose FMT name is not an ArduPilot message name (1-4 of A-Z, 0-9; a name becomes a
  file name in ``tlm convert``, so ``../x`` or ``/abs`` must not) is dropped, and so is a
  second type claiming a name already taken; their messages are counted in ``BinIndex.lost``;
* a message that runs past the end of the file ends the walk (as in pymavlink). Right after
  a complete message it is an incomplete final message, dropped and reported as
  ``tail_bytes`` (every reference SITL log ends with one); after skipped bytes, the rest of
  the file counts as skipped. Bytes after the last message that start no message count as
  skipped too.

The walk always advances, so it ends on any input (at most one pass over the bytes). Nothing
is printed; ``BinIndex.issues`` describes what was skipped, ``BinIndex.lost`` counts the
messages dropped per type, and the readers turn the issues into ``BinLogWarning`` s.
DataFlash has no checksums: a deletion that removes whole messages, or one whose resync lands
exactly on a message boundary (the cut message then holds bytes of a later one), cannot be
seen in the bytes and is not reported.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numba import njit

from tlm_sim.ardupilot import FMT_TYPE, HEAD1, HEAD2

from .schema import FORMAT_CHARS

__all__ = [
    "FMT_TYPE",
    "FMT_LENGTH",
    "BinLogError",
    "BinLogWarning",
    "LogFormat",
    "BinIndex",
    "scan_bin",
    "check_log_file",
    "is_message_name",
]

#: length of FMT (fixed in every ArduPilot log and assumed by pymavlink; its type id is
#: ardupilot.FMT_TYPE)
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
def _take_fmt(data: np.ndarray, i: int, sizes: np.ndarray, lengths: np.ndarray,
              fmt_at: np.ndarray, rejected_at: np.ndarray, stats: np.ndarray) -> None:
    """The FMT message at ``i`` (see :func:`_scan`): a self-consistent one defines its type
    (length, offset) unless the type is defined already (then a different one counts as
    conflicting); any other is counted as rejected."""
    if not _fmt_ok(data, i, sizes):
        stats[3] += 1
        if stats[4] < 0:
            stats[4] = i
        if rejected_at[data[i + _F_TYPE]] < 0:
            rejected_at[data[i + _F_TYPE]] = i
        return
    ft = data[i + _F_TYPE]
    if fmt_at[ft] < 0:
        lengths[ft] = data[i + _F_LEN]
        fmt_at[ft] = i
    elif not _same_fmt(data, fmt_at[ft], i):
        stats[5] += 1
        if stats[6] < 0:
            stats[6] = i


@njit(cache=True, nogil=True)
def _end_skipped(stats: np.ndarray, run_start: int, end: int) -> None:
    """Count the run of skipped bytes ``run_start`` to ``end`` (see :func:`_scan`'s stats)."""
    stats[0] += end - run_start
    stats[1] += 1
    if stats[2] < 0:
        stats[2] = run_start


@njit(cache=True, nogil=True)
def _grown(offsets: np.ndarray, types: np.ndarray, count: int):  # noqa: ANN202 - numba tuple
    """(offsets, types) with twice the room, their first ``count`` entries kept."""
    grown = np.empty(2 * count, dtype=np.int64)
    grown[:count] = offsets[:count]
    grown_t = np.empty(2 * count, dtype=np.uint8)
    grown_t[:count] = types[:count]
    return grown, grown_t


@njit(cache=True, nogil=True)
def _scan(data: np.ndarray, sizes: np.ndarray):  # noqa: ANN202 - numba tuple
    """Walk the messages of ``data`` (uint8). See the module docstring for the rules.

    Returns (offsets int64[n] grouped by type (``_by_type``), bounds int64[257] (type t's
    offsets are offsets[bounds[t]:bounds[t + 1]]), fmt_at int64[256] (offset of the FMT that
    defined each type, -1 if none), stats int64[8], unknown int64[256], rejected_at
    int64[256]):
    stats = skipped bytes, skipped runs, first skipped offset (-1), rejected FMTs,
    first rejected FMT offset (-1), conflicting FMTs, first conflicting FMT offset (-1),
    bytes of the incomplete final message (0 if none); unknown = message headers of each
    undefined type met in skipped bytes (the messages of a type whose FMT was rejected);
    rejected_at = offset of the first rejected FMT claiming each type id (-1 if none).
    """
    n = data.size
    lengths = np.zeros(256, dtype=np.int64)
    lengths[FMT_TYPE] = FMT_LENGTH
    fmt_at = np.full(256, -1, dtype=np.int64)
    rejected_at = np.full(256, -1, dtype=np.int64)
    unknown = np.zeros(256, dtype=np.int64)
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
                    _take_fmt(data, i, sizes, lengths, fmt_at, rejected_at, stats)
                if run_start >= 0:
                    _end_skipped(stats, run_start, i)
                    run_start = -1
                if count == offsets.size:
                    offsets, types = _grown(offsets, types, count)
                offsets[count] = i
                types[count] = t
                count += 1
                i += length
                continue
            if length > 0:  # a message cut by the end of the file: stop, as pymavlink
                break
            unknown[t] += 1
        if run_start < 0:
            run_start = i
        i += 1
    if run_start >= 0:  # trailing bytes that are not messages
        _end_skipped(stats, run_start, n)
    elif i < n:  # an incomplete final message (or 1-2 bytes of a header)
        stats[7] = n - i
    ordered, bounds = _by_type(offsets, types, count)
    return ordered, bounds, fmt_at, stats, unknown, rejected_at


@njit(cache=True, nogil=True)
def _by_type(offsets: np.ndarray, types: np.ndarray, count: int):  # noqa: ANN202 - numba tuple
    """The first ``count`` offsets grouped by type, file order kept within a type (a counting
    sort: one int64 per message, no argsort, no per-type copies). Returns (ordered int64[count],
    bounds int64[257]): type t's offsets are ordered[bounds[t]:bounds[t + 1]]."""
    bounds = np.zeros(257, dtype=np.int64)
    for k in range(count):
        bounds[types[k] + 1] += 1
    bounds = np.cumsum(bounds)
    pos = bounds[:256].copy()
    ordered = np.empty(count, dtype=np.int64)
    for k in range(count):
        t = types[k]
        ordered[pos[t]] = offsets[k]
        pos[t] += 1
    return ordered, bounds


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
        lost: what could not be read, as label → messages: a type's name or "type <id>
            (<why>)" → messages dropped (damaged or unsafe FMT, a name claimed twice, message
            headers of undefined types met in skipped bytes). Bytes skipped that held no
            message header (cut messages) are only in ``skipped_bytes``.
        issues: one line per kind of damage (the readers warn with them).
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
    lost: dict[str, int] = field(default_factory=dict)
    issues: list[str] = field(default_factory=list)

    @property
    def size(self) -> int:
        """File size in bytes."""
        return int(self.data.size)

    def count(self, name: str) -> int:
        """Number of complete messages of type ``name`` (0 when the log has no such type)."""
        f = self.by_name.get(name)
        return 0 if f is None else int(self.offsets.get(f.type, np.zeros(0)).size)


#: ArduPilot message names: 1-4 upper-case letters and digits (every name the reference SITL
#: logs define). A name read from a log becomes a file name (``tlm convert``, ``FlightLog.write``),
#: so a type named otherwise (``../x``, ``/abs``, ``a.b``) is skipped and reported.
MESSAGE_NAME = re.compile(r"[A-Z0-9]{1,4}")


def is_message_name(name: str) -> bool:
    """Whether ``name`` is an ArduPilot message name (1-4 of A-Z, 0-9): safe as a file name."""
    return MESSAGE_NAME.fullmatch(name) is not None


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


def _fmt_name(data: np.ndarray, at: int) -> str:
    """The name field of the FMT message at byte ``at``, as text (for messages)."""
    return _cstr(data[at + _F_NAME : at + _F_FORMAT].tobytes())


def check_log_file(path: str | os.PathLike) -> Path:
    """``path`` as a Path, if it is a non-empty regular file (checked before reading: a device
    such as /dev/zero would be read forever).

    Raises:
        FileNotFoundError: no such file.
        BinLogError: not a regular file (a folder, device or pipe), or an empty file.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(f"no such log: {p}")
    if not p.is_file():
        raise BinLogError(f"{p}: not a regular file (a folder, device or pipe), "
                          "not an ArduPilot DataFlash log")
    if p.stat().st_size == 0:
        raise BinLogError(f"{p}: empty file, not an ArduPilot DataFlash log")
    return p


def read_bytes(path: str | os.PathLike) -> tuple[Path, np.ndarray]:
    """The file's bytes (uint8; read, not memory-mapped: a log truncated while mapped would
    kill the process with SIGBUS). Raises as ``check_log_file``."""
    p = check_log_file(path)
    data = np.fromfile(p, dtype=np.uint8)
    if data.size == 0:  # emptied since stat
        raise BinLogError(f"{p}: empty file, not an ArduPilot DataFlash log")
    return p, data


def _lost_text(lost: dict[str, int]) -> str:
    """``{"VIBE": 12, "type 7": 1}`` → ``"VIBE 12, type 7 1"``."""
    return ", ".join(f"{k} {v}" for k, v in lost.items())


def _formats(p: Path, data: np.ndarray, fmt_at: np.ndarray, counts: np.ndarray,
             lost: dict[str, int], issues: list[str]) -> dict[int, LogFormat]:
    """type id → LogFormat of each FMT the scan accepted whose text is usable and whose name
    is a message name (``is_message_name``); the messages of the others go into ``lost``.

    ``counts``: messages indexed per type id.
    """
    formats: dict[int, LogFormat] = {
        FMT_TYPE: LogFormat(FMT_TYPE, "FMT", FMT_LENGTH, _FMT_FORMAT, _FMT_COLUMNS)
    }
    bad_text: list[int] = []
    for t in np.flatnonzero(fmt_at >= 0):
        if t == FMT_TYPE:
            continue
        o = int(fmt_at[t])
        f = _parse_fmt(data[o + 3 : o + FMT_LENGTH].tobytes())
        if f is None:
            bad_text.append(int(t))
            if counts[t]:
                lost[f"type {t} (damaged FMT)"] = int(counts[t])
        elif not is_message_name(f.name):
            issues.append(f"{p.name}: skipped {int(counts[t])} message(s) of type {t}: its FMT "
                          f"names it {f.name!r}, not a message name (1-4 of A-Z, 0-9)")
            if counts[t]:
                lost[f"type {t} ({f.name!r})"] = int(counts[t])
        else:
            formats[int(t)] = f
    if bad_text:
        issues.append(f"{p.name}: ignored {len(bad_text)} damaged FMT message(s) with unreadable "
                      f"text (type{'s' if len(bad_text) > 1 else ''} "
                      f"{', '.join(map(str, bad_text))}); dropped their messages")
    return formats


def _by_name(p: Path, formats: dict[int, LogFormat], fmt_at: np.ndarray, counts: np.ndarray,
             lost: dict[str, int], issues: list[str]) -> dict[str, LogFormat]:
    """name → LogFormat, the first FMT (in file order) of each name; later types that claim
    the same name are removed from ``formats`` and their messages go into ``lost``."""
    by_name: dict[str, LogFormat] = {}
    for t in sorted(formats, key=lambda t: (fmt_at[t], t)):
        f = formats[t]
        if f.name in by_name:
            issues.append(f"{p.name}: FMT types {by_name[f.name].type} and {t} are both "
                          f"named {f.name!r}; kept type {by_name[f.name].type}, dropped "
                          f"{int(counts[t])} message(s) of type {t}")
            if counts[t]:
                lost[f"type {t} ({f.name!r} again)"] = int(counts[t])
            del formats[t]
        else:
            by_name[f.name] = f
    return by_name


def _one_bit_apart(a: str, b: str) -> bool:
    """Whether names ``a`` and ``b`` differ by one flipped bit (same length, one character)."""
    if len(a) != len(b):
        return False
    diff = [ord(x) ^ ord(y) for x, y in zip(a, b, strict=True) if x != y]
    return len(diff) == 1 and diff[0] & (diff[0] - 1) == 0


def _renamed(p: Path, by_name: dict[str, LogFormat]) -> list[str]:
    """Types whose FMT name looks damaged: their layout (format and columns) is exactly that
    of a message tlm knows which the log does not define, and their name is one flipped bit
    from that message's (e.g. RATE's FMT read as 'RAUE', so that every RATE message is read
    under another name). The bit test keeps real messages of the same layout apart: a log cut
    before XKF1's FMT still holds NKF1, whose layout is XKF1's."""
    from .schema import SCHEMAS

    layouts = {(s.fmt, s.columns): n for n, s in SCHEMAS.items() if n not in by_name}
    out = []
    for name, f in by_name.items():
        known = SCHEMAS.get(name)
        if known is not None and (known.fmt, known.columns) == (f.format, f.columns):
            continue
        was = layouts.get((f.format, f.columns))
        if was is not None and _one_bit_apart(name, was):
            out.append(f"{p.name}: type {f.type} is named {name!r} but has the layout of "
                       f"{was}, which the log does not define: a damaged FMT name? (its "
                       f"messages are read as {name}, none as {was})")
    return out


def _damage(p: Path, data: np.ndarray, stats: np.ndarray, unknown: np.ndarray,
            rejected_at: np.ndarray, lost: dict[str, int]) -> list[str]:
    """Issues for skipped bytes and FMT messages the scan rejected or ignored; the message
    headers met in skipped bytes go into ``lost`` (per type id)."""
    skipped, runs, first, rejected, _, conflicts, first_conflict, _ = (int(x) for x in stats)
    heads: dict[str, int] = {}
    for t in np.flatnonzero(unknown):
        r = int(rejected_at[t])
        label = f"type {t}" if r < 0 else f"type {t} ({_fmt_name(data, r)!r}, damaged FMT)"
        heads[label] = int(unknown[t])
    lost.update(heads)
    issues = []
    if skipped:
        what = f"; lost messages: {_lost_text(heads)}" if heads else ""
        issues.append(
            f"{p.name}: skipped {skipped} bytes that are not messages "
            f"({runs} place{'s' if runs != 1 else ''}, first at byte {first}{what})"
        )
    if rejected:
        issues.append(f"{p.name}: ignored {rejected} damaged FMT message(s)")
    if conflicts:
        t = int(data[first_conflict + _F_TYPE])
        issues.append(
            f"{p.name}: ignored {conflicts} FMT message(s) redefining a type differently "
            f"(first at byte {first_conflict}: type {t} as {_fmt_name(data, first_conflict)!r}); "
            "kept the first definition"
        )
    return issues


def scan_bin(path: str | os.PathLike) -> BinIndex:
    """Index a DataFlash file (one pass; see the module docstring for damaged input).

    Raises:
        FileNotFoundError: no such file.
        BinLogError: not a regular file, empty file, or no valid FMT message (not a DataFlash
            log).
    """
    p, data = read_bytes(path)
    ordered, bounds, fmt_at, stats, unknown, rejected_at = _scan(data, _CHAR_SIZES)
    counts = np.diff(bounds)
    lost: dict[str, int] = {}
    issues = _damage(p, data, stats, unknown, rejected_at, lost)
    formats = _formats(p, data, fmt_at, counts, lost, issues)
    if len(formats) == 1 and fmt_at[FMT_TYPE] < 0:
        what = "no FMT message" if not counts[FMT_TYPE] else "no valid FMT message"
        raise BinLogError(f"{p}: not an ArduPilot DataFlash log ({what})")
    by_name = _by_name(p, formats, fmt_at, counts, lost, issues)
    issues += _renamed(p, by_name)
    offsets: dict[int, np.ndarray] = {}
    for t in formats:
        a, b = bounds[t], bounds[t + 1]
        if b > a:
            offsets[t] = ordered[a:b]  # views of one array
    return BinIndex(
        path=p, data=data, formats=formats, by_name=by_name, offsets=offsets,
        skipped_bytes=int(stats[0]), skipped_runs=int(stats[1]), first_skipped=int(stats[2]),
        rejected_fmt=int(stats[3]), conflicting_fmt=int(stats[5]), tail_bytes=int(stats[7]),
        lost=lost, issues=issues,
    )
