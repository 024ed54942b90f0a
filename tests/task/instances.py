"""Task problems for the bound and routing tests, and an independent statement of their rules.

``small_instance`` draws a random cost table with the corner cases of the ``mixed``
encoding (robots starting in a goal room or outside every room, per-robot targets, one of
them in another robot's start room, a room that is not a goal, missing moves, pairs that
save a lot, a little or nothing). ``exact_optimum`` searches every sequence of single
moves and offered pairs that obeys the entry rules (Dijkstra over the states: positions,
visited rooms, target rooms visited by their robot), knowing nothing of the bound.
``building_instance`` is a larger table with a building's structure: two rows of rooms
along a corridor, costs growing with the distance driven, pairs only for robots that
drive near each other.
"""

from __future__ import annotations

import heapq
import itertools
import random
from collections.abc import Iterable

from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.encodings import offered_pairs as _useful_pairs
from tmpnav.types import CostTable, Goals, MoveKey

Step = tuple[MoveKey, ...]


def small_instance(
    rnd: random.Random, n_robots: int, n_rooms: int, pair_density: float, metric: bool = False
) -> tuple[CostTable, Goals]:
    """A random table on ``n_rooms`` rooms (and maybe one more that is not a goal).

    Costs are noisy distances plus a constant, and about 3% of the moves are missing; with
    ``metric`` every move exists and costs its robot's factor times the distance plus a
    constant, so no detour is ever cheaper than the direct move."""
    robots = tuple(f"r{i + 1}" for i in range(n_robots))
    rooms = [f"L{i + 1}" for i in range(n_rooms)]
    extra = rnd.random() < 0.3
    if extra:
        rooms.append("X")
    start = {r: f"{r}-start" for r in robots}
    if rnd.random() < 0.5:
        start[robots[0]] = rooms[0]  # a goal room visited from the outset
    if n_robots > 2 and rnd.random() < 0.3:
        start[robots[2]] = start[robots[1]] = rooms[-1]  # two robots share a start room
    visit = [x for x in rooms if x != "X"]
    per_robot: dict[str, tuple[str, ...]] = {}
    for r in robots:
        if rnd.random() < 0.4:
            per_robot[r] = tuple(rnd.sample(visit, min(len(visit), rnd.choice([1, 2]))))
    if rnd.random() < 0.3 and len(visit) > 1:
        visit.remove(rnd.choice(visit))  # a room that only a robot's target names, or nobody's goal
    goals = Goals(visit=tuple(visit), per_robot=tuple(per_robot.items()))
    locations = tuple(dict.fromkeys([*rooms, *start.values()]))
    xy = {loc: (rnd.uniform(0, 20), rnd.uniform(0, 10)) for loc in locations}
    single: dict[MoveKey, float] = {}
    for r in robots:
        factor, constant = rnd.uniform(0.8, 1.3), rnd.uniform(0.5, 3.0)
        for a, b in itertools.permutations(locations, 2):
            if b in rooms and b != start[r] and (metric or rnd.random() > 0.03):  # a few moves are missing
                d = ((xy[a][0] - xy[b][0]) ** 2 + (xy[a][1] - xy[b][1]) ** 2) ** 0.5
                noisy = d * rnd.uniform(0.8, 1.3) + rnd.uniform(0.5, 3.0)
                single[(r, a, b)] = d * factor + constant if metric else noisy
    keep = ENCODINGS["mixed"].pair_filter(goals, start)
    pair: dict[tuple[MoveKey, MoveKey], float] = {}
    for i, r1 in enumerate(robots):
        for r2 in robots[i + 1 :]:
            for m1 in (m for m in single if m[0] == r1):
                for m2 in (m for m in single if m[0] == r2):
                    if keep(m1, m2) and rnd.random() < pair_density:
                        gain = rnd.choice([0.0, 0.02, 0.1, 0.3, 0.6, -0.1])
                        pair[(m1, m2)] = (single[m1] + single[m2]) * (1.0 - gain)
    return CostTable(robots, tuple(rooms), locations, start, single, pair), goals


def without_pairs(table: CostTable) -> CostTable:
    return CostTable(table.robots, table.rooms, table.locations, table.start_location, table.single, {})


class Rules:
    """The entry rules of the ``mixed`` encoding, applied to explicit states."""

    def __init__(self, table: CostTable, goals: Goals, min_gain: float = 0.0):
        self.table, self.goals = table, goals
        self.robots = table.robots
        self.targets = {(r, x) for r, rooms in goals.per_robot for x in rooms}
        self.singles: dict[tuple[str, str], list[MoveKey]] = {}
        for m in table.single:
            self.singles.setdefault(m[:2], []).append(m)
        self.pairs: dict[tuple[str, str, str, str], list[tuple[Step, float]]] = {}
        for (m1, m2), c in _useful_pairs(table, min_gain).items():
            self.pairs.setdefault((*m1[:2], *m2[:2]), []).append(((m1, m2), c))

    def start(self) -> tuple:
        pos = tuple(self.table.start_location[r] for r in self.robots)
        by = frozenset((r, loc) for r, loc in zip(self.robots, pos, strict=True) if (r, loc) in self.targets)
        return pos, frozenset(pos), by

    def done(self, state: tuple) -> bool:
        return set(self.goals.visit) <= state[1] and self.targets <= state[2]

    def may_enter(self, r: str, room: str, state: tuple) -> bool:
        return room not in state[1] or ((r, room) in self.targets and (r, room) not in state[2])

    def apply(self, state: tuple, step: Step) -> tuple:
        """The state after ``step``; AssertionError if the encoding would not allow it."""
        pos, visited, by = list(state[0]), set(state[1]), set(state[2])
        for r, o, t in step:
            assert pos[self.robots.index(r)] == o, f"{r} is not at {o}"
            assert self.may_enter(r, t, state), f"{r} may not enter {t}"
        for r, _, t in step:
            pos[self.robots.index(r)] = t
            visited.add(t)
            if (r, t) in self.targets:
                by.add((r, t))
        return tuple(pos), frozenset(visited), frozenset(by)

    def successors(self, state: tuple) -> Iterable[tuple[float, tuple]]:
        pos = state[0]
        for r, o in zip(self.robots, pos, strict=True):
            for m in self.singles.get((r, o), ()):
                if self.may_enter(r, m[2], state):
                    yield self.table.single[m], self.apply(state, (m,))
        for (r1, o1), (r2, o2) in itertools.combinations(zip(self.robots, pos, strict=True), 2):
            for step, c in self.pairs.get((r1, o1, r2, o2), ()):
                if all(self.may_enter(r, t, state) for r, _, t in step):
                    yield c, self.apply(state, step)


def exact_optimum(table: CostTable, goals: Goals, min_gain: float = 0.0) -> float:
    """The cost of the cheapest plan of the ``mixed`` encoding (inf if there is none)."""
    rules = Rules(table, goals, min_gain)
    start = rules.start()
    best, queue, counter = {start: 0.0}, [(0.0, 0, start)], itertools.count()
    while queue:
        cost, _, state = heapq.heappop(queue)
        if cost > best[state]:
            continue
        if rules.done(state):
            return cost
        for c, nxt in rules.successors(state):
            if cost + c < best.get(nxt, float("inf")):
                best[nxt] = cost + c
                heapq.heappush(queue, (cost + c, next(counter), nxt))
    return float("inf")


def plan_cost(table: CostTable, goals: Goals, steps: list[Step], min_gain: float = 0.0) -> float:
    """The table cost of a plan, after checking every step against the rules and the goals."""
    rules, offered = Rules(table, goals, min_gain), _useful_pairs(table, min_gain)
    state, cost = rules.start(), 0.0
    for step in steps:
        state = rules.apply(state, step)
        cost += table.single[step[0]] if len(step) == 1 else offered[step]  # type: ignore[index]
    assert rules.done(state), "the plan leaves goals unvisited"
    return cost


def greedy_cost(table: CostTable, goals: Goals) -> float:
    """Nearest neighbour: repeatedly the cheapest allowed single move into an unmet goal."""
    rules = Rules(table, goals)
    state, cost = rules.start(), 0.0
    while not rules.done(state):
        need = set(goals.visit) - state[1]
        moves = [
            (table.single[m], m)
            for r, o in zip(rules.robots, state[0], strict=True)
            for m in rules.singles.get((r, o), ())
            if rules.may_enter(r, m[2], state) and (m[2] in need or (r, m[2]) in rules.targets - state[2])
        ]
        c, m = min(moves)
        state, cost = rules.apply(state, (m,)), cost + c
    return cost


def building_instance(
    rnd: random.Random, n_rooms: int, n_robots: int, max_pairs: int = 20_000
) -> tuple[CostTable, Goals]:
    """Two rows of rooms off a corridor (5 m apart), robots on the corridor, every room a
    goal, one target room per robot; costs ~ distance driven (via the corridor) plus a
    constant; pairs (at most ``max_pairs``) for moves whose origins and targets lie within
    10 m of each other, saving 5-25%."""
    robots = tuple(f"r{i + 1}" for i in range(n_robots))
    rooms = tuple(f"R{i + 1}" for i in range(n_rooms))
    xy = {x: (5.0 * (i // 2), 4.0 if i % 2 else -4.0) for i, x in enumerate(rooms)}
    start = {r: f"{r}-start" for r in robots}
    for i, r in enumerate(robots):
        xy[start[r]] = (5.0 * (n_rooms // 2) * i / max(1, n_robots - 1), 0.0)
    targets = {r: (rooms[rnd.randrange(n_rooms)],) for r in robots if rnd.random() < 0.5}
    goals = Goals(visit=rooms, per_robot=tuple(targets.items()))

    def driven(a: str, b: str) -> float:
        (xa, ya), (xb, yb) = xy[a], xy[b]
        return abs(xa - xb) + abs(ya) + abs(yb)

    single = {
        (r, a, b): driven(a, b) * rnd.uniform(0.95, 1.1) + 2.0
        for r in robots
        for a in (start[r], *rooms)
        for b in rooms
        if a != b
    }
    near = {a: [b for b in xy if b != a and driven(a, b) <= 10.0] for a in xy}
    keep = ENCODINGS["mixed"].pair_filter(goals, start)
    pair: dict[tuple[MoveKey, MoveKey], float] = {}
    moves = list(single)
    for _ in range(5 * max_pairs):  # a random sample of the pairs of moves that drive near each other
        if len(pair) >= max_pairs:
            break
        m1 = rnd.choice(moves)
        r2 = rnd.choice([r for r in robots if r != m1[0]])
        m2 = (r2, rnd.choice([m1[1], *near[m1[1]]]), rnd.choice(near[m1[2]]))
        if robots.index(r2) < robots.index(m1[0]):
            m1, m2 = m2, m1
        if m1 in single and m2 in single and keep(m1, m2) and (m1, m2) not in pair:
            pair[(m1, m2)] = (single[m1] + single[m2]) * (1.0 - rnd.uniform(0.05, 0.25))
    locations = (*rooms, *start.values())
    return CostTable(robots, rooms, locations, start, single, pair), goals
