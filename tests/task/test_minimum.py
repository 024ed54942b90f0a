"""A minimum of work rooms per robot (planner.min_rooms, tmpnav.task.minimum): the first routes,
the edits between routes and the anytime search keep it, on a table where the sum of costs
leaves half the fleet idle."""

from __future__ import annotations

import itertools

from tmpnav.task.minimum import counts, need, shortfall, work_rooms
from tmpnav.task.model import PlanCost, TableModel
from tmpnav.task.objectives import strict_price
from tmpnav.task.plans import Rules, with_origins
from tmpnav.task.routes import route_edits
from tmpnav.task.routing import solve_routes
from tmpnav.task.search import SearchOptions, search
from tmpnav.types import CostTable, Goals

#: eight rooms on a line, 10 m apart from 10 m on; r1 and r3 start at 0 m, r2 and r4 at 90 m
ROBOTS = ("r1", "r2", "r3", "r4")
ROOMS = tuple(f"L{k}" for k in range(1, 9))
AT = {
    "r1-start": 0.0,
    "r3-start": 0.0,
    "r2-start": 90.0,
    "r4-start": 90.0,
    **{x: 10.0 * (k + 1) for k, x in enumerate(ROOMS)},
}
START = {r: f"{r}-start" for r in ROBOTS}
GOALS = Goals(ROOMS, ())


def line_table() -> CostTable:
    """Every robot's moves: a tenth of their length, plus 1 for each move (a robot that sweeps
    the line costs less than two that share it)."""
    single, duration = {}, {}
    for r in ROBOTS:
        for a, b in itertools.product((START[r], *ROOMS), ROOMS):
            if a != b:
                duration[(r, a, b)] = abs(AT[a] - AT[b])
                single[(r, a, b)] = 1.0 + 0.1 * duration[(r, a, b)]
    return CostTable(ROBOTS, ROOMS, (*START.values(), *ROOMS), START, single, {}, duration)


def rooms_per_robot(moves: list[tuple[str, ...]]) -> dict[str, int]:
    return {r: counts([[m] for m in moves], work_rooms(GOALS)).get(r, 0) for r in ROBOTS}


def test_the_minimum_is_lowered_to_the_goals_share_and_ends_are_no_work() -> None:
    assert need(GOALS, START, 3) == 2  # 8 rooms for 4 robots
    assert need(GOALS, START, 1) == 1
    assert need(GOALS, START, 0) == 0
    assert need(GOALS, {**START, "r1": "L1"}, 3) == 1  # 7 rooms to enter for 4 robots
    docked = Goals(ROOMS[:4], (("r1", ("L5",)),), ends=(("r2", "L8"),))
    assert work_rooms(docked) == frozenset({"L1", "L2", "L3", "L4", "L5"})
    assert shortfall({"r1": 3, "r2": 0}, ["r1", "r2", "r3"], 2) == 4
    assert shortfall({}, ["r1"], 0) == 0


def test_a_room_short_ranks_a_plan_below_any_sum_of_costs() -> None:
    kept, short = PlanCost(100.0, (100.0,)), PlanCost(1.0, (1.0,), short=1)
    assert short.ranked(0.0) - kept.ranked(0.0) > 0.5 * strict_price(0.0)
    assert short.value(0.0) == 1.0  # the objective itself is the plan's


def test_the_first_routes_give_every_robot_its_share() -> None:
    table = line_table()
    free = solve_routes(table, GOALS, time_limit=10.0, solution_limit=200)
    assert min(rooms_per_robot(free.moves(table)).values()) == 0, "without a minimum two robots sweep the line"
    kept = solve_routes(table, GOALS, time_limit=10.0, solution_limit=200, min_rooms=2)
    assert min(rooms_per_robot(kept.moves(table)).values()) >= 2


def test_the_edits_between_routes_put_idle_robots_to_work_first() -> None:
    table = line_table()
    sweep = [("r1", x) for x in ROOMS[:4]] + [("r2", x) for x in reversed(ROOMS[4:])]
    plan = with_origins([(m,) for m in sweep], START)
    rules = Rules(START, GOALS)
    assert route_edits(plan, table, GOALS, rules, span_weight=0.0) == [], "the sum of costs has nothing better"
    edits = route_edits(plan, table, GOALS, rules, span_weight=0.0, least=(2, work_rooms(GOALS)))
    assert edits
    first = [m for step in edits[0] for m in step]
    assert {r for r, _ in first} > {"r1", "r2"}, "an idle robot takes a room"


def test_the_search_keeps_the_minimum_where_the_sum_of_costs_would_not() -> None:
    table = line_table()
    options = SearchOptions(budget=60, seed=1, parallel=1, first_routes=True)
    free = search(TableModel(table), GOALS, options)
    assert min(rooms_per_robot([m for s in free.plan for m in s]).values()) == 0
    kept = search(TableModel(table), GOALS, SearchOptions(budget=60, seed=1, parallel=1, min_rooms=3))
    assert min(rooms_per_robot([m for s in kept.plan for m in s]).values()) >= 2  # 3, lowered to 8 / 4
    assert kept.cost.short == 0
    assert kept.cost.total > free.cost.total  # what the minimum costs
