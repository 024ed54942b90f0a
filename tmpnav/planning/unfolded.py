"""The exact search with carried costs: the belief space unfolded (:mod:`tmpnav.attachment.unfold`)
and searched by ENHSP (:func:`tmpnav.task.stage.plan_unfolded`); where it is too large to
unfold, the anytime search, unless the exact search was asked for by name."""

from __future__ import annotations

from tmpnav.attachment.unfold import unfold
from tmpnav.errors import InputError
from tmpnav.planning.anytime import anytime_carried
from tmpnav.planning.run import Planned, TaskRun
from tmpnav.task.plans import Rules
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
    return Planned(
        run.canonical.seen(), plan_unfolded(graph, run.carried, rules, run.planner, run.search, run.span_weight)
    )
