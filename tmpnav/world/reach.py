"""How far a disc robot can be moved in each direction before it hits a wall: sector reach.

The directional part of the collision bound (docs/models.md, "Collision bound"). Around a
nominal position mu the plane is cut into K sectors of angle w = 2 pi / K, sector k holding
the directions theta in [k w, (k+1) w). The **reach** R_k(mu) is a lower bound on the distance
from mu to the hit set H (the cells where the footprint hits a wall: clearance <= radius, and
everything off the grid) within sector k, capped at :data:`REACH`:

    R_k(mu) <= min { ||x - mu|| : x in H, x - mu in sector k },   R_k(mu) <= REACH.

A true position x that hits a wall therefore lies in some sector k at least R_k from mu,
which is what the bound integrates (:mod:`tmpnav.belief.risk`).

Computed per sub-cell (a grid cell cut into :data:`SUBDIVISIONS` x :data:`SUBDIVISIONS`
squares of side res / s), so that it holds for every mu there: for a hit cell h and the
sub-cell c of mu, the vectors x - mu with mu in c and x in h are exactly the square of side
res (1 + 1/s) centred on h's centre less c's, so their lengths are at least that square's
distance from the origin and their directions lie between its corners' bearings. Only hit
cells with a free 8-neighbour are scanned: the nearest point of H in a sector (a convex cone)
lies on H's boundary. A sub-cell of a hit cell, or off the grid, has reach 0 in every sector.

Sub-cells are computed when first asked for and remembered (:class:`SectorReach`): a plan of
a building asks for some thousands among millions of poses, a fleet's for millions.

A reach is 0, :data:`REACH` or the distance of one of the offsets' squares, so the table keeps
each sector as a code, the index of its value among those few thousand distances (``values``):
2 bytes where a float takes 8, and every value read back is the float computed, bit for bit.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from scipy import ndimage

from tmpnav.world.grid import OccupancyGrid, among, cell_key, merged

#: sectors of the directional bound (5.625 degrees each)
SECTORS = 64
#: how far the reach looks (m): hit cells farther than this count as this far
REACH = 2.5
#: sub-cells per cell and axis: a pose's reach is measured from its sub-cell, losing at most
#: res / s per axis to where in it the pose lies (res with whole cells)
SUBDIVISIONS = 2
#: the key of a pose off the grid (reach 0: the bound is 1)
OFF_GRID = -1


class SectorReach:
    """The reach of every sub-cell of ``grid`` for a disc of ``radius`` (m), computed on demand.

    ``clear`` is the grid's clearance (:func:`tmpnav.world.grid.clearance`); ``subdivisions``
    per cell and axis (1: whole cells). Places are named by the flat index of their sub-cell,
    ``row * (cols * s) + col`` (:meth:`cells`), :data:`OFF_GRID` for a point off the grid.
    """

    def __init__(self, grid: OccupancyGrid, clear: np.ndarray, radius: float, subdivisions: int = SUBDIVISIONS):
        self.grid = grid
        self.subdivisions = subdivisions
        hit = np.ones((grid.shape[0] + 2, grid.shape[1] + 2), dtype=bool)  # one ring off the grid
        hit[1:-1, 1:-1] = clear <= radius
        self.hit = hit
        self.boundary = hit & ndimage.binary_dilation(~hit, structure=np.ones((3, 3), dtype=bool))
        self.keys = np.zeros(0, dtype=np.int64)  # the sub-cells computed, sorted
        self.key_rows = np.zeros(0, dtype=np.int64)  # and their rows of the table
        self._offsets = _offsets(grid.resolution, subdivisions, REACH, SECTORS)
        #: every reach there can be (V,) m, sorted: 0, the offsets' distances below REACH, REACH
        self.values, self._offset_codes = _codebook(self._offsets)
        #: (R, K) each sub-cell's reach as codes, indices into :attr:`values` (uint16 while V fits);
        #: row 0 is off the grid, reach 0
        self.codes: np.ndarray = np.zeros((1, SECTORS), dtype=code_type(self.values.size))
        self.rows = 1
        self._lookup: tuple[np.ndarray, ...] | None = None  # _offset_index() and _boundary_rows(), when first needed
        self._new: list[np.ndarray] | None = None  # keys computed since :meth:`take_new`, once called

    def cells(self, points: np.ndarray) -> np.ndarray:
        """The key of each point's sub-cell (..., 2) -> (...,) int64, OFF_GRID off the grid.
        (Compiled: every nominal motion asks for the sub-cells of its poses.)"""
        p = np.asarray(points, dtype=float)[..., :2]
        flat = np.ascontiguousarray(p.reshape(-1, 2))
        size = self.grid.resolution / self.subdivisions
        rows, cols = self.grid.shape[0] * self.subdivisions, self.grid.shape[1] * self.subdivisions
        x0, y0 = float(self.grid.origin[0]), float(self.grid.origin[1])
        return _sub_cells(flat, x0, y0, size, rows, cols).reshape(p.shape[:-1])

    def of_cells(self, cells: np.ndarray) -> np.ndarray:
        """R (..., K) m for sub-cell keys (...,) (:meth:`cells`)."""
        cells = np.asarray(cells, dtype=np.int64)
        rows = self.rows_of(cells.ravel())  # before the table is read: it may grow
        return self.values[self.codes[rows]].reshape(*cells.shape, SECTORS)

    def rows_of(self, cells: np.ndarray) -> np.ndarray:
        """The row of :attr:`codes` holding the reach of each sub-cell key (N,) (:meth:`cells`),
        computing those not known yet; row 0 (reach 0) off the grid. Rows stay where they are
        as the table grows."""
        flat = np.asarray(cells, dtype=np.int64)
        on = flat >= 0
        wanted = flat[on]
        # looked up first: most sub-cells a motion asks for are known, and the unique of every
        # key asked took a fleet's oracle seconds
        at = np.searchsorted(self.keys, wanted)
        missing = (
            self.keys[np.minimum(at, self.keys.size - 1)] != wanted if self.keys.size else np.ones(wanted.size, bool)
        )
        if missing.any():
            self._compute(np.unique(wanted[missing]))
            at = np.searchsorted(self.keys, wanted)
        rows = np.zeros(flat.size, dtype=np.int64)
        rows[on] = self.key_rows[at]
        return rows

    def at(self, points: np.ndarray) -> np.ndarray:
        """R (..., K) m at positions (..., 2)."""
        return self.of_cells(self.cells(points))

    def take_new(self) -> tuple[np.ndarray, np.ndarray]:
        """The sub-cells computed here since the last call, and their reach's codes (N, K): what
        a worker's copy of the table hands back to its parent's (:meth:`learn`; every copy has
        the same :attr:`values`). The first call starts the record and returns none: only a
        worker's copy keeps one."""
        keys = np.concatenate(self._new) if self._new else np.zeros(0, dtype=np.int64)
        self._new = []
        return keys, self.codes[self.rows_of(keys)]

    def learn(self, keys: np.ndarray, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Take the reach's codes (N, K) of sub-cells ``keys`` (N,) another copy of this table
        computed (:meth:`take_new`), for those not known yet, and return those sub-cells and codes."""
        keys, codes = np.asarray(keys, dtype=np.int64), np.asarray(codes)
        fresh = ~among(keys, self.keys)
        keys, codes = keys[fresh], codes[fresh]
        if keys.size:
            self._store(keys, codes)
        return keys, codes

    def _compute(self, keys: np.ndarray) -> None:
        if self._new is not None:
            self._new.append(keys)
        s, cols = self.subdivisions, self.grid.shape[1] * self.subdivisions
        out = np.empty((keys.size, SECTORS), dtype=self.codes.dtype)
        if self._lookup is None:
            self._lookup = (_offset_index(self._offsets), *_boundary_rows(self.boundary))
        index, starts, columns = self._lookup
        far = self.values.size - 1  # REACH's code: the largest value
        si, sj = keys // cols, keys % cols
        _sector_reach(self.hit, starts, columns, s, si, sj, REACH, far, self._offsets, self._offset_codes, index, out)
        self._store(keys, out)

    def _store(self, keys: np.ndarray, codes: np.ndarray) -> None:
        """Rows for sub-cells ``keys`` (none known yet, sorted or not) holding their reach's ``codes``."""
        need = self.rows + keys.size
        if need > self.codes.shape[0]:
            grown = np.zeros((max(need, 2 * self.codes.shape[0]), SECTORS), dtype=self.codes.dtype)
            grown[: self.rows] = self.codes[: self.rows]
            self.codes = grown
        self.codes[self.rows : need] = codes
        self.keys, self.key_rows = merged(self.keys, self.key_rows, keys, np.arange(self.rows, need))
        self.rows = need


@nb.njit(cache=True)
def _offsets(res, sub, reach, K):
    """The cells around a sub-cell that can bound its reach, for each of the ``sub`` x ``sub``
    places of a sub-cell in its cell (index a * sub + b for row a, column b): the cell's offset
    (di, dj) from the sub-cell's cell, its distance d (the module docstring's construction) and
    the sectors k0..k1 it covers (taken modulo K; k0 = -1 for a neighbour d <= 0, which zeroes
    every sector). Only the offsets, not the map, enter: computed once per table."""
    w = 2.0 * math.pi / K
    n = math.ceil(reach / res) + 2
    half = 0.5 * res * (1.0 + 1.0 / sub)  # half the side of the squares x - mu lies in
    side = 2 * n + 1
    di = np.empty((sub * sub, side * side), dtype=np.int64)
    dj = np.empty_like(di)
    dist = np.empty((sub * sub, side * side))
    k0s = np.empty_like(di)
    k1s = np.empty_like(di)
    count = np.zeros(sub * sub, dtype=np.int64)
    for a in range(sub):
        oy = (a + 0.5) * res / sub - 0.5 * res  # the sub-cell's centre from its cell's
        for b in range(sub):
            ox = (b + 0.5) * res / sub - 0.5 * res
            q = a * sub + b
            for i in range(-n, n + 1):
                dy = i * res - oy
                for j in range(-n, n + 1):
                    dx = j * res - ox
                    ex = max(abs(dx) - half, 0.0)
                    ey = max(abs(dy) - half, 0.0)
                    d = math.sqrt(ex * ex + ey * ey)
                    if d >= reach:
                        continue
                    c = count[q]
                    di[q, c], dj[q, c], dist[q, c] = i, j, d
                    count[q] = c + 1
                    if d <= 0.0:  # a neighbour of c: mu may touch it however little it moves
                        k0s[q, c], k1s[q, c] = -1, -1
                        continue
                    phi = math.atan2(dy, dx)
                    lo, hi = 0.0, 0.0
                    for sx in (-half, half):
                        for sy in (-half, half):
                            t = math.atan2(dy + sy, dx + sx) - phi
                            if t > math.pi:
                                t -= 2.0 * math.pi
                            elif t < -math.pi:
                                t += 2.0 * math.pi
                            lo = min(lo, t)
                            hi = max(hi, t)
                    k0s[q, c] = math.floor((phi + lo) / w) % K
                    k1s[q, c] = k0s[q, c] + (math.floor((phi + hi) / w) - math.floor((phi + lo) / w))
    return di, dj, dist, k0s, k1s, count


@nb.njit(cache=True)
def _offset_index(offsets):
    """index[q, di + n, dj + n]: which of the ``offsets`` (:func:`_offsets`) around place q is the
    cell (di, dj) away, -1 for a cell beyond the reach; n the offsets' largest |di|, |dj|."""
    di, dj, _, _, _, count = offsets
    n = 0
    for q in range(count.shape[0]):
        for c in range(count[q]):
            n = max(n, abs(di[q, c]), abs(dj[q, c]))
    index = np.full((count.shape[0], 2 * n + 1, 2 * n + 1), -1, dtype=np.int64)
    for q in range(count.shape[0]):
        for c in range(count[q]):
            index[q, di[q, c] + n, dj[q, c] + n] = c
    return index


def _boundary_rows(boundary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The boundary cells row by row: ``columns[starts[i]:starts[i + 1]]`` (sorted) are row i's."""
    rows, columns = np.nonzero(boundary)
    starts = np.searchsorted(rows, np.arange(boundary.shape[0] + 1))
    return starts.astype(np.int64), columns.astype(np.int64)


def code_type(values: int) -> type:
    """The unsigned integer type of codes into ``values`` distinct reaches."""
    return np.uint16 if values <= np.iinfo(np.uint16).max + 1 else np.uint32


def encoded(reach: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reaches (R, K) m as a table's codes (R, K) and the values they index (V,): any array of
    reaches in the form the kernels read (:class:`tmpnav.belief.sequences.MotionArrays`)."""
    values, inverse = np.unique(np.asarray(reach, dtype=float), return_inverse=True)
    return inverse.reshape(reach.shape).astype(code_type(values.size)), values


def _codebook(offsets: tuple[np.ndarray, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The distinct reaches a table can hold (V,), sorted (0 first, :data:`REACH` last), and the
    code of each offset's distance (sub * sub, C) (:func:`_offsets`; 0 where d <= 0)."""
    _, _, dist, _, _, count = offsets
    used = np.arange(dist.shape[1])[None, :] < count[:, None]
    values = np.unique(np.concatenate([[0.0, REACH], dist[used & (dist > 0.0)]]))
    codes = np.where(used & (dist > 0.0), np.searchsorted(values, np.where(used, dist, 0.0)), 0)
    return values, codes.astype(np.int64)


@nb.njit(cache=True)
def _sector_reach(hit, starts, columns, sub, si, sj, reach, far, offsets, codes, index, out):
    """Fill out (N, K) with the codes of the reach of sub-cells (si, sj) (the module docstring's
    construction; ``sub`` sub-cells per cell and axis): the least distance, per sector, of the
    boundary cells among ``offsets`` (:func:`_offsets`, found by ``index``, :func:`_offset_index`)
    around each, as its code (``codes`` of each offset, :func:`_codebook`; 0 for reach 0 and
    ``far`` for ``reach``, the cap).
    ``hit`` and the boundary cells (``starts``, ``columns``: :func:`_boundary_rows`) carry one
    ring of cells around the grid (grid cell (i, j) is their (i + 1, j + 1)). The boundary is
    read row by row from its list: a sub-cell meets the few hundred boundary cells within reach
    rather than testing the thousands of offsets, in the offsets' order."""
    _, _, dist, k0s, k1s, _ = offsets
    K = out.shape[1]
    n = (index.shape[1] - 1) // 2
    best = np.empty(K)
    for p in range(si.shape[0]):
        i0, j0 = si[p] // sub + 1, sj[p] // sub + 1
        q = (si[p] % sub) * sub + (sj[p] % sub)
        for k in range(K):
            best[k] = reach
            out[p, k] = far
        if hit[i0, j0]:
            for k in range(K):
                out[p, k] = 0
            continue
        for i in range(max(i0 - n, 0), min(i0 + n + 1, hit.shape[0])):
            e = _first_at_least(columns, starts[i], starts[i + 1], j0 - n)
            while e < starts[i + 1] and columns[e] <= j0 + n:
                c = index[q, i - i0 + n, columns[e] - j0 + n]
                e += 1
                if c < 0:
                    continue
                d = dist[q, c]
                if k0s[q, c] < 0:
                    for k in range(K):
                        best[k] = 0.0
                        out[p, k] = 0
                    continue
                for k in range(k0s[q, c], k1s[q, c] + 1):
                    kk = k % K
                    if d < best[kk]:
                        best[kk] = d
                        out[p, kk] = codes[q, c]


@nb.njit(cache=True, inline="always")
def _first_at_least(values, lo, hi, v):
    """The first index in [lo, hi) of the sorted ``values`` holding at least v (hi if none)."""
    while lo < hi:
        mid = (lo + hi) // 2
        if values[mid] < v:
            lo = mid + 1
        else:
            hi = mid
    return lo


@nb.njit(cache=True)
def _sub_cells(points: np.ndarray, x0: float, y0: float, size: float, rows: int, cols: int) -> np.ndarray:
    """:meth:`SectorReach.cells` of points (P, 2): ``row * cols + col`` of the sub-cell of side
    ``size``, OFF_GRID off the grid."""
    out = np.empty(points.shape[0], dtype=np.int64)
    for k in range(points.shape[0]):
        cell = cell_key(points[k, 0], points[k, 1], x0, y0, size, rows, cols)
        out[k] = cell if cell >= 0 else OFF_GRID
    return out
