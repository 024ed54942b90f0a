"""The oracle's worker processes never outlive ``tmpnav plan``, however it is killed.

Through the real CLI: a plan whose oracle keeps two worker processes busy is killed with
SIGTERM (a clean shutdown: the workers are terminated first) and with SIGKILL (nothing runs
in the parent: the kernel or the workers' watchdog ends them).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: about 10 s of oracle work on two workers: long enough to be killed in the middle of it
SCENARIO = ROOT / "configs" / "corridor-4robots.yaml"


def alive(pid: int) -> bool:
    """Is ``pid`` running? (A zombie, killed but not reaped yet, counts as dead.)"""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False


def forked_children(pid: int) -> list[int]:
    """Children of ``pid`` running the same command line: its forked pool workers."""
    try:
        import psutil  # optional: more portable than /proc

        parent = psutil.Process(pid)
        return [c.pid for c in parent.children() if c.cmdline() == parent.cmdline()]
    except ImportError:
        pass
    except Exception:  # the process ended while we looked
        return []
    out = []
    try:
        cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
    except FileNotFoundError:
        return []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            if ppid == pid and (entry / "cmdline").read_bytes() == cmdline:
                out.append(int(entry.name))
        except (FileNotFoundError, ProcessLookupError, IndexError, ValueError):
            continue
    return out


def wait_for_workers(proc: subprocess.Popen[str], count: int, timeout: float) -> list[int]:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        workers = forked_children(proc.pid)
        if len(workers) >= count:
            return workers
        time.sleep(0.05)
    raise AssertionError(f"no {count} oracle workers appeared (exit code {proc.poll()})")


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc to find the workers")
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_killed_plan_leaves_no_worker_behind(sig: signal.Signals, tmp_path: Path) -> None:
    stderr_file = tmp_path / "stderr.txt"
    workers: list[int] = []
    with open(stderr_file, "w") as stderr:  # a file, not a pipe: orphans would hold a pipe open
        proc = subprocess.Popen(
            [sys.executable, "-m", "tmpnav", "plan", str(SCENARIO), "--no-cache", "--workers", "2", "-q"],
            stdout=subprocess.DEVNULL,
            stderr=stderr,
            cwd=tmp_path,
            env={**os.environ, "TMPNAV_CACHE_DIR": str(tmp_path / "cache")},
        )
    try:
        workers = wait_for_workers(proc, 2, timeout=120)
        time.sleep(1.0)  # in the middle of the oracle's work
        assert proc.poll() is None, "the plan ended before it could be killed"
        proc.send_signal(sig)
        proc.wait(timeout=60)
        deadline = time.monotonic() + 15
        while any(alive(w) for w in workers) and time.monotonic() < deadline:
            time.sleep(0.05)
        survivors = [w for w in workers if alive(w)]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for w in workers:  # never leave them to load the machine, even when the test fails
            if alive(w):
                os.kill(w, signal.SIGKILL)
    assert proc.returncode == -sig
    assert not survivors, f"worker processes {survivors} outlived tmpnav plan ({sig.name})"
    if sig == signal.SIGTERM:
        assert "Traceback" not in stderr_file.read_text(), stderr_file.read_text()


#: a process that starts a worker which watches it, prints the worker's pid and exits
ORPHAN = """
import os, sys, time
from tmpnav.oracle import executors
parent = os.getpid()
worker = os.fork()
if worker == 0:
    os.close(1)  # the test reads our parent's output to its end
    executors.die_with_parent(parent, use_prctl=False)  # the watchdog alone
    time.sleep(120)
    os._exit(0)
print(worker, flush=True)
"""


def test_the_watchdog_ends_a_worker_whose_parent_is_gone() -> None:
    """Where prctl is missing (not Linux), a worker notices its parent's death itself."""
    out = subprocess.run([sys.executable, "-c", ORPHAN], capture_output=True, text=True, timeout=60, check=True)
    worker = int(out.stdout)
    deadline = time.monotonic() + 10
    while alive(worker) and time.monotonic() < deadline:
        time.sleep(0.05)
    still = alive(worker)
    if still:
        os.kill(worker, signal.SIGKILL)
    assert not still
