"""Motion floors: no move costs less, whatever beliefs it starts from, alone or paired."""

from __future__ import annotations

import pytest

from tests.attachment.support import carried_problem, cheapest_plan_by_enumeration
from tmpnav.attachment.floors import motion_floors
from tmpnav.attachment.unfold import unfold
from tmpnav.task.bound import lower_bound


@pytest.mark.slow
@pytest.mark.parametrize(
    ("config", "rooms"),
    [("corridor-2robots.yaml", ("L2", "L5", "L9")), ("sparse-warehouse.yaml", ("P1", "P3", "P8", "P5"))],
)
def test_every_action_of_the_belief_space_costs_at_least_its_floors(config: str, rooms: tuple[str, ...]) -> None:
    scenario, _, carried = carried_problem(config, rooms, 2)
    floors = motion_floors(scenario, carried.lib.roadmap, carried.start_location, scenario.goals)
    graph = unfold(carried, scenario.goals, scenario.planner.pair_min_gain)
    assert graph is not None and len(graph.edges) > 20
    assert any(len(e.step) == 2 for e in graph.edges) or config.startswith("corridor")
    for edge in graph.edges:  # every action in every context the plans reach
        assert sum(floors.single[m] for m in edge.step) <= edge.cost * (1 + 1e-9), edge
    best, _, _ = cheapest_plan_by_enumeration(carried, scenario.goals, scenario.planner.pair_min_gain)
    assert lower_bound(floors, scenario.goals, 0.0).value <= best
