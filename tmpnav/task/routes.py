"""Edits between the robots' routes, as vehicle routing's local searches make them.

A plan's single steps, read robot by robot, are routes. Three kinds of edit change them:

* **relocate**: one room leaves its robot's route and enters another robot's route (or the same
  route elsewhere), at any position;
* **exchange**: two robots swap a room each;
* **2-opt\\***: two robots swap the tails of their routes (every room from a point on).

An edit keeps the plan's other steps where they were: a relocated room's step moves next to its
new robot's neighbouring step, an exchanged or swapped step keeps its place and changes robot.
Robots in a paired step keep their routes (a pair's cost is no sum of single moves), and so do
the rooms that only one robot may have (its own targets, its end, a job for some robots).

Every edit is screened on the single moves' table, the cheapest first: the routes' costs added,
plus ``span_weight`` times the longest route's driving and service time (what the objective
prices when the team moves at once, waits left out). :func:`route_edits` returns the edits whose
screened value is below the plan's and that the plan rules accept; the caller costs them with
its model (tmpnav.task.search).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from tmpnav.task.plans import Plan, Rules, targets_only, with_origins
from tmpnav.types import CostTable, Goals

#: steps as (robot, target) pairs: what :func:`tmpnav.task.plans.with_origins` takes
Steps = list[tuple[tuple[str, str], ...]]
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
    scored: list[tuple[float, int, Steps]] = []
    for n, (changed, edited) in enumerate(_edits(steps, routes, pinned, goals, rules)):
        trial = dict(legs)
        for r, rooms in changed.items():
            trial[r] = screen.route(r, rooms)
        value = screen.value(trial.values())
        if value < now - EPSILON * max(1.0, abs(now)):
            scored.append((value, n, edited))
    scored.sort(key=lambda s: (s[0], s[1]))
    out: list[Steps] = []
    for _, _, edited in scored:
        if rules.valid(with_origins(edited, rules.start_location)):
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
        cost = time = 0.0
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
                    yield _relocated(rooms, a, i, b, p), _relocate_steps(plan.steps, plan.routes, k, b, p, x)


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


def _relocate_steps(steps: Steps, routes: dict[str, list[tuple[int, str]]], k: int, b: str, p: int, x: str) -> Steps:
    """The steps with step k (a single move into x) taken out and a single move of b into x put
    where b's route has position p: right after b's step before it, or before b's first step."""
    route = routes[b]
    at = (route[0][0] if route else k) if p == 0 else route[p - 1][0] + 1
    edited: Steps = list(steps)
    edited.insert(at, ((b, x),))
    del edited[k + 1 if at <= k else k]
    return edited
