"""The occupancy grid every map becomes, with clearance and line of sight.

Cell (row i, column j) covers x in [x0 + j r, x0 + (j+1) r) and y in [y0 + i r, y0 + (i+1) r):
row 0 is the lowest y (ROS images are flipped on import). Everything outside the grid is
occupied. A disc robot of radius rho centred at p is collision-free when the clearance of
p's cell is at least rho + r (one cell of margin covers the discretisation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from scipy import ndimage

from tmpnav.world.geometry import distance_to_segment, points_in_polygon


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    occupied: np.ndarray  # (rows, cols) bool
    origin: tuple[float, float]  # world (x, y) of the lower-left corner of cell (0, 0)
    resolution: float  # m per cell

    @property
    def shape(self) -> tuple[int, int]:
        return self.occupied.shape

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """xmin, ymin, xmax, ymax of the grid in metres."""
        rows, cols = self.shape
        x0, y0 = self.origin
        return x0, y0, x0 + cols * self.resolution, y0 + rows * self.resolution

    def cell_centers(self) -> tuple[np.ndarray, np.ndarray]:
        rows, cols = self.shape
        xs = self.origin[0] + (np.arange(cols) + 0.5) * self.resolution
        ys = self.origin[1] + (np.arange(rows) + 0.5) * self.resolution
        return xs, ys

    def cells(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Row and column of each point (..., 2), and whether it lies inside the grid."""
        j = np.floor((points[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        i = np.floor((points[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        rows, cols = self.shape
        inside = (i >= 0) & (i < rows) & (j >= 0) & (j < cols)
        return np.clip(i, 0, rows - 1), np.clip(j, 0, cols - 1), inside

    def is_occupied(self, points: np.ndarray) -> np.ndarray:
        i, j, inside = self.cells(points)
        return ~inside | self.occupied[i, j]


def fill_polygon(grid: np.ndarray, xs: np.ndarray, ys: np.ndarray, polygon: np.ndarray, value: bool) -> None:
    """Set the cells whose centres lie inside ``polygon`` to ``value`` (in place)."""
    cols = np.nonzero((xs >= polygon[:, 0].min()) & (xs <= polygon[:, 0].max()))[0]
    rows = np.nonzero((ys >= polygon[:, 1].min()) & (ys <= polygon[:, 1].max()))[0]
    if cols.size == 0 or rows.size == 0:
        return
    gx, gy = np.meshgrid(xs[cols], ys[rows])
    inside = points_in_polygon(np.column_stack([gx.ravel(), gy.ravel()]), polygon)
    block = grid[np.ix_(rows, cols)]
    block[inside.reshape(block.shape)] = value
    grid[np.ix_(rows, cols)] = block


def fill_segment(
    grid: np.ndarray,
    xs: np.ndarray,
    ys: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    thickness: float,
    value: bool,
    flat_caps: bool = False,
) -> None:
    """Set the cells within thickness/2 of the segment a-b to ``value`` (in place).

    Round caps (the default) join wall polylines; ``flat_caps`` stops at the segment's
    ends, so an open door is exactly as wide as it was declared.
    """
    half = thickness / 2.0
    lo, hi = np.minimum(a, b) - half, np.maximum(a, b) + half
    cols = np.nonzero((xs >= lo[0]) & (xs <= hi[0]))[0]
    rows = np.nonzero((ys >= lo[1]) & (ys <= hi[1]))[0]
    if cols.size == 0 or rows.size == 0:
        return
    gx, gy = np.meshgrid(xs[cols], ys[rows])
    pts = np.column_stack([gx.ravel(), gy.ravel()])
    near = distance_to_segment(pts, a, b) <= half
    if flat_caps:
        ab = b - a
        t = (pts - a) @ ab / max(float(ab @ ab), 1e-12)
        near &= (t >= 0.0) & (t <= 1.0)
    block = grid[np.ix_(rows, cols)]
    block[near.reshape(block.shape)] = value
    grid[np.ix_(rows, cols)] = block


def clearance(grid: OccupancyGrid) -> np.ndarray:
    """Distance (m) from each cell centre to the nearest occupied cell centre (0 if occupied).

    The border of the grid counts as occupied, so nothing can leave the map.
    """
    free = np.pad(~grid.occupied, 1, constant_values=False)
    return ndimage.distance_transform_edt(free)[1:-1, 1:-1] * grid.resolution


def footprint_margins(grid: OccupancyGrid, clear: np.ndarray, points: np.ndarray, radius: float) -> np.ndarray:
    """The free distance a disc of ``radius`` centred at each point (..., 2) has around it, at
    least: ``clear[cell] - radius - sqrt(2) resolution`` (m; -inf outside the grid).

    ``clear`` (:func:`clearance`) is the distance from a cell's centre to the nearest
    occupied cell's centre. A point lies within resolution/sqrt(2) of its cell's centre and
    an occupied cell reaches as far from its own, so the distance from the point to the
    occupied region is at least ``clear`` less sqrt(2) resolution: a disc moved by less than
    the margin stays free (docs/models.md, "Collision bound")."""
    i, j, inside = grid.cells(points)
    free = clear[np.where(inside, i, 0), np.where(inside, j, 0)] - radius - np.sqrt(2.0) * grid.resolution
    return np.where(inside, free, -np.inf)


def line_of_sight(grid: OccupancyGrid, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether segments a[k]-b[k] (k, 2) cross no occupied cell -> (k,) bool.

    Samples every half cell; samples within 1.5 cells of either end are ignored so a
    landmark mounted on a wall, or a robot touching one, is still visible.
    """
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    length = np.linalg.norm(b - a, axis=1)
    n = max(2, int(np.ceil(length.max(initial=0.0) / (0.5 * grid.resolution))) + 1)
    t = np.linspace(0.0, 1.0, n)
    pts = a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]
    margin = 1.5 * grid.resolution
    dist_along = t[None, :] * length[:, None]
    interior = (dist_along > margin) & (dist_along < length[:, None] - margin)
    blocked = grid.is_occupied(pts) & interior
    return ~blocked.any(axis=1)


def line_of_sight_traced(grid: OccupancyGrid, clear: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Line of sight by sphere tracing on the clearance map: same answer as
    :func:`line_of_sight` up to the grid, in a dozen steps per segment instead of one per
    half cell. From a point whose cell has clearance c, every point closer than c - 1.5 r lies
    in a free cell, so the walk may jump that far; near walls it falls back to half cells.
    """
    a, b = np.atleast_2d(a).astype(float), np.atleast_2d(b).astype(float)
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    unit = d / np.where(length > 0, length, 1.0)[:, None]
    margin = 1.5 * grid.resolution
    t = np.full(length.shape, margin)
    visible = np.ones(length.shape, dtype=bool)
    active = np.nonzero(t < length - margin)[0]
    while active.size:
        p = a[active] + t[active, None] * unit[active]
        i, j, inside = grid.cells(p)
        hit = ~inside | grid.occupied[i, j]
        visible[active[hit]] = False
        step = np.maximum(clear[i, j] - 1.5 * grid.resolution, 0.5 * grid.resolution)
        t[active] += step
        keep = ~hit & (t[active] < length[active] - margin)
        active = active[keep]
    return visible


@nb.njit(cache=True)
def cell_key(x: float, y: float, x0: float, y0: float, size: float, rows: int, cols: int) -> int:
    """``row * cols + col`` of the cell of side ``size`` holding (x, y) on a grid of ``rows`` x
    ``cols`` cells from (x0, y0), as :meth:`OccupancyGrid.cells` finds it; -1 off the grid. For
    the compiled loops that key a motion's poses (tmpnav.world.lidar, tmpnav.world.reach)."""
    col = np.int64(math.floor((x - x0) / size))
    row = np.int64(math.floor((y - y0) / size))
    return int(row * cols + col) if 0 <= row < rows and 0 <= col < cols else -1


def among(keys: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Whether each of the cell ``keys`` is one of ``known`` (sorted): a binary search of each,
    where ``np.isin`` sorts both every time (the scan and reach tables ask it of every motion's
    cells)."""
    if not known.size:
        return np.zeros(keys.shape, dtype=bool)
    at = np.minimum(np.searchsorted(known, keys), known.size - 1)
    return known[at] == keys


def merged(
    known: np.ndarray, rows: np.ndarray, keys: np.ndarray, new_rows: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The sorted cell keys ``known`` with their table ``rows``, and the new ``keys`` (none of them
    known, sorted or not) with theirs merged in where they belong: sorting them all again at every
    block a worker hands back took a fleet's processes seconds."""
    order = np.argsort(keys, kind="stable")
    at = np.searchsorted(known, keys[order])
    return np.insert(known, at, keys[order]), np.insert(rows, at, new_rows[order])
