"""ENHSP in the run's one JVM (tmpnav.task.enhsp_jvm: a server process) against ENHSP as a
process per solve.

The server is the test process's own: once started it stays for the session, so these tests
share it (as the sub-problems of a run do).
"""

from __future__ import annotations

import functools
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.children import start_python
from tests.task.instances import small_instance
from tests.task.test_pddl_text import validate_with_unified_planning
from tmpnav.errors import PlannerTimeoutError
from tmpnav.task import enhsp_jvm
from tmpnav.task.pddl_text import PddlTask, sample_task, write_task
from tmpnav.task.solve import side_by_side, solve_text, warm_up

pytestmark = pytest.mark.skipif(enhsp_jvm.unavailable() is not None, reason=str(enhsp_jvm.unavailable()))

#: a numeric problem whose blind search takes minutes: 5,000 x 5,000 states before the goal
SLOW_DOMAIN = """(define (domain count) (:requirements :numeric-fluents) (:functions (x) (y))
  (:action incx :parameters () :precondition (< (x) 100000) :effect (increase (x) 1))
  (:action incy :parameters () :precondition (< (y) 100000) :effect (increase (y) 1)))"""
SLOW_PROBLEM = """(define (problem far) (:domain count) (:init (= (x) 0) (= (y) 0))
  (:goal (and (>= (x) 5000) (>= (y) 5000))))"""

#: (seed, robots, rooms, encoding, planner): sub-problem sized tasks of both encodings
CASES = [
    (1, 2, 3, "single", "enhsp-blind"),
    (2, 2, 4, "mixed", "enhsp-blind"),
    (3, 3, 3, "mixed", "enhsp-opt"),
    (4, 2, 4, "mixed", "enhsp"),
]


def _task(seed: int, robots: int, rooms: int, encoding: str) -> PddlTask:
    table, goals = small_instance(random.Random(seed), robots, rooms, 0.3)
    return write_task(table, goals, encoding, min_gain=0.0)


def _solve(task: PddlTask, planner: str, timeout: float = 60.0) -> tuple[tuple[str, tuple[str, ...]], ...]:
    return solve_text(task.domain, task.problem, planner, timeout).actions


def test_the_jvm_gives_the_plans_of_a_process_per_solve_and_they_validate(monkeypatch: pytest.MonkeyPatch) -> None:
    tasks = [(_task(*case[:4]), case[4]) for case in CASES]
    in_jvm = [_solve(task, planner) for task, planner in tasks]
    assert enhsp_jvm.unavailable() is None  # they ran in the JVM, not in a fallback
    monkeypatch.setenv(enhsp_jvm.MODE_ENV, "process")
    assert enhsp_jvm.unavailable() == "TMPNAV_ENHSP=process"
    in_processes = [_solve(task, planner) for task, planner in tasks]
    assert in_jvm == in_processes
    for (task, _), actions in zip(tasks, in_jvm, strict=True):
        validate_with_unified_planning(task, actions)


def test_a_solve_does_not_depend_on_the_solves_before_it() -> None:
    """ENHSP keeps static state; a slot reused in another order plans the same."""
    tasks = [_task(*case[:4]) for case in CASES[:3]]
    forwards = [_solve(task, "enhsp-blind") for task in tasks]
    backwards = [_solve(task, "enhsp-blind") for task in reversed(tasks)]
    assert forwards == backwards[::-1]  # the server's slots reused, their statics put back
    server = enhsp_jvm._JVM.server
    assert server is not None and server.process.poll() is None


def test_two_solves_at_once_get_their_own_plans() -> None:
    """The anytime search solves two sub-problems side by side: each in a slot of its own."""
    tasks = [_task(*case[:4]) for case in CASES[:2]] * 2
    alone = [_solve(task, "enhsp-blind") for task in tasks]
    together: list[object] = [None] * len(tasks)

    def solve(i: int) -> None:
        together[i] = _solve(tasks[i], "enhsp-blind")

    threads = [threading.Thread(target=solve, args=(i,)) for i in range(len(tasks))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert together == alone


def test_a_search_past_its_time_limit_is_a_timeout_and_the_run_goes_on() -> None:
    small = _task(*CASES[0][:4])
    _solve(small, "enhsp-blind")  # the JVM started: the limit below times ENHSP only
    start = time.perf_counter()
    with pytest.raises(PlannerTimeoutError, match="time limit of 1 s"):
        solve_text(SLOW_DOMAIN, SLOW_PROBLEM, "enhsp-blind", 1.0)
    assert time.perf_counter() - start < 1.0 + enhsp_jvm.STOP_GRACE + 2.0
    # Java 17-19 stop the search and keep the JVM; later Javas leave the run to processes
    assert enhsp_jvm.unavailable() is None or "could not be stopped" in str(enhsp_jvm.unavailable())
    assert _solve(small, "enhsp-blind")


def test_without_the_jvm_the_process_path_plans(monkeypatch: pytest.MonkeyPatch) -> None:
    task = _task(*CASES[1][:4])
    expected = _solve(task, "enhsp-blind")
    monkeypatch.setattr(enhsp_jvm._JVM, "broken", "the JVM did not start: test")
    assert not enhsp_jvm.usable("")
    assert enhsp_jvm.describe() == "in a JVM process per solve (the JVM did not start: test)"
    called = []
    monkeypatch.setattr(enhsp_jvm, "run", lambda *a: called.append(a))
    assert _solve(task, "enhsp-blind") == expected
    assert not called


def test_without_the_servers_jar_the_reason_is_said(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setattr(enhsp_jvm, "HELPER_JAR", tmp_path / "missing.jar")
    assert "make java" in str(enhsp_jvm.unavailable())
    assert "a JVM process per solve" in enhsp_jvm.describe()


def _java_children(pid: int) -> str:
    return subprocess.run(["pgrep", "-P", str(pid), "java"], capture_output=True, text=True).stdout


def _gone(pids: str, within: float = 5.0) -> bool:
    """Whether the processes ``pids`` (pgrep's lines) have all ended within ``within`` seconds."""
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        if all(not os.path.exists(f"/proc/{p}") or _zombie(p) for p in pids.split()):
            return True
        time.sleep(0.05)
    return False


def _zombie(pid: str) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] == "Z"
    except OSError:
        return True


def guarded_run(imports: str, call: str) -> str:
    """A run in miniature, guarded as the command line guards it: ``call`` searches with ENHSP,
    and an interrupted or terminated run exits with 130 or 143."""
    return f"""
import functools, sys
from tmpnav.lifetime import Terminated, guard
from tmpnav.task.solve import {imports}
guard()
try:
    print("solving", flush=True)
    {call}
except KeyboardInterrupt:
    sys.exit(130)
except Terminated:
    sys.exit(143)
"""


#: one search in the JVM
INTERRUPTED_RUN = guarded_run("solve_text", f"solve_text({SLOW_DOMAIN!r}, {SLOW_PROBLEM!r}, 'enhsp-blind', 120.0)")


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_during_a_search_in_the_jvm_ends_the_run_at_once(sig: signal.Signals, code: int) -> None:
    """The JVM (-Xrs) leaves SIGINT and SIGTERM to tmpnav: the run ends as interrupted, now."""
    proc = start_python(INTERRUPTED_RUN)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "solving\n"
        time.sleep(4.0)  # the server started, ENHSP searching
        assert proc.poll() is None
        server = _java_children(proc.pid)
        assert len(server.split()) == 1  # one java process: the run's server
        start = time.perf_counter()
        proc.send_signal(sig)
        assert proc.wait(timeout=10) == code
        assert time.perf_counter() - start < 3.0
        assert _gone(server)  # the server ended with the run
    finally:
        proc.kill()
        proc.wait()


#: two searches side by side in the JVM, as the anytime search solves sub-problems
INTERRUPTED_PAIR = guarded_run(
    "side_by_side, solve_text",
    f"side_by_side([functools.partial(solve_text, {SLOW_DOMAIN!r}, {SLOW_PROBLEM!r}, 'enhsp-blind', 120.0)] * 2)",
)


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_during_searches_side_by_side_ends_the_run_at_once(sig: signal.Signals, code: int) -> None:
    """The kernel may give the signal to a pool thread or a JVM thread: the main thread still
    handles it within a slice, and the searches under way are stopped, not waited for (their
    time limit is 120 s)."""
    proc = start_python(INTERRUPTED_PAIR)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "solving\n"
        time.sleep(4.0)  # the server started, both searches running
        assert proc.poll() is None
        server = _java_children(proc.pid)
        start = time.perf_counter()
        proc.send_signal(sig)
        assert proc.wait(timeout=30) == code
        assert time.perf_counter() - start < 3.0
        assert _gone(server)
    finally:
        proc.kill()
        proc.wait()


def test_a_killed_run_leaves_no_server_behind() -> None:
    """A run killed outright (no handler runs) still ends its server: the kernel closes the
    server's input, and the server ends when its input does."""
    proc = start_python(INTERRUPTED_RUN)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "solving\n"
        time.sleep(3.0)
        server = _java_children(proc.pid)
        assert server
        proc.kill()
        proc.wait(timeout=10)
        assert _gone(server)
    finally:
        proc.kill()
        proc.wait()


def test_warmed_searches_are_ready_and_plan_as_cold_ones() -> None:
    """warm_up has the server make one slot per search, each after a search of the sample;
    the searches after it plan as cold ones did."""
    task, sample = _task(*CASES[1][:4]), sample_task("mixed", 1.0, 0.05)
    cold = _solve(task, "enhsp-blind")
    warm_up("enhsp-blind", 2, sample.domain, sample.problem)
    warming = enhsp_jvm._JVM.warming
    assert warming is not None and warming.daemon
    together = side_by_side([functools.partial(_solve, task, "enhsp-blind")] * 2)
    assert enhsp_jvm.settle(60)
    assert together == [cold, cold]
    warm_up("enhsp-blind", 2, sample.domain, sample.problem)  # two idle slots: nothing to make
    assert enhsp_jvm.settle(10)


def test_the_warm_up_sample_is_a_sub_problem_enhsp_solves() -> None:
    for encoding, span in (("mixed", 1.0), ("mixed", 0.0), ("single", 0.5)):
        sample = sample_task(encoding, span, 0.05)
        actions = _solve(sample, "enhsp-blind")
        assert actions
        validate_with_unified_planning(sample, actions)


#: a run that ends while the warm-up still loads ENHSP or searches its sample
ENDING_WHILE_WARMING = """
import sys, time
from tmpnav.task.pddl_text import sample_task
from tmpnav.task.solve import warm_up
sample = sample_task("mixed", 1.0, 0.05)
warm_up("enhsp-blind", 2, sample.domain, sample.problem)
time.sleep(float(sys.argv[1]))
sys.exit(130)
"""


@pytest.mark.parametrize("delay", [0.1, 0.2, 0.25, 0.3, 0.4])
def test_a_run_that_ends_while_the_warm_up_runs_ends_at_once(delay: float) -> None:
    """A run may end while its server still loads ENHSP or searches the sample (with the JVM
    inside tmpnav, until 2026-11-28, 2 runs in 10 of this hung or crashed at exit): it ends
    at once, cleanly."""
    proc = subprocess.run(
        [sys.executable, "-c", ENDING_WHILE_WARMING, str(delay)], capture_output=True, text=True, timeout=30
    )
    assert proc.returncode == 130, proc.stderr
    assert "Traceback" not in proc.stderr and "Fatal" not in proc.stderr


def test_a_released_server_ends_and_the_next_search_starts_another() -> None:
    """A command's searches over, its JVM is let go (enhsp_jvm.release); a later search in the
    same process starts a new server and plans as before."""
    task = _task(*CASES[1][:4])
    first = _solve(task, "enhsp-blind")
    server = enhsp_jvm._JVM.server
    assert server is not None
    assert enhsp_jvm.release() is True
    assert server.process.poll() is not None and enhsp_jvm._JVM.server is None
    assert enhsp_jvm.release() is False  # nothing left to let go
    assert _solve(task, "enhsp-blind") == first
    assert enhsp_jvm._JVM.server is not None and enhsp_jvm._JVM.server is not server
