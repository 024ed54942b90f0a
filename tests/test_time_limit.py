"""``--time-limit S`` (``planner.time_limit``) bounds a whole run: the best plan so far, or exit 5.

Each test is bounded by its limit, never timed: a run with no plan at its limit ends with exit
code 5 and one line naming the stage that took the time, and writes nothing; a search whose
time runs out after its first plan returns that plan.
"""

from __future__ import annotations

import os
import random
import re
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import pytest
import yaml

from tests.task.instances import building_instance
from tmpnav import deadline
from tmpnav.errors import TimeLimitError
from tmpnav.task.budget import SEARCH_CAP
from tmpnav.task.model import TableModel
from tmpnav.task.plans import Plan
from tmpnav.task.search import SearchOptions, search
from tmpnav.types import CostTable, Goals

ROOT = Path(__file__).resolve().parents[1]
LINE = re.compile(r"error: no plan within --time-limit 0\.2 s: the \w+ stage took the time \(.*\)")


def tmpnav(*args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, env=env, cwd=ROOT)


@pytest.mark.slow
def test_no_plan_within_the_limit_is_exit_5_naming_the_stage_and_writes_nothing(tmp_path: Path) -> None:
    out = tmp_path / "out"
    proc = tmpnav("plan", "configs/building-20.yaml", "--no-cache", "--time-limit", "0.2", "-o", str(out))
    assert proc.returncode == 5, proc.stderr
    assert LINE.fullmatch(proc.stderr.strip()), proc.stderr
    assert not out.exists() and proc.stdout == ""


@pytest.mark.slow
def test_the_scenario_key_bounds_the_run_too(tmp_path: Path) -> None:
    scenario = yaml.safe_load((ROOT / "configs" / "building-20.yaml").read_text())
    scenario.setdefault("planner", {})["time_limit"] = 0.2
    path = tmp_path / "limited.yaml"
    path.write_text(yaml.safe_dump(scenario))
    proc = tmpnav("plan", str(path), "--no-cache")
    assert proc.returncode == 5 and LINE.fullmatch(proc.stderr.strip()), proc.stderr


def test_a_bad_time_limit_is_one_line_and_exit_2() -> None:
    proc = tmpnav("plan", "configs/corridor.yaml", "--time-limit", "-3")
    assert proc.returncode == 2 and "--time-limit" in proc.stderr and "Traceback" not in proc.stderr


class OutOfTime(TableModel):
    """A table whose sub-problems' costs are asked for past the run's time limit (the oracle
    then raises TimeLimitError between its blocks of work, tmpnav.deadline)."""

    def subtable(self, head: Plan, robots: Sequence[str], rooms: Sequence[str], goals: Goals) -> CostTable:
        raise TimeLimitError("no plan within --time-limit 1 s", 1.0)


def test_past_the_limit_the_search_returns_its_best_plan_so_far() -> None:
    table, goals = building_instance(random.Random(4), 12, 2)
    result = search(OutOfTime(table, 0.05), goals, SearchOptions(parallel=1, work=50))
    assert result.plan and result.stopped == "time budget" and SEARCH_CAP in result.capped
    assert result.cost.total == pytest.approx(TableModel(table, 0.05).plan_cost(result.plan).total)


def test_the_least_threshold_is_not_searched_for_past_the_time_limit(monkeypatch: pytest.MonkeyPatch) -> None:
    """A plan over its max_risk at the end of its --time-limit: the error says so at once. The
    search for the least threshold that has a plan planned again with a fresh limit (a run of
    twice its limit or more)."""
    import time
    from types import SimpleNamespace

    from tmpnav import pipeline
    from tmpnav.errors import RiskError

    def never(*_: object) -> None:
        raise AssertionError("planned again past the run's time limit")

    monkeypatch.setattr(pipeline, "_planned", never)
    monkeypatch.setattr(pipeline, "_worst_move", lambda _: "r1's move A -> B is at 0.3")
    planner = SimpleNamespace(max_risk=0.05, time_limit=10.0, max_risk_from="--max-risk")
    report = SimpleNamespace(
        scenario=SimpleNamespace(planner=planner, map=None),
        worst_risk=0.3,
        times=SimpleNamespace(started=time.perf_counter() - 11.0),
    )
    with pytest.raises(RiskError, match=r"within max_risk 0\.05 .*: r1.s move A -> B is at 0\.3"):
        pipeline.check_risk("x.yaml", pipeline.PlanOptions(), report)  # type: ignore[arg-type]


def test_a_commands_limit_counts_from_the_commands_start_for_its_first_run_only(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The command's imports are within its limit; a closed loop's replans and the plans of
    tmpnav serve each count from their own start."""
    monkeypatch.setattr(deadline, "COMMAND_STARTED", 100.0)
    assert deadline.run_started(102.5) == 100.0
    assert deadline.run_started(130.0) == 130.0  # the next run of the same process
    monkeypatch.setattr(deadline, "COMMAND_STARTED", 200.0)
    assert deadline.run_started(150.0) == 150.0  # a clock from before the command: its own


def test_the_search_leaves_a_share_of_the_limit_to_the_stages_after_it() -> None:
    assert deadline.Deadline(None).after_search() == 0.0
    assert deadline.Deadline(10.0).after_search() == deadline.AFTER_SEARCH_MIN
    assert deadline.Deadline(600.0).after_search() == pytest.approx(deadline.AFTER_SEARCH_SHARE * 600.0)
    # a long plan's files and figures take longer: 200 goals keep 15 s of a 120 s limit
    assert deadline.Deadline(120.0).after_search(200) == pytest.approx(deadline.AFTER_SEARCH_PER_GOAL * 200)
    assert deadline.Deadline(120.0).after_search(20) == pytest.approx(deadline.AFTER_SEARCH_SHARE * 120.0)


@pytest.mark.slow
def test_a_simulation_ended_by_its_time_limit_exits_with_its_files_written(tmp_path: Path) -> None:
    """Its sessions run on worker processes, forked while the parent held SIGTERM: the pool stopped
    at the limit must end them, else the command waits for them at exit forever."""
    out = tmp_path / "out"
    args = ("simulate", "configs/corridor-2robots.yaml", "--sessions", "100000", "--workers", "2")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", *args, "--time-limit", "6", "-o", str(out)],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    assert re.search(r"--time-limit 6 s: \d+ of 100000 sessions ran", proc.stdout), proc.stdout
    assert (out / "summary.md").is_file()
