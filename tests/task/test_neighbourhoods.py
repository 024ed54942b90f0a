"""Neighbourhoods stay near their size even where paired steps interleave."""

from __future__ import annotations

import random

from tmpnav.task.neighbourhoods import SLACK, Closeness, neighbourhood
from tmpnav.types import CostTable


def test_interleaved_pairs_do_not_pull_in_every_route() -> None:
    # both robots move together in every step; A's seed is its first room, and the room of
    # B's route closest to it is B's last: closing the pairs would open both whole routes
    n = 20
    a = [f"a{j}" for j in range(n)]
    b = [f"b{j}" for j in range(n)]
    plan = tuple(
        ((("A", "A-start" if j == 0 else a[j - 1], a[j])), ("B", "B-start" if j == 0 else b[j - 1], b[j]))
        for j in range(n)
    )
    single = {("A", x, y): float(abs(i - j)) for i, x in enumerate(a) for j, y in enumerate(a) if i != j}
    single |= {("B", x, y): float(abs(i - j)) for i, x in enumerate(b) for j, y in enumerate(b) if i != j}
    single |= {("B", b[-1], a[0]): 0.1, ("A", "A-start", a[0]): 1.0, ("B", "B-start", b[0]): 1.0}
    start = {"A": "A-start", "B": "B-start"}
    table = CostTable(("A", "B"), tuple(a + b), tuple(a + b + ["A-start", "B-start"]), start, single, {})
    near = Closeness(table, start, ("A", "B"))
    hood = neighbourhood(plan, 0, 0, 8, near, random.Random(0), 2)
    assert len(hood.rooms) <= 8 + SLACK
    assert hood.robots == ("A",) and hood.removed == frozenset(range(8))
