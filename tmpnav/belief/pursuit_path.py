"""The path nav2's Regulated Pure Pursuit drives: a roadmap path densified, its corners rounded.

nav2's global plans come one point per costmap cell, smoothed: :func:`driven_path` gives the
polyline RPP pursues (tmpnav.belief.pursuit's law, the planner's rollout and ``tmpnav
simulate``'s follower alike), resampled every :data:`RESOLUTION` m, with its corners rounded to
arcs (tmpnav.roadmap.shortcut.round_corners) where a :class:`Rounding` is given, and
:func:`length_left` its length from each point to its end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from tmpnav.roadmap.shortcut import round_corners

#: m: the spacing of the densified path (nav2's global plans come one per costmap cell)
RESOLUTION = 0.05


def densify(points: np.ndarray, spacing: float = RESOLUTION) -> tuple[np.ndarray, np.ndarray]:
    """The polyline ``points`` (k, 2) resampled every ``spacing`` m or closer, every vertex kept;
    and the index of each vertex in the result (k,)."""
    points = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
    if points.shape[0] == 0:
        return np.zeros((0, 2)), np.zeros(0, dtype=np.int64)
    return _densify(points, float(spacing))


@nb.njit(cache=True)
def _densify(points, spacing):  # pragma: no cover
    """:func:`densify`, compiled: each segment a -> b cut into n = ceil(|b - a| / spacing) (at
    least 1) equal steps, the points a + (b - a) k / n for k = 1..n."""
    P = points.shape[0]
    at = np.zeros(P, dtype=np.int64)
    counts = np.zeros(P, dtype=np.int64)
    for k in range(1, P):
        d = math.hypot(points[k, 0] - points[k - 1, 0], points[k, 1] - points[k - 1, 1])
        counts[k] = max(1, math.ceil(d / spacing))
        at[k] = at[k - 1] + counts[k]
    out = np.empty((at[P - 1] + 1, 2))
    out[0, 0], out[0, 1] = points[0, 0], points[0, 1]
    for k in range(1, P):
        n = counts[k]
        for i in range(1, n + 1):
            f = i / n
            out[at[k - 1] + i, 0] = points[k - 1, 0] + (points[k, 0] - points[k - 1, 0]) * f
            out[at[k - 1] + i, 1] = points[k - 1, 1] + (points[k, 1] - points[k - 1, 1]) * f
    return out, at


@dataclass(frozen=True, eq=False)
class Rounding:
    """How a path's corners are rounded before RPP drives it (tmpnav.roadmap.shortcut.round_corners):
    the clearance the arcs keep (m) and the map's clearance grid, its origin and resolution."""

    required: float
    clearance: np.ndarray
    origin: tuple[float, float]
    resolution: float


def driven_path(points: np.ndarray, rounding: Rounding | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The densified path RPP drives along the polyline ``points`` (k, 2), and the index of each of
    its points in it (k,): the polyline itself, or with ``rounding`` its corners rounded (a
    rounded corner's index is its arc's middle)."""
    if rounding is None:
        return densify(points)
    rounded, at = rounded_path(points, rounding)
    path, dense_at = densify(rounded)
    return path, dense_at[at]


def rounded_path(points: np.ndarray, rounding: Rounding | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The polyline :func:`driven_path` densifies, (m, 2), and the index of each of ``points`` (k, 2)
    in it (k,): with ``rounding`` their corners rounded, else the points themselves. A few
    points a corner where the densified path has one every :data:`RESOLUTION` m: what a caller
    that drives one path from many headings keeps of it."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
    if rounding is None:
        return pts, np.arange(pts.shape[0], dtype=np.int64)
    r = rounding
    return round_corners(pts, r.required, r.clearance, r.origin, r.resolution)


def length_left(path: np.ndarray) -> np.ndarray:
    """(n,) the length (m) of the polyline ``path`` (n, 2) from each of its points to its end."""
    return _length_left(np.ascontiguousarray(path, dtype=float))


@nb.njit(cache=True)
def _length_left(path):  # pragma: no cover
    """:func:`length_left`, summed from the end as a cumulative sum of the reversed segments is
    (compiled: every rollout takes it of a path densified to a few centimetres)."""
    left = np.zeros(path.shape[0])
    for k in range(path.shape[0] - 2, -1, -1):
        left[k] = left[k + 1] + math.hypot(path[k + 1, 0] - path[k, 0], path[k + 1, 1] - path[k, 1])
    return left


@nb.njit(cache=True)
def densified(rounded, at):  # pragma: no cover
    """Compiled, the densified path along the polyline ``rounded`` (m, 2) (:func:`densify`), the
    index in it of each of its points ``at`` (k,) and its :func:`length_left`: :func:`driven_path`
    and its lengths from :func:`rounded_path`'s polyline, within a compiled caller."""
    path, dense_at = _densify(rounded, RESOLUTION)
    return path, dense_at[at], _length_left(path)
