"""A room's cells -> a simple polygon in metres, with few vertices."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from tmpnav.world.geometry import distance_to_segment, polygon_area
from tmpnav.world.grid import OccupancyGrid

TOLERANCE = 0.1  # m: largest distance of the simplified outline from the cells' outline


def outline(mask: np.ndarray, grid: OccupancyGrid, tolerance: float = TOLERANCE) -> np.ndarray:
    """The outer boundary of the cells in ``mask`` (holes ignored) as a counter-clockwise simple
    polygon (k, 2) in metres, simplified by Douglas-Peucker within ``tolerance``.

    The boundary runs along the cells' edges (its vertices are snapped to cell corners), so the
    polygon covers the room's free cells and its share of each doorway. When simplifying would
    make the polygon cross itself (a thin part of a room), the tolerance is halved until it
    does not.
    """
    from skimage.measure._find_contours import find_contours  # skimage.measure would import scipy.signal

    box = ndimage.find_objects(mask.astype(np.int8))
    if not box or box[0] is None:
        raise ValueError("empty mask")
    rows, cols = box[0]
    # twice as fine: the contour of a cell's corner is cut a quarter cell from the corner (not a
    # half), so that snapping the vertices to cell corners is never ambiguous
    fine = np.kron(ndimage.binary_fill_holes(mask[rows, cols]), np.ones((2, 2), dtype=bool))
    ring = max(find_contours(np.pad(fine, 1).astype(float), 0.5), key=lambda c: abs(polygon_area(c)))
    corners = np.rint((ring - 0.5) / 2.0)  # cells from the box's lower-left corner
    tol = tolerance / grid.resolution
    while True:
        simple = _dedup(simplify(corners, tol)[:-1])  # closed: the last point repeats the first
        if (simple.shape[0] >= 3 and is_simple(simple)) or tol < 0.25:
            break
        tol /= 2
    if simple.shape[0] < 3 or not is_simple(simple):
        simple = _dedup(corners[:-1])
    x0, y0 = grid.origin
    r = grid.resolution
    xy = np.column_stack([x0 + (cols.start + simple[:, 1]) * r, y0 + (rows.start + simple[:, 0]) * r])
    return xy if polygon_area(xy) > 0 else xy[::-1]


def simplify(chain: np.ndarray, tolerance: float) -> np.ndarray:
    """The points of ``chain`` (k, 2) that Douglas-Peucker keeps: both ends and, between two kept
    points, the one farthest from the segment joining them while it lies farther than
    ``tolerance`` (its distance to the segment, so a point beyond an end counts from that end)."""
    keep = np.zeros(len(chain), dtype=bool)
    keep[[0, -1]] = True
    stack = [(0, len(chain) - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        gap = distance_to_segment(chain[a + 1 : b], chain[a], chain[b])
        k = int(np.argmax(gap))
        if gap[k] > tolerance:
            stack += [(a + 1 + k, b), (a, a + 1 + k)]
            keep[a + 1 + k] = True
    return chain[keep]


def _dedup(points: np.ndarray) -> np.ndarray:
    """Points (k, 2) of a closed ring without consecutive repeats and without collinear middles."""
    keep = np.any(points != np.roll(points, 1, axis=0), axis=1)
    points = points[keep] if keep.any() else points[:1]
    if points.shape[0] < 3:
        return points
    before, after = np.roll(points, 1, axis=0) - points, np.roll(points, -1, axis=0) - points
    turn = before[:, 0] * after[:, 1] - before[:, 1] * after[:, 0]
    return points[turn != 0]


def is_simple(polygon: np.ndarray) -> bool:
    """Whether no two non-adjacent edges of the closed polygon (k, 2) touch or cross."""
    k = polygon.shape[0]
    a, b = polygon, np.roll(polygon, -1, axis=0)
    for i in range(k):
        js = np.arange(i + 2, k if i > 0 else k - 1)  # edges sharing a vertex with edge i are skipped
        if js.size and np.any(_segments_touch(a[i], b[i], a[js], b[js])):
            return False
    return True


def _segments_touch(p: np.ndarray, q: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Whether segment p-q touches or crosses each segment r[j]-s[j]."""

    def orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        cross = (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
        return np.sign(cross)

    def on(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        return np.all((c >= lo - 1e-12) & (c <= hi + 1e-12), axis=-1)

    o1, o2 = orient(p, q, r), orient(p, q, s)
    o3, o4 = orient(r, s, p), orient(r, s, q)
    crossing = (o1 * o2 < 0) & (o3 * o4 < 0)
    touching = (
        ((o1 == 0) & on(p, q, r))
        | ((o2 == 0) & on(p, q, s))
        | ((o3 == 0) & on(r, s, p[None]))
        | ((o4 == 0) & on(r, s, q[None]))
    )
    return crossing | touching
