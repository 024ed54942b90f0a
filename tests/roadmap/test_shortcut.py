"""The shortened path (tmpnav/roadmap/shortcut.py) against the greedy pass written plainly: from
each kept point, every later point tried in turn before the first narrow one (below the clearance
asked for, and on the ridge of its passage), the last that keeps its clearance taken."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from tmpnav.roadmap.shortcut import shortcut

RES = 0.05


def least(a: np.ndarray, b: np.ndarray, clear: np.ndarray, origin: tuple[float, float]) -> float:
    """The least clearance of the cells of a -> b, sampled as the module samples them."""
    n = max(2, math.ceil(math.hypot(*(b - a)) / RES) + 1)
    out = math.inf
    for k in range(n):
        s = k / (n - 1)
        i = math.floor((a[1] + s * (b[1] - a[1]) - origin[1]) / RES)
        j = math.floor((a[0] + s * (b[0] - a[0]) - origin[0]) / RES)
        inside = 0 <= i < clear.shape[0] and 0 <= j < clear.shape[1]
        out = min(out, clear[i, j] if inside else -math.inf)
    return out


def narrow(points: np.ndarray, k: int, required: float, clear: np.ndarray, origin: tuple[float, float]) -> bool:
    """Point k is below ``required`` and no side of it, three cells across the path, is clearer
    by more than a cell."""
    here = least(points[k], points[k], clear, origin)
    if here >= required:
        return False
    along = points[min(k + 1, len(points) - 1)] - points[max(k - 1, 0)]
    if not np.any(along):
        return True
    across = np.array([-along[1], along[0]]) / math.hypot(*along)
    sides = (points[k] + side * 3 * RES * across for side in (-1.0, 1.0))
    return all(least(p, p, clear, origin) <= here + RES for p in sides)


def plain(points: np.ndarray, required: float, clear: np.ndarray, origin: tuple[float, float]) -> list[int]:
    if len(points) <= 2:
        return list(range(len(points)))
    keep, i = [0], 0
    while i < len(points) - 1:
        nxt, kept = i + 1, least(points[i], points[i + 1], clear, origin)
        for j in range(i + 2, len(points)):
            if narrow(points, j - 1, required, clear, origin):
                break
            kept = min(kept, least(points[j - 1], points[j], clear, origin))
            if least(points[i], points[j], clear, origin) >= min(kept, required):
                nxt = j
        keep.append(nxt)
        i = nxt
    return keep


def clutter(seed: int) -> np.ndarray:
    """The clearance (m) of a 10 m square of random wall blocks, the outside a wall."""
    rng = np.random.default_rng(seed)
    occupied = np.zeros((200, 200), dtype=bool)
    occupied[[0, -1], :] = occupied[:, [0, -1]] = True
    for _ in range(25):
        i, j = rng.integers(0, 200, 2)
        h, w = rng.integers(2, 30, 2)
        occupied[i : i + h, j : j + w] = True
    return ndimage.distance_transform_edt(~occupied) * RES


@pytest.mark.parametrize("seed", range(6))
def test_the_shortened_path_is_the_plain_greedy_pass(seed: int) -> None:
    clear, origin = clutter(seed), (0.0, 0.0)
    rng = np.random.default_rng(100 + seed)
    for _ in range(40):
        points = np.cumsum(rng.normal(0.0, 0.8, (int(rng.integers(0, 30)), 2)), axis=0) + rng.uniform(2.0, 8.0, 2)
        required = float(rng.uniform(0.1, 0.6))
        assert shortcut(points, required, clear, origin, RES).tolist() == plain(points, required, clear, origin)


def test_a_milestone_beside_a_corridor_wall_is_skipped_a_door_middle_is_not() -> None:
    """A 2.4 m corridor (y 1-3.4) over a room (y below 1) joined by a 1 m door at x 7-8. A roadmap
    path that touches the corridor's north wall on its way to the door is cut straight past that
    point; the door's middle, below the clearance asked for but the clearest point across the door,
    is gone through."""
    occupied = np.zeros((80, 240), dtype=bool)  # 4 m x 12 m at 5 cm
    occupied[:, [0, -1]] = occupied[[0, -1], :] = True
    occupied[68:, :] = True  # the corridor's north wall, from y 3.4 m
    occupied[18:20, :] = True  # the wall between the corridor and the room, y 0.9-1.0 m
    occupied[18:20, 140:160] = False  # its door, x 7-8 m
    clear = ndimage.distance_transform_edt(~occupied) * RES
    points = np.array([[1.0, 2.2], [5.0, 3.1], [7.5, 1.6], [7.5, 0.95], [7.5, 0.4]])
    kept = shortcut(points, 0.8, clear, (0.0, 0.0), RES).tolist()
    assert 1 not in kept  # 5.0, 3.1: 0.3 m from the north wall, the corridor clear to its south
    assert 3 in kept  # the door's middle
    assert kept == plain(points, 0.8, clear, (0.0, 0.0))
