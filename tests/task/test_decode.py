"""The canonical order of a plan's steps (tmpnav.task.decode)."""

from __future__ import annotations

import heapq
import random

import pytest

from tmpnav.task.decode import canonical_order
from tmpnav.types import MoveKey


def _every_pair(steps: list[tuple[MoveKey, ...]], robots: tuple[str, ...]) -> list[int]:
    """The order written plainly: a step waits for every earlier step sharing a robot or a room."""
    rank = {r: i for i, r in enumerate(robots)}
    touches = [{x for m in step for x in m} for step in steps]
    deps = [{j for j in range(i) if touches[i] & touches[j]} for i in range(len(steps))]
    done: set[int] = set()
    out: list[int] = []
    ready = [(min(rank[m[0]] for m in steps[i]), i) for i in range(len(steps)) if not deps[i]]
    heapq.heapify(ready)
    while ready:
        _, i = heapq.heappop(ready)
        out.append(i)
        done.add(i)
        for u in range(i + 1, len(steps)):
            if u not in done and i in deps[u] and deps[u] <= done and all(u != k for _, k in ready):
                heapq.heappush(ready, (min(rank[m[0]] for m in steps[u]), u))
    return out


@pytest.mark.parametrize("seed", range(30))
def test_the_order_is_the_one_every_pair_of_steps_gives(seed: int) -> None:
    rnd = random.Random(seed)
    robots = tuple(f"r{k}" for k in range(rnd.randint(1, 5)))
    rooms = [f"R{k}" for k in range(rnd.randint(2, 12))]
    at = {r: f"{r}-start" for r in robots}
    steps: list[tuple[MoveKey, ...]] = []
    for _ in range(rnd.randint(0, 40)):
        movers = rnd.sample(robots, min(len(robots), rnd.choice((1, 1, 2))))
        step = []
        for r in movers:
            target = rnd.choice([x for x in rooms if x != at[r]])
            step.append((r, at[r], target))
            at[r] = target
        steps.append(tuple(step))
    order = canonical_order(steps, robots)
    assert order == _every_pair(steps, robots)
    assert sorted(order) == list(range(len(steps)))
