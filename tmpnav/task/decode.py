"""Stage 6c: a plan's steps (robot moves, decoded by the encoded task) -> their costs and a canonical order."""

from __future__ import annotations

from tmpnav.types import CostTable, MoveKey


def step_cost(table: CostTable, step: tuple[MoveKey, ...]) -> float:
    """The table cost of one plan step, as the planner saw it (before reshaping)."""
    if len(step) == 1:
        return table.single[step[0]]
    m1, m2 = step
    return table.pair[(m1, m2)] if (m1, m2) in table.pair else table.pair[(m2, m1)]


def canonical_order(steps: list[tuple[MoveKey, ...]], robots: tuple[str, ...]) -> list[int]:
    """The plan's step indices in one canonical order, among the orders the planner could
    equally have returned.

    Two steps that share no robot and no room commute: each one's preconditions and
    effects concern only its own robots and rooms. So a plan is a partial order, and the
    planner's tie-breaking between its interleavings depends on the order in which the
    PDDL writer happens to list objects (Python's per-process string hashing). Steps keep
    their order relative to every step they depend on; among the free ones, the step of
    the earliest robot (scenario order) comes first. Same cost, reproducible output.
    """
    import heapq

    rank = {r: i for i, r in enumerate(robots)}
    # each step waits for the last earlier step of each robot and room it touches: the steps
    # before that one wait for it in turn, so the order is that of every earlier step sharing
    # one (linear in the plan's length; every pair of steps took minutes at 200 rooms)
    n = len(steps)
    last: dict[str, int] = {}
    deps: list[set[int]] = []
    for i, step in enumerate(steps):
        names = {name for m in step for name in m}
        deps.append({last[x] for x in names if x in last})
        last.update(dict.fromkeys(names, i))
    waiting = [len(d) for d in deps]
    users: list[list[int]] = [[] for _ in range(n)]
    for i, d in enumerate(deps):
        for j in d:
            users[j].append(i)

    def key(i: int) -> tuple[int, int]:
        return (min(rank[m[0]] for m in steps[i]), i)

    ready = [key(i) for i in range(n) if waiting[i] == 0]
    heapq.heapify(ready)
    out: list[int] = []
    while ready:
        _, i = heapq.heappop(ready)
        out.append(i)
        for u in users[i]:
            waiting[u] -= 1
            if waiting[u] == 0:
                heapq.heappush(ready, key(u))
    return out
