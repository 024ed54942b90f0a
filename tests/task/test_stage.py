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


def test_the_exact_plan_over_schedules_is_remembered_too(tmp_path: Path) -> None:
    """A warm run of --costs table --search exact with a price on time read its plan from the
    cache, not the A* again (10 s at 10 rooms); a problem too large for the A* is remembered as
    such, so the warm run goes straight to the anytime search."""
    from tests.task.test_objectives import instance
    from tmpnav.task import stage

    table, goals = instance(3)
    task = TaskProblem(table, goals, PlannerOptions("enhsp-blind", "mixed", 120.0, 0.05), "stage-test", 1.0)
    store = DiskCache(tmp_path)
    try:
        cold = stage.plan_schedules(task, None, store)
        warm = stage.plan_schedules(task, None, store)
        again = stage.plan_schedules(task, None, store, replan=True)
        free = stage.plan_schedules(task)  # no store: found, not remembered
    finally:
        store.close()
    assert cold is not None and warm is not None and again is not None and free is not None
    assert not cold.plan_hit and warm.plan_hit and not again.plan_hit and not free.plan_hit
    assert cold.steps == warm.steps == again.steps == free.steps
    assert cold.step_costs == warm.step_costs and cold.schedule == warm.schedule
    assert cold.bound == warm.bound and cold.bound is not None and cold.bound.proved_optimal
    assert cold.counts == warm.counts and cold.engine == warm.engine == stage.SCHEDULES_ENGINE


def test_a_problem_too_large_for_the_schedules_is_remembered_as_such(tmp_path: Path, monkeypatch) -> None:
    from tests.task.test_objectives import instance
    from tmpnav.task import stage

    table, goals = instance(5)
    task = TaskProblem(table, goals, PlannerOptions("enhsp-blind", "mixed", 120.0, 0.05), "stage-test", 1.0)
    calls: list[int] = []
    real = stage.exact_schedule

    def limited(*args, **kw):
        calls.append(1)
        return real(*args, **kw, max_states=0)

    monkeypatch.setattr(stage, "exact_schedule", limited)
    store = DiskCache(tmp_path)
    try:
        assert stage.plan_schedules(task, None, store) is None
        assert stage.plan_schedules(task, None, store) is None
    finally:
        store.close()
    assert len(calls) == 1
