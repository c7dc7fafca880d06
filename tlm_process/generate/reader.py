"""Reading a generated data set: the one loader that trusts the journal alone.

A flight is part of a data set iff its last line in ``DS/flights.jsonl`` says ``ok`` (its
commit record, see :mod:`tlm_process.generate.writer`). :func:`read_dataset_table` reads a
table of exactly those flights, each from exactly one file: a block file's rows when a block
holds it (:mod:`tlm_process.generate.compact`), else its part, else (a run killed between the
flight's journal line and its renames) its complete temporary part. Parts of flights without
an ok line, and parts a block already holds, are not read; :attr:`DatasetIndex.ignored` lists
them. Rows come in flight order.

The manifest's state says whether the data set is whole. Only a ``complete`` one is read by
default; ``running`` (a run is writing it or was killed), ``incomplete`` (a run stopped early
or flights failed) and ``compacting`` (a compaction runs or was killed) raise a one-line
:class:`~tlm_process.generate.errors.GenerateError` naming the state and the fix, unless
``partial=True`` asks for the committed flights only. A ``complete`` data set whose journal
does not list every flight as ok, or a committed flight whose part is gone, is refused
always. Typical use::

    from tlm_process.generate import read_dataset_table

    gps = read_dataset_table("ds", "GPS")          # flight, TimeUS, ... of every flight
    faults = read_dataset_table("ds", "faults")    # Eq. 4 records, one row per fault

``pandas.read_parquet("ds/GPS.parquet")`` reads the same rows only for a ``complete`` data set
(after a kill it may read a killed compaction's flights twice, or miss the parts of the flight
being committed); see ``docs/generate.md``, "What a kill can lose".
"""

from __future__ import annotations

import os
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc

from tlm_process.generate.compact import (
    FLIGHTS_KEY,
    block_flights,
    flight_row_groups,
    open_parquet,
)
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.layout import BLOCK_RE, PART_RE, owned_dirs, part_name, tmp_target
from tlm_process.generate.manifest import HEADER, read_header, read_journal

__all__ = ["STATES", "DatasetIndex", "index_dataset", "read_dataset_table"]

COMPLETE = "complete"
#: what each manifest state means
STATES: dict[str, str] = {
    "complete": "every flight is in it",
    "running": "a run is writing it, or was killed",
    "incomplete": "its last run stopped early or some flights failed",
    "compacting": "a compaction is running, or was killed",
}
_FIX = "run the same tlm generate command again to finish it"


@dataclass(frozen=True)
class DatasetIndex:
    """What :func:`index_dataset` found: the header, the manifest ``state``, ``flights`` N,
    the ``committed`` flights (ok in the journal), the ``tables`` with files, the files not
    read (``ignored``, relative to ``root``), and ``skipped_lines`` (journal lines that could
    not be read: a line cut by a kill). ``partial``: whether the data set is read although
    it is not complete."""

    root: Path
    header: dict[str, Any]
    state: str
    flights: int
    committed: tuple[int, ...]
    tables: tuple[str, ...]
    ignored: tuple[str, ...]
    skipped_lines: int
    partial: bool
    sources: dict[str, dict[int, Path]] = field(repr=False)

    @property
    def whole(self) -> bool:
        """Whether the data set is complete (every flight 0..N-1 committed)."""
        return self.state == COMPLETE

    def summary(self) -> dict[str, Any]:
        """JSON-ready description (for reports)."""
        return {"path": str(self.root), "state": self.state, "flights": self.flights,
                "committed": len(self.committed), "partial": self.partial,
                "ignored_files": len(self.ignored), "skipped_journal_lines": self.skipped_lines}


def _state_error(root: Path, state: str, n_ok: int, n: int) -> GenerateError:
    what = STATES.get(state, "not a state tlm writes")
    return GenerateError(f"{root} is not complete (state {state}: {what}; {n_ok} of {n} "
                         f"flights finished): {_FIX}, or read the finished flights only "
                         "(tlm process --partial; partial=True)")


def _resolve_dir(d: Path, committed: set[int]) -> tuple[dict[int, Path], list[Path]]:
    """(flight -> the file to read it from, files not read) of table folder ``d``."""
    names = sorted(p.name for p in d.iterdir())
    src: dict[int, Path] = {}
    ignored: list[Path] = []
    for name in names:
        if BLOCK_RE.match(name):
            for flight, _ in block_flights(d / name):
                if flight in committed and flight not in src:
                    src[flight] = d / name
    for name in names:
        m = PART_RE.match(name)
        if m is not None and m.group(2) == "parquet":
            f = int(m.group(1))
            if f in committed and f not in src:
                src[f] = d / name
            else:
                ignored.append(d / name)
    for name in names:
        target = tmp_target(name)
        m = PART_RE.match(target or "")
        if m is not None and int(m.group(1)) in committed and int(m.group(1)) not in src:
            src[int(m.group(1))] = d / name  # committed, killed before its rename
        elif target is not None:
            ignored.append(d / name)
    return src, ignored


def index_dataset(ds: str | os.PathLike, *, partial: bool = False) -> DatasetIndex:
    """Find the file of every committed flight of every table of data set ``ds`` (see the
    module docstring). Raises GenerateError: not a data set, not complete (unless
    ``partial``), or inconsistent (a committed flight's part missing, a ``complete``
    manifest whose journal lacks flights)."""
    root = Path(ds)
    header = read_header(root)
    if header is None:
        raise GenerateError(f"{root} is not a tlm data set (no {HEADER})")
    state, n = str(header.get("state")), int(header.get("flights") or 0)
    entries, skipped = read_journal(root)
    committed = {f for f, e in entries.items() if e.get("status") == "ok" and f < n}
    if state == COMPLETE and len(committed) != n:
        raise GenerateError(f"{root} is inconsistent: its manifest says complete but the "
                            f"journal lists {len(committed)} of {n} flights as finished; "
                            f"{_FIX}")
    if state != COMPLETE and not partial:
        raise _state_error(root, state, len(committed), n)
    sources: dict[str, dict[int, Path]] = {}
    ignored: list[Path] = []
    for d in owned_dirs(root):
        if d.name.endswith(".parquet"):
            sources[d.name[: -len(".parquet")]], skip = _resolve_dir(d, committed)
            ignored.extend(skip)
    _check_committed(root, entries, committed, sources)
    return DatasetIndex(root, header, state, n, tuple(sorted(committed)),
                        tuple(sorted(sources)), tuple(str(p.relative_to(root)) for p in ignored),
                        skipped, partial, sources)


def _check_committed(root: Path, entries: dict[int, dict[str, Any]], committed: set[int],
                     sources: dict[str, dict[int, Path]]) -> None:
    """Raise GenerateError when a committed flight lacks a part its journal line lists."""
    for f in sorted(committed):
        for table in entries[f].get("parts") or []:
            if f not in sources.get(table, {}):
                raise GenerateError(
                    f"{root} is damaged: flight {f}'s {table} part ({table}.parquet/"
                    f"{part_name(f)}) is gone though the journal lists the flight as "
                    f"finished; {_FIX} (it flies that flight again)")


def _read_pieces(files: dict[Path, list[int]]) -> list[pa.Table]:
    """The rows of the given flights of each file (a part: all; a block: their row groups)."""
    pieces = []
    for path, flights in files.items():
        try:
            with open_parquet(path) as pf:
                if BLOCK_RE.match(path.name):
                    groups = flight_row_groups(pf)
                    rg = [g for f in sorted(flights) for g in groups.get(f, [])]
                    table = pf.read_row_groups(rg) if rg else None
                else:
                    table = pf.read()
        except (OSError, ValueError, pa.ArrowException) as exc:
            raise GenerateError(f"cannot read {path}: {str(exc).splitlines()[0]} (a file cut "
                                "short by a power cut? delete it and run the same tlm "
                                "generate command again)") from None
        if table is not None:
            pieces.append(table)
    return pieces


def _empty_table(d: Path) -> pa.Table:
    for p in sorted(d.iterdir()):
        if PART_RE.match(p.name) or BLOCK_RE.match(p.name):
            with open_parquet(p) as pf:
                return pf.schema_arrow.empty_table()
    return pa.table({"flight": pa.array([], pa.int32())})


def read_dataset_table(ds: str | os.PathLike | DatasetIndex, table: str, *,
                       partial: bool = False) -> pd.DataFrame:
    """Table ``table`` (``"GPS"``, ``"faults"``, ...) of the committed flights of data set
    ``ds`` (a folder, or a :class:`DatasetIndex` to read several tables from one listing),
    in flight order, with its ``flight`` column; see the module docstring. ``partial``:
    read a data set that is not complete (its committed flights).

    Raises GenerateError: see :func:`index_dataset`; no such table."""
    idx = ds if isinstance(ds, DatasetIndex) else index_dataset(ds, partial=partial)
    if table not in idx.sources:
        raise GenerateError(f"{idx.root} has no table {table} (tables: "
                            f"{', '.join(idx.tables) or 'none'})")
    by_file: dict[Path, list[int]] = defaultdict(list)
    for f, path in sorted(idx.sources[table].items()):
        by_file[path].append(f)
    pieces = _read_pieces(dict(by_file))
    if not pieces:
        return _empty_table(idx.root / f"{table}.parquet").to_pandas()
    meta = {k: v for k, v in (pieces[0].schema.metadata or {}).items() if k != FLIGHTS_KEY}
    merged = pa.concat_tables([t.replace_schema_metadata(meta) for t in pieces])
    flight = merged.column("flight")
    if len(flight) > 1 and not pc.all(pc.greater_equal(flight[1:], flight[:-1])).as_py():
        merged = merged.take(pc.sort_indices(merged, sort_keys=[("flight", "ascending")]))
    return merged.to_pandas()
