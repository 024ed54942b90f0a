"""Motion floors: no move costs less, whatever beliefs it starts from, alone, paired or among
robots that move at once."""

from __future__ import annotations

import pytest

from tests.attachment.support import carried_problem, every_plan
from tmpnav.attachment.floors import motion_floors
from tmpnav.task.bound import lower_bound


@pytest.mark.slow
@pytest.mark.parametrize(
    ("config", "rooms"),
    [("corridor-2robots.yaml", ("L2", "L5", "L9")), ("sparse-warehouse.yaml", ("P1", "P3", "P8", "P5"))],
)
def test_every_move_of_every_schedule_costs_at_least_its_floor(config: str, rooms: tuple[str, ...]) -> None:
    scenario, _, carried = carried_problem(config, rooms, 2)
    floors = motion_floors(scenario, carried.lib.roadmap, carried.start_location, scenario.goals)
    plans = every_plan(carried, scenario.goals)
    assert any(len(s) == 2 for p in plans for s in p)
    best = float("inf")
    for plan in plans:  # every step of every plan, in the context the team's clock gives it
        cost = carried.plan_cost(plan)
        for step, c in zip(plan, cost.steps, strict=True):
            assert sum(floors.single[m] for m in step) <= c * (1 + 1e-9), step
        best = min(best, cost.total)
    assert lower_bound(floors, scenario.goals, 0.0).value <= best
