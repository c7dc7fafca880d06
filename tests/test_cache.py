"""The numba cache folder: when the cache home cannot be created, the fallback is private to
this user, never a shared world-writable folder (issue 17, item 11)."""

from __future__ import annotations

import os
import stat
import sys
import tempfile
from pathlib import Path

import pytest

from tlm_sim import _cache


@pytest.fixture
def no_cache_home(tmp_path, monkeypatch) -> Path:
    """XDG_CACHE_HOME below a regular file (mkdir fails, also as root), the temp dir in
    tmp_path, no NUMBA_CACHE_DIR, and numba's config left alone. Returns the temp dir."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker / "cache"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp))
    monkeypatch.delitem(sys.modules, "numba", raising=False)  # no config.reload_config()
    return tmp


def _configured() -> Path:
    _cache.configure_numba_cache()
    return Path(os.environ["NUMBA_CACHE_DIR"])


def _assert_private(folder: Path) -> None:
    st = os.lstat(folder)
    assert stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid()
    assert stat.S_IMODE(st.st_mode) == 0o700


def test_the_fallback_is_a_private_per_user_folder(no_cache_home):
    target = _configured()
    base = no_cache_home / f"tlm-numba-{os.getuid()}"
    assert target.parent == base
    _assert_private(base)
    assert _configured() == target  # the same folder next time (warm cache)


@pytest.mark.parametrize("how", ["world-writable", "symlink", "other owner"])
def test_a_fallback_folder_others_control_is_not_used(no_cache_home, monkeypatch, how):
    uid = os.getuid()
    if how == "other owner":  # the folder is this process's, but the process runs as uid + 1
        uid += 1
        monkeypatch.setattr(os, "getuid", lambda: uid)
    planted = no_cache_home / f"tlm-numba-{uid}"
    if how == "symlink":
        elsewhere = no_cache_home / "elsewhere"
        elsewhere.mkdir(mode=0o700)
        planted.symlink_to(elsewhere)
    else:
        planted.mkdir()
        planted.chmod(0o777 if how == "world-writable" else 0o700)
    target = _configured()
    assert planted not in target.parents and no_cache_home / "elsewhere" not in target.parents
    st = os.lstat(target.parent)
    assert stat.S_ISDIR(st.st_mode) and stat.S_IMODE(st.st_mode) == 0o700
    assert not list(planted.iterdir() if planted.is_dir() else [])  # nothing written there


def test_the_cache_home_is_used_when_it_can_be_created(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    assert _cache.cache_base() == tmp_path / "cache" / "tlm" / "numba"
