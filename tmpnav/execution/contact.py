"""What a session counts after each control step, compiled: the true poses that hit a wall and
the robots that touch (:meth:`tmpnav.execution.session.Session._collide`).

A robot hits a wall when its cell's clearance is at most its radius, or it is off the grid
(:func:`tmpnav.belief.risk.hits_wall`, the same cells and comparison); two robots touch when
their true positions are closer than their radii added. One call per step instead of a dozen
small numpy ones (benchmarks/README.md, "simulate").
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from tmpnav.world import World


def walls_and_touches(world: World, truth: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n,) whether each robot's true pose (n, 3) hits a wall, and (n,) whether it touches another."""
    grid = world.grid
    walls, touch = np.empty(truth.shape[0], dtype=np.bool_), np.empty(truth.shape[0], dtype=np.bool_)
    _count(
        np.ascontiguousarray(truth, dtype=float), radii, world.clearance,
        float(grid.origin[0]), float(grid.origin[1]), float(grid.resolution), walls, touch,
    )  # fmt: skip
    return walls, touch


@nb.njit(cache=True)
def _count(truth, radii, clear, x0, y0, res, walls, touch):
    rows, cols = clear.shape
    n = truth.shape[0]
    for a in range(n):
        j = math.floor((truth[a, 0] - x0) / res)
        i = math.floor((truth[a, 1] - y0) / res)
        inside = 0 <= i < rows and 0 <= j < cols
        walls[a] = (not inside) or clear[min(max(i, 0), rows - 1), min(max(j, 0), cols - 1)] <= radii[a]
        touch[a] = False
        for b in range(n):
            if b != a and math.hypot(truth[a, 0] - truth[b, 0], truth[a, 1] - truth[b, 1]) < radii[a] + radii[b]:
                touch[a] = True
