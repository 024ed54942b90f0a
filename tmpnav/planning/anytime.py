"""The anytime search of a run (:mod:`tmpnav.task.search`): on table costs computed as it asks
for them, or on carried costs in two phases."""

from __future__ import annotations

from dataclasses import replace

from tmpnav.choices import exact_fits
from tmpnav.planning.bound import certified_bound
from tmpnav.planning.run import Planned, TaskRun
from tmpnav.planning.table import full_table
from tmpnav.results import TaskResult
from tmpnav.task.bound import Bound
from tmpnav.task.plans import Plan
from tmpnav.task.stage import AnytimeTask, TaskProblem, plan_anytime, plan_task

#: seconds of the run's budget kept for what runs after the search's budget is spent (its last
#: sub-problem, the re-simulation)
BUDGET_MARGIN = 0.5


def anytime_table(run: TaskRun) -> Planned:
    """The anytime search on table costs, with the certified lower bound of the table."""
    bound = _bound(run)
    task = plan_anytime(
        AnytimeTask(run.canonical, run.goals, run.planner, run.span_weight), run.search, _left(run), bound
    )
    return Planned(run.canonical.seen(), task)


def anytime_carried(run: TaskRun) -> Planned:
    """The anytime search with carried costs, in two phases: first with table costs (each
    computed once and shared by every sub-problem) for up to half the budget, then with
    carried costs from the cheapest of its plan, OR-Tools' routes and (where quick) the
    exact plan of the table, every plan costed as executed."""
    seeds: dict[str, Plan] = {}
    if exact_fits(len(run.goals.all_rooms), len(run.scenario.robots), "table"):
        table = full_table(run.scenario, run.world, run.canonical.oracle, run.times)
        exact = plan_task(TaskProblem.of(run.scenario, table), run.store, run.replan, run.times)
        seeds["the exact plan of the cost table"] = exact.steps
    phase = replace(run.search, label="table costs")
    first = plan_anytime(AnytimeTask(run.canonical, run.goals, run.planner, run.span_weight), phase, run.left() / 2)
    seeds["the anytime search's plan with table costs"] = first.steps
    bound = _bound(run)
    task = plan_anytime(
        AnytimeTask(run.carried, run.goals, run.planner, run.span_weight), run.search, _left(run), bound, seeds
    )
    return Planned(run.canonical.seen(), _after(task, first))


def _bound(run: TaskRun) -> Bound:
    with run.times.timed("bound"):
        return certified_bound(run)


def _left(run: TaskRun) -> float:
    """The search's budget: the run's, less what its stages spent and :data:`BUDGET_MARGIN`."""
    return max(run.left() - BUDGET_MARGIN, 0.0)


def _after(task: TaskResult, first: TaskResult) -> TaskResult:
    """The carried phase's result, its summary telling of the phase with table costs before it."""
    assert task.search is not None and first.search is not None
    search = replace(
        task.search,
        start=f"{task.search.start}; before it, the search with table costs: "
        f"{first.search.subproblems} sub-problems, stopped: {first.search.stopped}",
        subproblems=task.search.subproblems + first.search.subproblems,
    )
    return replace(task, search=search)
