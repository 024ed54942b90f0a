"""A roadmap path shortened and smoothed within its clearance, and the clearance a path or a
rollout keeps.

nav2's global plans are smoothed before a controller drives them; tmpnav's RPP motions
(``models.controller: rpp``, tmpnav.belief.pursuit) drive the roadmap's shortest path with its
zig-zag between milestones cut: :func:`shortcut` skips a path's nodes where the straight line
between two of them keeps the clearance required of it, and :func:`round_corners` rounds the
corners left to arcs RPP drives without slowing (docs/models.md, "Regulated Pure Pursuit").
Clearances are read off the map's distance grid (tmpnav.world.grid.clearance: from
each cell's centre to the nearest occupied one), a cell apart.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from tmpnav.types import SAFE_MARGIN, RoadmapParams


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


def required_clearance(radius: float, roadmap: RoadmapParams, resolution: float) -> float:
    """The clearance (m, from a robot's centre to the nearest occupied cell's centre) a shortened
    or rounded path keeps: the robot's ``radius``, the roadmap's margin (``roadmap.clearance``, else
    :data:`~tmpnav.types.SAFE_MARGIN`) and a cell's diagonal of the map's ``resolution``."""
    return radius + (roadmap.clearance or SAFE_MARGIN) + math.sqrt(2.0) * resolution


def least_clearance(
    points: np.ndarray, clearance: np.ndarray, origin: tuple[float, float], resolution: float, polyline: bool = True
) -> float:
    """The least clearance (m) of the cells of ``points`` (P, 2 or 3): along the polyline through
    them, sampled a cell apart, or, with ``polyline`` False, at the points alone (a rollout's
    poses). Off the grid: -inf."""
    pts = np.ascontiguousarray(points, dtype=float)  # a rollout's poses as they are: the loop reads x and y
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
        here = _least(pts[k, 0], pts[k, 1], pts[k, 0], pts[k, 1], clear, x0, y0, res)
        narrow[k] = here < required and _on_ridge(pts, k, here, clear, x0, y0, res)
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


#: cells across the path a point's clearance is compared at (:func:`_on_ridge`)
RIDGE_CELLS = 3


@nb.njit(cache=True)
def _on_ridge(pts, k, here, clear, x0, y0, res):  # pragma: no cover
    """Whether point k of the path lies on the ridge of its passage: RIDGE_CELLS cells to either
    side across the path (square to the line from the point before it to the point after it) the
    clearance is no more than a cell above ``here``, its own. The middle of a door is on its ridge;
    a milestone the roadmap put beside a wall of a wide corridor is not (one side is clearer)."""
    P = pts.shape[0]
    a = pts[max(k - 1, 0)]
    b = pts[min(k + 1, P - 1)]
    dx, dy = b[0] - a[0], b[1] - a[1]
    norm = math.hypot(dx, dy)
    if norm == 0.0:
        return True
    nx, ny = -dy / norm, dx / norm
    off = RIDGE_CELLS * res
    for side in (-1.0, 1.0):
        px, py = pts[k, 0] + side * off * nx, pts[k, 1] + side * off * ny
        if _least(px, py, px, py, clear, x0, y0, res) > here + res:
            return False
    return True


#: m: the radius a corner is rounded to at most, nav2 RPP's ``regulated_linear_scaling_min_radius``:
#: on an arc that wide RPP does not slow down for the curvature
CORNER_RADIUS = 0.9
#: m: the spacing of a rounded corner's points (a costmap cell, as the densified path's)
ARC_SPACING = 0.05


def round_corners(
    points: np.ndarray,
    required: float,
    clearance: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    radius: float = CORNER_RADIUS,
) -> tuple[np.ndarray, np.ndarray]:
    """The polyline ``points`` (P, 2) with its corners rounded, as nav2's smoothers round a global
    plan, and the index of each of its points in the result (P,): a rounded corner's point is the
    middle of its arc. Each corner becomes a circular arc tangent to its two segments, of radius
    ``radius`` or less: the arc takes at most half of a segment it shares with another corner (all
    of a first or last one), and keeps the clearance the corner it replaces keeps, or ``required``
    where that is less (the rule of :func:`shortcut`); where the arc does not, half the radius is
    tried, then a quarter, then the corner stays. Through a door or another narrow passage the
    arc comes no nearer to the walls than the corner it replaces. On arcs of ``CORNER_RADIUS``
    RPP drives at full speed where a sharp corner slows it to its least regulated speed."""
    pts = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
    if pts.shape[0] <= 2:
        return pts.copy(), np.arange(pts.shape[0], dtype=np.int64)
    x0, y0 = origin
    return _round_corners(pts, float(required), clearance, float(x0), float(y0), float(resolution), float(radius))


@nb.njit(cache=True)
def _arc(px, py, u1x, u1y, u2x, u2y, radius, half):  # pragma: no cover
    """The points (n, 2) of the arc of ``radius`` that rounds the corner (px, py) between the unit
    directions u1 (in) and u2 (out), whose deflection's half angle is ``half``, from its first
    tangent point to its second."""
    t = radius * math.tan(half)
    ax, ay = px - u1x * t, py - u1y * t
    side = 1.0 if u1x * u2y - u1y * u2x > 0.0 else -1.0  # left turn: the centre on the left
    cx, cy = ax - side * u1y * radius, ay + side * u1x * radius
    a0 = math.atan2(ay - cy, ax - cx)
    sweep = side * 2.0 * half
    n = max(2, math.ceil(radius * abs(sweep) / ARC_SPACING))
    out = np.empty((n + 1, 2))
    for i in range(n + 1):
        a = a0 + sweep * i / n
        out[i, 0], out[i, 1] = cx + radius * math.cos(a), cy + radius * math.sin(a)
    return out


@nb.njit(cache=True)
def _corner(pts, k, seg, required, clear, x0, y0, res, radius):  # pragma: no cover
    """The points that replace the corner k of the polyline ``pts`` (``seg`` its segments'
    lengths): its arc (:func:`round_corners` states the rule), or the corner itself."""
    P = pts.shape[0]
    corner = np.empty((1, 2))
    corner[0, 0], corner[0, 1] = pts[k, 0], pts[k, 1]
    if seg[k - 1] <= 1e-9 or seg[k] <= 1e-9:
        return corner
    u1x, u1y = (pts[k, 0] - pts[k - 1, 0]) / seg[k - 1], (pts[k, 1] - pts[k - 1, 1]) / seg[k - 1]
    u2x, u2y = (pts[k + 1, 0] - pts[k, 0]) / seg[k], (pts[k + 1, 1] - pts[k, 1]) / seg[k]
    half = 0.5 * math.acos(min(1.0, max(-1.0, u1x * u2x + u1y * u2y)))
    if not 1e-3 < half < 0.5 * math.pi - 1e-3:  # straight on, or turning back
        return corner
    room = min(seg[k - 1] * (1.0 if k == 1 else 0.5), seg[k] * (1.0 if k == P - 2 else 0.5))
    r = min(radius, room / math.tan(half))
    for _ in range(3):
        t = r * math.tan(half)
        ax, ay = pts[k, 0] - u1x * t, pts[k, 1] - u1y * t
        bx, by = pts[k, 0] + u2x * t, pts[k, 1] + u2y * t
        kept = min(
            _least(ax, ay, pts[k, 0], pts[k, 1], clear, x0, y0, res),
            _least(pts[k, 0], pts[k, 1], bx, by, clear, x0, y0, res),
        )
        floor = min(kept, required)
        arc = _arc(pts[k, 0], pts[k, 1], u1x, u1y, u2x, u2y, r, half)
        least = np.inf
        for i in range(arc.shape[0] - 1):
            least = min(least, _least(arc[i, 0], arc[i, 1], arc[i + 1, 0], arc[i + 1, 1], clear, x0, y0, res, floor))
            if least < floor:
                break
        if least >= floor:
            return arc
        r *= 0.5
    return corner


@nb.njit(cache=True)
def _round_corners(pts, required, clear, x0, y0, res, radius):  # pragma: no cover
    """:func:`round_corners`, compiled."""
    P = pts.shape[0]
    seg = np.empty(P - 1)
    for k in range(P - 1):
        seg[k] = math.hypot(pts[k + 1, 0] - pts[k, 0], pts[k + 1, 1] - pts[k, 1])
    pieces = [pts[:1].copy()]
    at = np.zeros(P, dtype=np.int64)
    count = 1
    for k in range(1, P - 1):
        piece = _corner(pts, k, seg, required, clear, x0, y0, res, radius)
        pieces.append(piece)
        at[k] = count + piece.shape[0] // 2  # a corner's own point, or its arc's middle
        count += piece.shape[0]
    pieces.append(pts[P - 1 :].copy())
    at[P - 1] = count
    out = np.empty((count + 1, 2))
    i = 0
    for piece in pieces:
        for j in range(piece.shape[0]):
            out[i, 0], out[i, 1] = piece[j, 0], piece[j, 1]
            i += 1
    return out, at
