"""The shortened path (tmpnav/roadmap/shortcut.py) against the greedy pass written plainly: from
each kept point, every later point tried in turn before the first narrow one, the last that keeps
its clearance taken."""

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


def plain(points: np.ndarray, required: float, clear: np.ndarray, origin: tuple[float, float]) -> list[int]:
    if len(points) <= 2:
        return list(range(len(points)))
    keep, i = [0], 0
    while i < len(points) - 1:
        nxt, kept = i + 1, least(points[i], points[i + 1], clear, origin)
        for j in range(i + 2, len(points)):
            if least(points[j - 1], points[j - 1], clear, origin) < required:
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
