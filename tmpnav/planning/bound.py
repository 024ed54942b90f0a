"""The certified lower bound of a run's plan space, for the anytime search's gap."""

from __future__ import annotations

from dataclasses import replace

from tmpnav.attachment.floors import motion_floors
from tmpnav.planning.run import TaskRun
from tmpnav.task.bound import Bound, lower_bound, makespan_bound

#: paired moves beyond which the bound of the table gives way to the motion floors: bounding
#: each pair without joint simulation takes about 0.2 ms (20 rooms and 2 robots: 130,000 pairs)
MAX_BOUND_PAIRS = 25_000


def certified_bound(run: TaskRun) -> Bound:
    """A lower bound on the objective of every plan of the anytime search's plan space.

    On the sum of action costs: with table costs and at most :data:`MAX_BOUND_PAIRS` paired
    moves possible, the bound of the table with every pair at its cost or its lower bound
    (:func:`tmpnav.task.bound.lower_bound`); otherwise, and with carried costs (where a move's
    cost depends on the beliefs it starts from), the bound of the moves' motion floors
    (:mod:`tmpnav.attachment.floors`), which hold in every context and for every paired move.
    When the objective prices time, plus its price of the makespan's lower bound from the
    moves' time floors (:func:`tmpnav.task.bound.makespan_bound`): both bounds hold for every
    plan at once, so their weighted sum bounds its objective."""
    sp, goals, canonical = run.planner, run.goals, run.canonical
    floors = motion_floors(run.scenario, canonical.oracle.ctx.roadmap, canonical.start_location, goals)
    bound = None
    if run.choice.costs == "table":
        table = canonical.bound_table(goals, MAX_BOUND_PAIRS)
        if table is not None:
            if sp.encoding != "mixed":
                table = replace(table, pair={})
            bound = lower_bound(table, goals, sp.pair_min_gain)
    if bound is None:
        bound = lower_bound(floors, goals, 0.0)
        bound = replace(bound, relaxation=f"motion floors, {bound.relaxation}")
    if not run.span_weight:
        return bound
    span = makespan_bound(floors, goals)
    value = bound.value + run.span_weight * span
    parts = {**bound.parts, "makespan": span}
    return replace(bound, value=value, relaxation=f"{bound.relaxation} + makespan floor {span:.1f} s", parts=parts)
