"""The anytime search's first plan: OR-Tools' routes on the single moves (tmpnav.task.routing),
within limits that make the routes the same on every machine where they can be: a number of
solutions, a number without improvement, and a time limit only as a cap. Where OR-Tools finds
no routes in time, cheapest insertion gives them (tmpnav.task.insertion)."""

from __future__ import annotations

from collections.abc import Sequence

from tmpnav.task.insertion import insertion_routes
from tmpnav.task.plans import Plan
from tmpnav.task.routing import NO_ROBOT_CAN_ENTER, Routes, solve_routes
from tmpnav.types import CostTable, Goals

#: OR-Tools' guided local search stops after this many solutions: on 20-60 rooms and 2-8
#: robots it reaches in 0.1-1.2 s the routes it reaches in 10 s (within 0.02%)
ROUTING_SOLUTIONS = 500
#: ... and for a team of more than :data:`FLEET_ROBOTS` robots (past the sizes measured above)
#: after :data:`FLEET_SOLUTIONS`. Each solution costs more as the model grows, and later ones
#: most (office, 100 rooms, 16 robots: 100 solutions in 0.55 s, 500 in 5.2 s, each routing), and
#: the search after the first plan moves the work between robots anyway. On offices of 100
#: rooms and 16 robots (seeds 1-3, benchmarks/fleet/fleet_solutions.txt) the runs took 4-7 s
#: less, their plans as good or better (seed 1 1766.0 against 1813.0, seed 2 the same, seed 3
#: 1822.4 against 1822.2).
FLEET_SOLUTIONS, FLEET_ROBOTS = 100, 8
#: ... and up to :data:`FEW_ROOMS` rooms and two robots, also after this many in a row that did
#: not improve its objective. On the generated 20-room offices and warehouses with 2 robots
#: (benchmarks/routing/first_routes.txt) it gave the same or cheaper first plans than the fixed
#: 100 solutions it replaces on all 20 (cheaper on 4, by 2.3-10.9%), in 0.2-0.5 s more; against
#: all 500 solutions, the same on 17, dearer on 2 warehouses (1.6%, 15.7%: improvements after 122
#: and 400 solutions without one), in a quarter of the time. With more robots or rooms such long
#: plateaus are common (188-297 solutions on building-4robots, building-8robots and a 60-room
#: office, whose first plans it made 0.3-5.6% dearer): those run all :data:`ROUTING_SOLUTIONS`.
FEW_STAGNATION, FEW_ROOMS = 100, 20
#: ... and a replan's, which starts from the plan under way, after this many in a row that did
#: not improve its objective, whatever the team's size: on 20 seeded states of building-20 and
#: building-4robots each it gave the same revisions as 100 and as all 500 (in 0.3-0.4 s less)
REPLAN_STAGNATION = 25
#: OR-Tools' first solution for a fleet (more robots than a neighbourhood holds) where time is
#: priced. The cheapest arc out of each route's end, robot after robot, hands the first robots
#: most rooms and leaves the last idle; the span cost's guided local search did not even them out
#: (office, 40 rooms, 8 robots, weighted: makespan 216 s with one robot on 2 rooms; inserting
#: every room where it adds least, into all routes at once: 194 s, every robot on 4-7 rooms)
FLEET_FIRST_SOLUTION = "PARALLEL_CHEAPEST_INSERTION"
#: OR-Tools' time limit at most (a quarter of the budget below it): its solutions, not the clock,
#: should end it. At 60 rooms and 8 robots its 500 solutions took 9.8 s on a busy 2-core machine,
#: and a cap of 10 s left the first plan to the machine's speed (962.0 or 1016.7 on one office)
ROUTING_CAP = 30.0


def first_routes(
    singles: CostTable,
    goals: Goals,
    robots: Sequence[str],
    *,
    budget: float,
    routing_time: float | None,
    time_left: float,
    fleet: bool,
    span_weight: float,
    start_from: Plan | None = None,
    second: bool = False,
    min_rooms: int = 0,
) -> tuple[Routes, bool]:
    """The routes of the search's first plan, and whether OR-Tools stopped at its time limit
    (the plan then depends on the machine's speed). OR-Tools' guided local search stops after
    :data:`ROUTING_SOLUTIONS` solutions (:data:`FLEET_SOLUTIONS` for a team of more than
    :data:`FLEET_ROBOTS`); a replan's (``start_from``: the plan under way, where
    the search starts) after :data:`REPLAN_STAGNATION` without improvement, few rooms and
    robots after :data:`FEW_STAGNATION`; or at its own time limit, ``routing_time`` or a
    quarter of the search's ``budget`` (not what a cold oracle left of the budget: cut to 0.1 s,
    its first solution left robots of a shift at their docks, tests/test_team_objective.py),
    within ``time_left``. A ``fleet`` (more robots than a neighbourhood holds) whose objective
    prices time (``span_weight``) starts from :data:`FLEET_FIRST_SOLUTION`. A ``second`` routing
    (the search's makespan-first candidate) stops after :data:`FEW_STAGNATION` solutions in a
    row without improvement whatever the size. ``min_rooms``: the work rooms each route should
    enter (tmpnav.task.minimum)."""
    limit = routing_time if routing_time is not None else min(ROUTING_CAP, max(1.0, budget / 4))
    few = len(goals.all_rooms) <= FEW_ROOMS and len(robots) <= 2
    routes = solve_routes(
        singles,
        goals,
        time_limit=max(0.001, min(limit, time_left)),
        solution_limit=FLEET_SOLUTIONS if len(robots) > FLEET_ROBOTS else ROUTING_SOLUTIONS,
        stagnation=REPLAN_STAGNATION if start_from is not None else FEW_STAGNATION if few or second else None,
        first_solution=FLEET_FIRST_SOLUTION if fleet and span_weight else "PATH_CHEAPEST_ARC",
        span_weight=span_weight,
        initial=None if start_from is None else routes_of(start_from, robots),
        min_rooms=min_rooms,
    )
    timed_out = routes.timed_out
    if not routes.found and routes.status != NO_ROBOT_CAN_ENTER:
        # OR-Tools ran out of time before its first solution: routes all the same
        routes = insertion_routes(singles, goals, routes.status, span_weight)
    return routes, timed_out


def no_routes(routes: Routes) -> str:
    """Why there is no first plan, in words: a goal room no allowed robot can enter, or none
    of the routes OR-Tools and cheapest insertion tried visits every goal."""
    if routes.status == NO_ROBOT_CAN_ENTER:
        return f"no plan of single moves reaches the goals: no robot allowed there can enter {routes.detail}"
    return f"no plan of single moves reaches the goals ({routes.status}): {routes.detail}"


def routes_of(plan: Plan, robots: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """Each robot's rooms in the order the plan takes it there."""
    out: dict[str, list[str]] = {r: [] for r in robots}
    for step in plan:
        for r, _, target in step:
            out[r].append(target)
    return {r: tuple(xs) for r, xs in out.items()}
