"""With carried beliefs the unfolded search finds the schedule of least objective.

Each instance is a shipped world with two robots and 3-4 rooms to visit. A test enumerates
every plan of the entry rules (tests.attachment.support.every_plan), runs each on the team's
clock and prices it by the objective; the unfolded search's plan (its space: single moves,
and paired moves that save ``pair_min_gain`` when they start) can be no worse than the best
plan of single moves alone, no better than the best plan of all, and the value its search
reached is its plan's value on the clock.
"""

from __future__ import annotations

import pytest

from tests.attachment.support import carried_problem, every_plan, objective
from tmpnav.attachment.unfold import unfold
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.task.plans import Rules
from tmpnav.task.search_run import SearchRun
from tmpnav.task.stage import plan_unfolded

CASES = [
    ("corridor-2robots.yaml", ("L2", "L5", "L9")),
    ("corridor-2robots.yaml", ("L1", "L4", "L6", "L10")),
    ("sparse-warehouse.yaml", ("P1", "P3", "P8")),
    ("sparse-warehouse.yaml", ("P2", "P4", "P5", "P6")),
]


@pytest.mark.slow
@pytest.mark.parametrize(("config", "rooms"), CASES)
@pytest.mark.parametrize("span_weight", [0.0, 1.0])
def test_the_unfolded_plan_is_the_best_schedule(config: str, rooms: tuple[str, ...], span_weight: float) -> None:
    scenario, _, carried = carried_problem(config, rooms, 2)
    gain = scenario.planner.pair_min_gain
    graph = unfold(carried, scenario.goals, gain, span_weight)
    assert graph is not None
    rules = Rules(carried.start_location, scenario.goals)
    result = plan_unfolded(graph, carried, rules, scenario.planner, SearchRun(), span_weight)
    plans = every_plan(carried, scenario.goals)
    values = {p: objective(carried, p, span_weight) for p in plans}
    singles_only = min(v for p, v in values.items() if all(len(s) == 1 for s in p))
    ours = objective(carried, result.steps, span_weight)
    assert len(plans) > 10
    assert result.bound is not None and result.bound.value == pytest.approx(ours, rel=1e-9)
    assert min(values.values()) - 1e-9 <= ours <= singles_only + 1e-9, result.steps


@pytest.mark.slow
def test_five_rooms_through_the_pipeline() -> None:
    """`tmpnav plan`'s default (carried costs, auto search) on 5 rooms and 2 robots: the exact
    search, no worse than any schedule of single moves, and its planner cost is its re-simulated cost."""
    rooms = ("P1", "P2", "P3", "P5", "P8")
    scenario, world, _ = carried_problem("sparse-warehouse.yaml", rooms, 2)
    report = plan(scenario.source, PlanOptions.of(use_cache=False, workers=1), loaded=(scenario, world))
    assert report.task.search is not None and report.task.search.mode == "exact"
    assert report.task.bound is not None and report.task.bound.proved_optimal
    assert report.resimulated_cost == pytest.approx(report.planner_cost, rel=1e-12)
    assert report.schedule.makespan == pytest.approx(report.task.schedule.makespan)  # type: ignore[union-attr]
