"""What one scan tells the localiser: its information J per pose, kept per grid cell and heading.

J = sum_i H_i^T H_i / sigma_i^2 over the beams that return (tmpnav.world.lidar casts them and
gives each H_i), or the likelihood field's version of it for nav2's AMCL (docs/models.md, "What
a localiser achieves"). :class:`ScanInformation` keeps J's factor per cell and heading,
computed when first asked for (the oracle's motions read a few thousand cells of a building),
and :func:`localisability` maps how well one scan pins a robot down.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from tmpnav.types import RangeSensor
from tmpnav.world.grid import OccupancyGrid, among, cell_key, merged
from tmpnav.world.lidar import (
    MIN_STEP,
    bracketed_hit,
    localiser_angles,
    returned,
    ringed,
    ringed_field,
    sensor_params,
)

#: heading bins of the scan information table (5 degrees each) for a sensor with a limited field of view
HEADINGS = 72
#: flat cell index of a pose off the grid: no information
OFF_GRID = -1
#: the most keys (cells x heading bins) whose rows a table looks up in an array of them (4 bytes
#: a key: 16 MB), not by searching the keys it knows: a 100-room office's cells, a sensor that
#: sees all around
DENSE_KEYS = 4 * 2**20


@nb.njit(cache=True)
def _information(sdf, ring, x0, y0, res, x, y, theta, angles, params, J, beams):
    """J (3, 3) = sum over the returning beams of H_i^T H_i / var_i: var_i the range's variance
    (``beams``), or for the likelihood field (params[5] = 1) the endpoint's variance params[6],
    plus the particle cloud's heading spread params[8] times the range squared, stretched along
    the beam by 1/cos beta (cos² beta = 1 / (h0² + h1²)) and divided by the
    information share params[7]: a_i a_iᵀ eta kappa / sigma², a_i = cos beta H_i the endpoint's
    distance to the wall (docs/models.md, "What a localiser achieves"). ``ring`` is ``sdf``
    inside its ring (tmpnav.world.lidar.ringed); ``beams`` (4, B) room for the beams'
    directions, ranges and gradients (:func:`cast_scan`)."""
    for a in range(3):
        for b in range(3):
            J[a, b] = 0.0
    psis, r, gx, gy = beams[0], beams[1], beams[2], beams[3]
    for k in range(angles.shape[0]):
        psis[k] = theta + angles[k]
    cast_scan(sdf, ring, x0, y0, res, x, y, psis, params[1], r, gx, gy)
    likelihood_field = params[5] > 0.0
    for k in range(angles.shape[0]):
        ok, _, h0, h1, h2, v = returned(r[k], gx[k], gy[k], psis[k], params)
        if not ok:
            continue
        w = params[7] / ((params[6] + r[k] * r[k] * params[8]) * (h0 * h0 + h1 * h1)) if likelihood_field else 1.0 / v
        J[0, 0] += h0 * h0 * w
        J[0, 1] += h0 * h1 * w
        J[0, 2] += h0 * h2 * w
        J[1, 1] += h1 * h1 * w
        J[1, 2] += h1 * h2 * w
        J[2, 2] += h2 * h2 * w
    J[1, 0], J[2, 0], J[2, 1] = J[0, 1], J[0, 2], J[1, 2]


@nb.njit(cache=True)
def cast_scan(sdf, ring, x0, y0, res, x, y, psis, r_max, r, gx, gy):
    """tmpnav.world.lidar.cast of every beam psis (B,) rad from (x, y) into r, gx, gy (B,), the
    marches in lockstep on ``ring`` (``sdf`` inside its ring, tmpnav.world.lidar.ringed_field):
    one beam's march is a chain of dependent reads of the field, and stepping the beams in turn
    lets the processor overlap their reads (this and the ring halve the scan table's time).
    Each beam takes cast's steps in cast's arithmetic: the same ranges to the bit."""
    phi0, _, _ = ringed_field(ring, x0, y0, res, x, y)
    if phi0 <= 0.0:
        r[:], gx[:], gy[:] = math.nan, 0.0, 0.0
        return
    B = psis.shape[0]
    dx, dy = np.empty(B), np.empty(B)
    for b in range(B):
        dx[b], dy[b] = math.cos(psis[b]), math.sin(psis[b])
    t, t_prev, phi, f_prev = np.zeros(B), np.zeros(B), np.full(B, phi0), np.empty(B)
    marching, m = np.arange(B), B
    floor = MIN_STEP * res
    while m > 0:  # one step of each beam still marching; r[b] 0 for a hit to bracket
        still = 0
        for a in range(m):
            b = marching[a]
            t_prev[b], f_prev[b] = t[b], phi[b]
            t[b] += max(0.8 * phi[b], floor)
            if t[b] > r_max + floor:
                r[b] = math.inf
                continue
            phi[b], _, _ = ringed_field(ring, x0, y0, res, x + t[b] * dx[b], y + t[b] * dy[b])
            if phi[b] < 0.0:
                r[b] = 0.0
                continue
            marching[still] = b
            still += 1
        m = still
    for b in range(B):
        if r[b] == math.inf:
            gx[b], gy[b] = 0.0, 0.0
        else:
            r[b], gx[b], gy[b] = bracketed_hit(
                sdf, x0, y0, res, x, y, dx[b], dy[b], t_prev[b], t[b], f_prev[b], phi[b], r_max
            )


@nb.njit(cache=True)
def _factors(sdf, ring, x0, y0, res, xs, ys, thetas, angles, params, out):
    """out[p] (3, 3): the rows G of J = G^T G at (xs[p], ys[p], thetas[p]), J the scan's
    information, each of its eigenvalues less the information floor params[9] (none below it;
    the heading's taken per metre, docs/models.md); ``ring`` is ``sdf`` inside its ring (tmpnav.world.lidar.ringed)."""
    J = np.empty((3, 3))
    beams = np.empty((4, angles.shape[0]))
    for p in range(xs.shape[0]):
        _information(sdf, ring, x0, y0, res, xs[p], ys[p], thetas[p], angles, params, J, beams)
        lam, vec = np.linalg.eigh(J)
        top = max(lam[2], 0.0)
        for k in range(3):
            lam[k] -= params[9]  # the floor AMCL's particles do not resolve (0: none)
            s = math.sqrt(lam[k]) if lam[k] > 1e-12 * top and lam[k] > 0.0 else 0.0
            for c in range(3):
                out[p, k, c] = s * vec[c, k]


def information_matrices(sdf: np.ndarray, grid: OccupancyGrid, sensor: RangeSensor, poses: np.ndarray) -> np.ndarray:
    """The scan information J (..., 3, 3) at poses (..., 3): sum_i H_i^T H_i / var_i over the
    beams that return (m^-2, m^-1 rad^-1, rad^-2)."""
    flat = np.ascontiguousarray(poses, dtype=float).reshape(-1, 3)
    G = np.empty((flat.shape[0], 3, 3))
    x0, y0 = grid.origin
    _factors(
        sdf,
        ringed(sdf, grid.resolution),
        x0,
        y0,
        grid.resolution,
        flat[:, 0],
        flat[:, 1],
        flat[:, 2],
        localiser_angles(sensor),
        sensor_params(sensor, grid.resolution),
        G,
    )
    return np.matmul(G.transpose(0, 2, 1), G).reshape(*poses.shape[:-1], 3, 3)


class ScanInformation:
    """One scan's information, as the factor G (3, 3) of J = G^T G, per grid cell and heading bin.

    Keys name a cell and a heading bin, ``cell * bins + bin`` (:meth:`keys`); the factor of a
    key is computed at the cell's centre and the bin's heading when first asked for
    (:meth:`rows`) and kept in :attr:`table`, whose row 0 is zero (no information: a pose off
    the grid). G's rows are sqrt(lambda_k) e_k^T over J's eigenpairs, so the update with the
    scan is three scalar ones (tmpnav.belief.kernel). A sensor that sees all around has one
    bin: turning it only moves its beams along the circle, by less than their spacing.
    """

    def __init__(self, grid: OccupancyGrid, sdf: np.ndarray, sensor: RangeSensor):
        self.grid, self.sdf, self.sensor = grid, sdf, sensor
        self.angles = localiser_angles(sensor)
        self.params = sensor_params(sensor, grid.resolution)
        self.bins = 1 if sensor.fov >= 2.0 * math.pi - 1e-9 else HEADINGS
        #: the grid's origin (m), resolution (m) and shape as :func:`_scan_keys` takes them
        self._frame = (float(grid.origin[0]), float(grid.origin[1]), float(grid.resolution), *grid.shape)
        keys = grid.shape[0] * grid.shape[1] * self.bins
        #: the table row of every key (0: not known yet), where they are few enough (DENSE_KEYS):
        #: looked up where searching the sorted keys took a fleet's oracle a second in twenty
        self._dense: np.ndarray | None = np.zeros(keys, dtype=np.int32) if keys <= DENSE_KEYS else None
        self._keys = np.zeros(0, dtype=np.int64)  # sorted
        self._rows = np.zeros(0, dtype=np.int64)  # table row of each of _keys
        self.table = np.zeros((1, 3, 3))
        self.size = 1
        self._preloaded = 0
        self._new: list[np.ndarray] | None = None  # keys computed since :meth:`take_new`, once called

    def keys(self, poses: np.ndarray) -> np.ndarray:
        """The key (..., ) int64 of each pose (..., 3): its cell and its heading's bin; OFF_GRID off the grid.
        (Compiled: every nominal motion asks for the keys of its poses.)"""
        poses = np.asarray(poses, dtype=float)
        flat = np.ascontiguousarray(poses.reshape(-1, 3))
        return _scan_keys(flat, *self._frame, self.bins).reshape(poses.shape[:-1])

    def rows(self, keys: np.ndarray) -> np.ndarray:
        """The :attr:`table` row (...,) of each key (...,), computing those not seen before."""
        keys = np.asarray(keys, dtype=np.int64)
        flat = keys.ravel()
        inside = flat >= 0
        out = np.zeros(flat.shape, dtype=np.int64)
        if self._dense is not None:  # a row per key: read, and the keys not known yet computed
            on = flat[inside]
            found = self._dense[on]
            missing = found == 0
            if missing.any():
                self._compute(np.unique(on[missing]))
                found[missing] = self._dense[on[missing]]
            out[inside] = found
            return out.reshape(keys.shape)
        wanted = np.unique(flat[inside])
        new = wanted[~among(wanted, self._keys)]
        if new.size:
            self._compute(new)
        at = np.searchsorted(self._keys, flat[inside])
        out[inside] = self._rows[at]
        return out.reshape(keys.shape)

    def __getstate__(self) -> dict[str, object]:
        """Pickled (a Ray worker's world) without the rows by key, rebuilt from the keys known."""
        state = self.__dict__.copy()
        state["_dense"] = self._dense is not None
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        dense = state.pop("_dense")
        self.__dict__.update(state)
        self._dense = None
        if dense:
            self._dense = np.zeros(self.grid.shape[0] * self.grid.shape[1] * self.bins, dtype=np.int32)
            self._dense[self._keys] = self._rows

    @functools.cached_property
    def ring(self) -> np.ndarray:
        """The signed distance field inside its ring, as the table's casts march on it (tmpnav.world.lidar.ringed)."""
        return ringed(self.sdf, self.grid.resolution)

    @property
    def computed(self) -> int:
        """Keys computed here rather than preloaded (:meth:`preload`)."""
        return self.size - 1 - self._preloaded

    def contents(self) -> tuple[np.ndarray, np.ndarray]:
        """Every key known (sorted) and its factor (K, 3, 3): what :meth:`preload` takes."""
        return self._keys.copy(), self.table[self._rows].copy()

    def preload(self, keys: np.ndarray, factors: np.ndarray) -> None:
        """Take factors computed earlier (:meth:`contents`, read from the cache directory) for the
        keys not known yet."""
        self._preloaded += self.learn(keys, factors)[0].size

    def take_new(self) -> tuple[np.ndarray, np.ndarray]:
        """The keys computed here since the last call, and their factors (K, 3, 3): what a
        worker's copy of the table hands back to its parent's (:meth:`learn`). The first call
        starts the record and returns none: only a worker's copy keeps one."""
        keys = np.concatenate(self._new) if self._new else np.zeros(0, dtype=np.int64)
        self._new = []
        return keys, self.table[self.rows(keys)] if keys.size else np.zeros((0, 3, 3))

    def learn(self, keys: np.ndarray, factors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Take factors another copy of this table computed in this run (:meth:`take_new`) for
        the keys not known yet, and return those keys and factors; unlike :meth:`preload`, they
        count as :attr:`computed`."""
        keys = np.asarray(keys, dtype=np.int64)
        fresh = self._dense[keys] == 0 if self._dense is not None else ~among(keys, self._keys)
        keys, factors = keys[fresh], np.asarray(factors, dtype=float)[fresh]
        self._add(keys, factors)
        return keys, factors

    def _compute(self, keys: np.ndarray) -> None:
        if self._new is not None:
            self._new.append(keys)
        cols, res = self.grid.shape[1], self.grid.resolution
        cell, b = keys // self.bins, keys % self.bins
        x0, y0 = self.grid.origin
        xs = x0 + (cell % cols + 0.5) * res
        ys = y0 + (cell // cols + 0.5) * res
        thetas = b * (2.0 * math.pi / self.bins)
        G = np.empty((keys.size, 3, 3))
        _factors(self.sdf, self.ring, x0, y0, res, xs, ys, thetas, self.angles, self.params, G)
        self._add(keys, G)

    def _add(self, keys: np.ndarray, G: np.ndarray) -> None:
        """Rows for ``keys`` (none known yet) with their factors G (K, 3, 3)."""
        need = self.size + keys.size
        if need > self.table.shape[0]:
            grown = np.zeros((max(need, 2 * self.table.shape[0]), 3, 3))
            grown[: self.size] = self.table[: self.size]
            self.table = grown
        self.table[self.size : need] = G
        rows = np.arange(self.size, need)
        if self._dense is not None:
            self._dense[keys] = rows
        self._keys, self._rows = merged(self._keys, self._rows, keys, rows)
        self.size = need


#: localisability maps are computed on at most this many points (a coarser spacing on larger views)
LOCALISABILITY_POINTS = 25_000
#: headings averaged for a sensor that does not see all around
LOCALISABILITY_HEADINGS = 8


@dataclass(frozen=True, eq=False)
class Localisability:
    """How well one scan pins a robot down, on a regular grid of points: ``sigma`` (rows, cols) m is
    the position standard deviation along the worst direction after one scan from a belief that
    knew nothing (the position block of J's inverse, heading marginalised); inf where the scan
    leaves a direction unseen (a featureless corridor, along it) or returns nothing, nan on walls.
    Points ``xs`` (cols,), ``ys`` (rows,) m."""

    xs: np.ndarray
    ys: np.ndarray
    sigma: np.ndarray


def localisability(
    grid: OccupancyGrid,
    sdf: np.ndarray,
    sensor: RangeSensor,
    view: tuple[float, float, float, float] | None = None,
    points: int = LOCALISABILITY_POINTS,
) -> Localisability:
    """The :class:`Localisability` of ``sensor`` over ``view`` (xmin, ymin, xmax, ymax; the whole grid
    for None), on at most about ``points`` points; a sensor with a limited field of view gets the
    information averaged over :data:`LOCALISABILITY_HEADINGS` headings."""
    x0, y0, x1, y1 = view if view is not None else grid.extent
    spacing = max(grid.resolution, math.sqrt((x1 - x0) * (y1 - y0) / points))
    xs = np.arange(x0 + spacing / 2, x1, spacing)
    ys = np.arange(y0 + spacing / 2, y1, spacing)
    gx, gy = np.meshgrid(xs, ys)
    at = np.column_stack([gx.ravel(), gy.ravel()])
    i, j, inside = grid.cells(at)
    free = inside & (sdf[i, j] > 0)
    headings = 1 if sensor.fov >= 2.0 * math.pi - 1e-9 else LOCALISABILITY_HEADINGS
    J = np.zeros((int(free.sum()), 3, 3))
    for h in range(headings):
        poses = np.column_stack([at[free], np.full(int(free.sum()), 2.0 * math.pi * h / headings)])
        J += information_matrices(sdf, grid, sensor, poses) / headings
    sigma = np.full(at.shape[0], np.nan)
    sigma[free] = _worst_position_std(J)
    return Localisability(xs, ys, sigma.reshape(gx.shape))


def _worst_position_std(J: np.ndarray) -> np.ndarray:
    """sqrt of the largest eigenvalue of the position block of J⁻¹ (..., 3, 3): 1 / sqrt of the
    smallest eigenvalue of the position information with the heading marginalised (J's Schur
    complement); inf where that is singular."""
    a, b, c = J[:, 0, 0], J[:, 0, 1], J[:, 1, 1]
    t = J[:, 2, 2]
    safe = t > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(safe, a - J[:, 0, 2] ** 2 / t, a)
        b = np.where(safe, b - J[:, 0, 2] * J[:, 1, 2] / t, b)
        c = np.where(safe, c - J[:, 1, 2] ** 2 / t, c)
    smallest = 0.5 * (a + c) - np.sqrt(0.25 * (a - c) ** 2 + b**2)
    top = np.maximum(0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b**2), 0.0)
    with np.errstate(divide="ignore"):
        return np.where(smallest > 1e-9 * top, 1.0 / np.sqrt(np.maximum(smallest, 1e-300)), np.inf)


@nb.njit(cache=True)
def _scan_keys(
    poses: np.ndarray, x0: float, y0: float, resolution: float, rows: int, cols: int, bins: int
) -> np.ndarray:
    """:meth:`ScanInformation.keys` of poses (P, 3): the cell of (x, y) as
    :meth:`tmpnav.world.grid.OccupancyGrid.cells` finds it, times ``bins``, plus the bin
    nearest the heading taken modulo 2 pi; OFF_GRID off the grid."""
    out = np.empty(poses.shape[0], dtype=np.int64)
    turn = 2.0 * math.pi
    for k in range(poses.shape[0]):
        cell = cell_key(poses[k, 0], poses[k, 1], x0, y0, resolution, rows, cols)
        if cell < 0:
            out[k] = OFF_GRID
            continue
        b = np.int64(math.floor((poses[k, 2] % turn) * (bins / turn) + 0.5)) % bins
        out[k] = cell * bins + b
    return out
