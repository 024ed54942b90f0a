"""A roadmap path shortened within its clearance, and the clearance a path or a rollout keeps.

nav2's global plans are smoothed before a controller drives them; tmpnav's RPP motions
(``models.controller: rpp``, tmpnav.belief.pursuit) drive the roadmap's shortest path with its
zig-zag between milestones cut: :func:`shortcut` skips a path's nodes where the straight line
between two of them keeps the clearance required of it (docs/models.md, "Regulated Pure
Pursuit"). Clearances are read off the map's distance grid (tmpnav.world.grid.clearance: from
each cell's centre to the nearest occupied one), a cell apart.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np


def shortcut(
    points: np.ndarray, required: float, clearance: np.ndarray, origin: tuple[float, float], resolution: float
) -> np.ndarray:
    """The indices of the points of the polyline ``points`` (P, 2) a shortened path keeps, first
    and last included. From each kept point the path goes straight to the farthest later point
    such that the straight line's least clearance (the cells of ``clearance`` along it, sampled a
    cell apart) is at least ``required`` (m), or at least the polyline's own least clearance
    between the two where that is less: a shortcut keeps the clearance ``required``, and where
    the path it replaces came closer to an obstacle, it comes no closer than that path. A point
    whose own clearance is below ``required`` (the middle of a door, or another narrow passage)
    is never skipped: the path goes through the passage where the roadmap does. Greedy (OMPL's
    ``PathSimplifier::shortcutPath`` tries random pairs; the farthest first is deterministic)."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
    if pts.shape[0] <= 2:
        return np.arange(pts.shape[0], dtype=np.int64)
    x0, y0 = origin
    return _shortcut(pts, float(required), clearance, float(x0), float(y0), float(resolution))


def least_clearance(
    points: np.ndarray, clearance: np.ndarray, origin: tuple[float, float], resolution: float, polyline: bool = True
) -> float:
    """The least clearance (m) of the cells of ``points`` (P, 2 or 3): along the polyline through
    them, sampled a cell apart, or, with ``polyline`` False, at the points alone (a rollout's
    poses). Off the grid: -inf."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=float)[:, :2])
    x0, y0 = origin
    return float(_least_along(pts, clearance, float(x0), float(y0), float(resolution), polyline))


@nb.njit(cache=True)
def _least_along(pts, clear, x0, y0, res, polyline):  # pragma: no cover
    """:func:`least_clearance`, compiled."""
    least = np.inf
    if not polyline or pts.shape[0] == 1:
        rows, cols = clear.shape
        for k in range(pts.shape[0]):
            i = math.floor((pts[k, 1] - y0) / res)
            j = math.floor((pts[k, 0] - x0) / res)
            c = clear[i, j] if 0 <= i < rows and 0 <= j < cols else -np.inf
            least = min(least, c)
        return least
    for k in range(pts.shape[0] - 1):
        least = min(least, _least(pts[k, 0], pts[k, 1], pts[k + 1, 0], pts[k + 1, 1], clear, x0, y0, res))
    return least


@nb.njit(cache=True)
def _least(ax, ay, bx, by, clear, x0, y0, res, floor=-np.inf):  # pragma: no cover
    """The least clearance of the cells of the segment a -> b, sampled at most a cell apart; with
    a ``floor``, the first clearance found below it (the walk stops there): whether the segment
    keeps ``floor`` is whether the result is at least it."""
    rows, cols = clear.shape
    n = max(2, math.ceil(math.hypot(bx - ax, by - ay) / res) + 1)
    least = np.inf
    for k in range(n):
        s = k / (n - 1)
        i = math.floor((ay + s * (by - ay) - y0) / res)
        j = math.floor((ax + s * (bx - ax) - x0) / res)
        c = clear[i, j] if 0 <= i < rows and 0 <= j < cols else -np.inf
        if c < least:
            least = c
            if least < floor:
                break
    return least


@nb.njit(cache=True)
def _shortcut(pts, required, clear, x0, y0, res):  # pragma: no cover
    """:func:`shortcut`'s greedy pass: from each kept point i, the farthest j it may go straight
    to, tried from the farthest down (the first that keeps its clearance is the farthest), among
    the points before the first narrow one after i."""
    P = pts.shape[0]
    edge = np.empty(P - 1)
    for k in range(P - 1):
        edge[k] = _least(pts[k, 0], pts[k, 1], pts[k + 1, 0], pts[k + 1, 1], clear, x0, y0, res)
    narrow = np.empty(P, dtype=np.bool_)
    for k in range(P):
        narrow[k] = _least(pts[k, 0], pts[k, 1], pts[k, 0], pts[k, 1], clear, x0, y0, res) < required
    kept = np.empty(P)  # kept[j]: the polyline's least clearance from i to j
    keep = np.empty(P, dtype=np.int64)
    keep[0] = 0
    m, i = 1, 0
    while i < P - 1:
        last = i + 1  # the farthest j: a narrow point is gone through, not skipped
        kept[last] = edge[i]
        while last < P - 1 and not narrow[last]:
            last += 1
            kept[last] = min(kept[last - 1], edge[last - 1])
        nxt = i + 1
        for j in range(last, i + 1, -1):
            floor = min(kept[j], required)
            if _least(pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1], clear, x0, y0, res, floor) >= floor:
                nxt = j
                break
        keep[m] = nxt
        m += 1
        i = nxt
    return keep[:m].copy()
