"""Writing a data set folder: per-flight Parquet parts, atomically, and the journal.

Layout (``DS`` = the output folder; names in :mod:`tlm_process.generate.layout`)::

    DS/manifest.json                 header (settings, state, runs)   see manifest.py
    DS/flights.jsonl                 journal, one line per finished flight
    DS/manifest.parquet              the journal as a table
    DS/GPS.parquet/flight-00000000.parquet    one part per flight and table, `flight` column
    DS/IMU.parquet/...
    DS/faults.parquet/flight-00000000.parquet Eq. 4 records (zero rows: no faults)
    DS/bin/flight-00000000.bin       with --bin

The journal line is a flight's commit record: a flight is part of the data set iff its last
journal line says ok. :meth:`DatasetWriter.put` writes every part of a flight under its
hidden temporary name (``.flight-....parquet.tmp``, which Parquet readers skip), then appends
the journal line, then renames the parts into place (the fault records first). So a flight
whose journal line is missing has no visible part at all, and a flight killed between its
journal line and the last rename is rolled forward (its temporary parts renamed) when the
data set is opened again; other temporary files are removed then, as are the visible parts of
flights without an ok line (a data set written by an older tlm). An interrupted run loses at
most the flights that were being written. Read a data set with
:mod:`tlm_process.generate.reader`, which trusts the journal alone.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tlm_process.cliutil import UsageError, foreign_entries, prepare_out

if TYPE_CHECKING:
    import pandas as pd
from tlm_process.generate.compact import block_flights, drop_compacted_parts
from tlm_process.generate.errors import GenerateError
from tlm_process.generate.layout import (
    BIN_DIR,
    BLOCK_RE,
    PART_RE,
    ROOT_FILES,
    WRITE_PROBE,
    owned_dirs,
    part_name,
    tmp_name,
    tmp_target,
)
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

#: what to do after a failed write
_AGAIN = "free space or fix the folder, then run the same command again to continue"

#: the data set card (tlm_process.generate.card), rewritten when a run closes
CARD = "README.md"


def _why(exc: OSError) -> str:
    """``strerror (file)`` of an OSError, in one line."""
    where = f" ({exc.filename})" if exc.filename else ""
    return f"{exc.strerror or exc}{where}"


def _write_file(path: Path, data: bytes) -> None:
    with path.open("wb") as fh:
        fh.write(data)


def _unlink_quietly(paths: Iterable[Path]) -> None:
    for p in paths:
        try:
            p.unlink()
        except OSError:
            pass


class DatasetWriter:
    """Puts finished flights into data set folder ``root`` (see the module docstring)."""

    def __init__(self, root: str | os.PathLike) -> None:
        self.root = Path(root)
        self.header: dict[str, Any] = {}
        self.status: dict[int, str] = {}
        self._journal: int | None = None  # file descriptor, O_APPEND
        self._dirs: set[str] = set()

    # -- opening ------------------------------------------------------------------------
    def open(self, wanted: Mapping[str, Any]) -> dict[int, str]:
        """Create or reopen the data set for a run with header fields ``wanted`` (format,
        versions, seed, settings, flights); returns the status ("ok" / "failed") of every
        flight the journal lists.

        Raises GenerateError: the folder cannot be written, holds something else than a tlm
        data set, a table or bin folder that is a symbolic link, or a data set made with
        other settings."""
        root = self.root
        try:
            prepare_out(root)
        except UsageError as exc:
            raise GenerateError(str(exc)) from None
        header = read_header(root)
        if header is None:
            foreign = foreign_entries(root)
            if foreign:
                raise GenerateError(f"{root} is not empty and holds no tlm data set "
                                    f"({foreign[0]}, ...); use a new or empty --out folder")
            header = {"format": FORMAT, "format_version": FORMAT_VERSION, "runs": []}
        else:
            check_compatible(header, wanted, root)
        owned_dirs(root)  # refuses symbolic links before anything is renamed or deleted
        entries, bad = read_journal(root)
        self.status = {f: str(e.get("status")) for f, e in entries.items()}
        self.header = {**header, **{k: v for k, v in wanted.items() if k != "flights"}}
        self.header["flights"] = max(int(header.get("flights", 0)), int(wanted["flights"]))
        self.header["state"] = "running"
        self.header.setdefault("runs", [])
        try:
            self._clean({f for f, st in self.status.items() if st == "ok"})
            lost = self._drop_damaged(entries)
            if lost or bad or not self._journal_clean(len(entries)):
                self._rewrite_journal(entries)
            write_json_atomic(root / HEADER, self.header)
            self._journal = os.open(root / JOURNAL, os.O_WRONLY | os.O_APPEND | os.O_CREAT,
                                    0o644)
        except OSError as exc:
            raise GenerateError(f"cannot open data set {root}: {_why(exc)}") from None
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
        tmp = path.with_name(tmp_name(path.name))
        with tmp.open("w", encoding="utf-8") as fh:
            for flight in sorted(entries):
                fh.write(json.dumps(entries[flight]) + "\n")
        os.replace(tmp, path)

    def _clean(self, ok: set[int]) -> None:
        """Put the folder in the state the journal describes, touching only tlm's own names
        (:mod:`~tlm_process.generate.layout`): remove tlm's temporary files at the top, parts
        a block file already holds (see :mod:`tlm_process.generate.compact`), and in the
        table and bin folders the parts of flights the journal does not list as ok; rename
        the temporary parts of ok flights into place (a kill between a flight's journal line
        and its renames) and remove every other temporary file there."""
        for name in (*ROOT_FILES, WRITE_PROBE):
            _unlink_quietly([self.root / tmp_name(name)] if name != WRITE_PROBE
                            else [self.root / name])
        drop_compacted_parts(self.root)
        for d in owned_dirs(self.root):
            names = {p.name for p in d.iterdir()}
            in_blocks = {f for n in names if BLOCK_RE.match(n)
                         for f, _ in block_flights(d / n)}
            for name in sorted(names):
                self._clean_one(d, name, ok, in_blocks, names)

    def _drop_damaged(self, entries: dict[int, dict[str, Any]]) -> list[int]:
        """Forget the ok flights that lack a part their journal line lists (deleted outside
        tlm, or lost to a power cut): their lines are dropped from ``entries`` and their
        parts deleted, so this run flies them again (where a block file still holds the
        flight, the next open drops the new part again, see :func:`drop_compacted_parts`).
        Returns them."""
        have: dict[str, set[int]] = {}
        for d in owned_dirs(self.root):
            flights = have.setdefault(d.name.removesuffix(".parquet"), set())
            for p in d.iterdir():
                m = PART_RE.match(p.name)
                if m is not None:
                    flights.add(int(m.group(1)))
                elif BLOCK_RE.match(p.name):
                    flights.update(f for f, _ in block_flights(p))
        lost = [f for f, e in entries.items() if e.get("status") == "ok"
                and any(f not in have.get(t, set()) for t in e.get("parts") or [])]
        for f in lost:
            del entries[f]
            del self.status[f]
            for d in owned_dirs(self.root):
                _unlink_quietly([d / part_name(f, "bin" if d.name == BIN_DIR else "parquet")])
        return lost

    @staticmethod
    def _clean_one(d: Path, name: str, ok: set[int], in_blocks: set[int],
                   names: set[str]) -> None:
        """Clean up file ``name`` of table or bin folder ``d`` (see :meth:`_clean`)."""
        m = PART_RE.match(name)
        if m is not None:
            if int(m.group(1)) not in ok:
                (d / name).unlink()
            return
        target = tmp_target(name)
        if target is None:
            return  # not a name tlm writes: leave it
        t = PART_RE.match(target)
        if (t is not None and int(t.group(1)) in ok and target not in names
                and int(t.group(1)) not in in_blocks):
            os.replace(d / name, d / target)  # committed: roll forward
        elif t is not None or BLOCK_RE.match(target):
            (d / name).unlink()

    # -- writing ------------------------------------------------------------------------
    def put(self, result: Mapping[str, Any]) -> dict[str, Any]:
        """Write a finished flight (a :func:`~tlm_process.generate.task.fly_job` result):
        its parts and ``.bin`` under temporary names, then its journal line (the commit),
        then the renames; returns the journal entry.

        Raises GenerateError when a file cannot be written (a full disk): nothing of the
        flight is visible then and the run should stop."""
        flight = int(result["flight"])
        ok = result.get("status") == "ok"
        parts = sorted(result.get("parts") or {}) if ok else []
        files: list[tuple[Path, bytes]] = []
        for name in sorted(parts, key=lambda n: (n != "faults", n)):  # faults visible first
            files.append((self._dir(f"{name}.parquet") / part_name(flight),
                          result["parts"][name]))
        if ok and result.get("bin") is not None:
            files.append((self._dir(BIN_DIR) / part_name(flight, "bin"), result["bin"]))
        entry = self._entry(result, flight, ok, parts, sum(len(b) for _, b in files))
        tmps = [p.with_name(tmp_name(p.name)) for p, _ in files]
        try:
            for tmp, (_, data) in zip(tmps, files, strict=True):
                _write_file(tmp, data)
            self._append(entry)
        except OSError as exc:
            _unlink_quietly(tmps)
            raise GenerateError(f"cannot write flight {flight} to {self.root}: {_why(exc)}; "
                                f"{_AGAIN}") from None
        self.status[flight] = entry["status"]
        try:
            for tmp, (path, _) in zip(tmps, files, strict=True):
                os.replace(tmp, path)
        except OSError as exc:  # committed: the next open renames the rest
            raise GenerateError(f"cannot rename flight {flight}'s files in {self.root}: "
                                f"{_why(exc)}; {_AGAIN}") from None
        return entry

    def _dir(self, name: str) -> Path:
        d = self.root / name
        if name not in self._dirs:
            try:
                d.mkdir(exist_ok=True)
            except OSError as exc:
                raise GenerateError(f"cannot write to {self.root}: {_why(exc)}; "
                                    f"{_AGAIN}") from None
            self._dirs.add(name)
        return d

    @staticmethod
    def _entry(result: Mapping[str, Any], flight: int, ok: bool, parts: list[str],
               nbytes: int) -> dict[str, Any]:
        """The journal entry of a flight result."""
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
        return entry

    def _append(self, entry: Mapping[str, Any]) -> None:
        """Append one journal line with unbuffered writes (nothing of a failed line is left
        in a buffer to be flushed later)."""
        if self._journal is None:
            raise GenerateError("the data set is not open")
        data = (json.dumps(entry) + "\n").encode("utf-8")
        while data:
            n = os.write(self._journal, data)
            data = data[n:]

    # -- closing ------------------------------------------------------------------------
    def close(self, run: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Finish the run: sync the journal, write ``manifest.parquet`` and the header with
        the counts and state (``complete`` when every flight 0..N-1 is ok) and ``run`` added
        to its runs. Returns the header.

        Raises GenerateError when a file cannot be written; the header is still written
        when only the journal sync or ``manifest.parquet`` failed."""
        failed: list[OSError] = []
        if self._journal is not None:
            fd, self._journal = self._journal, None
            for step in (os.fsync, os.close):
                try:
                    step(fd)
                except OSError as exc:
                    failed.append(exc)
        n = int(self.header.get("flights", 0))
        ok = sum(1 for f, st in self.status.items() if st == "ok" and f < n)
        bad = sum(1 for f, st in self.status.items() if st != "ok" and f < n)
        frame = None
        try:
            frame = self._write_manifest_table()
        except OSError as exc:
            failed.append(exc)
        self.header["counts"] = {"ok": ok, "failed": bad, "missing": n - ok - bad}
        self.header["state"] = "complete" if ok == n else "incomplete"
        if run is not None:
            self.header["runs"] = [*self.header.get("runs", []), dict(run)]
        try:
            write_json_atomic(self.root / HEADER, self.header)
        except OSError as exc:
            _unlink_quietly([self.root / tmp_name(HEADER)])
            raise GenerateError(f"cannot close data set {self.root}: {_why(exc)}; its manifest "
                                f"still says running; {_AGAIN}") from None
        if frame is not None:
            try:
                self._write_card(frame)
            except OSError as exc:
                failed.append(exc)
        if failed:
            raise GenerateError(f"cannot finish data set {self.root}: {_why(failed[0])}; "
                                f"its manifest says {self.header['state']}; {_AGAIN}")
        return self.header

    def _write_card(self, frame: pd.DataFrame) -> None:
        """``README.md``: the data set card (tlm_process.generate.card)."""
        from tlm_process.generate.card import generate_card

        tables = sorted(p.name[:-len(".parquet")] for p in self.root.glob("*.parquet")
                        if p.is_dir() and p.name != "faults.parquet")
        tmp = self.root / tmp_name(CARD)
        tmp.write_text(generate_card(self.header, frame, tables))
        os.replace(tmp, self.root / CARD)

    def _write_manifest_table(self) -> pd.DataFrame:
        frame = manifest_frame(read_journal(self.root)[0])
        tmp = self.root / tmp_name(MANIFEST_TABLE)
        try:
            with tmp.open("wb") as fh:  # a file object: pyarrow cannot open non-UTF-8 paths
                frame.to_parquet(fh, index=False)
            os.replace(tmp, self.root / MANIFEST_TABLE)
        except OSError:
            _unlink_quietly([tmp])
            raise
        return frame
