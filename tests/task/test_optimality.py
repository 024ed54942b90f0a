"""Plans are optimal for their cost table: ENHSP's plan against exhaustive search.

The exhaustive search below is an independent statement of each encoding's rules
(who may move where, what a move costs), searched with Dijkstra over every state. It
knows nothing of reshaping or of PDDL, so it also checks that reshaping keeps the optimum.
"""

from __future__ import annotations

import heapq
import itertools
import random

import pytest

from tmpnav.task.decode import canonical_order, step_cost
from tmpnav.task.encode import encode
from tmpnav.task.encodings import ENCODINGS, scaled
from tmpnav.task.solve import solve
from tmpnav.types import CostTable, Goals, MoveKey


def random_table(seed: int, n_robots: int, n_rooms: int, targets: bool) -> tuple[CostTable, Goals]:
    """Robots start in the first rooms; goals are the other rooms (some per robot)."""
    rnd = random.Random(seed)
    robots = tuple(f"r{i + 1}" for i in range(n_robots))
    rooms = tuple(f"L{i + 1}" for i in range(n_rooms + n_robots))
    start = {r: rooms[i] for i, r in enumerate(robots)}
    goal_rooms = rooms[n_robots:]
    per_robot: dict[str, tuple[str, ...]] = {}
    visit = list(goal_rooms)
    if targets:
        r = robots[0]
        per_robot[r] = (visit.pop(),)
    goals = Goals(visit=tuple(visit), per_robot=tuple(per_robot.items()))
    xy = {room: (rnd.uniform(0, 20), rnd.uniform(0, 10)) for room in rooms}
    single: dict[MoveKey, float] = {}
    for r in robots:
        for a in [start[r], *goal_rooms]:
            for b in goal_rooms:
                if a != b:
                    d = ((xy[a][0] - xy[b][0]) ** 2 + (xy[a][1] - xy[b][1]) ** 2) ** 0.5
                    single[(r, a, b)] = d * rnd.uniform(0.8, 1.3) + rnd.uniform(0.5, 3.0)
    pair: dict[tuple[MoveKey, MoveKey], float] = {}
    for i, r1 in enumerate(robots):
        for r2 in robots[i + 1 :]:
            for m1 in (m for m in single if m[0] == r1):
                for m2 in (m for m in single if m[0] == r2):
                    # most pairs gain nothing, some a lot, a few cost more together
                    gain = rnd.choice([0.0, 0.0, 0.02, 0.3, 0.6, -0.1])
                    pair[(m1, m2)] = (single[m1] + single[m2]) * (1.0 - gain)
    return CostTable(robots, rooms, rooms, start, single, pair), goals


def exhaustive_optimum(table: CostTable, goals: Goals, encoding: str, min_gain: float = 0.0) -> int:
    """The cheapest plan (in scaled integer cost) under the encoding's rules."""
    robots = table.robots
    targets = {(r, room) for r, rooms in goals.per_robot for room in rooms}
    start_pos = tuple(table.start_location[r] for r in robots)
    start_visited = frozenset(start_pos)
    start_by = frozenset((r, table.start_location[r]) for r in robots if (r, table.start_location[r]) in targets)
    need_visit, need_by = set(goals.visit), targets

    def may_enter(r: str, room: str, visited: frozenset, by: frozenset) -> bool:
        if encoding == "paper":
            return True
        return room not in visited or ((r, room) in targets and (r, room) not in by)

    def apply(pos: tuple, visited: frozenset, by: frozenset, moves: tuple[MoveKey, ...]) -> tuple:
        p = list(pos)
        v, b = set(visited), set(by)
        for r, _, t in moves:
            p[robots.index(r)] = t
            v.add(t)
            if (r, t) in targets:
                b.add((r, t))
        return tuple(p), frozenset(v), frozenset(b)

    def successors(state: tuple):  # type: ignore[no-untyped-def]
        pos, visited, by = state
        at = dict(zip(robots, pos, strict=True))
        if encoding in ("single", "mixed"):
            for m in table.single:
                r, o, t = m
                if at[r] == o and may_enter(r, t, visited, by):
                    yield scaled(table.single[m]), apply(pos, visited, by, (m,))
        if encoding == "mixed":
            for (m1, m2), c in table.pair.items():
                alone = scaled(table.single[m1]) + scaled(table.single[m2])
                if not (scaled(c) < alone and scaled(c) <= (1 - min_gain) * alone):
                    continue
                at_origins = at[m1[0]] == m1[1] and at[m2[0]] == m2[1]
                if at_origins and may_enter(m1[0], m1[2], visited, by) and may_enter(m2[0], m2[2], visited, by):
                    yield scaled(c), apply(pos, visited, by, (m1, m2))
        if encoding == "paper":
            for (m1, m2), c in table.pair.items():
                if at[m1[0]] == m1[1] and at[m2[0]] == m2[1]:
                    yield scaled(c), apply(pos, visited, by, (m1, m2))

    start = (start_pos, start_visited, start_by)
    best = {start: 0}
    queue = [(0, 0, start)]
    counter = itertools.count()
    while queue:
        cost, _, state = heapq.heappop(queue)
        if cost > best[state]:
            continue
        if need_visit <= state[1] and need_by <= state[2]:
            return cost
        for c, nxt in successors(state):
            if cost + c < best.get(nxt, 1 << 62):
                best[nxt] = cost + c
                heapq.heappush(queue, (cost + c, next(counter), nxt))
    raise AssertionError("no plan exists")


def validate(encoded, result, table: CostTable) -> None:  # type: ignore[no-untyped-def]
    """The planner's plan, and the same plan in tmpnav's canonical order, are both valid."""
    from unified_planning.engines import ValidationResultStatus
    from unified_planning.plans import SequentialPlan
    from unified_planning.shortcuts import PlanValidator

    order = canonical_order(encoded.decode(result), table.robots)
    canonical = SequentialPlan([result.plan.actions[i] for i in order])
    with PlanValidator(problem_kind=encoded.problem.kind) as validator:
        for plan in (result.plan, canonical):
            outcome = validator.validate(encoded.problem, plan)
            assert outcome.status == ValidationResultStatus.VALID, outcome


CASES = [
    # (encoding, seed, robots, goal rooms, per-robot target)
    ("single", 1, 2, 3, False),
    ("single", 2, 3, 3, True),
    ("mixed", 3, 2, 4, False),
    ("mixed", 4, 2, 5, True),
    ("mixed", 5, 3, 4, False),
    ("mixed", 6, 3, 3, True),
    ("paper", 7, 2, 2, False),
    ("paper", 8, 2, 3, True),
    ("paper", 9, 3, 2, False),
]


@pytest.mark.slow
@pytest.mark.parametrize(("encoding", "seed", "robots", "rooms", "targets"), CASES)
def test_plan_cost_equals_exhaustive_optimum(encoding: str, seed: int, robots: int, rooms: int, targets: bool) -> None:
    table, goals = random_table(seed, robots, rooms, targets)
    keep = ENCODINGS[encoding].pair_filter(goals, table.start_location)  # None: the encoding has no pairs
    table = CostTable(
        table.robots,
        table.rooms,
        table.locations,
        table.start_location,
        table.single,
        {k: v for k, v in table.pair.items() if keep is not None and keep(*k)},
    )
    encoded = encode(table, goals, encoding, min_gain=0.0)
    result = solve(encoded.problem, "enhsp-opt", 120)
    validate(encoded, result, table)
    steps = encoded.decode(result)
    planner = sum(scaled(step_cost(table, s)) for s in steps)
    assert planner == exhaustive_optimum(table, goals, encoding)


@pytest.mark.slow
def test_pair_min_gain_is_within_its_bound() -> None:
    table, goals = random_table(11, 2, 5, False)
    exact = exhaustive_optimum(table, goals, "mixed", 0.0)
    encoded = encode(table, goals, "mixed", min_gain=0.25)
    result = solve(encoded.problem, "enhsp-opt", 120)
    cost = sum(scaled(step_cost(table, s)) for s in encoded.decode(result))
    assert cost == exhaustive_optimum(table, goals, "mixed", 0.25)
    assert exact <= cost <= exact / (1 - 0.25) + 1


@pytest.mark.slow
def test_odd_number_of_rooms_needs_no_extra_visit_with_mixed() -> None:
    """Three rooms, two robots: mixed enters exactly the three goal rooms; the paper's
    pair action must move both robots each time and so enters a fourth room."""
    table, goals = random_table(21, 2, 3, False)
    entered = {}
    for encoding in ("mixed", "paper"):
        keep = ENCODINGS[encoding].pair_filter(goals, table.start_location)
        assert keep is not None
        t = CostTable(
            table.robots,
            table.rooms,
            table.locations,
            table.start_location,
            table.single,
            {k: v for k, v in table.pair.items() if keep(*k)},
        )
        encoded = encode(t, goals, encoding)
        steps = encoded.decode(solve(encoded.problem, "enhsp-opt", 120))
        entered[encoding] = [m[2] for step in steps for m in step]
    assert sorted(entered["mixed"]) == sorted(goals.visit)
    assert len(entered["paper"]) == 4
