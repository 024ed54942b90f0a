"""Writing files all or nothing: groups, a late rename failure, the leftovers of killed writers."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tmpnav import atomic
from tmpnav.atomic import remove_stale, write_file, write_files


def names(folder: Path) -> list[str]:
    return sorted(os.listdir(folder))


def test_a_group_is_written_in_order_with_the_umask_mode(tmp_path: Path) -> None:
    def figure(path: Path) -> None:
        path.write_bytes(b"\x89PNG")

    old = os.umask(0o027)
    try:
        written = write_files(tmp_path / "out", {"b.txt": "bee", "a.bin": b"\x00\x01", "c.png": figure})
    finally:
        os.umask(old)
    assert [p.name for p in written] == ["b.txt", "a.bin", "c.png"]
    assert names(tmp_path / "out") == ["a.bin", "b.txt", "c.png"]  # nothing else
    assert (tmp_path / "out" / "b.txt").read_text() == "bee"
    assert (tmp_path / "out" / "a.bin").read_bytes() == b"\x00\x01"
    assert {(tmp_path / "out" / n).stat().st_mode & 0o777 for n in names(tmp_path / "out")} == {0o640}


def test_a_failing_content_leaves_the_earlier_files_and_no_new_folder(tmp_path: Path) -> None:
    (tmp_path / "a.txt").write_text("old a")

    def broken(path: Path) -> None:
        path.write_text("half")
        raise RuntimeError("cannot draw")

    with pytest.raises(RuntimeError):
        write_files(tmp_path, {"a.txt": "new a", "b.txt": broken})
    assert names(tmp_path) == ["a.txt"] and (tmp_path / "a.txt").read_text() == "old a"
    with pytest.raises(RuntimeError):
        write_files(tmp_path / "new", {"b.txt": broken})
    assert not (tmp_path / "new").exists()


def test_a_group_reaches_into_sub_folders_and_removes_those_it_made_on_failure(tmp_path: Path) -> None:
    out = tmp_path / "out"
    (out / "nav2").mkdir(parents=True)
    (out / "nav2" / f".r1.csv.tmpnav-{dead_pid()}-0123abcd.tmp").write_text("left by a killed run")
    written = write_files(out, {"plan.json": "{}", "nav2/r1.csv": "x", "deep/er/f.txt": "f"})
    assert written == [out / "plan.json", out / "nav2" / "r1.csv", out / "deep" / "er" / "f.txt"]
    assert names(out / "nav2") == ["r1.csv"]  # the leftover is gone

    def broken(path: Path) -> None:
        raise RuntimeError("cannot draw")

    with pytest.raises(RuntimeError):
        write_files(out, {"plan.json": "{new}", "new/a.txt": "a", "new/b/c.txt": broken})
    assert names(out) == ["deep", "nav2", "plan.json"] and (out / "plan.json").read_text() == "{}"


@pytest.mark.parametrize("name", ["../escape.txt", "/etc/passwd", "a/../../b", ""])
def test_a_name_must_stay_inside_the_folder(name: str, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="is not a file name inside"):
        write_files(tmp_path / "out", {name: "x"})
    assert not (tmp_path / "out").exists()


def test_a_late_rename_failure_restores_the_earlier_set_and_names_the_file(tmp_path: Path) -> None:
    for name in ("a.txt", "b.txt"):
        (tmp_path / name).write_text(f"old {name}")
    (tmp_path / "c.txt").mkdir()  # the third rename fails: a directory is in the way
    (tmp_path / "c.txt" / "inside").write_text("x")
    with pytest.raises(IsADirectoryError) as caught:
        write_files(tmp_path, {"a.txt": "new", "b.txt": "new", "d.txt": "new", "c.txt": "new"})
    assert caught.value.filename == str(tmp_path / "c.txt")
    assert ".tmp" not in str(caught.value)
    assert names(tmp_path) == ["a.txt", "b.txt", "c.txt"]  # d.txt, new in this group, is gone again
    assert [(tmp_path / n).read_text() for n in ("a.txt", "b.txt")] == ["old a.txt", "old b.txt"]


def test_an_error_while_staging_names_the_target(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    def full_disk(tmp: Path, content: atomic.Content) -> None:
        raise OSError(28, "No space left on device", str(tmp))

    monkeypatch.setattr(atomic, "_stage", full_disk)
    with pytest.raises(OSError, match="No space left") as caught:
        write_file(tmp_path / "plan.json", "{}")
    assert caught.value.filename == str(tmp_path / "plan.json")
    assert names(tmp_path) == []


@pytest.fixture
def ctrl_c(monkeypatch: pytest.MonkeyPatch) -> None:
    """tmpnav's Ctrl-C handler for one test (and a clean record of signals after it)."""
    from tmpnav import lifetime

    monkeypatch.setattr(lifetime, "_signalled", None)
    monkeypatch.setattr(lifetime, "_deferred", False)
    previous = signal.signal(signal.SIGINT, lifetime._raise_interrupted)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.parametrize("when", ["temporary file made", "first rename done"])
def test_ctrl_c_at_any_instant_of_a_write_leaves_the_earlier_files_and_no_temporary_one(
    when: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, ctrl_c: None
) -> None:
    """A real SIGINT right after a temporary file is created (before it was recorded, it
    leaked: a Ctrl-C'd plan left ``.plan.png.tmpnav-*.tmp``) and between two renames."""
    for name in ("a.txt", "b.txt"):
        (tmp_path / name).write_text(f"old {name}")
    made, replace = atomic._temporary, os.replace

    def temporary(target: Path, kind: str) -> Path:
        path = made(target, kind)
        if when == "temporary file made" and kind == "tmp" and target.name == "b.txt":
            os.kill(os.getpid(), signal.SIGINT)
        return path

    def rename(src: str | os.PathLike[str], dst: str | os.PathLike[str]) -> None:
        replace(src, dst)
        if when == "first rename done" and Path(dst).name == "a.txt" and Path(src).suffix == ".tmp":
            os.kill(os.getpid(), signal.SIGINT)

    monkeypatch.setattr(atomic, "_temporary", temporary)
    monkeypatch.setattr(atomic.os, "replace", rename)
    with pytest.raises(KeyboardInterrupt):
        write_files(tmp_path, {"a.txt": "new", "b.txt": "new", "c.txt": "new"})
    assert names(tmp_path) == ["a.txt", "b.txt"]
    assert [(tmp_path / n).read_text() for n in ("a.txt", "b.txt")] == ["old a.txt", "old b.txt"]


def dead_pid() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(proc.stdout)


def test_stale_temporary_files_of_dead_writers_are_removed(tmp_path: Path) -> None:
    dead = tmp_path / f".plan.json.tmpnav-{dead_pid()}-0a1b2c3d.tmp"
    mine = tmp_path / f".plan.png.tmpnav-{os.getpid()}-0a1b2c3d.tmp"  # a live writer's: kept
    old = tmp_path / f".x.tmpnav-{os.getpid()}-00000000.bak"
    other = tmp_path / ".not-ours.tmp"  # not named by tmpnav: never touched
    for path in (dead, mine, old, other):
        path.write_text("partial")
    os.utime(old, (time.time() - 2 * atomic.STALE_AFTER,) * 2)
    assert remove_stale(tmp_path) == 2
    assert names(tmp_path) == sorted([mine.name, other.name])


def test_a_writer_killed_mid_write_leaves_a_file_the_next_write_removes(tmp_path: Path) -> None:
    """SIGKILL while a figure is being written: its temporary file stays, until the next write."""
    code = (
        "import sys, time; from pathlib import Path; from tmpnav.atomic import write_file\n"
        "def slow(path):\n"
        "    path.write_text('half a figure'); print('writing', flush=True); time.sleep(60)\n"
        f"write_file(Path({str(tmp_path / 'plan.png')!r}), slow)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "writing"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    leftovers = names(tmp_path)
    assert len(leftovers) == 1 and leftovers[0].startswith(".plan.png.tmpnav-")
    write_file(tmp_path / "summary.md", "# done\n")
    assert names(tmp_path) == ["summary.md"]
