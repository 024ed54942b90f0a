"""Cache and output files as a user meets them, through the real command line: a damaged
roadmap in the cache, a read-only cache, the leftovers of a killed run, a rename that fails
after the first files of a plan were replaced."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tmpnav.cachedir import CacheDir

ROOT = Path(__file__).resolve().parent.parent
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


def tmpnav(*args: str, prefix: tuple[str, ...] = ()) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*prefix, sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, cwd=ROOT, timeout=600
    )


def dead_pid() -> int:
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    return int(proc.stdout)


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A cache directory that holds the two-rooms scenario's roadmap, costs and plan."""
    folder = tmp_path_factory.mktemp("cache")
    proc = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(folder), "-q")
    assert proc.returncode == 0, proc.stderr
    return folder


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["truncated", "empty"])
def test_a_damaged_roadmap_is_set_aside_and_grown_again(cache: Path, damage: str) -> None:
    (stored,) = CacheDir(cache).roadmaps.glob("*.npz")
    stored.write_bytes(b"" if damage == "empty" else stored.read_bytes()[:100])
    proc = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q")
    assert proc.returncode == 0, proc.stderr
    warnings = proc.stderr.strip().splitlines()
    assert len(warnings) == 1 and warnings[0].startswith("warning: stored roadmap"), proc.stderr
    assert "growing it again" in warnings[0] and "Traceback" not in proc.stderr
    assert "roadmap grown" in proc.stdout and f"cache warning: stored roadmap {stored}" in proc.stdout
    again = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q")
    assert again.returncode == 0 and again.stderr == "", again.stderr
    assert "roadmap from cache" in again.stdout
    info = tmpnav("cache", "info", "--cache-dir", str(cache))
    assert "roadmaps: 1" in info.stdout and "set aside: " in info.stdout


def read_only_prefix() -> tuple[str, ...]:
    """How to run a command that cannot write where permissions forbid it (root can, by default)."""
    if os.geteuid() != 0:
        return ()
    if shutil.which("setpriv") is None:
        pytest.skip("running as root without setpriv: permissions cannot be enforced")
    return ("setpriv", "--bounding-set=-dac_override,-dac_read_search,-fowner", "--")


def test_clearing_a_read_only_cache_is_one_error_line(tmp_path: Path) -> None:
    cache = CacheDir(tmp_path / "cache")
    cache.ensure(cache.roadmaps)
    cache.database.write_bytes(b"SQLite format 3\x00")
    cache.roadmap("ab" * 32).write_bytes(b"PK")
    prefix = read_only_prefix()
    for folder in (cache.roadmaps, cache.root):
        folder.chmod(0o555)
    try:
        proc = tmpnav("cache", "clear", "--cache-dir", str(cache.root), prefix=prefix)
    finally:
        for folder in (cache.root, cache.roadmaps):
            folder.chmod(0o755)
    assert proc.returncode == 8, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: cannot clear the cache {cache.root}: "), proc.stderr
    assert "Permission denied" in lines[0] and "internal error" not in lines[0]
    assert cache.database.exists()
    done = tmpnav("cache", "clear", "--cache-dir", str(cache.root))
    assert done.returncode == 0 and "1 cache file(s), 1 roadmap(s)" in done.stdout


def test_leftovers_of_killed_runs_are_removed_by_the_next_write(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    leftover = out / f".plan.json.tmpnav-{dead_pid()}-0123abcd.tmp"
    leftover.write_text('{"half": ')
    proc = tmpnav("show", str(TWO_ROOMS), "-o", str(out / "world.png"))
    assert proc.returncode == 0, proc.stderr
    assert sorted(os.listdir(out)) == ["world.png"]


def test_cache_clear_removes_leftovers_and_set_aside_files(tmp_path: Path) -> None:
    cache = CacheDir(tmp_path)
    cache.ensure(cache.roadmaps)
    (cache.roadmaps / f".{'cd' * 32}.npz.tmpnav-{dead_pid()}-0123abcd.tmp").write_bytes(b"PK")
    (cache.roadmaps / f"{'ab' * 32}.npz.corrupt-20260101-000000-1").write_bytes(b"")
    Path(f"{cache.database}.corrupt-20260101-000000-1").write_bytes(b"junk")
    proc = tmpnav("cache", "clear", "--cache-dir", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert list(cache.roadmaps.iterdir()) == [] and not any(tmp_path.glob("oracle*"))


@pytest.mark.slow
def test_a_rename_that_fails_late_restores_the_earlier_plan(cache: Path, tmp_path: Path) -> None:
    """problem.pddl is a directory: plan.json, plan.png, schedule.png and domain.pddl were already replaced
    when its rename fails. They get their earlier content back; the error names problem.pddl."""
    out = tmp_path / "out"
    first = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q", "-o", str(out))
    assert first.returncode == 0, first.stderr
    earlier = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "problem.pddl").unlink()
    (out / "problem.pddl").mkdir()
    (out / "problem.pddl" / "notes.txt").write_text("in the way")
    proc = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q", "-o", str(out), "--no-mutual-observations")
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == f"error: cannot write {out / 'problem.pddl'}: Is a directory"
    now = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert now == {k: v for k, v in earlier.items() if k != "problem.pddl"}
    assert json.loads(now["plan.json"])["mutual_observations"] is True  # the earlier plan, not the new one
    assert sorted(os.listdir(out)) == ["domain.pddl", "plan.json", "plan.png", "problem.pddl", "schedule.png"]


@pytest.mark.parametrize(
    ("command", "name", "magic"),
    [("show", "world.svg", b"<?xml"), ("show", "world.JPG", b"\xff\xd8\xff"), ("roadmap", "roadmap.pdf", b"%PDF")],
)
def test_a_picture_is_written_in_the_format_its_suffix_names(
    command: str, name: str, magic: bytes, tmp_path: Path
) -> None:
    """`show -o x.svg` and `roadmap -o r.pdf` used to write PNG bytes under those names."""
    proc = tmpnav(command, str(TWO_ROOMS), "-o", str(tmp_path / name))
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / name).read_bytes().startswith(magic)


@pytest.mark.parametrize("name", ["world.txt", "world"])
def test_a_picture_name_without_a_known_format_is_refused_before_any_work(name: str, tmp_path: Path) -> None:
    proc = tmpnav("show", str(TWO_ROOMS), "-o", str(tmp_path / name))
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith(
        f"error: Invalid value for '-o' / '--output': {tmp_path / name}: expected a picture file ending in .png, .svg"
    ), proc.stderr
    assert len(proc.stderr.splitlines()) == 1 and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_the_plan_and_its_waypoints_are_written_all_or_nothing(cache: Path, tmp_path: Path) -> None:
    """The nav2 files were a second write with temporary files of their own: a killed run's
    leftovers in nav2/ stayed for good, and a failure there left the new plan beside the
    earlier waypoints. Now the plan and its waypoints are one group of tmpnav.atomic."""
    out = tmp_path / "out"
    first = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q", "-o", str(out), "--export", "nav2")
    assert first.returncode == 0, first.stderr
    earlier = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    leftover = out / "nav2" / f".r1.csv.tmpnav-{dead_pid()}-0123abcd.tmp"
    leftover.write_text("index,x")
    (out / "nav2" / "r2.csv").unlink()
    (out / "nav2" / "r2.csv").mkdir()  # the last file of the group cannot be replaced
    proc = tmpnav(
        "plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q", "-o", str(out), "--export", "nav2",
        "--no-mutual-observations",
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines()[-1] == f"error: cannot write {out / 'nav2' / 'r2.csv'}: Is a directory"
    now = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert now == {k: v for k, v in earlier.items() if k != Path("nav2/r2.csv")}  # the earlier plan, whole
    (out / "nav2" / "r2.csv").rmdir()
    again = tmpnav("plan", str(TWO_ROOMS), "--cache-dir", str(cache), "-q", "-o", str(out), "--export", "nav2")
    assert again.returncode == 0, again.stderr
    assert sorted(p.name for p in (out / "nav2").iterdir()) == sorted(str(k.name) for k in earlier if k.parent.name)
