"""Point numba's on-disk cache at a folder keyed by a hash of tlm_sim's source.

numba invalidates a cached function when its own file changes, but not when a function it
calls (in another file) changes: ``run_flight`` would silently keep stale copies of the
physics, EKF or controllers. Keying the cache folder by the whole package's source makes every
edit start a fresh cache. The plain build (``TLM_JIT=plain``, :mod:`tlm_sim._jit`) gets a
folder of its own (``<hash>-plain``): numba's cache index does not record compile options, so
the two builds must not share one. Set NUMBA_CACHE_DIR yourself to override.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import tempfile
from pathlib import Path

KEEP = 4  # cache folders of other source versions kept (several checkouts may share a home)


def source_hash(root: Path) -> str:
    """Hash of every .py file under root (paths and contents)."""
    h = hashlib.sha1()
    for p in sorted(root.rglob("*.py")):
        h.update(p.relative_to(root).as_posix().encode())
        h.update(p.read_bytes())
    return h.hexdigest()[:16]


def configure_numba_cache() -> None:
    """Set NUMBA_CACHE_DIR to <cache home>/tlm/numba/<source hash> unless already set."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    root = Path(__file__).resolve().parent
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "tlm" / "numba"
    try:
        base.mkdir(parents=True, exist_ok=True)
    except OSError:
        base = Path(tempfile.gettempdir()) / "tlm-numba"
        base.mkdir(parents=True, exist_ok=True)
    plain = os.environ.get("TLM_JIT", "").strip().lower() == "plain"
    target = base / (source_hash(root) + ("-plain" if plain else ""))
    if not target.exists():
        target.mkdir(exist_ok=True)
        others = sorted((d for d in base.iterdir() if d.is_dir() and d != target),
                        key=lambda d: d.stat().st_mtime)
        for d in others[:-KEEP] if len(others) > KEEP else []:
            shutil.rmtree(d, ignore_errors=True)
    os.environ["NUMBA_CACHE_DIR"] = str(target)
    if "numba" in sys.modules:
        from numba.core import config

        config.reload_config()
