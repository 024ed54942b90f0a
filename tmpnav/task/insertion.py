"""First routes by cheapest insertion, for when OR-Tools finds none within its time limit.

OR-Tools' routing solver needs its first solution before its time limit; on a large problem
(200 rooms, 2 robots) on a busy machine it found none, and the run ended with no plan though
every room could be entered. Cheapest insertion always gives routes when there are any that
visit each goal from the room before it: each goal room in turn (the dearest to reach first, a
fixed order) goes where it adds least, over every robot that may take it and every position in
that robot's route, the objective's price of the team's time included (``span_weight`` times
what it adds to the longest route). A robot's end (``goals.ends``) stays last in its route;
optional goals are left undone (the search takes them up where that pays); time windows are left
to the plan's checks. The routes are a plan of single moves, as OR-Tools' are
(:class:`tmpnav.task.routing.Routes`), which the anytime search then improves.

Usage: ``routes = insertion_routes(table, goals, "ROUTING_FAIL_TIMEOUT")``.
"""

from __future__ import annotations

import math

from tmpnav.task.bound import required_entries
from tmpnav.task.routing import Routes
from tmpnav.types import CostTable, Goals


def insertion_routes(table: CostTable, goals: Goals, status: str, span_weight: float = 0.0) -> Routes:
    """Routes through every required goal by cheapest insertion (see the module docstring);
    ``status`` is OR-Tools' status that called for them, ``span_weight`` the objective's price of
    a second of the longest route. Routes with infinite cost, and the first room with no place in
    any route, when a room has none."""
    ends = dict(goals.ends)
    tasks = [row for row in required_entries(table, goals) if row not in goals.ends]
    routes: dict[str, list[str]] = {r: [] for r in table.robots}  # each robot's rooms, its end left out
    start = table.start_location

    def cost(r: str, a: str, b: str | None) -> float:
        """What the move a -> b costs robot r (nothing into the open end of a route; inf if missing)."""
        return 0.0 if b is None else table.single.get((r, a, b), math.inf)

    def seconds(r: str, rooms: list[str]) -> float:
        here, total = start[r], 0.0
        for room in [*rooms, *([ends[r]] if r in ends else [])]:
            total += table.duration.get((r, here, room), 0.0) if room != here else 0.0
            here = room
        return total

    # the dearest rooms to reach first: they have the fewest good places
    cheapest: dict[str, float] = {}
    for (_, _, x), c in table.single.items():
        cheapest[x] = min(cheapest.get(x, math.inf), c)

    def place(robot: str | None, room: str) -> bool:
        """``room`` where it adds least, if it has a place (the moves into and out of it exist)."""
        longest = max(seconds(r, routes[r]) for r in table.robots) if span_weight else 0.0
        best: tuple[float, str, int] | None = None
        for r in table.robots if robot is None else (robot,):
            path: list[str | None] = [start[r], *routes[r], ends.get(r)]
            for k in range(len(path) - 1):  # between path[k] and path[k + 1]
                a, b = path[k], path[k + 1]
                assert a is not None
                added = cost(r, a, room) + cost(r, room, b) - (cost(r, a, b) if b is not None and b != a else 0.0)
                if not math.isfinite(added):
                    continue
                if span_weight:
                    trial = [*routes[r][:k], room, *routes[r][k:]]
                    added += span_weight * max(0.0, seconds(r, trial) - longest)
                if best is None or added < best[0]:
                    best = (added, r, k)
        if best is None:
            return False
        _, r, k = best
        routes[r].insert(k, room)
        return True

    # a room with no place yet waits for the rooms placed after it: a room reached from few others
    # (a sparse table of moves) has a place once one of those is in a route
    pending = sorted(tasks, key=lambda row: (-cheapest.get(row[1], math.inf), row[1], row[0] or ""))
    while pending:
        left = [row for row in pending if not place(*row)]
        if len(left) == len(pending):
            return Routes({}, math.inf, status, "nothing", detail=_none_for(left[0][1]), by="cheapest insertion")
        pending = left
    return _finished(table, routes, ends, status)


def _finished(table: CostTable, routes: dict[str, list[str]], ends: dict[str, str], status: str) -> Routes:
    """Each robot's rooms with its end added (unless it is there already), as Routes at their cost."""
    rooms = {}
    for r, xs in routes.items():
        end = ends.get(r)
        rooms[r] = (*xs, end) if end is not None and end != (xs[-1] if xs else table.start_location[r]) else tuple(xs)
    total = sum(table.single.get(move, math.inf) for move in Routes(rooms, 0.0, status, "nothing").moves(table))
    if not math.isfinite(total):
        return Routes({}, math.inf, status, "nothing", detail=_none_for("a robot's end"), by="cheapest insertion")
    by = "cheapest insertion, OR-Tools having found no routes within its time limit"
    return Routes(rooms, total, status, "nothing", timed_out=True, by=by)


def _none_for(room: str) -> str:
    return (
        f"OR-Tools found no routes within its time limit, and cheapest insertion finds no place for {room} in any "
        "route (a move it needs is missing); a longer time limit may let OR-Tools find routes through other rooms"
    )
