"""Edits between the robots' routes, as vehicle routing's local searches make them.

A plan's single steps, read robot by robot, are routes. Five kinds of edit change them:

* **relocate**: one room leaves its robot's route and enters another robot's route (or the same
  route elsewhere), at any position;
* **exchange**: two robots swap a room each;
* **2-opt\\***: two robots swap the tails of their routes (every room from a point on);
* **tails passed round**: three robots' tails, each to the next robot (a cyclic 2-opt\\*: where
  work should move round a ring of robots, every edit between two of them is dearer);
* **unloading**, where the makespan counts: relocations chained from the robot that finishes
  last, each to the robot and place where its room adds least (:mod:`tmpnav.task.balance`);
* **trade**, where keeping the plan's robots apart leaves two of them in each other's way: the
  two swap their whole routes. Offered before every other edit, whatever its screen: robots
  docked in a row are in each other's way whenever the one behind has the work past the one in
  front, and the screen, which sees the same moves either way, does not tell them apart (the
  office of 100 rooms and 16 robots under ``--objective makespan``: three robots docked across
  the spine's junction, every edit the screen ranked first still sent the one behind through).

An edit keeps the plan's other steps where they were: a relocated room's step moves next to its
new robot's neighbouring step, an exchanged or swapped step keeps its place and changes robot.
Robots in a paired step keep their routes (a pair's cost is no sum of single moves), and so do
the rooms that only one robot may have (its own targets, its end, a job for some robots).

Every edit is screened on the single moves' table, the cheapest first: the routes' costs added,
plus ``span_weight`` times the longest route's driving and service time (what the objective
prices when the team moves at once, waits left out). Where the plan keeps robots apart, the price of
that (:class:`KeptApartPrice`) is added to the screen of every edit that changes none of their
routes, and left out for one that changes one: such an edit may free the plan of its waits, so
it is worth the model's costing when it is dearer than the plan as planned yet cheaper than the
plan as executed. :func:`route_edits` returns the edits whose
screened value is below the plan's and that the plan rules accept; the caller costs them with
its model (tmpnav.task.search). With a minimum of work rooms per robot (planner.min_rooms,
:mod:`tmpnav.task.minimum`), each room an edit leaves a robot short of it adds its price to the
screen, and each it makes up takes it off: an edit that puts an idle robot to work comes first.

**Each edit also reordered.** An edit that hands rooms to another robot leaves them in the order
they had, which is rarely the order the new robot would take them in: two robots whose routes
cross the building (each driving through the other's half) are untangled only by swapping the
tails *and* turning them round, and the screen of the swap alone prices it dearer than the
plan. So every changed route is also reordered by the local search of the travelling salesman's
solvers (Or-opt: a string of up to three rooms moved elsewhere in the route; 2-opt: a stretch
reversed; first improvement, until neither improves), each route on its own cost plus
``span_weight`` times its own time, a robot's end kept last (:mod:`tmpnav.task.route_orders`);
the edit is screened both as it is and reordered. On a generated 14-room office
whose two robots crossed each other's halves, the makespan's exact optimum (Held-Karp) was
reached this way, and by no edit alone (benchmarks/references/).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

from tmpnav.task.balance import Moves, relocated_steps, unloadings
from tmpnav.task.objectives import strict_price
from tmpnav.task.plans import Plan, Rules, targets_only, with_origins
from tmpnav.task.route_orders import Legs, Orders
from tmpnav.types import CostTable, Goals

#: steps as (robot, target) pairs: what :func:`tmpnav.task.plans.with_origins` takes
Steps = list[tuple[tuple[str, str], ...]]
#: relocations an unloading chains at most, per robot (tmpnav.task.balance)
UNLOADING_DEPTH = 2
#: screened values closer than this count as equal
EPSILON = 1e-9


def route_edits(
    plan: Plan,
    singles: CostTable,
    goals: Goals,
    rules: Rules,
    span_weight: float,
    limit: int = 6,
    apart: KeptApartPrice | None = None,
    least: tuple[int, frozenset[str]] = (0, frozenset()),
) -> list[Steps]:
    """Up to ``limit`` edits of ``plan`` that the single moves say are better, best first, each one
    the rules accept (module docstring); ``least``: the work rooms each robot should enter and
    those rooms (tmpnav.task.minimum), each room an edit leaves a robot short of them priced."""
    steps = targets_only(plan)
    robots = list(singles.robots) or sorted({r for step in steps for r, _ in step})
    routes: dict[str, list[tuple[int, str]]] = {r: [] for r in robots}
    for k, step in enumerate(steps):
        for r, x in step:
            routes.setdefault(r, []).append((k, x))
    pinned = {r for step in steps if len(step) > 1 for r, _ in step}
    screen = _Screen(singles, goals, span_weight)
    legs = {r: screen.route(r, [x for _, x in route]) for r, route in routes.items()}
    free = [r for r in routes if r not in pinned]
    plan_routes = _Routes(steps, routes, free, goals, rules, frozenset(x for _, x in goals.ends))
    edits = list(_edits(plan_routes))
    if span_weight:  # the makespan counts: chains of relocations from the robot that finishes last
        movable = plan_routes.movable
        edits += unloadings(steps, free, movable, Moves(singles, goals), span_weight, UNLOADING_DEPTH * len(robots))
    in_routes = [x for route in routes.values() for _, x in route]
    screened = Orders(singles, goals, span_weight, list(routes), in_routes).screen([changed for changed, _ in edits])
    current = {r: [x for _, x in route] for r, route in routes.items()}
    apart = apart or KeptApartPrice()
    scored = _scored(edits, screened, current, screen, legs, apart, least)
    out: list[Steps] = []
    seen: set[tuple[tuple[tuple[str, str], ...], ...]] = set()
    for edited in _trades(plan_routes, apart.stuck):
        if tuple(edited) not in seen and rules.valid(with_origins(edited, rules.start_location)):
            seen.add(tuple(edited))
            out.append(edited)
    for _, key in scored:
        n, v = divmod(key, 2)
        # each changed route's steps take its rooms in order: after a 2-opt*, a's head may come after b's tail
        made = edits[n][1]
        edited = _reordered(made() if callable(made) else made, edits[n][0] if v == 0 else screened[n][1])
        if tuple(edited) not in seen and rules.valid(with_origins(edited, rules.start_location)):
            seen.add(tuple(edited))
            out.append(edited)
            if len(out) >= limit:
                break
    return out


def _scored(
    edits: list[Edit],
    screened: list[tuple[Legs, dict[str, list[str]], Legs]],
    current: dict[str, list[str]],
    screen: _Screen,
    legs: Legs,
    price: KeptApartPrice,
    least: tuple[int, frozenset[str]] = (0, frozenset()),
) -> list[tuple[float, int]]:
    """(screened value, 2 n for edit n as it is, 2 n + 1 reordered) of the edits better than the
    plan, the plan's routes ``current`` and ``legs``; an edit that only gives the plan's own
    routes back (reordered) is none. The rooms an edit's routes lack of ``least`` (the
    minimum and the work rooms) against the plan's are priced at the search's
    :func:`~tmpnav.task.objectives.strict_price` each."""
    need, work = least
    held = work.__contains__
    #: each robot's shortfall of the minimum in the plan
    short_now = {r: max(need - sum(map(held, xs)), 0) for r, xs in current.items()} if need else {}

    def lacking(rooms: dict[str, list[str]]) -> int:
        """The rooms the edit's robots lack of the minimum, less those they lack in the plan (the
        same whatever the order of each route's rooms; :func:`~tmpnav.task.minimum.shortfall`
        robot by robot, counted without a dict: the screen asks this of every edit)."""
        return sum(max(need - sum(map(held, xs)), 0) - short_now.get(r, need) for r, xs in rooms.items())

    now = screen.value(legs.values()) + price.slack
    scored: list[tuple[float, int]] = []
    for n, (changed, (as_is, order, reordered)) in enumerate(zip((c for c, _ in edits), screened, strict=True)):
        short = strict_price(screen.span_weight) * lacking(changed) if need else 0.0
        for v, (rooms, changed_legs) in enumerate(
            ((changed, as_is), (order, reordered)) if order != changed else ((changed, as_is),)
        ):
            differ = {r for r, xs in rooms.items() if current[r] != xs}
            if not differ:
                continue
            value = screen.value_with(legs, changed_legs) + price.after(differ) + short
            if value < now - EPSILON * max(1.0, abs(now)):
                scored.append((value, 2 * n + v))
    return sorted(scored)


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

    def value_with(self, legs: Legs, changed: Legs) -> float:
        """:meth:`value` of ``legs`` with those of ``changed`` in their place (the same sums, in
        the same order, without a merged dict: the screen asks this of every edit)."""
        cost, span = 0.0, 0.0
        for r, leg in legs.items():
            c, t = changed.get(r, leg)
            cost += c
            span = t if t > span else span
        return cost + self.span_weight * span if self.span_weight else cost


#: the routes an edit changes (robot -> its rooms), and its steps (or what makes them)
Edit = tuple[dict[str, list[str]], Steps | Callable[[], Steps]]


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


def _edits(plan: _Routes) -> Iterator[Edit]:
    """Every relocate, exchange and 2-opt* edit."""
    yield from _relocations(plan)
    yield from _exchanges(plan)
    yield from _tail_swaps(plan)
    yield from _tail_cycles(plan)


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
                    yield _swapped(plan, a, i, b, j)


def _swapped(plan: _Routes, a: str, i: int, b: str, j: int) -> tuple[dict[str, list[str]], Steps]:
    """a's tail from i and b's tail from j swapped: the two routes, and the plan's steps."""
    tail_a, tail_b = plan.routes[a][i:], plan.routes[b][j:]
    changed = {a: plan.rooms(a)[:i] + [y for _, y in tail_b], b: plan.rooms(b)[:j] + [x for _, x in tail_a]}
    edited = list(plan.steps)
    for k, x in tail_a:
        edited[k] = ((b, x),)
    for k, y in tail_b:
        edited[k] = ((a, y),)
    return changed, edited


def _trades(plan: _Routes, stuck: frozenset[tuple[str, str]]) -> Iterator[Steps]:
    """The plan's steps with each pair of ``stuck`` robots' whole routes swapped (module docstring:
    a trade: the 2-opt* from both routes' starts), where every room of each may go to the other."""
    for a, b in sorted(stuck):
        if a not in plan.free or b not in plan.free:
            continue
        movable = all(plan.movable(a, x, b) for _, x in plan.routes[a])
        if movable and all(plan.movable(b, y, a) for _, y in plan.routes[b]):
            yield _swapped(plan, a, 0, b, 0)[1]


@dataclass(frozen=True)
class KeptApartPrice:
    """What keeping the plan's robots apart adds to its objective (``slack``: waits and detours,
    the plan as executed less the plan as planned) and the robots whose conflicts it pays for:
    an edit that changes one of their routes may free the plan of that price, any other keeps it."""

    slack: float = 0.0
    robots: frozenset[str] = frozenset()
    #: the pairs of them that nothing keeps apart (their conflicts left)
    stuck: frozenset[tuple[str, str]] = frozenset()

    def after(self, changed: set[str]) -> float:
        """The price an edit that changes the routes of the robots ``changed`` is screened with."""
        return 0.0 if self.robots & changed else self.slack


#: cyclic tail swaps screened at most per pass: three routes' cut points multiply (16 robots of 6
#: rooms would make some 380,000), so past this many the cycles are left out
MAX_CYCLES = 20_000


def _tail_cycles(plan: _Routes) -> Iterator[Edit]:
    """Three robots' tails passed round: a takes b's tail from j, b takes c's from m, c takes a's
    from i (at most one of them empty: with two, it is a 2-opt*). They are many, so their steps
    are made only for the edits offered."""
    free = plan.free
    rooms = {r: plan.rooms(r) for r in free}
    cycles = [(a, b, c) for ia, a in enumerate(free) for b in free[ia + 1 :] for c in free[ia + 1 :] if b != c]
    if sum((len(rooms[a]) + 1) * (len(rooms[b]) + 1) * (len(rooms[c]) + 1) for a, b, c in cycles) > MAX_CYCLES:
        return
    tails = {(r, t): _movable_tails(plan, r, t) for r in free for t in free if r != t}
    for a, b, c in cycles:
        ends = (len(rooms[a]), len(rooms[b]), len(rooms[c]))
        cuts_a, cuts_b, cuts_c = tails[(a, c)], tails[(b, a)], tails[(c, b)]  # a's tail goes to c, ...
        for i, j, m in itertools.product(cuts_a, cuts_b, cuts_c):
            if (i == ends[0]) + (j == ends[1]) + (m == ends[2]) > 1:
                continue
            changed = {
                a: rooms[a][:i] + rooms[b][j:],
                b: rooms[b][:j] + rooms[c][m:],
                c: rooms[c][:m] + rooms[a][i:],
            }
            yield changed, functools.partial(_cycled_steps, plan, (a, b, c), (i, j, m))


def _movable_tails(plan: _Routes, robot: str, to: str) -> list[int]:
    """The points from which ``robot``'s tail may go to ``to``'s route: every room of it movable."""
    rooms = plan.rooms(robot)
    cuts = [len(rooms)]
    for i in range(len(rooms) - 1, -1, -1):
        if not plan.movable(robot, rooms[i], to):
            break
        cuts.append(i)
    return cuts[::-1]


def _cycled_steps(plan: _Routes, robots: tuple[str, str, str], cuts: tuple[int, int, int]) -> Steps:
    """The plan's steps with the tails of ``robots`` from ``cuts`` passed round (:func:`_tail_cycles`)."""
    edited = list(plan.steps)
    for n, (r, i) in enumerate(zip(robots, cuts, strict=True)):
        taker = robots[n - 1]  # a's tail to c, b's to a, c's to b
        for k, x in plan.routes[r][i:]:
            edited[k] = ((taker, x),)
    return edited


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
