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
    px, py = points[:, 0][:, None], points[:, 1][:, None]
    x0, y0 = polygon[:, 0][None, :], polygon[:, 1][None, :]
    x1, y1 = np.roll(polygon[:, 0], -1)[None, :], np.roll(polygon[:, 1], -1)[None, :]
    straddles = (y0 > py) != (y1 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    crossings = straddles & (px < x_cross)
    return (np.count_nonzero(crossings, axis=1) % 2) == 1


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
