"""Each route an edit changes, reordered: the travelling salesman's local search on the single moves.

An edit between routes (:mod:`tmpnav.task.routes`) hands rooms to a robot in the order they had,
which is rarely the order the robot would take them in. Every changed route is reordered by
Or-opt (a string of up to three rooms moved elsewhere in the route) and 2-opt (a stretch
reversed), first improvement, until neither improves, on the route's own cost plus
``span_weight`` times its own time, a robot's end kept last. The moves are asymmetric (a move's
cost depends on its direction through the headings), so every trial route is priced in full.
Edits share most of their routes, so each distinct route is reordered once, and all of them in
one compiled call.
"""

from __future__ import annotations

from collections.abc import Sequence

import numba as nb
import numpy as np
import numpy.typing as npt

from tmpnav.types import CostTable, Goals

#: a route's screened (cost, time) by robot
Legs = dict[str, tuple[float, float]]


class Orders:
    """Routes reordered and screened on the single moves (module docstring), as
    :class:`tmpnav.task.routes._Screen` screens them: per robot, matrices of a move's cost and of
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
        lists where no order is better), and their legs reordered; all in one compiled call, each
        distinct route once (edits share most of theirs: every relocation of a room of a's leaves
        a the same route, and three robots' tails passed round are made of two robots' ones)."""
        if not changes:
            return []
        unique: dict[tuple[str, tuple[str, ...]], int] = {}
        keys = [[unique.setdefault((r, tuple(rooms)), len(unique)) for r, rooms in c.items()] for c in changes]
        flat: list[int] = []
        offsets, robot_of, starts, fixed = [0], [], [], []
        for r, rooms in unique:
            flat += [self.index[x] for x in rooms]
            offsets.append(len(flat))
            robot_of.append(self.robots[r])
            starts.append(self.index[self.start[r]])
            fixed.append(bool(rooms) and self.goals.end_of(r) == rooms[-1])
        order = np.array(flat, dtype=np.int64)
        bounds = np.array(offsets, dtype=np.int64)
        whose, first = np.array(robot_of, dtype=np.int64), np.array(starts, dtype=np.int64)
        before = self._legs(order, bounds, whose, first)
        improve_routes(self.value, whose, first, bounds, order, np.array(fixed, dtype=np.bool_))
        after = self._legs(order, bounds, whose, first)
        names = list(self.index)
        reordered_rooms = [[names[i] for i in order[offsets[k] : offsets[k + 1]]] for k in range(len(unique))]
        out = []
        for changed, ks in zip(changes, keys, strict=True):
            routes = {r: list(reordered_rooms[k]) for r, k in zip(changed, ks, strict=True)}
            as_is = {r: before[k] for r, k in zip(changed, ks, strict=True)}
            reordered = {r: after[k] for r, k in zip(changed, ks, strict=True)}
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
    """The sum of each stretch ``values[bounds[k]:bounds[k + 1]]`` (0 when empty, inf when it holds
    inf), each added on its own: differences of one running sum over every stretch lose the
    cents of a route to the penalties of the others (a move over the chance constraint costs some
    1e11, and their running sum reaches 1e15, where a float's step is 0.125)."""
    return [float(s) for s in _stretch_sums(values, bounds)]


@nb.njit(cache=True)
def _stretch_sums(values: npt.NDArray[np.float64], bounds: npt.NDArray[np.int64]) -> npt.NDArray[np.float64]:
    out = np.zeros(len(bounds) - 1)
    for k in range(len(bounds) - 1):
        total = 0.0
        for i in range(bounds[k], bounds[k + 1]):
            total += values[i]  # inf stays inf
        out[k] = total
    return out


#: passes of the route improvement at most (each pass ends at its first improvement)
MAX_PASSES = 200
#: the longest string of rooms Or-opt moves
OR_OPT = 3


@nb.njit(cache=True)
def route_value(value: npt.NDArray[np.float64], start: int, route: npt.NDArray[np.int64]) -> float:
    total, at = 0.0, start
    for x in route:
        total += value[at, x]
        at = x
    return total


@nb.njit(cache=True)
def improve_routes(
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
        best = route_value(matrix, start, route)
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
                v = route_value(matrix, start, trial)
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
            v = route_value(matrix, start, trial)
            if _improves(v, best):
                route[:] = trial
                return v
    return best
