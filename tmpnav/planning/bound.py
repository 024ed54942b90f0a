"""The certified lower bound of a run's plan space, for the anytime search's gap."""

from __future__ import annotations

import math
from dataclasses import replace

from tmpnav.attachment.floors import motion_floors
from tmpnav.oracle.executors import library
from tmpnav.planning.run import TaskRun
from tmpnav.task.bound import CUT_ROUNDS, Bound, lower_bound, makespan_bound
from tmpnav.types import CostTable, Goals

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
    moves' time floors and the jobs' services and windows (:func:`tmpnav.task.bound.makespan_bound`:
    each goal's least round trip of a robot that may serve it, from its start to its end; or
    :func:`_work_bound` where higher): both bounds hold for every plan at once, so their
    weighted sum bounds its objective."""
    sp, goals, canonical = run.planner, run.goals, run.canonical
    # with carried beliefs a robot leaves a room with the heading it arrived with
    arrived = run.choice.costs == "carried"
    paths = library(canonical.oracle.ctx).graph
    floors = motion_floors(run.scenario, paths, canonical.start_location, goals, arrived)
    bound = None
    if run.choice.costs == "table":
        table = canonical.bound_table(goals, MAX_BOUND_PAIRS)
        if table is not None:
            if sp.encoding != "mixed":
                table = replace(table, pair={})
            bound = lower_bound(table, goals, sp.pair_min_gain)
    # a replan (its incumbent the plan under way) has a short budget: the plain LP, no cuts
    rounds = 0 if run.incumbent else CUT_ROUNDS
    if bound is None:
        bound = lower_bound(floors, goals, 0.0, rounds)
        bound = replace(bound, relaxation=f"motion floors, {bound.relaxation}")
    if not run.span_weight:
        return bound
    timed = floors.with_service(goals)  # a move's time until its robot is free again
    span = max(makespan_bound(timed, goals), _work_bound(timed, goals, rounds))
    value = bound.value + run.span_weight * span
    parts = {**bound.parts, "makespan": span}
    return replace(bound, value=value, relaxation=f"{bound.relaxation} + makespan floor {span:.1f} s", parts=parts)


def _work_bound(floors: CostTable, goals: Goals, rounds: int = CUT_ROUNDS) -> float:
    """A lower bound on every schedule's makespan: the relaxation of :func:`lower_bound` over
    the moves' time floors bounds the summed time of every plan's moves (the argument of
    tmpnav/task/bound.py holds for any non-negative move prices, and a paired move takes each
    of its robots at least its own floor), the robots share that driving and each is busy for
    at most the makespan, so the makespan is at least the sum over the number of robots."""
    durations = replace(floors, single={m: floors.duration[m] for m in floors.single if m in floors.duration})
    work = lower_bound(durations, goals, 0.0, rounds).value
    return max(0.0, work) / max(1, len(floors.robots)) if math.isfinite(work) else 0.0
