"""Planar geometry on numpy arrays: polygons, segments, distances (metres), angles (radians)."""

from __future__ import annotations

import math

import numba as nb
import numpy as np

PI = math.pi
TWO_PI = 2.0 * math.pi


def polygon_area(polygon: np.ndarray) -> float:
    """Signed area of a polygon (k, 2) by the shoelace formula (> 0 counter-clockwise)."""
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def points_in_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Even-odd rule: which of ``points`` (m, 2) lie inside ``polygon`` (k, 2)? -> (m,) bool."""
    return _even_odd(np.ascontiguousarray(points, dtype=float), np.ascontiguousarray(polygon, dtype=float))


@nb.njit(cache=True)
def _even_odd(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """A ray from each point towards +x crosses the polygon's edges an odd number of times
    inside it. The crossing's x is computed by the same operations, in the same order, as
    numpy's broadcast form of the rule did, so the same points are inside."""
    k = polygon.shape[0]
    inside = np.zeros(points.shape[0], dtype=np.bool_)
    for m in range(points.shape[0]):
        px, py = points[m, 0], points[m, 1]
        odd = False
        for e in range(k):
            x0, y0 = polygon[e, 0], polygon[e, 1]
            x1, y1 = polygon[(e + 1) % k, 0], polygon[(e + 1) % k, 1]
            if (y0 > py) != (y1 > py) and px < x0 + (py - y0) * (x1 - x0) / (y1 - y0):
                odd = not odd
        inside[m] = odd
    return inside


def distance_to_segment(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Euclidean distance from each point (m, 2) to the segment a-b."""
    ab = b - a
    denom = float(np.dot(ab, ab))
    if denom == 0.0:
        return np.linalg.norm(points - a, axis=1)
    t = np.clip((points - a) @ ab / denom, 0.0, 1.0)
    closest = a + t[:, None] * ab
    return np.linalg.norm(points - closest, axis=1)


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Angle(s) ``a`` (rad, any shape) wrapped to [-pi, pi): the one wrapping rule of tmpnav.

    Angles already in range are returned bit-for-bit unchanged, so wrapping is idempotent.
    Others map to (a + pi) mod 2pi - pi, where a result that rounds up to pi becomes -pi.
    Compiled code uses the scalar twin :func:`wrap_angle_scalar`, which follows the same
    rule operation for operation (the tests hold the two to bit equality).
    """
    a = np.asarray(a, dtype=float)
    inside = (a >= -np.pi) & (a < np.pi)
    if inside.all():  # the common case, and the cheap one
        return a.copy()
    wrapped = np.mod(a + np.pi, TWO_PI) - np.pi
    # (a + pi) mod 2pi rounds up to exactly 2pi for a a hair below -pi
    wrapped = np.where(wrapped >= np.pi, -np.pi, wrapped)
    return np.where(inside, a, wrapped)


@nb.njit(cache=True)
def wrap_angle_scalar(a: float) -> float:
    """:func:`wrap_angle` of one angle, for compiled (numba) code."""
    if -PI <= a < PI:
        return a
    w = (a + PI) % TWO_PI - PI
    if w >= PI:
        w = -PI
    return w
