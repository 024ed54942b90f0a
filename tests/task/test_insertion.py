"""First routes when OR-Tools finds none in time: cheapest insertion, and no false "unreachable".

OR-Tools' routing solver needs its first solution within its time limit. With a tiny limit
(as a large problem on a busy machine has, at 200 rooms and 2 robots) it finds none
(ROUTING_FAIL_TIMEOUT), and the search used to end with "a goal room no robot can enter?",
exit code 3, though every room could be entered.
"""

from __future__ import annotations

import math
import random
from collections import Counter

import pytest

from tests.task.instances import building_instance, plan_cost
from tmpnav.errors import PlannerError
from tmpnav.task import first_routes
from tmpnav.task.bound import required_entries
from tmpnav.task.budget import ROUTING_CAP
from tmpnav.task.insertion import insertion_routes
from tmpnav.task.model import TableModel
from tmpnav.task.routing import Routes, solve_routes
from tmpnav.task.search import SearchOptions, search
from tmpnav.types import CostTable, Goals

#: OR-Tools' least time limit (1 ms). A first solution of 40 rooms can fit in it on a fast
#: machine; one of 200 rooms took 10-20 ms on a machine where 40 rooms took 2-5 ms.
TINY = 0.001


@pytest.mark.slow
def test_or_tools_times_out_on_two_hundred_rooms_with_a_tiny_limit() -> None:
    table, goals = building_instance(random.Random(2), 200, 2)
    routes = solve_routes(table, goals, time_limit=TINY, solution_limit=500)
    assert not routes.found and routes.status == "ROUTING_FAIL_TIMEOUT" and routes.timed_out


@pytest.mark.parametrize("seed", range(5))
def test_cheapest_insertion_routes_are_plans_through_every_goal(seed: int) -> None:
    table, goals = building_instance(random.Random(seed), 30, 3)
    routes = insertion_routes(table, goals, "ROUTING_FAIL_TIMEOUT")
    assert routes.found and routes.timed_out and "cheapest insertion" in routes.method
    cost = plan_cost(table, goals, [(m,) for m in routes.moves(table)])  # checked step by step
    assert cost == pytest.approx(routes.cost, rel=1e-12)
    entries = required_entries(table, goals)
    assert Counter(room for rooms in routes.rooms.values() for room in rooms) == Counter(x for _, x in entries)
    for r, x in entries:
        assert r is None or x in routes.rooms[r]  # a robot's own target is on its own route


def test_insertion_says_which_room_has_no_place() -> None:
    table, goals = building_instance(random.Random(5), 6, 2, max_pairs=0)
    single = {m: c for m, c in table.single.items() if m[2] != "R3"}
    table = CostTable(table.robots, table.rooms, table.locations, table.start_location, single, {})
    routes = insertion_routes(table, goals, "ROUTING_FAIL_TIMEOUT")
    assert not routes.found and "no place for R3" in routes.detail


@pytest.mark.slow
def test_a_routing_timeout_gives_a_plan_by_insertion_not_an_unreachable_room(monkeypatch: pytest.MonkeyPatch) -> None:
    """OR-Tools ends as it does at its time limit before a first solution (the test above),
    whatever the machine's speed."""
    table, goals = building_instance(random.Random(2), 40, 2)

    def timed_out(*_: object, **__: object) -> Routes:
        return Routes({}, math.inf, "ROUTING_FAIL_TIMEOUT", "nothing", timed_out=True)

    monkeypatch.setattr(first_routes, "solve_routes", timed_out)
    options = SearchOptions(work=4, parallel=1, budget=600)
    result = search(TableModel(table, 0.05), goals, options)
    assert result.start.startswith("cheapest insertion")
    assert ROUTING_CAP in result.capped  # the plan depends on the machine's speed: said so
    assert plan_cost(table, goals, list(result.plan)) == pytest.approx(result.cost.total)


def test_a_room_no_robot_can_enter_is_named() -> None:
    table, goals = building_instance(random.Random(5), 6, 2, max_pairs=0)
    single = {m: c for m, c in table.single.items() if m[2] != "R3"}
    table = CostTable(table.robots, table.rooms, table.locations, table.start_location, single, {})
    with pytest.raises(PlannerError, match=r"no robot allowed there can enter R3$"):
        search(TableModel(table, 0.05), Goals(goals.visit, goals.per_robot), SearchOptions(parallel=1, budget=30))


def test_a_room_entered_only_from_another_waits_for_it() -> None:
    """R3 is entered from R5 only, at a price that puts it first: it is placed once R5 is."""
    table, goals = building_instance(random.Random(5), 6, 2, max_pairs=0)
    single = {m: (1e6 if m[2] == "R3" else c) for m, c in table.single.items() if m[2] != "R3" or m[1] == "R5"}
    table = CostTable(table.robots, table.rooms, table.locations, table.start_location, single, {})
    routes = insertion_routes(table, goals, "ROUTING_FAIL_TIMEOUT")
    assert routes.found and any("R3" in rooms for rooms in routes.rooms.values())
    assert plan_cost(table, goals, [(m,) for m in routes.moves(table)]) == pytest.approx(routes.cost)
