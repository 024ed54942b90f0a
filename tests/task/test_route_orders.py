"""The route improvement of tmpnav.task.route_orders (Or-opt and 2-opt on asymmetric moves): a
permutation of the route, never dearer, its last room kept where asked, and a local optimum
that no single Or-opt or 2-opt move improves."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.task.route_orders import OR_OPT, _sums, improve_routes, route_value
from tmpnav.types import RISK_PENALTY


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


def test_each_route_is_summed_on_its_own_beside_penalised_routes() -> None:
    """A route of action costs beside routes holding moves over the chance constraint (some
    1e11 each) keeps its cents: a running sum over all routes would round it to 0.125."""
    rng = np.random.default_rng(3)
    stretches = [rng.uniform(1.0, 20.0, 12) for _ in range(6)]
    for k in (0, 2, 4):
        stretches[k][3] = RISK_PENALTY * rng.uniform(0.05, 0.95)
    stretches.insert(3, np.array([]))
    values = np.concatenate(stretches)
    bounds = np.cumsum([0, *(len(s) for s in stretches)])
    got = _sums(values, bounds)
    for g, s in zip(got, stretches, strict=True):
        assert g == pytest.approx(math.fsum(s), rel=1e-15, abs=1e-9)
    values[5] = math.inf  # a missing move: its route's sum is inf, the others unchanged
    assert _sums(values, bounds)[0] == math.inf and _sums(values, bounds)[1:] == got[1:]
