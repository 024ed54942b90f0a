"""The draws that make a :class:`tmpnav.execution.site.Site` of the map: its walls moved, its
clutter placed and its people's walks, each a signed distance field or plain arrays on the map's grid."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numba as nb
import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from tmpnav.world.lidar import cast

#: m: walls within about this distance of each other move together (a lattice of independent offsets)
WALL_STRETCH = 3.0
#: m: no clutter box comes this close to a point the robots must pass (``keep_clear``)
KEEP_CLEAR = 0.6
#: m: a polyline of ``keep_clear`` is kept clear at points this far apart along it
KEEP_SPACING = 0.1
#: m: around each box its exact distance is kept in the field out to this far beyond its corners
BOX_WINDOW = 0.3
#: the lower bound of the distance to the clutter is found on cells this many times larger
COARSE = 8
#: directions tried for each person's walk: the longest straight line through its start is kept
WALK_DIRECTIONS = 8
#: rounds of candidate boxes drawn before the clutter that fits is taken as it is
PLACEMENT_ROUNDS = 8


def offset_lattice(shape: tuple[int, int], res: float, std: float, rng: np.random.Generator) -> np.ndarray | None:
    """The walls' offsets: independent draws N(0, std²) (2, nodes, nodes) m of the displacement's
    x and y on a lattice of :data:`WALL_STRETCH` over a grid of ``shape``; None for walls where
    the map has them."""
    if std <= 0:
        return None
    nodes = [int((n * res) // WALL_STRETCH) + 2 for n in shape]
    return rng.standard_normal((2, *nodes)) * std


def shifted_walls(sdf: np.ndarray, res: float, offsets: np.ndarray) -> np.ndarray:
    """The map's field ``sdf`` with its walls moved by the lattice's ``offsets``
    (:func:`offset_lattice`): phi(p - a(p)), with a(p) the displacement interpolated bilinearly
    between the lattice's draws and divided by the root of the weights' sum of squares, which
    keeps its std the same between lattice points. A wall moves along its normal n by
    a.n ~ N(0, std²): stretches of a few metres together, continuously, by any fraction of a cell."""
    out = np.empty_like(sdf)
    _warp(sdf, res, WALL_STRETCH, offsets, out)
    return out


@nb.njit(cache=True)
def _weights(n, res, stretch):
    """For n cell centres along an axis: the lattice node below each, the fraction towards the next
    and the root of the sum of the two weights' squares."""
    lo, frac, norm = np.empty(n, np.int64), np.empty(n), np.empty(n)
    for k in range(n):
        u = (k + 0.5) * res / stretch
        lo[k] = math.floor(u)
        frac[k] = u - lo[k]
        norm[k] = math.sqrt((1.0 - frac[k]) ** 2 + frac[k] ** 2)
    return lo, frac, norm


@nb.njit(cache=True)
def _warp(sdf, res, stretch, z, out):
    """out[i, j] = sdf at cell (i, j)'s centre less the displacement a there (:func:`shifted_walls`),
    bilinear between the centres and held at the grid's edge."""
    R, C = sdf.shape
    i0, fy, ny = _weights(R, res, stretch)
    j0, fx, nx = _weights(C, res, stretch)
    for i in range(R):
        for j in range(C):
            a, b = i0[i], j0[j]
            w00, w01 = (1.0 - fy[i]) * (1.0 - fx[j]), (1.0 - fy[i]) * fx[j]
            w10, w11 = fy[i] * (1.0 - fx[j]), fy[i] * fx[j]
            scale = 1.0 / (ny[i] * nx[j] * res)
            dx = (w00 * z[0, a, b] + w01 * z[0, a, b + 1] + w10 * z[0, a + 1, b] + w11 * z[0, a + 1, b + 1]) * scale
            dy = (w00 * z[1, a, b] + w01 * z[1, a, b + 1] + w10 * z[1, a + 1, b] + w11 * z[1, a + 1, b + 1]) * scale
            y = min(max(i - dy, 0.0), R - 1.0)
            x = min(max(j - dx, 0.0), C - 1.0)
            r, c = min(int(y), R - 2), min(int(x), C - 2)
            ty, tx = y - r, x - c
            top = sdf[r, c] + (sdf[r, c + 1] - sdf[r, c]) * tx
            bottom = sdf[r + 1, c] + (sdf[r + 1, c + 1] - sdf[r + 1, c]) * tx
            out[i, j] = top + (bottom - top) * ty


def keep_points(keep_clear: np.ndarray | Sequence[np.ndarray] | None) -> np.ndarray | None:
    """``keep_clear`` as points (K, 2): an array's rows as they are, a sequence's polylines
    sampled every :data:`KEEP_SPACING` along their segments."""
    if keep_clear is None:
        return None
    if isinstance(keep_clear, np.ndarray):
        return np.atleast_2d(keep_clear.astype(float))[:, :2]
    points = []
    for line in keep_clear:
        xy = np.atleast_2d(np.asarray(line, dtype=float))[:, :2]
        for a, b in itertools.pairwise(xy):
            n = max(1, math.ceil(float(np.hypot(*(b - a))) / KEEP_SPACING))
            points.append(a + np.linspace(0.0, 1.0, n, endpoint=False)[:, None] * (b - a))
        points.append(xy[-1:])
    return np.concatenate(points) if points else None


def place_clutter(
    sdf: np.ndarray,
    origin: tuple[float, float],
    res: float,
    count: int,
    size: float,
    keep: np.ndarray | None,
    rng: np.random.Generator,
) -> np.ndarray:
    """``count`` boxes (N, 3: x, y m, theta rad) of side ``size``, uniform over the map's free
    floor and turned at random, each wholly in free space and its centre at least
    :data:`KEEP_CLEAR` plus its half-diagonal from every ``keep`` point, so that no point of it
    comes within :data:`KEEP_CLEAR` of one. Fewer where not that many fit."""
    half_diag = size / math.sqrt(2.0)
    cells = np.flatnonzero(sdf.ravel() >= half_diag + res)  # the jitter below stays within the cell
    if count <= 0 or cells.size == 0:
        return np.zeros((0, 3))
    tree = cKDTree(keep[:, :2]) if keep is not None and len(keep) else None
    cols = sdf.shape[1]
    found: list[np.ndarray] = []
    for _ in range(PLACEMENT_ROUNDS):
        pick = rng.choice(cells, size=2 * count)
        xy = np.column_stack([origin[0] + (pick % cols + 0.5) * res, origin[1] + (pick // cols + 0.5) * res])
        xy += rng.uniform(-0.5 * res, 0.5 * res, xy.shape)
        boxes = np.column_stack([xy, rng.uniform(0.0, 0.5 * math.pi, len(xy))])
        if tree is not None:
            # a point of a polyline's segment lies within KEEP_SPACING / 2 of one of its samples
            boxes = boxes[tree.query(xy)[0] >= KEEP_CLEAR + half_diag + 0.5 * KEEP_SPACING]
        found.append(boxes)
        if sum(map(len, found)) >= count:
            break
    return np.concatenate(found)[:count]


def box_field(
    shape: tuple[int, int], origin: tuple[float, float], res: float, boxes: np.ndarray, size: float
) -> np.ndarray:
    """The signed distance to the boxes (rows, cols) m, exact at the cell centres within
    :data:`BOX_WINDOW` beyond a box's corners and a lower bound elsewhere, as sphere tracing
    needs: there, the distance to the nearest box centre less its half-diagonal, from a distance
    transform on cells :data:`COARSE` times larger (less their diagonal, for where in their coarse
    cells the point and the centre lie), and never less than the window, which a cell outside
    every window is beyond."""
    half, half_diag = 0.5 * size, size / math.sqrt(2.0)
    reach = half_diag + BOX_WINDOW
    i = np.floor((boxes[:, 1] - origin[1]) / res).astype(np.int64)
    j = np.floor((boxes[:, 0] - origin[0]) / res).astype(np.int64)
    seeds = np.ones((-(-shape[0] // COARSE), -(-shape[1] // COARSE)), dtype=bool)
    seeds[i // COARSE, j // COARSE] = False
    coarse = COARSE * res
    far = ndimage.distance_transform_edt(seeds) * coarse - math.sqrt(2.0) * coarse - half_diag
    far = far[np.arange(shape[0]) // COARSE][:, np.arange(shape[1]) // COARSE]
    near = np.full(shape, np.inf)
    span = math.ceil(reach / res) + 1
    for (x, y, theta), bi, bj in zip(boxes, i, j, strict=True):
        r0, r1, c0, c1 = (
            max(bi - span, 0),
            min(bi + span + 1, shape[0]),
            max(bj - span, 0),
            min(bj + span + 1, shape[1]),
        )
        gx = origin[0] + (np.arange(c0, c1) + 0.5) * res - x
        gy = (origin[1] + (np.arange(r0, r1) + 0.5) * res - y)[:, None]
        lx = np.abs(math.cos(theta) * gx + math.sin(theta) * gy) - half
        ly = np.abs(-math.sin(theta) * gx + math.cos(theta) * gy) - half
        d = np.hypot(np.maximum(lx, 0.0), np.maximum(ly, 0.0)) + np.minimum(np.maximum(lx, ly), 0.0)
        block = near[r0:r1, c0:c1]
        np.minimum(block, np.where(np.hypot(gx, gy) <= reach, d, np.inf), out=block)
    cap = reach - half_diag  # a box whose window does not hold a cell is at least this far from it
    return np.where(np.isfinite(near), np.minimum(near, cap), np.maximum(far, cap))


def walks(
    field: np.ndarray,
    origin: tuple[float, float],
    res: float,
    radius: float,
    count: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each person's walk: the start (P, 2) m and unit direction (P, 2) of its straight line,
    the line's length (P,) m and where along it the person is at t = 0 (P,) m. A person starts
    at a uniform free point of the site and walks the longest line through it of
    :data:`WALK_DIRECTIONS` random ones, out to a radius short of the walls or clutter it meets."""
    cells = np.flatnonzero(field.ravel() >= radius + res)
    if count == 0 or cells.size == 0:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), np.zeros(0)
    far = math.hypot(*field.shape) * res
    pick = rng.choice(cells, size=count)
    cols = field.shape[1]
    centres = np.column_stack([origin[0] + (pick % cols + 0.5) * res, origin[1] + (pick // cols + 0.5) * res])
    start, direction, length, phase = np.empty((count, 2)), np.empty((count, 2)), np.empty(count), np.empty(count)
    for p, (x, y) in enumerate(centres):
        best = (-1.0, 0.0, 0.0)
        for psi in rng.uniform(0.0, 2.0 * math.pi, WALK_DIRECTIONS):
            ahead = min(cast(field, *origin, res, x, y, psi, far)[0], far) - radius
            behind = min(cast(field, *origin, res, x, y, psi + math.pi, far)[0], far) - radius
            if ahead + behind > best[0]:
                best = (ahead + behind, psi, max(behind, 0.0))
        u = np.array([math.cos(best[1]), math.sin(best[1])])
        start[p], direction[p] = (x, y) - best[2] * u, u
        length[p], phase[p] = max(best[0], 0.0), best[2]
    return start, direction, length, phase
