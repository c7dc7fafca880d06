"""File names of a data set folder, in one place: what tlm writes, and so all it may delete.

``DS`` holds ``manifest.json``, ``flights.jsonl``, ``manifest.parquet``, one folder per table
(``<TABLE>.parquet``, TABLE a message tlm_sim logs or ``faults``) and ``bin``. Inside a table
folder: per-flight parts ``flight-NNNNNNNN.parquet`` and block files
``flights-AAAAAAAA-BBBBBBBB.parquet`` (:mod:`~tlm_process.generate.compact`); inside ``bin``:
``flight-NNNNNNNN.bin``. Every file is first written under its temporary name ``.<name>.tmp``
(hidden: Parquet readers skip it) and then renamed. tlm deletes nothing else, and follows no
symbolic link: a table or ``bin`` folder that is a link is refused (:func:`owned_dirs`).
"""

from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

from tlm_process.cliutil import WRITE_PROBE
from tlm_process.generate.errors import GenerateError

__all__ = ["BIN_DIR", "BLOCK_RE", "PART_RE", "ROOT_FILES", "WRITE_PROBE", "owned_dirs",
           "part_name", "table_names", "tmp_name", "tmp_target"]

BIN_DIR = "bin"
#: a per-flight part (table folders: .parquet; bin: .bin)
PART_RE = re.compile(r"^flight-(\d{8})\.(parquet|bin)$")
#: a block file of compacted flights
BLOCK_RE = re.compile(r"^flights-(\d{8})-(\d{8})\.parquet$")
#: files tlm writes at the top of a data set (plus its write probe)
ROOT_FILES = ("manifest.json", "flights.jsonl", "manifest.parquet")
_TMP_RE = re.compile(r"^\.(.+)\.tmp$")


def part_name(flight: int, suffix: str = "parquet") -> str:
    """File name of flight ``flight``'s part (8 digits, so names sort by flight)."""
    return f"flight-{flight:08d}.{suffix}"


def tmp_name(name: str) -> str:
    """The hidden temporary name ``name`` is written under before its rename."""
    return f".{name}.tmp"


def tmp_target(name: str) -> str | None:
    """The file a temporary name stands for (``.x.tmp`` -> ``x``), None for another name."""
    m = _TMP_RE.match(name)
    return m.group(1) if m else None


@lru_cache(maxsize=1)
def table_names() -> frozenset[str]:
    """Names of the table folders tlm may write (without ``.parquet``)."""
    from tlm_sim.flightlog.schema import LOGGED_MESSAGES

    return frozenset((*LOGGED_MESSAGES, "faults"))


def owned_dirs(root: Path) -> list[Path]:
    """The table folders and ``bin`` folder of data set ``root`` that exist, sorted by name.

    Raises GenerateError when one of them is a symbolic link (tlm would write, clean or read
    files outside the data set through it) or not a folder."""
    names = sorted(f"{t}.parquet" for t in table_names()) + [BIN_DIR]
    out = []
    for name in names:
        p = root / name
        if p.is_symlink():
            raise GenerateError(f"{p} is a symbolic link: tlm writes, cleans and reads only real "
                                "folders inside a data set; replace it with the folder itself")
        if p.exists():
            if not p.is_dir():
                raise GenerateError(f"{p} is not a folder: it is not part of a tlm data set; "
                                    "move it away")
            out.append(p)
    return out
