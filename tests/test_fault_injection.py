"""Fault injection: ``tmpnav plan -o DIR`` killed by SIGINT, SIGTERM or SIGKILL at several points.

For each signal one cache directory and one output folder go through its runs: killed
while the oracle's worker processes compute costs, killed while ENHSP's JVM runs (held at
its start by a JVM option: it would run on forever if nothing ended it), killed while the
output files are being written (SIGTERM only there: :data:`POINTS_OF`), then run to its end.
After each kill:

- no process of the run is left: the oracle's workers, the JVM (which unified-planning
  starts in a session of its own, out of reach of signals to tmpnav's process group) and
  tmpnav's own sentinel (tmpnav.lifetime), and none of its temporary files (ENHSP's);
- no output file is half-written: the folder holds the files of the earlier plan, byte
  for byte, and nothing else a user sees (a SIGKILL may leave hidden temporary files,
  which the next write removes);
- the final run gives the plan of an undisturbed run, from a cache the kills left behind.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parent.parent
#: about 2 s of oracle work on two workers, 1-2 s of ENHSP search, 1 s to draw plan.png:
#: each stage lasts long enough to be caught in the middle
SCENARIO = ROOT / "configs" / "corridor-2robots.yaml"
OUTPUTS = ("domain.pddl", "plan.json", "plan.png", "problem.pddl", "schedule.png")
#: plan.json keys that describe the plan itself (the others: timings, cache hits)
PLAN_KEYS = ("status", "goals", "cost", "robots", "actions", "trajectories")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc to see the run's processes"),
]


def plan_args(cache: Path, out: Path, *extra: str) -> list[str]:
    # a budget the search does not reach (it converges in about 6 s): the plan must not depend
    # on how far a loaded machine got in 10 s, or "the same next plan" cannot be checked
    return [sys.executable, "-m", "tmpnav", "plan", str(SCENARIO), "-q", "--workers", "2", "--anytime-budget", "60",
            "--cache-dir", str(cache), "-o", str(out), *extra]  # fmt: skip


def start(args: list[str], log: Path, env: dict[str, str]) -> subprocess.Popen[bytes]:
    """The run, with SIGINT at its default (a shell's background job would ignore it), its
    output in a file (a pipe would be held open by any process left behind) and its
    temporary files in a folder of its own (:func:`scratch_left`)."""
    scratch = log.parent / "tmp"
    scratch.mkdir(exist_ok=True)
    with open(log, "wb") as fh:
        return subprocess.Popen(
            args, stdout=fh, stderr=subprocess.STDOUT, cwd=ROOT, env={**os.environ, **env, "TMPDIR": str(scratch)},
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )  # fmt: skip


def children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            out += [int(c) for c in (task / "children").read_text().split()]
        except (FileNotFoundError, ProcessLookupError):
            continue
    return out


def descendants(pid: int) -> list[int]:
    found = []
    for child in children(pid):
        found += [child, *descendants(child)]
    return found


def command(pid: int) -> list[str]:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace").split("\0")[:-1]
    except (FileNotFoundError, ProcessLookupError):
        return []


def alive(pid: int) -> bool:
    """Is ``pid`` running? (A zombie, ended but not reaped yet, counts as gone.)"""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (FileNotFoundError, ProcessLookupError):
        return False


def oracle_workers(proc: subprocess.Popen[bytes], out: Path) -> bool:
    """Both forked pool workers: children running tmpnav's own command line (one such
    child alone may be the sentinel, forked at the start, before it executes)."""
    mine = command(proc.pid)
    return bool(mine) and sum(command(c) == mine for c in children(proc.pid)) >= 2


def planner_jvm(proc: subprocess.Popen[bytes], out: Path) -> bool:
    """ENHSP's JVM has started (not ``java -version``) and is held at its start (paused_jvm)."""
    enhsp = any(any(part.endswith("enhsp.jar") for part in command(c)) for c in children(proc.pid))
    return enhsp and (out.parent / PAUSE_FILE).exists()


def writing_figure(proc: subprocess.Popen[bytes], out: Path) -> bool:
    """plan.png is being drawn into its temporary file (plan.json is already staged)."""
    return out.is_dir() and any(out.glob(".plan.png.tmpnav-*.tmp"))


PAUSE_FILE = "jvm.paused"


def paused_jvm(folder: Path) -> dict[str, str]:
    """JVM options that hold ENHSP's JVM at its start until a file is removed, which nobody
    does: a planner that never ends on its own (a real search may end early by chance, of
    the pipes a dead tmpnav closed, or of its input files removed in a clean-up)."""
    pause = f"-XX:+UnlockDiagnosticVMOptions -XX:+PauseAtStartup -XX:PauseAtStartupFile={folder / PAUSE_FILE}"
    # a JVM process per solve, the path whose lifetime this guards (the in-process JVM ends with
    # tmpnav by construction: tests/task/test_enhsp_persistent.py signals a run searching in it)
    return {"TMPNAV_JAVA_OPTIONS": pause, "TMPNAV_ENHSP": "process"}


def no_change(folder: Path) -> dict[str, str]:
    return {}


#: where a run is killed: when the test sees it there, and the environment of that run
POINTS: dict[str, tuple[Callable[[subprocess.Popen[bytes], Path], bool], Callable[[Path], dict[str, str]]]] = {
    "oracle": (oracle_workers, no_change),
    "planner": (planner_jvm, paused_jvm),
    "writing": (writing_figure, no_change),
}


def kill_at(point: str, sig: signal.Signals, args: list[str], out: Path, log: Path) -> tuple[int, list[int]]:
    """Run ``args`` until ``point`` is reached, send ``sig``; returns the exit status and
    the processes the run had started by then."""
    detect, env = POINTS[point]
    proc = start(args, log, env(log.parent))
    try:
        deadline = time.monotonic() + 300
        while not detect(proc, out):
            assert proc.poll() is None, f"the run ended before reaching {point}: {log.read_text()}"
            assert time.monotonic() < deadline, f"no {point} stage within 300 s"
            time.sleep(0.005)
        started = descendants(proc.pid)
        proc.send_signal(sig)
        code = proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return code, started


def leftovers(started: list[int]) -> list[str]:
    """The processes among ``started`` still running 3 s later (then killed: never left
    behind to load the machine, even when the test fails)."""
    deadline = time.monotonic() + 3
    while any(alive(p) for p in started) and time.monotonic() < deadline:
        time.sleep(0.05)
    left = [p for p in started if alive(p)]
    named = [" ".join(command(p))[:120] for p in left]
    for p in left:
        os.kill(p, signal.SIGKILL)
    return named


def scratch_left(log: Path) -> list[str]:
    """tmpnav's temporary folders the killed run left (its sentinel removes them, after the
    processes, which :func:`leftovers` waited for)."""
    return sorted(p.name for p in (log.parent / "tmp").glob("tmpnav-*"))


def visible(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir() if not p.name.startswith(".")}


def the_plan(folder: Path) -> dict[str, Any]:
    doc = json.loads((folder / "plan.json").read_text())
    return {k: doc[k] for k in PLAN_KEYS}


@pytest.fixture(scope="module")
def undisturbed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The output folder of a run nobody interrupts."""
    folder = tmp_path_factory.mktemp("undisturbed")
    out = folder / "out"
    proc = subprocess.run(plan_args(folder / "cache", out), capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert sorted(visible(out)) == sorted(OUTPUTS)
    return out


#: how each signal ends the run: Ctrl-C is exit code 130; SIGTERM and SIGKILL end it by the signal
ENDS = {signal.SIGINT: 130, signal.SIGTERM: -signal.SIGTERM, signal.SIGKILL: -signal.SIGKILL}
#: where each signal is sent. SIGTERM goes through the handler SIGINT goes through (tmpnav.lifetime):
#: it is sent while the outputs are written, where its exit differs; its end of the oracle's workers
#: and of a solving JVM is tests/oracle/test_worker_lifetime.py's and tests/task/test_enhsp_persistent.py's
POINTS_OF = {signal.SIGINT: tuple(POINTS), signal.SIGTERM: ("writing",), signal.SIGKILL: tuple(POINTS)}
#: the one line each says (a process killed by SIGKILL says nothing)
SAID = {signal.SIGINT: "error: interrupted", signal.SIGTERM: "error: terminated (SIGTERM)"}


@pytest.mark.parametrize("sig", list(ENDS), ids=lambda s: s.name)
def test_a_killed_plan_leaves_no_process_no_half_written_file_and_the_same_next_plan(
    sig: signal.Signals, undisturbed: Path, tmp_path: Path
) -> None:
    cache, out, log = tmp_path / "cache", tmp_path / "out", tmp_path / "log.txt"
    shutil.copytree(undisturbed, out)  # the earlier plan, which a killed run must leave as it was
    earlier = visible(out)
    for point in POINTS_OF[sig]:
        code, started = kill_at(point, sig, plan_args(cache, out), out, log)
        said = log.read_text()
        assert code == ENDS[sig], f"{point}: exit status {code}: {said}"
        assert leftovers(started) == [], f"{point}: processes outlived tmpnav plan ({sig.name})"
        assert scratch_left(log) == [], f"{point}: temporary files outlived tmpnav plan ({sig.name})"
        assert visible(out) == earlier, f"{point}: the earlier plan's files changed"
        assert "Traceback" not in said, said
        if sig != signal.SIGKILL:  # a run that could clean up did
            assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUTS), f"{point}: leftovers"
            assert said.strip() == SAID[sig], said
    done = subprocess.run(plan_args(cache, out), capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUTS)  # the killed runs' temporary files are gone
    assert_same_plan(out, undisturbed)


def assert_same_plan(out: Path, undisturbed: Path) -> None:
    """The next run plans as an undisturbed one: the same plan when both searches ran to their
    end (converged, optimal, solved); the anytime search stopped by its time budget may stop
    elsewhere on a loaded machine (the test's plan runs under the default budget), so then the
    plan must be a sound one: as costed, so executed, for the same goals."""
    mine, theirs = json.loads((out / "plan.json").read_text()), json.loads((undisturbed / "plan.json").read_text())
    budget = "time budget" in {(doc.get("search") or {}).get("stopped") for doc in (mine, theirs)}
    if not budget:
        assert the_plan(out) == the_plan(undisturbed)
        return
    assert mine["goals"] == theirs["goals"] and mine["status"] == theirs["status"]
    assert mine["cost"]["planner"] == pytest.approx(mine["cost"]["resimulated"], rel=1e-9)
