"""The exact search with carried costs: the belief space unfolded (:mod:`tmpnav.attachment.unfold`)
and searched by ENHSP (:func:`tmpnav.task.stage.plan_unfolded`); where it is too large to
unfold, the anytime search, unless the exact search was asked for by name. Where robots are kept
apart and that makes the exact plan dearer, the anytime search goes on from it, every plan
priced as executed."""

from __future__ import annotations

from tmpnav.attachment.apart import ExecutedCost
from tmpnav.attachment.unfold import unfold
from tmpnav.errors import InputError
from tmpnav.planning.anytime import anytime_carried, executed_cost
from tmpnav.planning.run import Planned, TaskRun
from tmpnav.results import TaskResult
from tmpnav.task.bound import Bound
from tmpnav.task.plans import Rules
from tmpnav.task.search import EPSILON
from tmpnav.task.stage import plan_unfolded


def exact_carried(run: TaskRun) -> Planned:
    """ENHSP's optimal plan over the unfolded belief space: the plan of least executed cost."""
    if run.goals.optional:  # the unfolded search has no price for a goal left undone
        if run.planner.search == "exact":
            raise InputError(
                "optional goals (goals.jobs[].penalty) are planned with carried costs by the anytime search; "
                "plan them with --search anytime (or auto), or --costs table for an exact search"
            )
        return anytime_carried(run)
    with run.times.timed("oracle"):
        graph = unfold(run.carried, run.goals, run.planner.pair_min_gain, run.span_weight)
    if graph is None:
        if run.planner.search == "exact":
            raise InputError(
                f"the belief space of {len(run.goals.all_rooms)} goal rooms and {len(run.scenario.robots)} robots "
                "is too large to unfold; plan it with --search anytime (or auto)"
            )
        return anytime_carried(run)
    rules = Rules(run.canonical.start_location, run.goals)
    task = plan_unfolded(graph, run.carried, rules, run.planner, run.search, run.span_weight)
    executed = executed_cost(run)
    if executed is not None and _dearer_kept_apart(run, task, executed):
        # its optimum as planned bounds every plan as executed (kept apart, a plan costs no less)
        floor = None if task.bound is None else Bound(task.bound.value, "exact, as planned")
        seeds = {"the exact plan of the unfolded belief space": task.steps}
        return anytime_carried(run, seeds, floor, executed)
    return Planned(run.canonical.seen(), task)


def _dearer_kept_apart(run: TaskRun, task: TaskResult, executed: ExecutedCost) -> bool:
    """Whether keeping the robots of the unfolded search's plan apart (waits, detours,
    sidesteps: what ``tmpnav plan`` will execute) costs more than the plan as searched. The
    unfolded belief space has no clock of where each robot is, so its optimum is the optimum as
    planned, robots passing through each other; where keeping them apart costs nothing it is
    the plan executed, else the anytime search goes on from it with every plan priced as
    executed (tmpnav.planning.anytime), so that the plan picked is the plan executed. A plan whose
    robots stay in each other's way under a chance constraint ranks dearer too (``PlanCost.ranked``)."""
    if not task.steps:
        return False
    planned = run.carried.plan_cost(task.steps)
    value = planned.value(run.span_weight)
    return executed(task.steps, planned).ranked(run.span_weight) > value * (1 + EPSILON) + EPSILON
