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
* a move into a room with a window (``goals.jobs``) arrives after the drive (its duration
  less the room's service); before the window opens the robot waits there, and a move that
  would arrive after it closes is not a step;
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
from dataclasses import dataclass, replace

from tmpnav.task.encodings import COST_SCALE, offered_pairs, potentials
from tmpnav.task.plans import Plan, Step
from tmpnav.task.timing import table_durations
from tmpnav.types import WINDOW_TOL, CostTable, Goals, MoveKey

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
        self.targets, self.entries = goals.targets, goals.entries
        self.duration = table_durations(table)
        self.moves: dict[tuple[str, str], list[MoveKey]] = {}
        for m in table.single:
            self.moves.setdefault(m[:2], []).append(m)
        self.pairs: dict[tuple[str, str, str, str], list[tuple[Step, float]]] = {}
        for (m1, m2), c in offered_pairs(table, min_gain).items():
            self.pairs.setdefault((*m1[:2], *m2[:2]), []).append(((m1, m2), c))
        pair_costs = offered_pairs(table, min_gain)
        # every room's potential, the optional goals' too (potentials() leaves them out of the PDDL's)
        every = potentials(table, replace(goals, jobs=tuple(replace(j, penalty=None) for j in goals.jobs)), pair_costs)
        self.h = {x: v / COST_SCALE for x, v in every.items()}
        self.quickest = self._quickest()
        self.windows = goals.windows
        self.ended = frozenset(goals.ends)
        # the cheapest move of each robot into its end: a move no room's potential counts
        self.end_cost = {
            (r, x): min((c for m, c in table.single.items() if m[0] == r and m[2] == x), default=0.0)
            for r, x in goals.ends
        }

    def _quickest(self) -> dict[tuple[str, str], float]:
        """(robot, room) -> the shortest duration of a move of that robot into the room."""
        out: dict[tuple[str, str], float] = {}
        for (r, _, x), d in self.table.duration.items():
            out[(r, x)] = min(out.get((r, x), math.inf), d)
        return out

    def start(self) -> _Node:
        at = tuple(self.table.start_location[r] for r in self.robots)
        by = self.goals.marked_at_start(dict(zip(self.robots, at, strict=True)))
        clocks = tuple(self.goals.held_for(r) for r in self.robots)  # a robot held where it starts
        return _Node(at, frozenset(at), by, clocks, 0.0)

    def done(self, n: _Node) -> bool:
        return (
            set(self.goals.required) <= n.visited
            and self.targets <= n.by
            and self.goals.ended(dict(zip(self.robots, n.at, strict=True)))
        )

    def drop_penalty(self, n: _Node) -> float:
        """What ending in ``n`` costs more: the penalties of the optional goals not visited."""
        return self.goals.drop_penalty(n.visited)

    def may_enter(self, n: _Node, robot: str, room: str) -> bool:
        if not self.goals.may_visit(robot, room):  # the room's job is for other robots
            return False
        return room not in n.visited or ((robot, room) in self.entries and (robot, room) not in n.by)

    def steps(self, n: _Node) -> Iterator[tuple[Step, float, _Node]]:
        """Every step the rules allow in ``n``: (step, its cost with the time's price, next state)."""
        for i, (r, here) in enumerate(zip(self.robots, n.at, strict=True)):
            if (r, here) in self.ended and (r, here) in n.by:
                continue  # a robot back at its end stays there (it could not enter it again)
            for m in self.moves.get((r, here), ()):
                if self.may_enter(n, r, m[2]) and (nxt := self._step(n, (m,), self.table.single[m], (i,))):
                    yield nxt
        for (i, (r1, o1)), (j, (r2, o2)) in itertools.combinations(enumerate(zip(self.robots, n.at, strict=True)), 2):
            if ((r1, o1) in self.ended and (r1, o1) in n.by) or ((r2, o2) in self.ended and (r2, o2) in n.by):
                continue
            for step, c in self.pairs.get((r1, o1, r2, o2), ()):
                if (
                    all(self.may_enter(n, r, t) for r, _, t in step)
                    and not (step[0][2] == step[1][2] and not any((r, t) in self.entries for r, _, t in step))
                    and (nxt := self._step(n, step, c, (i, j)))
                ):
                    yield nxt

    def _step(self, n: _Node, step: Step, cost: float, idx: tuple[int, ...]) -> tuple[Step, float, _Node] | None:
        times = self.duration(step) or (0.0,) * len(step)
        start = max(n.clocks[i] for i in idx)
        clocks, at = list(n.clocks), list(n.at)
        visited, by = set(n.visited), set(n.by)
        for i, (r, _, x), d in zip(idx, step, times, strict=True):
            service = self.goals.service(x)
            arrive = start + d - service
            if self.goals.too_late(x, arrive):
                return None  # it would arrive after the window closes
            clocks[i], at[i] = arrive + self.goals.opens(x, arrive) + service, x
            visited.add(x)
            if (r, x) in self.entries:
                by.add((r, x))
        span = max(n.span, *(clocks[i] for i in idx))
        nxt = _Node(tuple(at), frozenset(visited), frozenset(by), tuple(clocks), span)
        return step, cost + self.w * (span - n.span), nxt

    def estimate(self, n: _Node) -> float:
        """A lower bound on what reaching the goals from ``n`` still costs (module docstring)."""
        todo = [x for x in self.goals.required if x not in n.visited]
        todo += [x for r, x in self.targets - n.by]
        todo += [x for i, (r, x) in enumerate(self.goals.ends) if n.at[self.robots.index(r)] != x]
        cost = sum(self.h.get(x, 0.0) for x in set(todo) if x in self.h and x not in n.visited)
        # an optional goal not visited: entered (at least its potential) or left undone (its penalty)
        cost += sum(min(self.h.get(x, 0.0), p) for x, p in self.goals.optional.items() if x not in n.visited)
        at = dict(zip(self.robots, n.at, strict=True))
        cost += sum(c for (r, x), c in self.end_cost.items() if at[r] != x)  # a robot not at its end must go there
        if not todo or (not self.w and not self.windows):
            return cost
        reach = 0.0
        for x in set(todo):
            earliest = min(
                (n.clocks[i] + self.quickest.get((r, x), math.inf) for i, r in enumerate(self.robots)),
                default=math.inf,
            )
            if not math.isfinite(earliest):
                continue
            window = self.windows.get(x)
            if window is not None:  # done at the earliest when the window opens, and its service ends
                service = self.goals.service(x)
                if earliest - service > window[1] + WINDOW_TOL:
                    return math.inf  # no robot can get there before the window closes: a dead end
                earliest = max(earliest, window[0] + service)
            reach = max(reach, earliest)
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
    queue: list[tuple[float, int, float, _Node, bool]] = [(space.estimate(start), next(counter), 0.0, start, False)]
    expanded = 0
    while queue:
        _, _, g, node, final = heapq.heappop(queue)
        if final:  # the plan ends here, its optional goals left undone paid for
            return _plan(parent, node), g
        if g > best[node]:
            continue
        if space.done(node):  # end here (paying for what it leaves undone), or go on to an optional goal
            if not goals.optional:
                return _plan(parent, node), g
            ended = g + space.drop_penalty(node)
            heapq.heappush(queue, (ended, next(counter), ended, node, True))
        expanded += 1
        if expanded > max_states:
            return None
        for step, cost, nxt in space.steps(node):
            if g + cost < best.get(nxt, math.inf) - 1e-12:
                h = space.estimate(nxt)
                if math.isfinite(h):
                    best[nxt], parent[nxt] = g + cost, (node, step)
                    heapq.heappush(queue, (g + cost + h, next(counter), g + cost, nxt, False))
    return None


def _plan(parent: dict[_Node, tuple[_Node, Step]], node: _Node) -> Plan:
    steps = []
    while node in parent:
        node, step = parent[node]
        steps.append(step)
    return tuple(reversed(steps))
