"""tmpnav.lifetime.scratch: one folder of temporary files per process, gone however it ends."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from tmpnav import lifetime

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def tmpdir_here(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """The system's temporary folder is ``tmp_path``, and this process has made no scratch folder."""
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(lifetime, "_scratch", None)
    monkeypatch.delenv(lifetime.ENV, raising=False)
    return tmp_path


def test_one_folder_per_process_named_with_its_id(tmpdir_here: Path) -> None:
    first = lifetime.scratch()
    assert first == lifetime.scratch()
    assert first.parent == tmpdir_here and first.name.startswith(f"tmpnav-p{os.getpid()}-")
    with lifetime.scratch_folder("enhsp-") as folder:
        assert Path(folder).parent == first
        (Path(folder) / "plan.txt").write_text("plan")
    assert list(first.iterdir()) == []  # the block's folder is gone at its end


def test_a_run_names_its_folders_with_its_token(tmpdir_here: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(lifetime.ENV, "123-abc")
    assert lifetime.scratch().name.startswith(f"tmpnav-run-123-abc-p{os.getpid()}-")


def test_removed_by_token_or_by_process_and_no_other(tmpdir_here: Path) -> None:
    mine = tmpdir_here / "tmpnav-run-1-aa-p10-x"
    other_run = tmpdir_here / "tmpnav-run-2-bb-p11-y"
    other_process = tmpdir_here / "tmpnav-p12-z"
    for folder in (mine, other_run, other_process):
        (folder / "enhsp-q").mkdir(parents=True)
    assert lifetime.remove_scratch(token="1-aa") == 1
    assert not mine.exists() and other_run.exists() and other_process.exists()
    assert lifetime.remove_scratch(pid=12) == 1
    assert not other_process.exists() and other_run.exists()
    assert lifetime.remove_scratch(pid=1) == 0  # the token's own process id is not the folder's


def _child(tmp_path: Path, body: str) -> subprocess.Popen[bytes]:
    code = f"import os, signal, sys\nfrom tmpnav import lifetime\n{body}"
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    env.pop(lifetime.ENV, None)
    return subprocess.Popen([sys.executable, "-c", code], cwd=ROOT, env=env)


def _empty_within(folder: Path, seconds: float) -> bool:
    deadline = time.monotonic() + seconds
    while list(folder.glob("tmpnav-*")) and time.monotonic() < deadline:
        time.sleep(0.05)
    return not list(folder.glob("tmpnav-*"))


def test_removed_at_a_normal_exit(tmp_path: Path) -> None:
    body = (
        "with lifetime.scratch_folder('enhsp-') as f:\n"
        "    open(os.path.join(f, 'problem.pddl'), 'w').close()\n"
        "open(os.path.join(str(lifetime.scratch()), 'left.txt'), 'w').close()\n"
    )
    proc = _child(tmp_path, body)
    assert proc.wait(timeout=60) == 0
    assert not list(tmp_path.glob("tmpnav-*"))


@pytest.mark.skipif(not Path("/proc/self/environ").exists(), reason="the sentinel needs Linux")
def test_removed_by_the_sentinel_when_the_run_is_killed(tmp_path: Path) -> None:
    body = (
        "lifetime.guard()\n"
        "f = lifetime.scratch()\n"
        "open(os.path.join(str(f), 'domain.pddl'), 'w').close()\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    proc = _child(tmp_path, body)
    assert proc.wait(timeout=60) == -signal.SIGKILL
    assert _empty_within(tmp_path, 10.0), [p.name for p in tmp_path.iterdir()]
