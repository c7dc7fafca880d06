"""SHA-1 of every table (and the fault records and meta) of a few reference flights.

A refactoring of ``tlm_sim`` that must not change flights (bit-identical tables) is checked by
recording the hashes before it and comparing after every step::

    python tools/flight_hashes.py > /tmp/before.json          # record
    python tools/flight_hashes.py --check /tmp/before.json    # compare (exit 1 on a difference)

The flights: a normal flight, the paper's fault sequence (GPS, accel, engine, RC), an engine
crash (SIM_ENGINE_MUL 0 from 150 s, held to the end) and an RC failsafe (SIM_RC_FAIL 1 from
120 s, held), all on built-in mission 1 with seed 0 unless ``--seed`` says otherwise.
``--only NAME`` flies one of them. ``--catalogue`` adds one flight per other fault type of
:data:`~tlm_sim.faults.types.FAULT_TYPES` (``fault_<type>``: the fault from 120 s to 160 s, so
that its onset, its clearing and the recovery are hashed), for changes to fault code paths.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from collections.abc import Callable
from typing import Any

import numpy as np

from tlm_sim import fly
from tlm_sim.faults import Fault, FaultSchedule
from tlm_sim.flightlog import FlightLog


def _flights(seed: int) -> dict[str, Callable[[], FlightLog]]:
    """Name -> a function flying that reference flight."""
    return {
        "normal": lambda: fly(1, seed=seed),
        "paper": lambda: fly(1, FaultSchedule.paper(seed), seed=seed),
        "engine_crash": lambda: fly(1, FaultSchedule((Fault("engine", 150.0, None),)),
                                    seed=seed),
        "rc_failsafe": lambda: fly(1, FaultSchedule((Fault("rc", 120.0, None),)), seed=seed),
    }


def _catalogue(seed: int) -> dict[str, Callable[[], FlightLog]]:
    """``fault_<type>`` -> a function flying mission 1 with that fault from 120 s to 160 s."""
    from tlm_sim.faults.types import FAULT_TYPES

    def one(kind: str) -> Callable[[], FlightLog]:
        return lambda: fly(1, FaultSchedule((Fault(kind, 120.0, 160.0),)), seed=seed)

    return {f"fault_{k}": one(k) for k in FAULT_TYPES if k not in ("engine", "rc")}


def _sha1_json(obj: Any) -> str:
    return hashlib.sha1(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()


def table_hash(log: FlightLog, name: str) -> str:
    """SHA-1 of one table: its column names, dtypes and values (bytes)."""
    h = hashlib.sha1()
    for col, values in log.columns(name).items():
        a = np.ascontiguousarray(values)
        h.update(f"{col}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes() if a.dtype != object else repr(a.tolist()).encode())
    return h.hexdigest()


def flight_hashes(log: FlightLog) -> dict[str, str]:
    """Table name -> hash, plus ``faults`` (the fault records) and ``meta``."""
    out = {name: table_hash(log, name) for name in sorted(log.tables)}
    out["faults"] = _sha1_json(log.faults)
    out["meta"] = _sha1_json(log.meta)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", metavar="FILE", help="compare with hashes recorded earlier")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", action="append", metavar="NAME",
                    help="fly only this flight (repeatable)")
    ap.add_argument("--catalogue", action="store_true",
                    help="also fly every other fault type (fault_<type>, 120-160 s)")
    a = ap.parse_args(argv)
    flights = _flights(a.seed)
    names = list(flights)
    if a.catalogue or any(n.startswith("fault_") for n in a.only or ()):
        cat = _catalogue(a.seed)
        flights |= cat
        names += list(cat) if a.catalogue else []
    names = a.only or names
    got = {n: flight_hashes(flights[n]()) for n in names}
    if not a.check:
        json.dump(got, sys.stdout, indent=1, sort_keys=True)
        print()
        return 0
    with open(a.check, encoding="utf-8") as fh:
        want = json.load(fh)
    bad = [f"{n}.{k}" for n in names for k in sorted(set(want.get(n, {})) | set(got[n]))
           if want.get(n, {}).get(k) != got[n].get(k)]
    if bad:
        print("DIFFERENT: " + ", ".join(bad))
        return 1
    print(f"identical: {', '.join(names)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
