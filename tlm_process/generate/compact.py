"""Compacting a data set: each table's per-flight parts merged into one file per block of flights.

A run writes one Parquet part per flight and table (``DS/GPS.parquet/flight-00000042.parquet``),
which keeps writes atomic and runs resumable, but leaves ~20 files per flight: 200,000 for
10,000 flights, slow to list and to read. :func:`compact_dataset` (``tlm generate
--compact``) merges the parts of finished flights into block files of ``block`` flight
indices, ``DS/GPS.parquet/flights-00000000-00000099.parquet`` (flights 0..99), written
streaming (one row group per flight, so memory stays at one flight's table), renamed into
place, and only then are the merged parts deleted. Each block file records its flights and
their row counts in the Parquet key-value metadata (``tlm.flights``).

``pandas.read_parquet("DS/GPS.parquet")`` reads block files and parts alike; rows come in
file-name order (parts of flights flown after the last compaction first), so sort by
``flight`` when order matters. A block that gains flights later (a continued run) is
rewritten with them, in flight order. A part whose flight a block file already holds (a run
killed between the rename and the deletions) is deleted when the data set is opened again
(:func:`drop_compacted_parts`), so no flight is ever read twice.
"""

from __future__ import annotations

import json
import os
import re
from collections import defaultdict
from collections.abc import Collection
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq

from tlm_process.generate.parts import parquet_options

__all__ = ["BLOCK_FLIGHTS", "block_flights", "block_name", "compact_dataset",
           "drop_compacted_parts"]

#: flight indices per block file
BLOCK_FLIGHTS = 100
#: key-value metadata of a block file: JSON list of [flight, rows]
FLIGHTS_KEY = b"tlm.flights"
_PART_RE = re.compile(r"^flight-(\d+)\.parquet$")
_BLOCK_RE = re.compile(r"^flights-(\d+)-(\d+)\.parquet$")


def block_name(k: int, block: int = BLOCK_FLIGHTS) -> str:
    """File name of block ``k`` (flights ``k*block`` .. ``(k+1)*block - 1``)."""
    return f"flights-{k * block:08d}-{(k + 1) * block - 1:08d}.parquet"


def block_flights(path: Path) -> list[tuple[int, int]]:
    """(flight, rows) of every flight a block file holds, from its footer alone."""
    meta = pq.read_schema(path).metadata or {}
    return [(int(f), int(n)) for f, n in json.loads(meta.get(FLIGHTS_KEY, b"[]"))]


def _table_dirs(root: Path) -> list[Path]:
    return sorted(p for p in root.iterdir() if p.is_dir() and p.name.endswith(".parquet"))


def _parts(d: Path) -> dict[int, Path]:
    out = {}
    for p in d.iterdir():
        m = _PART_RE.match(p.name)
        if m:
            out[int(m.group(1))] = p
    return out


def drop_compacted_parts(root: Path) -> int:
    """Delete the parts of flights that a block file of the same table already holds;
    returns how many were deleted."""
    dropped = 0
    for d in _table_dirs(root):
        parts = _parts(d)
        for blk in d.iterdir():
            if _BLOCK_RE.match(blk.name):
                for flight, _ in block_flights(blk):
                    if flight in parts:
                        parts.pop(flight).unlink()
                        dropped += 1
    return dropped


Source = Path | tuple[pq.ParquetFile, int] | None  # a part, an old block's row group, no rows


def _write_block(target: Path, sources: dict[int, Source], rows: dict[int, int],
                 schema: pa.Schema) -> None:
    """Stream the flights of ``sources`` into ``target`` atomically, in flight order, one
    flight in memory at a time."""
    order = sorted(sources)
    meta = dict(schema.metadata or {})
    meta[FLIGHTS_KEY] = json.dumps([[f, rows[f]] for f in order]).encode()
    schema = schema.with_metadata(meta)
    tmp = target.with_name(f".{target.name}.tmp")
    with pq.ParquetWriter(tmp, schema, **parquet_options(schema)) as writer:
        for f in order:
            src = sources[f]
            if src is None:
                continue
            table = pq.read_table(src) if isinstance(src, Path) else src[0].read_row_group(src[1])
            writer.write_table(table.replace_schema_metadata(meta))
    os.replace(tmp, target)


def compact_dataset(root: str | os.PathLike, ok: Collection[int],
                    block: int | None = None) -> int:
    """Merge the parts of the flights ``ok`` into block files of ``block`` flight indices
    (default :data:`BLOCK_FLIGHTS`; see the module docstring); returns how many part files
    were merged."""
    root = Path(root)
    block = BLOCK_FLIGHTS if block is None else int(block)
    ok = set(ok)
    merged = 0
    for d in _table_dirs(root):
        by_block: dict[int, dict[int, Path]] = defaultdict(dict)
        for flight, path in _parts(d).items():
            if flight in ok:
                by_block[flight // block][flight] = path
        for k, members in sorted(by_block.items()):
            target = d / block_name(k, block)
            sources: dict[int, Source] = {}
            rows: dict[int, int] = {}
            schema = None
            old = pq.ParquetFile(target) if target.exists() else None
            if old is not None:
                schema = old.schema_arrow
                group = 0
                for flight, n in block_flights(target):
                    rows[flight] = n
                    sources[flight] = (old, group) if n else None
                    group += 1 if n else 0
            for flight in sorted(members):
                if flight in sources:
                    continue  # already in the block (a killed compaction): just drop the part
                path = members[flight]
                schema = schema or pq.read_schema(path)
                rows[flight] = pq.read_metadata(path).num_rows
                sources[flight] = path if rows[flight] else None
            assert schema is not None
            _write_block(target, sources, rows, schema)
            if old is not None:
                old.close()
            for path in members.values():
                path.unlink()
                merged += 1
    return merged
