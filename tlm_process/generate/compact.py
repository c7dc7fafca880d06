"""Compacting a data set: each table's per-flight parts merged into one file per block of flights.

A run writes one Parquet part per flight and table (``DS/GPS.parquet/flight-00000042.parquet``),
which keeps writes atomic and runs resumable, but leaves ~20 files per flight: 200,000 for
10,000 flights, slow to list and to read. :func:`compact_dataset` (``tlm generate
--compact``) merges the parts of finished flights into block files of ``block`` flight
indices, ``DS/GPS.parquet/flights-00000000-00000099.parquet`` (flights 0..99), written
streaming (one flight's rows after the other, so memory stays at one flight's table), renamed
into place, and only then are the merged parts deleted. Each block file records its flights
and their row counts in the Parquet key-value metadata (``tlm.flights``).

While it runs, the header's state is ``compacting`` (set before the first block is written,
set back after the last part is deleted). A compaction killed between a block's rename and
its parts' deletion leaves flights in two files: the tlm loader
(:mod:`tlm_process.generate.reader`) reads the block's copy only, refuses a ``compacting``
data set unless asked for a partial read, and opening the data set again
(:func:`drop_compacted_parts`) deletes the extra parts. ``pandas.read_parquet`` of a table
folder reads block files and parts alike, so it reads such flights twice: it is exact only
for a data set whose state is ``complete``. Rows come in file-name order (parts of flights
flown after the last compaction first), so sort by ``flight`` when order matters. A block
that gains flights later (a continued run) is rewritten with them, in flight order.
"""

from __future__ import annotations

import json
import os
from collections import defaultdict
from collections.abc import Collection, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from tlm_process.generate.errors import GenerateError
from tlm_process.generate.layout import BLOCK_RE, PART_RE, owned_dirs, tmp_name
from tlm_process.generate.parts import parquet_options

__all__ = ["BLOCK_FLIGHTS", "block_flights", "block_name", "compact_dataset",
           "drop_compacted_parts", "open_parquet", "read_parquet_table"]

#: flight indices per block file
BLOCK_FLIGHTS = 100
#: key-value metadata of a block file: JSON list of [flight, rows]
FLIGHTS_KEY = b"tlm.flights"
#: header state while a compaction runs
COMPACTING = "compacting"


@contextmanager
def open_parquet(path: Path) -> Iterator[pq.ParquetFile]:
    """A ParquetFile of ``path``, opened through Python (pyarrow cannot open a path that is
    not valid UTF-8)."""
    with path.open("rb") as fh, pq.ParquetFile(fh) as pf:
        yield pf


def read_parquet_table(path: Path) -> pa.Table:
    """The whole Parquet file ``path`` as an Arrow table (see :func:`open_parquet`)."""
    with open_parquet(path) as pf:
        return pf.read()


def block_name(k: int, block: int = BLOCK_FLIGHTS) -> str:
    """File name of block ``k`` (flights ``k*block`` .. ``(k+1)*block - 1``)."""
    return f"flights-{k * block:08d}-{(k + 1) * block - 1:08d}.parquet"


def _flights_meta(schema: pa.Schema) -> list[tuple[int, int]]:
    meta = schema.metadata or {}
    return [(int(f), int(n)) for f, n in json.loads(meta.get(FLIGHTS_KEY, b"[]"))]


def block_flights(path: Path) -> list[tuple[int, int]]:
    """(flight, rows) of every flight a block file holds, from its footer alone.

    Raises GenerateError when the file is not a readable block file."""
    try:
        with open_parquet(path) as pf:
            return _flights_meta(pf.schema_arrow)
    except (ValueError, TypeError, pa.ArrowException) as exc:
        raise GenerateError(f"cannot read block file {path}: {str(exc).splitlines()[0]}; "
                            "delete it and run the same tlm generate command again (its "
                            "flights are flown again)") from None


def flight_row_groups(pf: pq.ParquetFile) -> dict[int, list[int]]:
    """Row groups of each flight of an open block file (a flight with more rows than
    pyarrow's row group limit spans several; a flight without rows has none)."""
    sizes = [pf.metadata.row_group(i).num_rows for i in range(pf.num_row_groups)]
    out: dict[int, list[int]] = {}
    g = 0
    for flight, rows in _flights_meta(pf.schema_arrow):
        groups: list[int] = []
        while rows > 0 and g < len(sizes):
            groups.append(g)
            rows -= sizes[g]
            g += 1
        if rows != 0:
            raise ValueError(f"{pf.metadata} row groups do not match its tlm.flights list")
        out[flight] = groups
    return out


def _table_dirs(root: Path) -> list[Path]:
    return [d for d in owned_dirs(root) if d.name.endswith(".parquet")]


def _parts(d: Path) -> dict[int, Path]:
    out = {}
    for p in d.iterdir():
        m = PART_RE.match(p.name)
        if m and m.group(2) == "parquet":
            out[int(m.group(1))] = p
    return out


def drop_compacted_parts(root: Path) -> int:
    """Delete the parts of flights that a block file of the same table already holds;
    returns how many were deleted."""
    dropped = 0
    for d in _table_dirs(root):
        parts = _parts(d)
        for blk in d.iterdir():
            if BLOCK_RE.match(blk.name):
                for flight, _ in block_flights(blk):
                    if flight in parts:
                        parts.pop(flight).unlink()
                        dropped += 1
    return dropped


Source = Path | tuple[pq.ParquetFile, list[int]] | None  # a part, an old block's rows, none


def _write_block(target: Path, sources: dict[int, Source], rows: dict[int, int],
                 schema: pa.Schema) -> None:
    """Stream the flights of ``sources`` into ``target`` atomically, in flight order, one
    flight in memory at a time."""
    order = sorted(sources)
    meta = dict(schema.metadata or {})
    meta[FLIGHTS_KEY] = json.dumps([[f, rows[f]] for f in order]).encode()
    schema = schema.with_metadata(meta)
    tmp = target.with_name(tmp_name(target.name))
    try:
        with tmp.open("wb") as fh, pq.ParquetWriter(fh, schema,
                                                     **parquet_options(schema)) as writer:
            for f in order:
                src = sources[f]
                if src is None:
                    continue
                table = (read_parquet_table(src) if isinstance(src, Path)
                         else src[0].read_row_groups(src[1]))
                writer.write_table(table.replace_schema_metadata(meta))
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _set_state(root: Path, state: str) -> str:
    """Set the header's state (atomically); returns the state it had."""
    from tlm_process.generate.manifest import HEADER, read_header, write_json_atomic

    header = read_header(root) or {}
    before = str(header.get("state", ""))
    write_json_atomic(root / HEADER, {**header, "state": state})
    return before


def _plan(root: Path, ok: set[int], block: int) -> list[tuple[Path, int, dict[int, Path]]]:
    """(table folder, block index, {flight: part}) of every block that gains parts."""
    plan = []
    for d in _table_dirs(root):
        by_block: dict[int, dict[int, Path]] = defaultdict(dict)
        for flight, path in _parts(d).items():
            if flight in ok:
                by_block[flight // block][flight] = path
        plan.extend((d, k, members) for k, members in sorted(by_block.items()))
    return plan


def compact_dataset(root: str | os.PathLike, ok: Collection[int],
                    block: int | None = None) -> int:
    """Merge the parts of the flights ``ok`` into block files of ``block`` flight indices
    (default :data:`BLOCK_FLIGHTS`; see the module docstring); returns how many part files
    were merged. The header says ``compacting`` meanwhile (see the module docstring); when
    this raises, the state it had before is put back."""
    root = Path(root)
    block = BLOCK_FLIGHTS if block is None else int(block)
    plan = _plan(root, set(ok), block)
    if not plan:
        return 0
    before = _set_state(root, COMPACTING)
    merged = 0
    try:
        for d, k, members in plan:
            merged += _merge_block(d / block_name(k, block), members)
    except BaseException:
        drop_compacted_parts(root)  # if this fails too, the state stays "compacting"
        _set_state(root, before)
        raise
    _set_state(root, before)
    return merged


def _merge_block(target: Path, members: dict[int, Path]) -> int:
    """Write block ``target`` with the flights it holds and the parts ``members``, then
    delete the parts; returns how many were deleted."""
    sources: dict[int, Source] = {}
    rows: dict[int, int] = {}
    schema: Any = None
    with _maybe_open(target) as old:
        if old is not None:
            schema = old.schema_arrow
            groups = flight_row_groups(old)
            for flight, n in block_flights(target):
                rows[flight] = n
                sources[flight] = (old, groups[flight]) if n else None
        for flight in sorted(members):
            if flight in sources:
                continue  # already in the block (a killed compaction): just drop the part
            path = members[flight]
            with open_parquet(path) as pf:
                schema = schema or pf.schema_arrow
                rows[flight] = pf.metadata.num_rows
            sources[flight] = path if rows[flight] else None
        _write_block(target, sources, rows, schema)
    for path in members.values():
        path.unlink()
    return len(members)


@contextmanager
def _maybe_open(path: Path) -> Iterator[pq.ParquetFile | None]:
    if not path.exists():
        yield None
        return
    with open_parquet(path) as pf:
        yield pf
