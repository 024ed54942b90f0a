"""The exact search over every schedule of a cost table, for objectives that price time.

An objective that prices the team's time (``weighted``, ``makespan``: tmpnav.task.objectives)
is a sum of action costs plus ``span_weight`` times the makespan, a maximum over the robots'
clocks. ENHSP's optimal search is only sound for *simple* numeric planning, where every
effect adds a constant (Scala et al.; measured here: with the clocks of tmpnav.task.pddl_text
its blind search returned a plan 5% above the optimum of a 5-room, 3-robot table and called
it optimal). So the exact search with such an objective is this A* over the states of the
``mixed`` encoding's rules (tmpnav.task.plans) with the team's clock in them:

* a state is where the robots are, which rooms are visited (and targets by their robot),
  when each robot is free and the makespan so far;
* a step is a single move (the robot starts when it is free) or an offered paired move (it
  starts when both robots are free), costing its table cost plus ``span_weight`` times what
  it adds to the makespan;
* the heuristic never overestimates: for every room still to enter, the cheapest way into
  it (the potentials of tmpnav.task.encodings, a paired move counting half for each of its
  rooms), plus ``span_weight`` times what the makespan must still grow, since each such room
  is entered at the earliest when the quickest robot could get there from where it is free.

The first goal state taken from the queue is optimal (A* with an admissible heuristic,
states reopened when reached more cheaply). :func:`exact_schedule` gives up (None) past
``max_states`` expanded states; ``tests/task/test_objectives.py`` checks it against
enumeration on random tables and checks ENHSP's cost-objective plans likewise.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Iterator
from dataclasses import dataclass

from tmpnav.task.encodings import COST_SCALE, offered_pairs, potentials
from tmpnav.task.plans import Plan, Step
from tmpnav.task.timing import table_durations
from tmpnav.types import CostTable, Goals, MoveKey

#: states expanded before the exact search gives up (the anytime search takes over)
MAX_STATES = 400_000


@dataclass(frozen=True)
class _Node:
    at: tuple[str, ...]
    visited: frozenset[str]
    by: frozenset[tuple[str, str]]
    clocks: tuple[float, ...]
    span: float


class _Space:
    """The states and steps of a table's task, with the team's clock."""

    def __init__(self, table: CostTable, goals: Goals, min_gain: float, span_weight: float):
        self.table, self.goals, self.w = table, goals, span_weight
        self.robots = table.robots
        self.targets = frozenset((r, x) for r, rooms in goals.per_robot for x in rooms)
        self.duration = table_durations(table)
        self.moves: dict[tuple[str, str], list[MoveKey]] = {}
        for m in table.single:
            self.moves.setdefault(m[:2], []).append(m)
        self.pairs: dict[tuple[str, str, str, str], list[tuple[Step, float]]] = {}
        for (m1, m2), c in offered_pairs(table, min_gain).items():
            self.pairs.setdefault((*m1[:2], *m2[:2]), []).append(((m1, m2), c))
        pair_costs = offered_pairs(table, min_gain)
        self.h = {x: v / COST_SCALE for x, v in potentials(table, goals, pair_costs).items()}
        self.quickest = self._quickest()

    def _quickest(self) -> dict[tuple[str, str], float]:
        """(robot, room) -> the shortest duration of a move of that robot into the room."""
        out: dict[tuple[str, str], float] = {}
        for (r, _, x), d in self.table.duration.items():
            out[(r, x)] = min(out.get((r, x), math.inf), d)
        return out

    def start(self) -> _Node:
        at = tuple(self.table.start_location[r] for r in self.robots)
        by = frozenset((r, x) for r, x in zip(self.robots, at, strict=True) if (r, x) in self.targets)
        return _Node(at, frozenset(at), by, (0.0,) * len(self.robots), 0.0)

    def done(self, n: _Node) -> bool:
        return set(self.goals.visit) <= n.visited and self.targets <= n.by

    def may_enter(self, n: _Node, robot: str, room: str) -> bool:
        if not self.goals.may_visit(robot, room):  # the room's job is for other robots
            return False
        return room not in n.visited or ((robot, room) in self.targets and (robot, room) not in n.by)

    def steps(self, n: _Node) -> Iterator[tuple[Step, float, _Node]]:
        """Every step the rules allow in ``n``: (step, its cost with the time's price, next state)."""
        for i, (r, here) in enumerate(zip(self.robots, n.at, strict=True)):
            for m in self.moves.get((r, here), ()):
                if self.may_enter(n, r, m[2]):
                    yield self._step(n, (m,), self.table.single[m], (i,))
        for (i, (r1, o1)), (j, (r2, o2)) in itertools.combinations(enumerate(zip(self.robots, n.at, strict=True)), 2):
            for step, c in self.pairs.get((r1, o1, r2, o2), ()):
                if all(self.may_enter(n, r, t) for r, _, t in step) and not (
                    step[0][2] == step[1][2] and not any((r, t) in self.targets for r, _, t in step)
                ):
                    yield self._step(n, step, c, (i, j))

    def _step(self, n: _Node, step: Step, cost: float, idx: tuple[int, ...]) -> tuple[Step, float, _Node]:
        times = self.duration(step) or (0.0,) * len(step)
        start = max(n.clocks[i] for i in idx)
        clocks, at = list(n.clocks), list(n.at)
        visited, by = set(n.visited), set(n.by)
        for i, (r, _, x), d in zip(idx, step, times, strict=True):
            clocks[i], at[i] = start + d, x
            visited.add(x)
            if (r, x) in self.targets:
                by.add((r, x))
        span = max(n.span, *(clocks[i] for i in idx))
        nxt = _Node(tuple(at), frozenset(visited), frozenset(by), tuple(clocks), span)
        return step, cost + self.w * (span - n.span), nxt

    def estimate(self, n: _Node) -> float:
        """A lower bound on what reaching the goals from ``n`` still costs (module docstring)."""
        todo = [x for x in self.goals.visit if x not in n.visited]
        todo += [x for r, x in self.targets - n.by]
        cost = sum(self.h.get(x, 0.0) for x in set(todo) if x in self.h and x not in n.visited)
        if not self.w or not todo:
            return cost
        reach = 0.0
        for x in set(todo):
            earliest = min(
                (n.clocks[i] + self.quickest.get((r, x), math.inf) for i, r in enumerate(self.robots)),
                default=math.inf,
            )
            reach = max(reach, earliest if math.isfinite(earliest) else 0.0)
        return cost + self.w * max(0.0, reach - n.span)


def exact_schedule(
    table: CostTable, goals: Goals, min_gain: float, span_weight: float, max_states: int = MAX_STATES
) -> tuple[Plan, float] | None:
    """The plan of least table cost plus ``span_weight`` times its makespan, and that value;
    None when there is no plan or more than ``max_states`` states were expanded."""
    space = _Space(table, goals, min_gain, span_weight)
    start = space.start()
    best: dict[_Node, float] = {start: 0.0}
    parent: dict[_Node, tuple[_Node, Step]] = {}
    counter = itertools.count()
    queue = [(space.estimate(start), next(counter), 0.0, start)]
    expanded = 0
    while queue:
        _, _, g, node = heapq.heappop(queue)
        if g > best[node]:
            continue
        if space.done(node):
            return _plan(parent, node), g
        expanded += 1
        if expanded > max_states:
            return None
        for step, cost, nxt in space.steps(node):
            if g + cost < best.get(nxt, math.inf) - 1e-12:
                best[nxt], parent[nxt] = g + cost, (node, step)
                heapq.heappush(queue, (g + cost + space.estimate(nxt), next(counter), g + cost, nxt))
    return None


def _plan(parent: dict[_Node, tuple[_Node, Step]], node: _Node) -> Plan:
    steps = []
    while node in parent:
        node, step = parent[node]
        steps.append(step)
    return tuple(reversed(steps))
