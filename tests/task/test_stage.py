"""The task stage's entry point: a plan solved once, then remembered, never changed by the cache."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.task.test_optimality import random_table
from tmpnav.oracle.cache import DiskCache
from tmpnav.results import StageTimes
from tmpnav.task.decode import step_cost
from tmpnav.task.stage import TaskProblem, plan_task
from tmpnav.types import PlannerOptions

pytestmark = pytest.mark.slow


def test_plan_task_solves_then_remembers(tmp_path: Path) -> None:
    table, goals = random_table(3, 2, 3, False)
    task = TaskProblem(table, goals, PlannerOptions("enhsp-blind", "mixed", 120.0, 0.05), "stage-test")
    store = DiskCache(tmp_path)
    try:
        cold_times, warm_times = StageTimes(), StageTimes()
        cold = plan_task(task, store, times=cold_times)
        warm = plan_task(task, store, times=warm_times)
        again = plan_task(task, store, replan=True)
    finally:
        store.close()
    assert not cold.plan_hit and cold.pddl is not None and warm.plan_hit and warm.pddl is None
    assert not again.plan_hit
    assert cold.steps == warm.steps == again.steps and cold.action_names == warm.action_names
    assert cold.step_costs == tuple(step_cost(table, s) for s in cold.steps)
    assert cold.counts == warm.counts and cold.counts.single_moves == len(table.single)
    assert {"encode", "planner"} <= set(cold_times.seconds) and warm_times.seconds["encode"] == 0.0
    assert task.encode().n_actions == cold.counts.actions  # encoded again on demand


def test_without_a_store_nothing_is_remembered() -> None:
    table, goals = random_table(4, 2, 2, False)
    task = TaskProblem(table, goals, PlannerOptions("enhsp-blind", "single", 120.0, 0.05), "stage-test")
    first, second = plan_task(task), plan_task(task)
    assert not first.plan_hit and not second.plan_hit and first.steps == second.steps
