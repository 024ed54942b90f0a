"""Unloading: edits that move work from the robot that finishes last to the rest of the fleet.

A relocation (tmpnav.task.routes) takes one room from one robot. On a fleet whose robots end
close together, the robot that finishes last hands over a room and the next one is then last:
no single relocation shortens the makespan by much, and the detour it adds costs more than
the little it saves, so the search keeps robots idle that could help. An unloading chains
relocations: the robot that finishes last hands one of its rooms to the robot and the place in
its route where the room adds least (the moves' cost plus ``span_weight`` times the later end
of the two robots), provided both then end before it did; then the robot that finishes last
now does the same, up to ``depth`` times. Every prefix of the chain is an edit, screened with
the other edits between routes (:func:`tmpnav.task.routes.route_edits`). Where no one robot can
take a room of the last one's and still end before it (its neighbours end about when it does,
or only they have moves into its rooms), an ejection chain passes work on: a room to a robot
that then ends later, a room of that robot's to another, up to four robots, all ending before
the last one did.

Times and costs are those of the single moves' table: a route's time is its moves' durations
plus the services of its rooms (waits left out), as the screen prices them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator

from tmpnav.types import PENALISED, CostTable, Goals

#: steps as (robot, target) pairs, and the routes an edit changes with its steps
Steps = list[tuple[tuple[str, str], ...]]
Edit = tuple[dict[str, list[str]], Steps]
#: a robot's route: (step index, room) of its steps, in order
Route = list[tuple[int, str]]
#: times closer than this (s) count as equal
EPSILON = 1e-9


class Moves:
    """Cost and time of single moves and rooms on the table (inf where a move is missing)."""

    def __init__(self, singles: CostTable, goals: Goals):
        self.singles, self.goals = singles, goals

    def start(self, robot: str) -> str:
        return self.singles.start_location.get(robot, f"{robot}-start")

    def move(self, robot: str, a: str, b: str) -> tuple[float, float]:
        """The move a -> b's cost, and its duration plus b's service."""
        key = (robot, a, b)
        cost = self.singles.single.get(key, math.inf)
        return cost, self.singles.duration.get(key, math.inf) + self.goals.service(b)

    def route(self, robot: str, rooms: list[str]) -> tuple[float, float]:
        """The route's cost and its time (from the robot's hold, ``goals.held``)."""
        at, cost, time = self.start(robot), 0.0, self.goals.held_for(robot)
        for x in rooms:
            c, t = self.move(robot, at, x)
            cost, time, at = cost + c, time + t, x
        return cost, time

    def insertion(self, robot: str, rooms: list[str], p: int, x: str) -> tuple[float, float]:
        """What room ``x`` put at position ``p`` of the route adds to its cost and time."""
        before = rooms[p - 1] if p else self.start(robot)
        c1, t1 = self.move(robot, before, x)
        if p == len(rooms):
            return c1, t1
        c2, t2 = self.move(robot, x, rooms[p])
        c0, t0 = self.move(robot, before, rooms[p])
        return c1 + c2 - c0, t1 + t2 - t0

    def removal(self, robot: str, rooms: list[str], i: int) -> tuple[float, float]:
        """What taking room i out of the route changes in its cost and time (negative: saves)."""
        cost, time = self.insertion(robot, rooms[:i] + rooms[i + 1 :], i, rooms[i])
        return -cost, -time


def unloadings(
    steps: Steps,
    free: list[str],
    movable: Callable[[str, str, str], bool],
    moves: Moves,
    span_weight: float,
    depth: int,
) -> Iterator[Edit]:
    """The prefixes of the chain of unloadings from the plan's ``steps`` (module docstring):
    each (the changed robots' rooms, the steps). Only robots of ``free`` give or take rooms;
    ``movable(robot, room, to)`` says whether a room may leave a robot's route for ``to``'s."""
    steps = list(steps)
    routes = routes_of(steps)
    rooms = {r: [x for _, x in route] for r, route in routes.items()}
    for r in free:
        rooms.setdefault(r, [])
    times = {r: moves.route(r, xs)[1] for r, xs in rooms.items()}
    changed: set[str] = set()
    for _ in range(depth):
        last = max(times, key=lambda r: times[r])
        if last not in free:
            return
        chain = _next_unloading(last, rooms, times, free, movable, moves, span_weight)
        if not chain:
            return
        for giver, i, b, p in chain:
            k, x = routes[giver][i]
            steps = relocated_steps(steps, routes, k, b, p, x)
            routes = routes_of(steps)
            rooms[giver] = rooms[giver][:i] + rooms[giver][i + 1 :]
            rooms[b] = [*rooms[b][:p], x, *rooms[b][p:]]
            times[giver], times[b] = moves.route(giver, rooms[giver])[1], moves.route(b, rooms[b])[1]
            changed |= {giver, b}
        yield {r: list(rooms[r]) for r in changed}, list(steps)


def _next_unloading(
    last: str,
    rooms: dict[str, list[str]],
    times: dict[str, float],
    free: list[str],
    movable: Callable[[str, str, str], bool],
    moves: Moves,
    span_weight: float,
) -> list[Relocation]:
    """How ``last`` hands over work: its best relocation (:func:`_best_unloading`), unless it adds
    a move over the chance constraint and an ejection chain (:func:`_best_ejection`) is cheaper;
    the ejection chain where no relocation will do. Where the only robots that take ``last``'s
    rooms safely end about when it does (a corridor that only their docks reach within the
    constraint), every single relocation is penalised and the work has to pass along them."""
    direct = _best_unloading(last, rooms, times, free, movable, moves, span_weight)
    if direct and _added(rooms, direct, moves) < PENALISED:  # no move over the chance constraint
        return direct
    ejection = _best_ejection(last, rooms, times, free, movable, moves, span_weight)
    if not direct or not ejection:
        return direct or ejection
    return min((direct, ejection), key=lambda chain: _score(rooms, chain, moves, span_weight))


def _added(rooms: dict[str, list[str]], chain: list[Relocation], moves: Moves) -> float:
    """The cost the relocations of ``chain`` add to the routes they change."""
    return _change(rooms, chain, moves)[0]


def _score(rooms: dict[str, list[str]], chain: list[Relocation], moves: Moves, span_weight: float) -> float:
    """What the relocations of ``chain`` add in cost, plus ``span_weight`` times the latest end of
    the robots they change."""
    added, end = _change(rooms, chain, moves)
    return added + span_weight * end


def _change(rooms: dict[str, list[str]], chain: list[Relocation], moves: Moves) -> tuple[float, float]:
    """The cost the relocations of ``chain`` add to the routes they change, and the latest end of
    those routes after them."""
    after = _relocated_rooms(rooms, chain)
    changed = {r for giver, _, taker, _ in chain for r in (giver, taker)}
    legs = {r: moves.route(r, after[r]) for r in changed}
    added = sum(c for c, _ in legs.values()) - sum(moves.route(r, rooms[r])[0] for r in changed)
    return added, max(t for _, t in legs.values())


#: a relocation: (the robot that gives the room, its index in that robot's route, the robot that
#: takes it, its position there)
Relocation = tuple[str, int, str, int]
#: robots an ejection tries as the first taker, the cheapest first
EJECTION_TAKERS = 3


def _best_unloading(
    last: str,
    rooms: dict[str, list[str]],
    times: dict[str, float],
    free: list[str],
    movable: Callable[[str, str, str], bool],
    moves: Moves,
    span_weight: float,
    before: float | None = None,
) -> list[Relocation]:
    """The relocation of a room of ``last``'s that adds least cost plus ``span_weight`` times the
    later end of the two robots, of those after which both end before ``last`` did (or before
    ``before``); [] where none does."""
    end = times[last]
    limit = end if before is None else before
    best: tuple[float, int, str, int] | None = None
    for i, x in enumerate(rooms[last]):
        cost_out, time_out = moves.removal(last, rooms[last], i)
        if not math.isfinite(cost_out + time_out):
            continue
        for b in free:
            if b == last or not movable(last, x, b):
                continue
            for p in range(len(rooms[b]) + 1):
                cost_in, time_in = moves.insertion(b, rooms[b], p, x)
                later = max(end + time_out, times[b] + time_in)
                if not later < limit - EPSILON:  # inf too: a missing move
                    continue
                score = cost_out + cost_in + span_weight * later
                if best is None or score < best[0]:
                    best = (score, i, b, p)
    return [] if best is None else [(last, *best[1:])]


def _best_ejection(
    last: str,
    rooms: dict[str, list[str]],
    times: dict[str, float],
    free: list[str],
    movable: Callable[[str, str, str], bool],
    moves: Moves,
    span_weight: float,
) -> list[Relocation]:
    """Relocations in a chain where no one will do (the robots near ``last`` end about when it
    does): a room of ``last``'s to a robot b, which may then end later, a room of b's to a robot
    c, and so on, up to :data:`EJECTION_DEPTH` robots, after which all end before ``last`` did.
    Each robot passes a room to one of the :data:`EJECTION_TAKERS` that take one of its rooms
    cheapest; of the chains, the one that adds least cost plus ``span_weight`` times the latest
    end of its robots; [] where none does."""
    chains = _ejections(last, rooms, times, times[last], free, movable, moves, span_weight, EJECTION_DEPTH, {last})
    return min(chains, key=lambda chain: _score(rooms, chain, moves, span_weight), default=[])


#: robots an ejection chain holds at most, the robot that finishes last included
EJECTION_DEPTH = 4


def _ejections(
    giver: str,
    rooms: dict[str, list[str]],
    times: dict[str, float],
    end: float,
    free: list[str],
    movable: Callable[[str, str, str], bool],
    moves: Moves,
    span_weight: float,
    depth: int,
    used: set[str],
) -> Iterator[list[Relocation]]:
    """The chains of relocations from ``giver`` on after which all their robots end before
    ``end`` (:func:`_best_ejection`), at most ``depth`` robots long, none of ``used`` taking."""
    direct = _best_unloading(giver, rooms, times, free, movable, moves, span_weight, before=end)
    if direct:
        yield direct
        if _added(rooms, direct, moves) < PENALISED:
            return
    if depth <= 2:
        return
    firsts: dict[str, tuple[float, int, int]] = {}  # taker -> its cheapest (cost, i, p)
    for i, x in enumerate(rooms[giver]):
        cost_out, time_out = moves.removal(giver, rooms[giver], i)
        if not times[giver] + time_out < end - EPSILON:
            continue
        for b in free:
            if b in used or not movable(giver, x, b):
                continue
            for p in range(len(rooms[b]) + 1):
                cost_in = moves.insertion(b, rooms[b], p, x)[0]
                if math.isfinite(cost_in) and (b not in firsts or cost_out + cost_in < firsts[b][0]):
                    firsts[b] = (cost_out + cost_in, i, p)
    for b, (_, i, p) in sorted(firsts.items(), key=lambda item: item[1][0])[:EJECTION_TAKERS]:
        first: Relocation = (giver, i, b, p)
        after = _relocated_rooms(rooms, [first])
        ends = {**times, giver: moves.route(giver, after[giver])[1], b: moves.route(b, after[b])[1]}
        for rest in _ejections(b, after, ends, end, free, movable, moves, span_weight, depth - 1, used | {b}):
            yield [first, *rest]


def _relocated_rooms(rooms: dict[str, list[str]], chain: list[Relocation]) -> dict[str, list[str]]:
    """The routes after the relocations of ``chain``, one after the other."""
    out = dict(rooms)
    for giver, i, taker, p in chain:
        x = out[giver][i]
        out[giver] = out[giver][:i] + out[giver][i + 1 :]
        out[taker] = [*out[taker][:p], x, *out[taker][p:]]
    return out


def routes_of(steps: Steps) -> dict[str, Route]:
    """Each robot's (step index, room) in the order of the steps."""
    routes: dict[str, Route] = {}
    for k, step in enumerate(steps):
        for r, x in step:
            routes.setdefault(r, []).append((k, x))
    return routes


def relocated_steps(steps: Steps, routes: dict[str, Route], k: int, b: str, p: int, x: str) -> Steps:
    """The steps with step k (a single move into x) taken out and a single move of b into x put
    where b's route has position p: right after b's step before it, or before b's first step."""
    route = routes.get(b, [])
    at = (route[0][0] if route else k) if p == 0 else route[p - 1][0] + 1
    edited: Steps = list(steps)
    edited.insert(at, ((b, x),))
    del edited[k + 1 if at <= k else k]
    return edited
