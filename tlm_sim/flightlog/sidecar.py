"""Fault records that sit beside a DataFlash log: the sidecar.

Two layouts hold a log's fault records (paper Eq. 4: type, label, start/end TimeUS, ...) in a
JSON file next to it:

* ``<log>.json`` beside ``<log>.bin``: the reference SITL logs' sidecar
  (``{"faults": [...], "sitl": {...}, "mission": ...}``);
* ``faults.json`` in the log's folder: what ``tlm fly`` writes beside ``flight.bin``
  (``{"faults": [...]}``).

``fault_sidecar`` finds the file (``<log>.json`` first); ``read_sidecar_faults`` reads its
fault list; ``log_faults`` gives a log's records: the sidecar's when there is one, else the
log's own (``tlm_sim.faults.detect.faults_in_log``: tlm's fault MSG lines, or the SIM_*
parameter changes of a SITL log).
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pandas as pd

__all__ = ["FAULTS_JSON", "SidecarWarning", "fault_sidecar", "load_sidecar_json", "log_faults",
           "read_sidecar_faults"]

#: The fault-records file ``tlm fly`` writes beside its ``flight.bin``.
FAULTS_JSON = "faults.json"


class SidecarWarning(UserWarning):
    """A sidecar beside a log could not be read as fault records; the log's own were used."""


def fault_sidecar(path: str | os.PathLike) -> Path | None:
    """The fault sidecar of log ``path``: ``<log>.json`` beside it, else ``faults.json`` in
    its folder; None when neither is a file."""
    p = Path(path)
    for cand in (p.with_suffix(".json"), p.parent / FAULTS_JSON):
        if cand.is_file():
            return cand
    return None


def load_sidecar_json(path: str | os.PathLike, what: str = "sidecar") -> Any:
    """The JSON document of sidecar ``path``.

    Raises:
        ValueError: ``PATH is not a WHAT JSON (why)``, one line: not UTF-8, not JSON, or
            nested past Python's recursion limit.
        OSError: the file cannot be read.
    """
    p = Path(path)
    try:
        return json.loads(p.read_bytes().decode("utf-8"))
    except (ValueError, RecursionError) as exc:  # JSON, UTF-8 (ValueErrors) or nesting
        why = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ValueError(f"{p} is not a {what} JSON ({why})") from None


def read_sidecar_faults(sidecar: str | os.PathLike) -> list[dict[str, Any]]:
    """The fault list of a sidecar (``{"faults": [...]}``, or a bare list), as dicts.

    Raises:
        ValueError: not UTF-8 JSON, or no list of fault mappings in it (the message names the
            file and says why, in one line).
        OSError: the file cannot be read.
    """
    p = Path(sidecar)
    doc = load_sidecar_json(p, "fault sidecar")
    faults = doc.get("faults") if isinstance(doc, Mapping) else doc
    if faults is None:
        return []
    if (isinstance(faults, str | bytes) or not isinstance(faults, Sequence)
            or not all(isinstance(f, Mapping) for f in faults)):
        raise ValueError(f"{p} is not a fault sidecar JSON (its 'faults' is not a list of "
                         "records)")
    return [dict(f) for f in faults]


def log_faults(path: str | os.PathLike, msg: pd.DataFrame | None,
               changes: pd.DataFrame | None) -> tuple[list[dict[str, Any]], str | None]:
    """A log's fault records and where they came from.

    The sidecar's (``fault_sidecar``) when there is a readable one, else the log's own
    (``faults_in_log`` of its MSG table ``msg`` and its in-flight parameter ``changes``). A
    sidecar that cannot be read is named in a ``SidecarWarning`` (one line) and skipped.

    Returns:
        (records, source): source is the sidecar's path, "MSG" (tlm's fault lines), "PARM"
        (parameter changes) or None when no fault was found.
    """
    from tlm_sim.faults.detect import faults_in_log

    sidecar = fault_sidecar(path)
    if sidecar is not None:
        try:
            return read_sidecar_faults(sidecar), str(sidecar)
        except (ValueError, OSError) as exc:
            why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
            warnings.warn(f"{why}; using the fault records of the log itself", SidecarWarning,
                          stacklevel=3)
    found = faults_in_log(msg, changes)
    return found, (found[0]["source"] if found else None)
