"""Edits between the robots' routes, as vehicle routing's local searches make them.

A plan's single steps, read robot by robot, are routes. Four kinds of edit change them:

* **relocate**: one room leaves its robot's route and enters another robot's route (or the same
  route elsewhere), at any position;
* **exchange**: two robots swap a room each;
* **2-opt\\***: two robots swap the tails of their routes (every room from a point on);
* **unloading**, where the makespan counts: relocations chained from the robot that finishes
  last, each to the robot and place where its room adds least (:mod:`tmpnav.task.balance`).

An edit keeps the plan's other steps where they were: a relocated room's step moves next to its
new robot's neighbouring step, an exchanged or swapped step keeps its place and changes robot.
Robots in a paired step keep their routes (a pair's cost is no sum of single moves), and so do
the rooms that only one robot may have (its own targets, its end, a job for some robots).

Every edit is screened on the single moves' table, the cheapest first: the routes' costs added,
plus ``span_weight`` times the longest route's driving and service time (what the objective
prices when the team moves at once, waits left out). :func:`route_edits` returns the edits whose
screened value is below the plan's and that the plan rules accept; the caller costs them with
its model (tmpnav.task.search).

**Each edit also reordered.** An edit that hands rooms to another robot leaves them in the order
they had, which is rarely the order the new robot would take them in: two robots whose routes
cross the building (each driving through the other's half) are untangled only by swapping the
tails *and* turning them round, and the screen of the swap alone prices it dearer than the
plan. So every changed route is also reordered by the local search of the travelling salesman's
solvers (Or-opt: a string of up to three rooms moved elsewhere in the route; 2-opt: a stretch
reversed; first improvement, until neither improves), each route on its own cost plus
``span_weight`` times its own time, a robot's end kept last; the edit is screened both as it
is and reordered. The routes' moves are asymmetric (a move's cost depends on its direction
through the headings), so every trial route is priced in full. On a generated 14-room office
whose two robots crossed each other's halves, the makespan's exact optimum (Held-Karp) was
reached this way, and by no edit alone (benchmarks/references/).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass

import numba as nb
import numpy as np
import numpy.typing as npt

from tmpnav.task.balance import Moves, relocated_steps, unloadings
from tmpnav.task.plans import Plan, Rules, targets_only, with_origins
from tmpnav.types import CostTable, Goals

#: steps as (robot, target) pairs: what :func:`tmpnav.task.plans.with_origins` takes
Steps = list[tuple[tuple[str, str], ...]]
#: relocations an unloading chains at most, per robot (tmpnav.task.balance)
UNLOADING_DEPTH = 2
#: screened values closer than this count as equal
EPSILON = 1e-9


def route_edits(
    plan: Plan, singles: CostTable, goals: Goals, rules: Rules, span_weight: float, limit: int = 6
) -> list[Steps]:
    """Up to ``limit`` edits of ``plan`` that the single moves say are better, best first, each one
    the rules accept (module docstring)."""
    steps = targets_only(plan)
    robots = list(singles.robots) or sorted({r for step in steps for r, _ in step})
    routes: dict[str, list[tuple[int, str]]] = {r: [] for r in robots}
    for k, step in enumerate(steps):
        for r, x in step:
            routes.setdefault(r, []).append((k, x))
    pinned = {r for step in steps if len(step) > 1 for r, _ in step}
    screen = _Screen(singles, goals, span_weight)
    legs = {r: screen.route(r, [x for _, x in route]) for r, route in routes.items()}
    now = screen.value(legs.values())
    edits = list(_edits(steps, routes, pinned, goals, rules))
    if span_weight:  # the makespan counts: chains of relocations from the robot that finishes last
        free = [r for r in routes if r not in pinned]
        movable = _Routes(steps, routes, free, goals, rules, frozenset(x for _, x in goals.ends)).movable
        edits += unloadings(steps, free, movable, Moves(singles, goals), span_weight, UNLOADING_DEPTH * len(robots))
    in_routes = [x for route in routes.values() for _, x in route]
    screened = _Orders(singles, goals, span_weight, list(routes), in_routes).screen([changed for changed, _ in edits])
    scored: list[tuple[float, int]] = []  # (screened value, 2 n for edit n as it is, 2 n + 1 reordered)
    for n, (changed, (as_is, order, reordered)) in enumerate(zip((c for c, _ in edits), screened, strict=True)):
        for v, changed_legs in enumerate((as_is, reordered) if order != changed else (as_is,)):
            value = screen.value({**legs, **changed_legs}.values())
            if value < now - EPSILON * max(1.0, abs(now)):
                scored.append((value, 2 * n + v))
    scored.sort()
    out: list[Steps] = []
    seen: set[tuple[tuple[tuple[str, str], ...], ...]] = set()
    for _, key in scored:
        n, v = divmod(key, 2)
        # each changed route's steps take its rooms in order: after a 2-opt*, a's head may come after b's tail
        edited = _reordered(edits[n][1], edits[n][0] if v == 0 else screened[n][1])
        if tuple(edited) not in seen and rules.valid(with_origins(edited, rules.start_location)):
            seen.add(tuple(edited))
            out.append(edited)
            if len(out) >= limit:
                break
    return out


class _Screen:
    """A route's cost and time on the single moves' table (inf where a move is missing)."""

    def __init__(self, singles: CostTable, goals: Goals, span_weight: float):
        self.singles, self.goals, self.span_weight = singles, goals, span_weight

    def route(self, robot: str, rooms: list[str]) -> tuple[float, float]:
        at = self.singles.start_location.get(robot, f"{robot}-start")
        cost, time = 0.0, self.goals.held_for(robot)
        for x in rooms:
            move = (robot, at, x)
            cost += self.singles.single.get(move, math.inf)
            time += self.singles.duration.get(move, math.inf) + self.goals.service(x)
            at = x
        return cost, time

    def value(self, legs: Iterable[tuple[float, float]]) -> float:
        pairs = list(legs)
        cost = sum(c for c, _ in pairs)
        span = max((t for _, t in pairs), default=0.0)
        return cost + self.span_weight * span if self.span_weight else cost


Edit = tuple[dict[str, list[str]], Steps]  # the routes an edit changes (robot -> its rooms), the steps


@dataclass(frozen=True)
class _Routes:
    """The plan's steps and routes, the robots whose routes may change, and which rooms may move."""

    steps: Steps
    routes: dict[str, list[tuple[int, str]]]  # robot -> (step index, room) of its single steps
    free: list[str]  # robots in no paired step
    goals: Goals
    rules: Rules
    ends: frozenset[str]  # the robots' ends (goals.ends): rooms that stay where they are

    def rooms(self, robot: str) -> list[str]:
        return [x for _, x in self.routes[robot]]

    def movable(self, robot: str, room: str, to: str) -> bool:
        """Whether ``room`` may leave ``robot``'s route for ``to``'s: no one's end, not its own
        target, a job ``to`` may do."""
        return room not in self.ends and (robot, room) not in self.rules.targets and self.goals.may_visit(to, room)


def _edits(
    steps: Steps, routes: dict[str, list[tuple[int, str]]], pinned: set[str], goals: Goals, rules: Rules
) -> Iterator[Edit]:
    """Every relocate, exchange and 2-opt* edit."""
    free = [r for r in routes if r not in pinned]
    plan = _Routes(steps, routes, free, goals, rules, frozenset(x for _, x in goals.ends))
    yield from _relocations(plan)
    yield from _exchanges(plan)
    yield from _tail_swaps(plan)


def _relocations(plan: _Routes) -> Iterator[Edit]:
    """Room i of a's route to position p of b's (b may be a)."""
    rooms = {r: plan.rooms(r) for r in plan.free}
    for a in plan.free:
        for i, (k, x) in enumerate(plan.routes[a]):
            for b in plan.free:
                if not plan.movable(a, x, b):
                    continue
                for p in range(len(plan.routes[b]) + 1):
                    if b == a and p in (i, i + 1):
                        continue
                    yield _relocated(rooms, a, i, b, p), relocated_steps(plan.steps, plan.routes, k, b, p, x)


def _exchanges(plan: _Routes) -> Iterator[Edit]:
    """a's room i and b's room j swapped."""
    for ia, a in enumerate(plan.free):
        for b in plan.free[ia + 1 :]:
            for i, (k1, x) in enumerate(plan.routes[a]):
                if not plan.movable(a, x, b):
                    continue
                for j, (k2, y) in enumerate(plan.routes[b]):
                    if not plan.movable(b, y, a):
                        continue
                    changed = {a: plan.rooms(a), b: plan.rooms(b)}
                    changed[a][i], changed[b][j] = y, x
                    edited = list(plan.steps)
                    edited[k1], edited[k2] = ((a, y),), ((b, x),)
                    yield changed, edited


def _tail_swaps(plan: _Routes) -> Iterator[Edit]:
    """2-opt*: a's tail from i and b's tail from j swapped."""
    for ia, a in enumerate(plan.free):
        for b in plan.free[ia + 1 :]:
            for i in range(len(plan.routes[a]) + 1):
                tail_a = plan.routes[a][i:]
                if not all(plan.movable(a, x, b) for _, x in tail_a):
                    continue
                for j in range(len(plan.routes[b]) + 1):
                    tail_b = plan.routes[b][j:]
                    if (not tail_a and not tail_b) or not all(plan.movable(b, y, a) for _, y in tail_b):
                        continue
                    changed = {
                        a: plan.rooms(a)[:i] + [y for _, y in tail_b],
                        b: plan.rooms(b)[:j] + [x for _, x in tail_a],
                    }
                    edited = list(plan.steps)
                    for k, x in tail_a:
                        edited[k] = ((b, x),)
                    for k, y in tail_b:
                        edited[k] = ((a, y),)
                    yield changed, edited


def _relocated(rooms: dict[str, list[str]], a: str, i: int, b: str, p: int) -> dict[str, list[str]]:
    """The routes of a and b after a's room i moved to position p of b's route (p of b's route
    before the move)."""
    x = rooms[a][i]
    if a == b:
        route = list(rooms[a])
        route.insert(p, x)
        del route[i + 1 if p <= i else i]
        return {a: route}
    return {a: rooms[a][:i] + rooms[a][i + 1 :], b: [*rooms[b][:p], x, *rooms[b][p:]]}


def _reordered(steps: Steps, order: dict[str, list[str]]) -> Steps:
    """``steps`` with each robot of ``order`` taking its rooms in that order: its single steps keep
    their places in the plan and take the rooms one after the other."""
    out = list(steps)
    for r, rooms in order.items():
        at = [k for k, step in enumerate(out) if len(step) == 1 and step[0][0] == r]
        for k, x in zip(at, rooms, strict=True):
            out[k] = ((r, x),)
    return out


#: a route's screened (cost, time) by robot
Legs = dict[str, tuple[float, float]]


class _Orders:
    """Routes reordered and screened on the single moves (module docstring, "Each edit also
    reordered"), as :class:`_Screen` screens them: per robot, matrices of a move's cost and of
    its duration plus its target's service (inf where the table has no move: a route with such a
    move is never reordered, its value stays inf), and of the cost plus ``span_weight`` times
    that time, which the reordering minimises. ``robots`` and ``rooms``: every robot and room of
    the plan's routes."""

    def __init__(
        self, singles: CostTable, goals: Goals, span_weight: float, robots: Sequence[str], rooms: Sequence[str]
    ):
        self.goals = goals
        self.robots = {r: i for i, r in enumerate(robots)}
        self.start = {r: singles.start_location.get(r, f"{r}-start") for r in robots}
        names = list(dict.fromkeys([*self.start.values(), *singles.locations, *singles.rooms, *rooms]))
        self.index = {x: i for i, x in enumerate(names)}
        self.cost = np.full((len(robots), len(names), len(names)), np.inf)
        self.time = np.full_like(self.cost, np.inf)
        for matrix, known, service in ((self.cost, singles.single, False), (self.time, singles.duration, True)):
            for (r, a, b), amount in known.items():
                if r in self.robots and a in self.index and b in self.index:
                    matrix[self.robots[r], self.index[a], self.index[b]] = amount + (
                        goals.service(b) if service else 0.0
                    )
        self.value = self.cost + span_weight * self.time if span_weight else self.cost

    def screen(self, changes: list[dict[str, list[str]]]) -> list[tuple[Legs, dict[str, list[str]], Legs]]:
        """For each edit's changed routes: their legs as they are, the routes reordered (the same
        lists where no order is better), and their legs reordered; all in one compiled call."""
        flat: list[int] = []
        offsets, robot_of, starts, fixed = [0], [], [], []
        for changed in changes:
            for r, rooms in changed.items():
                flat += [self.index[x] for x in rooms]
                offsets.append(len(flat))
                robot_of.append(self.robots[r])
                starts.append(self.index[self.start[r]])
                fixed.append(bool(rooms) and self.goals.end_of(r) == rooms[-1])
        if not changes:
            return []
        order = np.array(flat, dtype=np.int64)
        bounds = np.array(offsets, dtype=np.int64)
        whose, first = np.array(robot_of, dtype=np.int64), np.array(starts, dtype=np.int64)
        before = self._legs(order, bounds, whose, first)
        _improve_routes(self.value, whose, first, bounds, order, np.array(fixed, dtype=np.bool_))
        after = self._legs(order, bounds, whose, first)
        names = list(self.index)
        out, k = [], 0
        for changed in changes:
            routes: dict[str, list[str]] = {}
            as_is: Legs = {}
            reordered: Legs = {}
            for r in changed:
                routes[r] = [names[i] for i in order[offsets[k] : offsets[k + 1]]]
                as_is[r], reordered[r] = before[k], after[k]
                k += 1
            out.append((as_is, routes, reordered))
        return out

    def _legs(
        self,
        order: npt.NDArray[np.int64],
        bounds: npt.NDArray[np.int64],
        whose: npt.NDArray[np.int64],
        first: npt.NDArray[np.int64],
    ) -> list[tuple[float, float]]:
        """(cost, time) of each route ``order[bounds[k]:bounds[k + 1]]`` of robot ``whose[k]`` from
        ``first[k]``, as :meth:`_Screen.route` adds them up (inf where a move is missing)."""
        lengths = np.diff(bounds)
        robot = np.repeat(whose, lengths)
        prev = np.empty_like(order)
        prev[1:] = order[:-1]
        starts_at = bounds[:-1][lengths > 0]
        prev[starts_at] = first[lengths > 0]
        costs, times = _sums(self.cost[robot, prev, order], bounds), _sums(self.time[robot, prev, order], bounds)
        return list(zip(costs, times, strict=True))


def _sums(values: npt.NDArray[np.float64], bounds: npt.NDArray[np.int64]) -> list[float]:
    """The sum of each stretch ``values[bounds[k]:bounds[k + 1]]`` (0 when empty, inf when it holds inf)."""
    missing = np.isinf(values)
    total = np.concatenate(([0.0], np.cumsum(np.where(missing, 0.0, values))))
    count = np.concatenate(([0], np.cumsum(missing)))
    sums = total[bounds[1:]] - total[bounds[:-1]]
    return [math.inf if c else float(s) for s, c in zip(sums, count[bounds[1:]] - count[bounds[:-1]], strict=True)]


#: passes of the route improvement at most (each pass ends at its first improvement)
MAX_PASSES = 200
#: the longest string of rooms Or-opt moves
OR_OPT = 3


@nb.njit(cache=True)
def _route_value(value: npt.NDArray[np.float64], start: int, route: npt.NDArray[np.int64]) -> float:
    total, at = 0.0, start
    for x in route:
        total += value[at, x]
        at = x
    return total


@nb.njit(cache=True)
def _improve_routes(
    value: npt.NDArray[np.float64],
    robot_of: npt.NDArray[np.int64],
    starts: npt.NDArray[np.int64],
    offsets: npt.NDArray[np.int64],
    rooms: npt.NDArray[np.int64],
    fixed_last: npt.NDArray[np.bool_],
) -> None:
    """Each route ``rooms[offsets[k]:offsets[k + 1]]`` of robot ``robot_of[k]`` from ``starts[k]``
    improved in place by Or-opt and 2-opt moves, first improvement, on ``value[robot]``; its last
    room stays last where ``fixed_last[k]``."""
    for k in range(len(offsets) - 1):
        a, b = offsets[k], offsets[k + 1]
        m = b - a - 1 if fixed_last[k] else b - a  # rooms 0..m-1 may move
        if m < 2:
            continue
        matrix, start = value[robot_of[k]], starts[k]
        route = rooms[a:b].copy()
        trial = np.empty(b - a, dtype=np.int64)
        best = _route_value(matrix, start, route)
        for _ in range(MAX_PASSES):
            better = _or_opt(matrix, start, route, m, trial, best)
            if better == best:
                better = _two_opt(matrix, start, route, m, trial, best)
            if better == best:
                break
            best = better
        rooms[a:b] = route


@nb.njit(cache=True)
def _improves(value: float, best: float) -> bool:
    return value < best - 1e-9 * max(1.0, abs(best))


@nb.njit(cache=True)
def _or_opt(
    matrix: npt.NDArray[np.float64],
    start: int,
    route: npt.NDArray[np.int64],
    m: int,
    trial: npt.NDArray[np.int64],
    best: float,
) -> float:
    """The first Or-opt move that improves ``route`` (rooms i..i+s-1 taken out and put back
    before the room at position j of the rest, among its first ``m`` rooms), made in place; the
    route's new value, or ``best`` where none improves."""
    n = len(route)
    for s in range(1, min(OR_OPT, m - 1) + 1):
        for i in range(m - s + 1):
            for j in range(m - s + 1):
                if j == i:
                    continue
                w = 0
                for p in range(m + 1):  # the rest, with the string put in at position j
                    if w == j:
                        for q in range(s):
                            trial[w] = route[i + q]
                            w += 1
                    if p < m and not i <= p < i + s:
                        trial[w] = route[p]
                        w += 1
                trial[m:n] = route[m:n]
                v = _route_value(matrix, start, trial)
                if _improves(v, best):
                    route[:] = trial
                    return v
    return best


@nb.njit(cache=True)
def _two_opt(
    matrix: npt.NDArray[np.float64],
    start: int,
    route: npt.NDArray[np.int64],
    m: int,
    trial: npt.NDArray[np.int64],
    best: float,
) -> float:
    """The first 2-opt move that improves ``route`` (rooms i..j reversed, j < ``m``), made in
    place; the route's new value, or ``best`` where none improves."""
    for i in range(m - 1):
        for j in range(i + 1, m):
            trial[:] = route
            for q in range(j - i + 1):
                trial[i + q] = route[j - q]
            v = _route_value(matrix, start, trial)
            if _improves(v, best):
                route[:] = trial
                return v
    return best
