"""Writing the scenario skeleton of ``tmpnav rooms``."""

from __future__ import annotations

from pathlib import Path

import pytest

from tmpnav.rooms.skeleton import save


def test_save_creates_folders_and_replaces_the_file(tmp_path: Path) -> None:
    target = tmp_path / "a" / "b" / "s.yaml"
    save(target, "name: one\n")
    save(target, "name: two\n")
    assert target.read_text() == "name: two\n"
    assert [p.name for p in target.parent.iterdir()] == ["s.yaml"]  # no temporary file left


def test_a_failed_save_names_the_file_asked_for(tmp_path: Path) -> None:
    """Written through tmpnav.atomic: the error names the target, never a temporary file."""
    target = tmp_path / "s.yaml"
    target.mkdir()
    with pytest.raises(OSError) as caught:
        save(target, "name: x\n")
    assert caught.value.filename == str(target) and ".tmp" not in str(caught.value)
    assert [p.name for p in tmp_path.iterdir()] == ["s.yaml"]
