"""The exact search with table costs: every cost the encoding may need first, then one optimal
search over the whole table: ENHSP's for the paper's sum of action costs (the paper's pipeline;
:func:`tmpnav.task.stage.plan_task`), the A* over every schedule when the objective prices
the team's time (:func:`tmpnav.task.stage.plan_schedules`)."""

from __future__ import annotations

from tmpnav.planning.anytime import anytime_table
from tmpnav.planning.run import Planned, TaskRun
from tmpnav.planning.table import full_table
from tmpnav.task.stage import TaskProblem, plan_schedules, plan_task


def exact_table(run: TaskRun) -> Planned:
    """The table of every move and paired move the encoding asks for, and its optimal plan: ENHSP's
    for the sum of action costs, the A* over every schedule (tmpnav.task.schedules) when the
    objective prices time; where that is too large, the anytime search."""
    table = full_table(run.scenario, run.world, run.canonical.oracle, run.times, run.canonical.origin)
    task = TaskProblem.of(run.scenario, table)
    if not task.span_weight and not run.goals.windows:  # ENHSP's search has no clock for windows
        return Planned(table, plan_task(task, run.store, run.replan, run.times))
    found = plan_schedules(task, run.times, run.store, run.replan)
    if found is None:
        return anytime_table(run)
    return Planned(table, found)
