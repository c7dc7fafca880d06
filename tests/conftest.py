"""Shared fixtures: reference SITL log location and flights flown once per test session."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
REFERENCE = REPO.parent / "shared" / "reference" / "sitl"
REAL = REPO.parent / "shared" / "reference" / "real"


def reference_path(name: str) -> Path:
    """Path of a reference SITL file; skips the test (with the reason) when it is absent."""
    p = REFERENCE / name
    if not p.exists():
        pytest.skip(f"reference SITL logs not found at {REFERENCE}")
    return p


def real_path(name: str) -> Path:
    """Path of a real (hardware) log; skips the test (with the reason) when it is absent.
    CI has ``../shared`` beside the clone, so these tests run there."""
    p = REAL / name
    if not p.exists():
        pytest.skip(f"real reference logs not found at {REAL}")
    return p


@lru_cache(maxsize=16)
def flown(mission: int, seed: int = 0):
    """A default flight of a built-in mission, flown once per test process."""
    from tlm_sim import fly

    return fly(mission, seed=seed)


@pytest.fixture(scope="session")
def normal_flight():
    """Built-in mission 1, seed 0, default parameters."""
    return flown(1, 0)


def close_dfreader(r) -> None:  # noqa: ANN001 - pymavlink's DFReader_binary
    """Close what pymavlink's DFReader_binary keeps open (it has no close of its own), so no
    ResourceWarning surfaces later inside another test's warning capture."""
    r.data_map.close()
    r.filehandle.close()
