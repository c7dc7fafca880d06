"""Writing a data set folder: per-flight Parquet parts, atomically, and the journal.

Layout (``DS`` = the output folder)::

    DS/manifest.json                 header (settings, state, runs)   see manifest.py
    DS/flights.jsonl                 journal, one line per finished flight
    DS/manifest.parquet              the journal as a table
    DS/GPS.parquet/flight-00000000.parquet    one part per flight and table, `flight` column
    DS/IMU.parquet/...                        (pandas.read_parquet("DS/GPS.parquet") reads all)
    DS/faults.parquet/flight-00000000.parquet Eq. 4 records (zero rows: no faults)
    DS/bin/flight-00000000.bin       with --bin

A flight is written part by part, each to a hidden temporary name (``.flight-....tmp``, which
Parquet readers skip) and renamed into place; its journal line is appended after the last
rename. A flight without a journal line does not count: when a data set is opened again, its
parts (left by a hard kill between the renames and the journal line) and any temporary files
are removed. So an interrupted run loses at most the flights that were being written.
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from tlm_process.generate.compact import drop_compacted_parts
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.manifest import (
    FORMAT,
    FORMAT_VERSION,
    HEADER,
    JOURNAL,
    MANIFEST_TABLE,
    check_compatible,
    manifest_frame,
    read_header,
    read_journal,
    write_json_atomic,
)

__all__ = ["BIN_DIR", "DatasetWriter", "part_name"]

BIN_DIR = "bin"
_PART_RE = re.compile(r"^flight-(\d+)\.(parquet|bin)$")


def part_name(flight: int, suffix: str = "parquet") -> str:
    """File name of flight ``flight``'s part (8 digits, so names sort by flight)."""
    return f"flight-{flight:08d}.{suffix}"


def _write_atomic(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("wb") as fh:
        fh.write(data)
    os.replace(tmp, path)


class DatasetWriter:
    """Puts finished flights into data set folder ``root`` (see the module docstring)."""

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)
        self.header: dict[str, Any] = {}
        self.status: dict[int, str] = {}
        self._journal: Any = None
        self._dirs: set[str] = set()

    # -- opening ------------------------------------------------------------------------
    def open(self, wanted: Mapping[str, Any]) -> dict[int, str]:
        """Create or reopen the data set for a run with header fields ``wanted`` (format,
        versions, seed, settings, flights); returns the status ("ok" / "failed") of every
        flight the journal lists.

        Raises GenerateError: the folder cannot be written, holds something else than a tlm
        data set, or a data set made with other settings."""
        root = self.root
        try:
            root.mkdir(parents=True, exist_ok=True)
            probe = root / ".tlm-write-test"
            probe.write_bytes(b"")
            probe.unlink()
        except OSError as exc:
            raise GenerateError(f"cannot write to output folder {root}: "
                                f"{exc.strerror or exc}") from None
        header = read_header(root)
        if header is None:
            foreign = [p.name for p in root.iterdir() if not p.name.startswith(".")]
            if foreign:
                raise GenerateError(f"{root} is not empty and holds no tlm data set "
                                    f"({foreign[0]}, ...); use a new or empty --out folder")
            header = {"format": FORMAT, "format_version": FORMAT_VERSION, "runs": []}
        else:
            check_compatible(header, wanted, root)
        entries, bad = read_journal(root)
        self.status = {f: str(e.get("status")) for f, e in entries.items()}
        self._clean({f for f, st in self.status.items() if st == "ok"})
        if bad or not self._journal_clean(len(entries)):
            self._rewrite_journal(entries)
        del entries
        self.header = {**header, **{k: v for k, v in wanted.items() if k != "flights"}}
        self.header["flights"] = max(int(header.get("flights", 0)), int(wanted["flights"]))
        self.header["state"] = "running"
        self.header.setdefault("runs", [])
        write_json_atomic(root / HEADER, self.header)
        self._journal = (root / JOURNAL).open("a", encoding="utf-8")
        return dict(self.status)

    def _journal_clean(self, n_entries: int) -> bool:
        """One line per flight and a final newline (so appending starts a new line)."""
        path = self.root / JOURNAL
        if not path.exists():
            return True
        with path.open("rb") as fh:
            lines = sum(1 for line in fh if line.strip())
            if lines == 0:
                return True
            fh.seek(-1, os.SEEK_END)
            return lines == n_entries and fh.read(1) == b"\n"

    def _rewrite_journal(self, entries: Mapping[int, Mapping[str, Any]]) -> None:
        path = self.root / JOURNAL
        tmp = path.with_name(f".{path.name}.tmp")
        with tmp.open("w", encoding="utf-8") as fh:
            for flight in sorted(entries):
                fh.write(json.dumps(entries[flight]) + "\n")
        os.replace(tmp, path)

    def _clean(self, ok: set[int]) -> None:
        """Remove temporary files, the parts of flights the journal does not list as ok, and
        parts a block file already holds (see :mod:`tlm_process.generate.compact`)."""
        drop_compacted_parts(self.root)
        for d in self.root.iterdir():
            if d.name.startswith(".") and d.is_file():
                d.unlink()
                continue
            if not d.is_dir() or not (d.name.endswith(".parquet") or d.name == BIN_DIR):
                continue
            for p in d.iterdir():
                m = _PART_RE.match(p.name)
                if p.name.startswith(".") or (m is not None and int(m.group(1)) not in ok):
                    p.unlink()

    # -- writing ------------------------------------------------------------------------
    def put(self, result: Mapping[str, Any]) -> dict[str, Any]:
        """Write a finished flight (a :func:`~tlm_process.generate.task.fly_job` result):
        its parts, its ``.bin`` and then its journal line; returns the journal entry."""
        flight = int(result["flight"])
        ok = result.get("status") == "ok"
        nbytes = 0
        parts = sorted(result.get("parts") or {}) if ok else []
        for name in parts:
            data = result["parts"][name]
            d = self.root / f"{name}.parquet"
            if name not in self._dirs:
                d.mkdir(exist_ok=True)
                self._dirs.add(name)
            _write_atomic(d / part_name(flight), data)
            nbytes += len(data)
        if ok and result.get("bin") is not None:
            d = self.root / BIN_DIR
            d.mkdir(exist_ok=True)
            _write_atomic(d / part_name(flight, "bin"), result["bin"])
            nbytes += len(result["bin"])
        w = result.get("worker") or {}
        entry = {
            "flight": flight,
            "status": "ok" if ok else "failed",
            "scenario": result.get("scenario"),
            "summary": result.get("summary") or {},
            "timing": result.get("timing") or {},
            "worker": f"{w.get('host')}:{w.get('pid')}" if w else None,
            "parts": parts,
            "bytes": nbytes,
        }
        if not ok:
            entry["error"] = result.get("error")
            entry["traceback"] = result.get("traceback")
        self._journal.write(json.dumps(entry) + "\n")
        self._journal.flush()
        self.status[flight] = entry["status"]
        return entry

    # -- closing ------------------------------------------------------------------------
    def close(self, run: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Finish the run: sync the journal, write ``manifest.parquet`` and the header with
        the counts and state (``complete`` when every flight 0..N-1 is ok) and ``run`` added
        to its runs. Returns the header."""
        if self._journal is not None:
            self._journal.flush()
            os.fsync(self._journal.fileno())
            self._journal.close()
            self._journal = None
        n = int(self.header.get("flights", 0))
        ok = sum(1 for f, st in self.status.items() if st == "ok" and f < n)
        failed = sum(1 for f, st in self.status.items() if st != "ok" and f < n)
        frame = manifest_frame(read_journal(self.root)[0])
        tmp = self.root / f".{MANIFEST_TABLE}.tmp"
        frame.to_parquet(tmp, index=False)
        os.replace(tmp, self.root / MANIFEST_TABLE)
        self.header["counts"] = {"ok": ok, "failed": failed, "missing": n - ok - failed}
        self.header["state"] = "complete" if ok == n else "incomplete"
        if run is not None:
            self.header["runs"] = [*self.header.get("runs", []), dict(run)]
        write_json_atomic(self.root / HEADER, self.header)
        return self.header
