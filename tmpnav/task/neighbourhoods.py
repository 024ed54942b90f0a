"""The anytime search's neighbourhoods: which robots and which stretch of each one's route to open.

Around a seed move (a robot entering room x0), the robots whose routes (or starts) come
closest to x0 take part, and each one's stretch grows, one room at a time, on whichever side
of whichever robot the next room is closest to x0, until the neighbourhood holds ``size``
rooms. Closeness is the cheapest single move between two rooms, either way. A paired step
opened for one of its robots is opened for the other too when both take part, so that each
robot's opened moves stay one stretch of its route. Where paired steps interleave, that
closure can pull in long stretches (24 rooms for a size of 8 on a 40-room building, whose
sub-problem asked the oracle for 840,000 paired moves): past ``size`` + :data:`SLACK` rooms
the robot farthest from x0 leaves the neighbourhood, down to the seed's robot alone.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from tmpnav.task.plans import Plan
from tmpnav.types import CostTable

#: rooms a neighbourhood may hold beyond its size after its paired steps are closed
SLACK = 2


@dataclass(frozen=True)
class Neighbourhood:
    robots: tuple[str, ...]
    removed: frozenset[int]  # step indices opened
    rooms: tuple[str, ...]  # rooms the opened moves of ``robots`` entered
    ends: dict[str, str]  # robot -> where it must end (it has moves after its stretch)


class Closeness:
    """How close two locations are: the cheapest single move between them, either way."""

    def __init__(self, singles: CostTable, start_location: dict[str, str], robots: tuple[str, ...]):
        near: dict[str, dict[str, float]] = {}
        for (_, a, b), c in singles.single.items():
            for x, y in ((a, b), (b, a)):
                row = near.setdefault(x, {})
                row[y] = min(row.get(y, math.inf), c)
        self.near = near
        self.start_location = start_location
        self.robots = robots

    def __call__(self, a: str, b: str) -> float:
        return 0.0 if a == b else self.near.get(a, {}).get(b, math.inf)


def neighbourhood(
    plan: Plan, k: int, i: int, size: int, d: Closeness, rng: random.Random, n_robots: int
) -> Neighbourhood:
    """Up to ``n_robots`` robots near the seed move ``plan[k][i]`` and a stretch of each route."""
    routes: dict[str, list[tuple[int, str]]] = {r: [] for r in d.robots}
    for idx, step in enumerate(plan):
        for r, _, x in step:
            routes[r].append((idx, x))
    r0, _, x0 = plan[k][i]
    others = sorted(
        (min([d(x0, d.start_location[r])] + [d(x0, x) for _, x in route]), rng.random(), r)
        for r, route in routes.items()
        if r != r0
    )
    robots = [r0] + [r for dist, _, r in others[: n_robots - 1] if math.isfinite(dist)]
    while True:
        windows = _windows(robots, routes, r0, k, x0, d)
        _grow(windows, routes, x0, size, d)
        _close_under_pairs(windows, routes)
        if len(robots) == 1 or sum(hi - lo + 1 for lo, hi in windows.values()) <= size + SLACK:
            break
        robots = robots[:-1]
    removed: set[int] = set()
    rooms: list[str] = []
    ends: dict[str, str] = {}
    for r, (lo, hi) in windows.items():
        route = routes[r]
        removed.update(idx for idx, _ in route[lo : hi + 1])
        rooms.extend(x for _, x in route[lo : hi + 1])
        if hi + 1 < len(route):
            ends[r] = route[hi][1]
    return Neighbourhood(tuple(robots), frozenset(removed), tuple(dict.fromkeys(rooms)), ends)


def _windows(
    robots: list[str], routes: dict[str, list[tuple[int, str]]], r0: str, k: int, x0: str, d: Closeness
) -> dict[str, list[int]]:
    """Each robot's stretch to start from: the seed move for its robot, the room closest
    to x0 for the others, an empty stretch for an idle robot."""
    windows: dict[str, list[int]] = {}
    for r in robots:
        route = routes[r]
        if not route:
            windows[r] = [0, -1]  # an idle robot: an empty stretch that can take rooms
            continue
        if r == r0:
            anchor = next(p for p, (idx, _) in enumerate(route) if idx == k)
        else:
            anchor = min(range(len(route)), key=lambda p: d(x0, route[p][1]))
        windows[r] = [anchor, anchor]
    return windows


def _grow(
    windows: dict[str, list[int]], routes: dict[str, list[tuple[int, str]]], x0: str, size: int, d: Closeness
) -> None:
    """Widen the stretches, one room at a time, towards the room closest to x0."""
    total = sum(hi - lo + 1 for lo, hi in windows.values())
    while total < size:
        options = []
        for r, (lo, hi) in windows.items():
            route = routes[r]
            if lo > 0:
                options.append((d(x0, route[lo - 1][1]), r, -1))
            if hi + 1 < len(route):
                options.append((d(x0, route[hi + 1][1]), r, +1))
        if not options:
            return
        _, r, side = min(options)
        windows[r][0 if side < 0 else 1] += side
        total += 1


def _close_under_pairs(windows: dict[str, list[int]], routes: dict[str, list[tuple[int, str]]]) -> None:
    """Widen the robots' stretches until every opened paired step is opened for both of its
    robots when both take part (a robot's opened moves must be one stretch of its route)."""
    position = {r: {idx: p for p, (idx, _) in enumerate(route)} for r, route in routes.items()}
    changed = True
    while changed:
        changed = False
        opened = {idx for r, (lo, hi) in windows.items() for idx, _ in routes[r][lo : hi + 1]}
        for r, window in windows.items():
            for idx in opened:
                p = position[r].get(idx)
                if p is not None and not window[0] <= p <= window[1]:
                    window[0], window[1] = min(window[0], p), max(window[1], p)
                    changed = True
