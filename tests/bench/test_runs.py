"""``tmpnav bench`` internals: ranges of counts, and a run killed at its time limit leaves no process behind."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tmpnav.bench.runs import Job, kill_group, make_jobs, rows
from tmpnav.bench.table import COLUMNS
from tmpnav.errors import InputError

#: a run that starts a helper process (as the oracle starts its worker pool) and hangs
HANGING_RUN = (
    "import subprocess, sys, time\n"
    "helper = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(300)'])\n"
    "print(helper.pid, flush=True)\n"
    "time.sleep(300)\n"
)


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a killed process that is not reaped yet is a zombie: dead for our purpose
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


def test_each_session_draws_its_own_goals_and_every_encoding_plans_the_same() -> None:
    names = [f"L{i}" for i in range(1, 11)]
    jobs = make_jobs("rooms", [2], [4], 3, ["mixed", "paper"], 0, Path("configs/corridor.yaml"), lambda _: names)
    by_session = {s: {j.goals for j in jobs if j.session == s} for s in range(3)}
    assert all(len(goals) == 1 for goals in by_session.values())  # both encodings, the same goals
    assert len({next(iter(g)) for g in by_session.values()}) == 3  # each session its own
    assert all(len(j.goals) == 4 and set(j.goals) <= set(names) for j in jobs)
    assert make_jobs("rooms", [2], [4], 3, ["mixed"], 0, Path("configs/corridor.yaml"), lambda _: names)[0].goals == (
        jobs[0].goals
    )  # drawn from the seed: the same on every run


def test_killing_a_run_kills_the_processes_it_started() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", HANGING_RUN],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    assert proc.stdout is not None
    helper = int(proc.stdout.readline())
    assert alive(helper)
    kill_group(proc)
    deadline = time.monotonic() + 10
    while alive(helper) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not alive(helper)
    assert proc.returncode is not None


def test_a_range_is_every_count_from_a_to_b_unless_it_names_its_step() -> None:
    from tmpnav.bench.runs import parse_counts

    assert parse_counts("2..4", "--rooms") == [2, 3, 4]
    assert parse_counts("2..10:2", "--rooms") == [2, 4, 6, 8, 10]
    assert parse_counts("10..40:10", "--rooms") == [10, 20, 30, 40]
    assert parse_counts("2,4,6", "--robots") == [2, 4, 6] and parse_counts("5", "--rooms") == [5]
    with pytest.raises(InputError, match=r"steps of 2 from 2 stop at 8, not 9; write 2\.\.8:2 or a list"):
        parse_counts("2..9:2", "--rooms")
    for bad in ("2..4:0", "two..ten", "0..3", "4..2"):
        with pytest.raises(InputError, match="--rooms"):
            parse_counts(bad, "--rooms")


def test_a_runs_row_records_the_makespan_next_to_cost_and_time() -> None:
    job = Job("rooms", "mixed", 2, 2, 0, ("L1", "L2"), Path("corridor-2robots.yaml"))
    measured = {"status": "solved-optimally", "times": {"total": 1.5}, "planner_cost": 10.0, "makespan": 161.5}
    out = rows(job, {"cold": measured, "warm": measured, "replan": {"status": "timeout"}})
    assert [list(r) for r in out] == [list(COLUMNS)] * 3 and COLUMNS[-1] == "makespan"
    assert [(r["total_s"], r["planner_cost"], r["makespan"]) for r in out] == [
        ("1.5", "10", "161.5"),
        ("1.5", "10", "161.5"),
        ("", "", ""),
    ]
