"""With carried beliefs the unfolded search finds the plan of least executed cost.

Each instance is a shipped world with two robots and 3-5 rooms to visit; a test enumerates
every task plan (single moves, and paired moves that save ``pair_min_gain`` over the same two
moves made alone from the same beliefs), runs each with beliefs carried step by step, and
compares the cheapest with the plan ``tmpnav plan`` returns (issue: carried beliefs).
"""

from __future__ import annotations

import pytest

from tests.attachment.support import carried_problem, cheapest_plan_by_enumeration
from tmpnav.attachment.unfold import unfold
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.task.plans import Rules
from tmpnav.task.search import SearchRun
from tmpnav.task.stage import plan_unfolded

CASES = [
    ("corridor-2robots.yaml", ("L2", "L5", "L9")),
    ("corridor-2robots.yaml", ("L1", "L4", "L6", "L10")),
    ("sparse-warehouse.yaml", ("P1", "P3", "P8")),
    ("sparse-warehouse.yaml", ("P2", "P4", "P5", "P6")),
]


@pytest.mark.slow
@pytest.mark.parametrize(("config", "rooms"), CASES)
def test_the_unfolded_plan_is_the_cheapest_of_every_plan(config: str, rooms: tuple[str, ...]) -> None:
    scenario, _, carried = carried_problem(config, rooms, 2)
    gain = scenario.planner.pair_min_gain
    best, best_plan, plans = cheapest_plan_by_enumeration(carried, scenario.goals, gain)
    graph = unfold(carried, scenario.goals, gain)
    assert graph is not None
    result = plan_unfolded(graph, Rules(carried.start_location, scenario.goals), scenario.planner, SearchRun())
    assert plans > 10
    assert result.planner_cost == pytest.approx(best, rel=1e-9), (result.steps, best_plan)
    assert carried.plan_cost(result.steps).total == pytest.approx(best, rel=1e-9)


@pytest.mark.slow
def test_five_rooms_through_the_pipeline(tmp_path: object) -> None:
    """`tmpnav plan`'s default (carried costs, auto search) on 5 rooms and 2 robots: the
    cheapest plan of all, and its planner cost is its re-simulated cost."""
    rooms = ("P1", "P2", "P3", "P5", "P8")
    scenario, world, carried = carried_problem("sparse-warehouse.yaml", rooms, 2)
    best, _, _ = cheapest_plan_by_enumeration(carried, scenario.goals, scenario.planner.pair_min_gain)
    report = plan(scenario.source, PlanOptions.of(use_cache=False, workers=1), loaded=(scenario, world))
    assert report.task.search is not None and report.task.search.mode == "exact"
    assert report.task.bound is not None and report.task.bound.proved_optimal
    assert report.planner_cost == pytest.approx(best, rel=1e-9)
    assert report.resimulated_cost == pytest.approx(report.planner_cost, rel=1e-12)
