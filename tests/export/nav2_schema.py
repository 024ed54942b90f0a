"""What a well-formed NavigateThroughPoses goal of a plan.json move is, checked independently of
the exporter: the message's fields, and the via points' rule.

A turn of a move's path: a place where the path bends away from a straight line by more than
the route tolerance. Counted as the fewest of the path's nodes that, kept as via points, leave
every node of the path within the tolerance of the leg between the kept poses around it. "At
most one via point per turn": a goal has exactly that many via points (:func:`fewest`, computed
here by a recursion of its own), each one needed (without it a node is left outside).
"""

from __future__ import annotations

import itertools
import math
from functools import cache
from typing import Any

import pytest

GOAL_FIELDS = ["poses", "behavior_tree"]


def distance_to_segment(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    ax, ay = a
    bx, by = b
    px, py = p
    dx, dy = bx - ax, by - ay
    if dx == dy == 0.0:
        return math.hypot(px - ax, py - ay)
    t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
    return math.hypot(ax + t * dx - px, ay + t * dy - py)


def covered(points: list[tuple[float, float]], kept: list[int], tolerance: float) -> bool:
    """Every node within ``tolerance`` of the leg between the kept nodes around it."""
    ends = [0, *kept, len(points) - 1]
    return all(
        distance_to_segment(points[k], points[i], points[j]) <= tolerance
        for i, j in itertools.pairwise(ends)
        for k in range(i + 1, j)
    )


def fewest(points: list[tuple[float, float]], tolerance: float) -> int:
    """The number of turns: the fewest via points that cover the path (a recursion from the goal
    backwards, unlike the exporter's breadth-first search from the start)."""
    last = len(points) - 1

    def fits(i: int, j: int) -> bool:
        return all(distance_to_segment(points[k], points[i], points[j]) <= tolerance for k in range(i + 1, j))

    @cache
    def via_from(i: int) -> int:
        if fits(i, last):
            return 0
        return 1 + min(via_from(j) for j in range(i + 1, last) if fits(i, j))

    return via_from(0) if last >= 1 else 0


def yaw_of(q: dict[str, float]) -> float:
    return 2.0 * math.atan2(q["z"], q["w"])


def same_angle(a: float, b: float) -> bool:
    return abs(math.remainder(a - b, 2.0 * math.pi)) < 1e-9


def check_goal(message: Any, move: dict[str, Any], tolerance: float) -> int:
    """Assert that ``message`` is a well-formed NavigateThroughPoses goal of plan.json ``move``;
    returns its number of via points."""
    assert isinstance(message, dict) and list(message) == GOAL_FIELDS
    assert message["behavior_tree"] == ""
    poses = message["poses"]
    assert isinstance(poses, list) and poses
    xy, yaw = [], []
    for pose in poses:
        assert pose["header"] == {"frame_id": "map"}
        assert list(pose["pose"]) == ["position", "orientation"]
        p, q = pose["pose"]["position"], pose["pose"]["orientation"]
        assert list(p) == ["x", "y", "z"] and list(q) == ["x", "y", "z", "w"]
        values = [*p.values(), *q.values()]
        assert all(isinstance(v, float) and math.isfinite(v) for v in values), values
        assert p["z"] == 0.0 and q["x"] == q["y"] == 0.0  # planar: a rotation about +z
        assert math.fsum(v * v for v in q.values()) == pytest.approx(1.0, abs=1e-12)
        xy.append((p["x"], p["y"]))
        yaw.append(yaw_of(q))
    gx, gy, gyaw = move["goal_pose"]
    assert xy[-1] == (gx, gy) and same_angle(yaw[-1], gyaw)  # the goal last, with the planned heading
    points = [tuple(p) for p in move["path_points"]]
    if math.dist(points[-1], (gx, gy)) > 1e-9:
        points.append((gx, gy))
    nodes = [points.index(v) for v in xy[:-1]]  # each via point a node of the path, in the path's order
    assert nodes == sorted(set(nodes)) and all(0 < k < len(points) - 1 for k in nodes)
    for k in range(len(xy) - 1):  # a via point faces the next pose
        (x0, y0), (x1, y1) = xy[k], xy[k + 1]
        assert same_angle(yaw[k], math.atan2(y1 - y0, x1 - x0))
    assert covered(points, nodes, tolerance)
    assert len(nodes) == fewest(points, tolerance)  # at most one via point per turn
    for k in range(len(nodes)):  # and each needed
        assert not covered(points, nodes[:k] + nodes[k + 1 :], tolerance)
    return len(nodes)
