"""The cost table, computed lazily: the moves the anytime search uses, when it uses them.

The exact task planner needs every paired move before it starts (rooms^4 of them). The
anytime search (:mod:`tmpnav.task.search`) does not: it starts from the single moves
between the goal rooms and asks for paired moves only inside its sub-problems, a few rooms
and robots at a time. :class:`CanonicalCosts` answers those questions with the table's
semantics (:mod:`tmpnav.oracle.table`): every move starts from its robot's canonical state
at its origin, pairs from two uncorrelated canonical states, and every cost is the oracle's
exact cost, cached on disk per request as always. It is the ``--costs table`` model of the
anytime search (:class:`tmpnav.task.model.CostModel`).

Which paired moves exist (the plan space): every pair of moves that the encoding's entry
rules allow together and that saves ``pair_min_gain``, as in the exact search.
:meth:`CanonicalCosts.bound_table` bounds every one of them without joint simulation (the
pair's cost until its robots can first see each other, :mod:`tmpnav.oracle.bounds`) when
there are few enough; the certified lower bound of the whole task is computed from it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from functools import cached_property

from tmpnav.attachment.floors import motion_floors
from tmpnav.attachment.team import paired_moves
from tmpnav.choices import Costs
from tmpnav.oracle.bounds import ControlFloors
from tmpnav.oracle.executors import library
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.requests import Request, StartState
from tmpnav.oracle.table import Origin, arrival_state, build_table, initial_state, start_locations
from tmpnav.task.model import PlanCost, entered, head_locations, robot_ends, sub_moves
from tmpnav.task.plans import Plan
from tmpnav.task.timing import schedule
from tmpnav.types import CostTable, Goals, MoveKey
from tmpnav.world import World

Pair = tuple[MoveKey, MoveKey]

#: up to this many single moves the search starts from all of them (robots x rooms^2)
FULL_SINGLES = 6000
#: beyond, from each goal room only to this many nearest ones (and from each start to all)
NEAREST = 10


class CanonicalCosts:
    """Action costs from canonical start states, computed on demand (see the module docstring)."""

    costs: Costs = "table"

    def __init__(self, oracle: Oracle, world: World, min_gain: float, origin: Mapping[str, Origin] | None = None):
        self.oracle = oracle
        scenario = oracle.ctx.scenario
        self.scenario = scenario
        self.robots = tuple(r.name for r in scenario.robots)
        self.start_location = start_locations(scenario, world)
        self.min_gain = min_gain
        self.single: dict[MoveKey, float | None] = {}  # None: no such move (unreachable)
        self.pair: dict[Pair, float | None] = {}  # None: not offered (saves too little, or no motion)
        self.duration: dict[MoveKey, float] = {}  # seconds each costed single move takes
        self.pair_duration: dict[Pair, tuple[float, float]] = {}
        self.dt = scenario.models.dt
        self.canonical: dict[tuple[str, str], StartState] = {
            (r, self.start_location[r]): initial_state(scenario, oracle.ctx.roadmap.starts[r], r) for r in self.robots
        }
        #: a replan's origins (tmpnav.oracle.table.Origin): where its robots reach the canonical
        #: states at the other rooms from, the plan being revised's table's; the others from their starts
        self.origin = {r: o for r, o in (origin or {}).items() if r in self.robots}
        for r, o in self.origin.items():
            if o.location != self.start_location[r]:
                self.canonical[(r, o.location)] = o.state

    @cached_property
    def controls(self) -> ControlFloors:
        """The robots' least control efforts, which turn away pairs before the oracle simulates them."""
        return ControlFloors(library(self.oracle.ctx))

    # ------------------------------------------------------------------ CostModel

    def singles(self, goals: Goals) -> CostTable:
        """The single moves the search starts from: every move between the robots' starts
        and the goal rooms (one cached table) up to :data:`FULL_SINGLES` moves; beyond, each
        robot's moves from its start to every goal room and from each goal room to its
        :data:`NEAREST` nearest goal rooms (by motion floor). A move left out is costed
        when a sub-problem asks for it."""
        rooms = tuple(dict.fromkeys(goals.all_rooms))
        if len(self.robots) * (len(rooms) + 1) * len(rooms) <= FULL_SINGLES:
            table = build_table(self.oracle, self.oracle_world, "goals", origin=self.origin)
            for move, cost in table.single.items():
                self.single.setdefault(move, cost)
                self.duration.setdefault(move, table.duration[move])
            return table
        floors = motion_floors(self.scenario, library(self.oracle.ctx).graph, self.start_location, goals).single
        moves: list[MoveKey] = []
        for r in self.robots:
            start = self.start_location[r]
            moves.extend((r, start, t) for t in rooms if t != start)
            for o in rooms:
                near = sorted((floors.get((r, o, t), math.inf), t) for t in rooms if t not in (o, start))
                moves.extend((r, o, t) for _, t in near[:NEAREST])
        self._ensure_singles(moves)
        single = {m: c for m in moves if (c := self.single.get(m)) is not None}
        locations = tuple(dict.fromkeys([*rooms, *self.start_location.values()]))
        return CostTable(self.robots, rooms, locations, dict(self.start_location), single, {}, self._durations(single))

    @property
    def oracle_world(self) -> World:
        return self.oracle.ctx.world

    def plan_cost(self, plan: Plan) -> PlanCost:
        self._ensure_singles([m for step in plan for m in step])
        self._ensure_pairs([(step[0], step[1]) for step in plan if len(step) == 2])
        costs = []
        for step in plan:
            c = self.single.get(step[0]) if len(step) == 1 else self.pair.get((step[0], step[1]))
            costs.append(math.inf if c is None else c)
        if not all(math.isfinite(c) for c in costs):
            return PlanCost.impossible(len(plan))
        goals = self.scenario.goals
        timed = schedule(plan, self.robots, self._step_durations, goals=goals)
        if timed is not None and timed.late(goals.windows):
            return PlanCost.impossible(len(plan))  # it arrives after a window closes
        dropped = goals.drop_penalty(entered(plan, self.start_location))
        return PlanCost(float(sum(costs)), tuple(costs), timed, dropped)

    def ends(self, head: Plan) -> dict[str, float]:
        self.plan_cost(head)  # costs (and so times) every move of the head
        return robot_ends(schedule(head, self.robots, self._step_durations, goals=self.scenario.goals), self.robots)

    def _step_durations(self, step: Sequence[MoveKey]) -> tuple[float, ...] | None:
        if len(step) == 1:
            d = self.duration.get(step[0])
            return None if d is None else (d,)
        return self.pair_duration.get((step[0], step[1]))

    def _durations(self, single: Iterable[MoveKey]) -> dict[MoveKey, float]:
        return {m: self.duration[m] for m in single if m in self.duration}

    def _pair_durations(self, pairs: Iterable[Pair]) -> dict[Pair, tuple[float, float]]:
        return {p: self.pair_duration[p] for p in pairs if p in self.pair_duration}

    def subtable(self, head: Plan, robots: Sequence[str], rooms: Sequence[str], goals: Goals) -> CostTable:
        at = head_locations(head, self.start_location, robots)
        moves = sub_moves(at, rooms)
        self._ensure_singles(moves)
        single = {m: c for m in moves if (c := self.single.get(m)) is not None}
        keep = paired_moves(self.scenario, goals, at)
        wanted = [
            _ordered(m1, m2, self.robots)
            for i, m1 in enumerate(single)
            for m2 in list(single)[i + 1 :]
            if m1[0] != m2[0] and keep(m1, m2)
        ]
        self._ensure_pairs(wanted)
        pair = {p: c for p in wanted if (c := self.pair.get(p)) is not None}
        locations = tuple(dict.fromkeys([*rooms, *at.values()]))
        timed = self._durations(single), self._pair_durations(pair)
        return CostTable(tuple(robots), tuple(rooms), locations, at, single, pair, *timed)

    def seen(self) -> CostTable:
        """The costs computed so far: the single and paired moves the search saw."""
        single = {m: c for m, c in self.single.items() if c is not None}
        pair = {p: c for p, c in self.pair.items() if c is not None}
        rooms = tuple(r.name for r in self.scenario.rooms)
        locations = tuple(dict.fromkeys([*rooms, *self.start_location.values()]))
        timed = self._durations(single), self._pair_durations(pair)
        return CostTable(self.robots, rooms, locations, dict(self.start_location), single, pair, *timed)

    # ------------------------------------------------------------------ the plan space of pairs

    def pair_space(self, goals: Goals, max_pairs: int) -> list[Pair] | None:
        """Every pair of single moves of the goal table that the entry rules allow together;
        None when there are more than ``max_pairs``."""
        keep = paired_moves(self.scenario, goals, self.start_location)
        by_robot: dict[str, list[MoveKey]] = {}
        for m, c in self.single.items():
            if c is not None:
                by_robot.setdefault(m[0], []).append(m)
        sizes = [len(by_robot.get(r, ())) for r in self.robots]
        if sum(a * b for i, a in enumerate(sizes) for b in sizes[i + 1 :]) > 4 * max_pairs:
            return None  # the rules keep about a quarter at most: too many to bound one by one
        out: list[Pair] = []
        for i, r1 in enumerate(self.robots):
            for r2 in self.robots[i + 1 :]:
                for m1 in by_robot.get(r1, ()):
                    out.extend((m1, m2) for m2 in by_robot.get(r2, ()) if keep(m1, m2))
                    if len(out) > max_pairs:
                        return None
        return out

    def bound_table(self, goals: Goals, max_pairs: int) -> CostTable | None:
        """The single moves between the goal rooms and every pair of the plan space, each at
        its exact cost or, when it was never simulated jointly, at a lower bound of it
        (:mod:`tmpnav.oracle.bounds`): what :func:`tmpnav.task.bound.lower_bound` needs to
        bound every plan. None when the plan space has more than ``max_pairs`` pairs."""
        rooms = tuple(dict.fromkeys(goals.all_rooms))
        if len(self.robots) * (len(rooms) + 1) * len(rooms) > FULL_SINGLES:
            return None  # the search starts from some single moves only: they cannot bound every plan
        singles = self.singles(goals)
        space = self.pair_space(goals, max_pairs)
        if space is None:
            return None
        todo = [p for p in space if p not in self.pair]
        self._ensure_canonical({(m[0], m[1]) for p in todo for m in p})
        requests = [
            Request(
                (m1[0], m2[0]),
                (self.canonical[(m1[0], m1[1])], self.canonical[(m2[0], m2[1])]),
                (m1[2], m2[2]),
                bound_only=True,
            )
            for m1, m2 in todo
        ]
        bounds = dict(zip(todo, self.oracle.evaluate(requests), strict=True))
        pair: dict[Pair, float] = {}
        for p in space:
            if p in bounds:
                res = bounds[p]
                if res is not None:
                    pair[p] = res.cost
            elif (c := self.pair.get(p)) is not None:
                pair[p] = c
        single = {m: c for m, c in self.single.items() if c is not None and m in singles.single}
        return CostTable(singles.robots, singles.rooms, singles.locations, singles.start_location, single, pair)

    # ------------------------------------------------------------------ computing

    def _ensure_singles(self, moves: Iterable[MoveKey]) -> None:
        todo = [m for m in dict.fromkeys(moves) if m not in self.single]
        if not todo:
            return
        self._ensure_canonical({(r, o) for r, o, _ in todo})
        ready = [m for m in todo if (m[0], m[1]) in self.canonical]
        for m in todo:
            if (m[0], m[1]) not in self.canonical:
                self.single[m] = None  # its robot can never be at the origin
        results = self.oracle.evaluate([Request((r,), (self.canonical[(r, o)],), (t,)) for r, o, t in ready])
        for m, res in zip(ready, results, strict=True):
            self.single[m] = None if res is None else res.cost
            if res is not None:
                self.duration[m] = res.steps[0] * self.dt + self.scenario.goals.service(m[2])

    def _ensure_canonical(self, states: set[tuple[str, str]]) -> None:
        """Canonical states at rooms: where a robot arrives driving there from its start (from
        its origin, in a replan)."""
        missing = sorted(s for s in states if s not in self.canonical)
        if not missing:
            return
        requests = [Request((r,), (self._origin_state(r),), (room,)) for r, room in missing]
        for (r, room), res in zip(missing, self.oracle.evaluate(requests), strict=True):
            if res is not None:
                self.canonical[(r, room)] = arrival_state(res)
                if r not in self.origin:  # the move from its start, costed on the way
                    self.single.setdefault((r, self.start_location[r], room), res.cost)
                    self.duration.setdefault((r, self.start_location[r], room), res.steps[0] * self.dt)

    def _origin_state(self, robot: str) -> StartState:
        o = self.origin.get(robot)
        return o.state if o is not None else self.canonical[(robot, self.start_location[robot])]

    def _ensure_pairs(self, pairs: Iterable[Pair]) -> None:
        todo = [p for p in dict.fromkeys(pairs) if p not in self.pair]
        if not todo:
            return
        self._ensure_singles([m for p in todo for m in p])
        self._ensure_canonical({(m[0], m[1]) for p in todo for m in p})
        ready = [p for p in todo if all(self.single.get(m) is not None and (m[0], m[1]) in self.canonical for m in p)]
        gain = self.min_gain if self.min_gain > 0 else None
        asked = [
            (
                (m1, m2),
                Request(
                    (m1[0], m2[0]),
                    (self.canonical[(m1[0], m1[1])], self.canonical[(m2[0], m2[1])]),
                    (m1[2], m2[2]),
                    min_gain=gain,
                ),
            )
            for m1, m2 in ready
        ]
        # those whose control effort alone cannot save min_gain are not offered (tmpnav.oracle.bounds.ControlFloors)
        asked = [(p, req) for p, req in asked if not self.controls.cannot_pair(req, self._alone(p), self.min_gain)]
        for p in todo:
            self.pair[p] = None
        for ((m1, m2), _), res in zip(asked, self.oracle.evaluate([req for _, req in asked]), strict=True):
            if res is None or res.pruned:
                continue
            if _offered(res.cost, self._alone((m1, m2)), self.min_gain):
                self.pair[(m1, m2)] = res.cost
                service = self.scenario.goals.service
                self.pair_duration[(m1, m2)] = (
                    res.steps[0] * self.dt + service(m1[2]),
                    res.steps[1] * self.dt + service(m2[2]),
                )

    def _alone(self, pair: Pair) -> float:
        """The cost of the pair's two single moves (both costed: the pair is ready)."""
        m1, m2 = pair
        return self.single[m1] + self.single[m2]  # type: ignore[operator]


def _offered(cost: float, alone: float, min_gain: float) -> bool:
    """The encoding's test (:func:`tmpnav.task.encodings.offered_pairs`), on scaled costs."""
    from tmpnav.task.encodings import scaled

    a, c = scaled(alone), scaled(cost)
    return c < a and c <= (1.0 - min_gain) * a


def _ordered(m1: MoveKey, m2: MoveKey, robots: tuple[str, ...]) -> Pair:
    """The pair with the robot first in the scenario's order first (the table's convention)."""
    return (m1, m2) if robots.index(m1[0]) < robots.index(m2[0]) else (m2, m1)
