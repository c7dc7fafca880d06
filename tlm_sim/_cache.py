"""Point numba's on-disk cache at a folder keyed by a hash of tlm_sim's source.

numba invalidates a cached function when its own file changes, but not when a function it
calls (in another file) changes: ``run_flight`` would silently keep stale copies of the
physics, EKF or controllers. Keying the cache folder by the whole package's source makes every
edit start a fresh cache. The plain build (``TLM_JIT=plain``, :mod:`tlm_sim._jit`) gets a
folder of its own (``<hash>-plain``): numba's cache index does not record compile options, so
the two builds must not share one. Set NUMBA_CACHE_DIR yourself to override.

numba loads (unpickles) whatever it finds in the cache folder, so the folder must be private:
when the cache home cannot be created, the fallback is ``<temp dir>/tlm-numba-<uid>`` created
with mode 0o700 and used only while it is a real folder owned by this user that no one else
can write; otherwise a fresh private temporary folder (a cold cache, compiled again).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import stat
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


def is_private_dir(path: Path) -> bool:
    """True when ``path`` is a folder (not a symlink) owned by this user and not writable by
    its group or others."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    owner_ok = not hasattr(os, "getuid") or st.st_uid == os.getuid()
    return stat.S_ISDIR(st.st_mode) and owner_ok and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def _private_fallback() -> Path:
    """``<temp dir>/tlm-numba-<uid>`` (created with mode 0o700) if it is private, else a fresh
    private temporary folder (see the module docstring)."""
    uid = os.getuid() if hasattr(os, "getuid") else 0
    base = Path(tempfile.gettempdir()) / f"tlm-numba-{uid}"
    try:
        base.mkdir(mode=0o700)
    except FileExistsError:
        pass
    except OSError:
        return Path(tempfile.mkdtemp(prefix="tlm-numba-"))
    if is_private_dir(base):
        return base
    return Path(tempfile.mkdtemp(prefix="tlm-numba-"))  # mode 0o700, owned by this user


def cache_base() -> Path:
    """The folder that holds the cache folders of every source version: <cache home>/tlm/numba,
    or a private fallback when that cannot be created (see the module docstring)."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "tlm" / "numba"
    try:
        base.mkdir(parents=True, exist_ok=True)
    except OSError:
        return _private_fallback()
    return base


def configure_numba_cache() -> None:
    """Set NUMBA_CACHE_DIR to <cache base>/<source hash> unless already set."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    root = Path(__file__).resolve().parent
    base = cache_base()
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
