"""The cache directory's layout: where it is, what is in it, what clearing removes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tmpnav.cachedir import DATABASE, CacheDir, default_cache_dir, set_aside
from tmpnav.errors import CacheError


def test_the_default_directory_follows_the_environment(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("TMPNAV_CACHE_DIR", str(tmp_path / "mine"))
    assert default_cache_dir() == tmp_path / "mine" == CacheDir.at(None).root
    monkeypatch.delenv("TMPNAV_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert default_cache_dir() == tmp_path / "xdg" / "tmpnav"
    assert CacheDir.at(tmp_path / "given").root == tmp_path / "given"


def test_info_and_clear_of_every_kind_of_file(tmp_path: Path) -> None:
    cache = CacheDir(tmp_path / "cache")
    assert cache.info().database_exists is False and cache.clear() == (0, 0)  # nothing there yet
    cache.ensure(cache.roadmaps)
    cache.roadmap("ab" * 32).write_bytes(b"x" * 10)
    cache.roadmap("cd" * 32).write_bytes(b"x" * 20)
    moved = set_aside(cache.roadmap("cd" * 32))
    assert moved is not None and moved.name.startswith(f"{'cd' * 32}.npz.corrupt-")
    Path(f"{cache.database}-wal").write_bytes(b"")
    info = cache.info()
    assert (info.roadmaps, info.roadmap_bytes, info.set_aside) == (1, 10, 1)
    assert cache.clear() == (1, 1)
    assert os.listdir(cache.roadmaps) == [] and not (cache.root / f"{DATABASE}-wal").exists()


def test_a_cache_directory_that_cannot_be_created_says_what_to_do(tmp_path: Path) -> None:
    (tmp_path / "a-file").write_text("")
    with pytest.raises(
        CacheError, match=r"cannot be used: .*a-file/cache: Not a directory \(use --cache-dir DIR or --no-cache\)"
    ):
        CacheDir(tmp_path / "a-file" / "cache").ensure()
