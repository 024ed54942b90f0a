"""The route improvement of tmpnav.task.route_orders (Or-opt and 2-opt on asymmetric moves): a
permutation of the route, never dearer, its last room kept where asked, and a local optimum
that no single Or-opt or 2-opt move improves."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.task.route_orders import OR_OPT, improve_routes, route_value


def neighbours(route: list[int], movable: int) -> list[list[int]]:
    """Every route one Or-opt or 2-opt move away, written out plainly."""
    out = []
    for s in range(1, OR_OPT + 1):
        for i in range(movable - s + 1):
            string, rest = route[i : i + s], route[:i] + route[i + s : movable]
            for j in range(len(rest) + 1):
                out.append(rest[:j] + string + rest[j:] + route[movable:])
    for i in range(movable - 1):
        for j in range(i + 1, movable):
            out.append(route[:i] + route[i : j + 1][::-1] + route[j + 1 :])
    return out


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(2, 9), st.booleans())
def test_a_route_is_improved_to_a_local_optimum(seed: int, n: int, fixed: bool) -> None:
    rng = np.random.default_rng(seed)
    value = rng.uniform(1.0, 10.0, size=(1, n + 1, n + 1))  # location 0: the start
    route = list(rng.permutation(np.arange(1, n + 1)))
    rooms = np.array(route, dtype=np.int64)
    improve_routes(value, np.zeros(1, np.int64), np.zeros(1, np.int64), np.array([0, n]), rooms, np.array([fixed]))
    got = [int(x) for x in rooms]
    assert sorted(got) == sorted(int(x) for x in route)
    if fixed:
        assert got[-1] == route[-1]
    best = route_value(value[0], 0, rooms)
    assert best <= route_value(value[0], 0, np.array(route, dtype=np.int64)) + 1e-12
    movable = n - 1 if fixed else n
    for other in neighbours(got, movable):
        assert route_value(value[0], 0, np.array(other, dtype=np.int64)) >= best - 1e-9 * max(1.0, best)


def test_routes_side_by_side_are_improved_each_on_its_robots_moves() -> None:
    """Two routes in one call: each on its own robot's matrix and start, neither touching the other."""
    line = np.abs(np.subtract.outer(np.arange(5.0), np.arange(5.0)))  # 5 locations on a line, 1 m apart
    value = np.stack([line, 2.0 * line])
    rooms = np.array([4, 2, 3, 1, 1, 3, 0, 2], dtype=np.int64)  # robot 0 from location 0, robot 1 from 4
    improve_routes(value, np.array([0, 1]), np.array([0, 4]), np.array([0, 4, 8]), rooms, np.array([False, False]))
    assert rooms.tolist() == [1, 2, 3, 4, 3, 2, 1, 0]
