"""What a 2D range finder sees of the map: ray casting, beam Jacobians and scan information.

The walls are the zero level set of a signed distance field: at each cell centre the distance
to the nearest cell of the other kind, less half a cell (positive in free space, negative in
occupied cells; off the grid is occupied), interpolated bilinearly between centres. Its zero
set runs along the boundary between free and occupied cells, smoothly enough that a beam's
range is a differentiable function of the pose, so the simulator's scans and the planner's
linearisation see the same walls. A beam from (x, y) in direction psi is marched along the
field (sphere tracing: a step of 0.8 times the distance, at least a quarter cell) to the first
point where the field turns negative, which bisection and a last secant step locate.

Range of beam i of a scan from pose (x, y, theta) at angle phi_i: r_i = ray(x, y, theta + phi_i).
With g the field's gradient at the hit point and d = (cos psi, sin psi), d' = (-sin psi, cos psi),
the implicit-function theorem on phi(p + r d) = 0 gives its Jacobian (docs/models.md, "Range
sensor"):

    H_i = [-g_x / (g.d),  -g_y / (g.d),  -r (g.d') / (g.d)]

which is Censi's -[v(alpha); r tan beta] / cos beta with alpha the normal into the wall and
beta the incidence. One scan informs the pose by J = sum_i H_i^T H_i / sigma^2 (beams as
independent), and :class:`ScanInformation` keeps J's factor per cell and heading, computed
when first asked for (the oracle's motions read a few thousand cells of a building).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np
from scipy import ndimage

from tmpnav.types import RangeSensor, ScanModelKind
from tmpnav.world.grid import OccupancyGrid, cell_key

#: heading bins of the scan information table (5 degrees each) for a sensor with a limited field of view
HEADINGS = 72
#: march at least this share of a cell per step near a wall
MIN_STEP = 0.25
#: bisection steps that bracket a hit (a quarter cell / 2**6: 0.2 mm on a 5 cm grid) before a secant step
BISECTIONS = 6
#: flat cell index of a pose off the grid: no information
OFF_GRID = -1


def signed_distance(grid: OccupancyGrid) -> np.ndarray:
    """The signed distance field (rows, cols) m at the cell centres: free cells +(distance to the
    nearest occupied centre - res/2), occupied cells -(distance to the nearest free centre - res/2).
    The grid's outside counts as occupied."""
    res = grid.resolution
    free = np.pad(~grid.occupied, 1, constant_values=False)
    outside = ndimage.distance_transform_edt(free)[1:-1, 1:-1] * res
    inside = ndimage.distance_transform_edt(~free)[1:-1, 1:-1] * res
    return np.where(grid.occupied, -(inside - 0.5 * res), outside - 0.5 * res)


@nb.njit(cache=True, inline="always")
def _field(sdf, x0, y0, res, x, y):
    """The bilinear field and its gradient at (x, y): (phi, gx, gy); off the grid -res/2."""
    u = (x - x0) / res - 0.5
    v = (y - y0) / res - 0.5
    j = math.floor(u)
    i = math.floor(v)
    fx, fy = u - j, v - i
    R, C = sdf.shape
    out = -0.5 * res
    f00 = sdf[i, j] if 0 <= i < R and 0 <= j < C else out
    f01 = sdf[i, j + 1] if 0 <= i < R and 0 <= j + 1 < C else out
    f10 = sdf[i + 1, j] if 0 <= i + 1 < R and 0 <= j < C else out
    f11 = sdf[i + 1, j + 1] if 0 <= i + 1 < R and 0 <= j + 1 < C else out
    a = f00 + (f01 - f00) * fx
    b = f10 + (f11 - f10) * fx
    phi = a + (b - a) * fy
    gx = ((f01 - f00) * (1.0 - fy) + (f11 - f10) * fy) / res
    gy = (b - a) / res
    return phi, gx, gy


@nb.njit(cache=True)
def cast(sdf, x0, y0, res, x, y, psi, r_max):
    """One beam from (x, y) in direction psi (rad): (range m, gx, gy) of its first hit within
    ``r_max``, with the field's gradient there; range inf for no hit, nan from inside a wall."""
    dx, dy = math.cos(psi), math.sin(psi)
    phi, _, _ = _field(sdf, x0, y0, res, x, y)
    if phi <= 0.0:
        return math.nan, 0.0, 0.0
    t_prev, t, f_prev = 0.0, 0.0, phi
    floor = MIN_STEP * res
    while True:
        t_prev, f_prev = t, phi
        t += max(0.8 * phi, floor)
        if t > r_max + floor:
            return math.inf, 0.0, 0.0
        phi, _, _ = _field(sdf, x0, y0, res, x + t * dx, y + t * dy)
        if phi < 0.0:
            break
    lo, hi = t_prev, t  # phi(lo) >= 0 > phi(hi)
    f_lo, f_hi = f_prev, phi  # the field at lo as the march found it
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        f_mid, _, _ = _field(sdf, x0, y0, res, x + mid * dx, y + mid * dy)
        if f_mid >= 0.0:
            lo, f_lo = mid, f_mid
        else:
            hi, f_hi = mid, f_mid
    r = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    if r > r_max:
        return math.inf, 0.0, 0.0
    _, gx, gy = _field(sdf, x0, y0, res, x + r * dx, y + r * dy)
    return r, gx, gy


@nb.njit(cache=True, inline="always")
def _beam_row(r, gx, gy, psi):
    """H_i = d r / d(x, y, theta) of a beam with range r and field gradient (gx, gy) at its hit."""
    gd = gx * math.cos(psi) + gy * math.sin(psi)
    gdp = -gx * math.sin(psi) + gy * math.cos(psi)
    return -gx / gd, -gy / gd, -r * gdp / gd


def sensor_params(sensor: RangeSensor, resolution: float = 0.0) -> np.ndarray:
    """The sensor as the compiled functions take it: (min_range m, range m, cos of the largest
    incidence, sigma_range m, divergence rad), then its localiser's scan model on a map of
    ``resolution`` m: (1 for the likelihood field else 0, its endpoint variance
    sigma_hit² + resolution²/12 m², the information share times the mixture factor eta;
    docs/models.md, "What a localiser achieves")."""
    model = sensor.localiser
    field = model.kind is ScanModelKind.AMCL
    return np.array(
        [
            sensor.min_range,
            sensor.range,
            math.cos(sensor.max_incidence),
            sensor.sigma_range,
            sensor.divergence,
            1.0 if field else 0.0,
            model.sigma_hit**2 + resolution**2 / 12.0,
            model.information * model.mixture_factor(sensor.range),
        ]
    )


def localiser_angles(sensor: RangeSensor) -> np.ndarray:
    """The beams (rad from the heading) the robot's localiser weighs: every beam for ``beams``;
    for ``amcl`` at most ``max_beams`` of them, evenly spaced, as nav2's AMCL picks them."""
    angles = sensor.beam_angles()
    keep = sensor.localiser.max_beams
    if sensor.localiser.kind is ScanModelKind.BEAMS or angles.size <= keep:
        return angles
    step = (angles.size - 1) / (keep - 1) if keep > 1 else 0.0
    return angles[np.round(np.arange(keep) * step).astype(int)]


@nb.njit(cache=True, inline="always")
def _beam(sdf, x0, y0, res, x, y, psi, params):
    """Beam psi from (x, y): (whether it returns, its range r, its Jacobian h0, h1, h2, the variance
    of its range). It returns with a hit within range, beyond the blind zone, on a surface met at
    most the largest incidence beta from head-on; its variance is sigma^2 + (r div tan beta)^2,
    the spot's spread along the surface (docs/models.md, "Range sensor")."""
    r, gx, gy = cast(sdf, x0, y0, res, x, y, psi, params[1])
    g = math.hypot(gx, gy)
    if not (r >= params[0] and r < math.inf) or g <= 0.0:
        return False, r, 0.0, 0.0, 0.0, 0.0
    cos_b = -(gx * math.cos(psi) + gy * math.sin(psi)) / g
    if cos_b < params[2]:
        return False, r, 0.0, 0.0, 0.0, 0.0
    h0, h1, h2 = _beam_row(r, gx, gy, psi)
    spread = r * params[4] * math.sqrt(max(1.0 - cos_b * cos_b, 0.0)) / cos_b
    return True, r, h0, h1, h2, params[3] * params[3] + spread * spread


@nb.njit(cache=True)
def scan(sdf, x0, y0, res, pose, angles, params, ranges, H, var):
    """Ray cast one scan from ``pose`` (x, y, theta) with the sensor's ``params``
    (:func:`sensor_params`): ``ranges`` (B,) m (nan: no return), ``H`` (B, 3), each beam's
    Jacobian, and ``var`` (B,) m², its range's variance (zero rows and 0 where it does not return)."""
    for b in range(angles.shape[0]):
        ok, r, h0, h1, h2, v = _beam(sdf, x0, y0, res, pose[0], pose[1], pose[2] + angles[b], params)
        ranges[b] = r if ok else math.nan
        H[b, 0], H[b, 1], H[b, 2], var[b] = h0, h1, h2, v


@nb.njit(cache=True)
def scan_beams(sdf, x0, y0, res, pose, angles, params, wanted, ranges, H, var):
    """:func:`scan` of the beams ``wanted`` (B,) bool only, the others left as beams that do not
    return (nan, zero rows, 0): the simulator casts the beams it can compare with a true return."""
    for b in range(angles.shape[0]):
        if not wanted[b]:
            ranges[b], H[b, 0], H[b, 1], H[b, 2], var[b] = math.nan, 0.0, 0.0, 0.0, 0.0
            continue
        ok, r, h0, h1, h2, v = _beam(sdf, x0, y0, res, pose[0], pose[1], pose[2] + angles[b], params)
        ranges[b] = r if ok else math.nan
        H[b, 0], H[b, 1], H[b, 2], var[b] = h0, h1, h2, v


@nb.njit(cache=True)
def _information(sdf, x0, y0, res, x, y, theta, angles, params, J):
    """J (3, 3) = sum over the returning beams of H_i^T H_i / var_i: var_i the range's variance
    (``beams``), or for the likelihood field (params[5] = 1) the endpoint's variance params[6]
    stretched along the beam by 1/cos beta (cos² beta = 1 / (h0² + h1²)) and divided by the
    information share params[7]: a_i a_iᵀ eta kappa / sigma², a_i = cos beta H_i the endpoint's
    distance to the wall (docs/models.md, "What a localiser achieves")."""
    for a in range(3):
        for b in range(3):
            J[a, b] = 0.0
    field = params[5] > 0.0
    for k in range(angles.shape[0]):
        ok, _, h0, h1, h2, v = _beam(sdf, x0, y0, res, x, y, theta + angles[k], params)
        if not ok:
            continue
        w = params[7] / (params[6] * (h0 * h0 + h1 * h1)) if field else 1.0 / v
        J[0, 0] += h0 * h0 * w
        J[0, 1] += h0 * h1 * w
        J[0, 2] += h0 * h2 * w
        J[1, 1] += h1 * h1 * w
        J[1, 2] += h1 * h2 * w
        J[2, 2] += h2 * h2 * w
    J[1, 0], J[2, 0], J[2, 1] = J[0, 1], J[0, 2], J[1, 2]


@nb.njit(cache=True)
def _factors(sdf, x0, y0, res, xs, ys, thetas, angles, params, out):
    """out[p] (3, 3): the rows G of J = G^T G at (xs[p], ys[p], thetas[p]), J the scan's information."""
    J = np.empty((3, 3))
    for p in range(xs.shape[0]):
        _information(sdf, x0, y0, res, xs[p], ys[p], thetas[p], angles, params, J)
        lam, vec = np.linalg.eigh(J)
        top = max(lam[2], 0.0)
        for k in range(3):
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
        g = self.grid
        rows, cols = g.shape
        out = _scan_keys(flat, float(g.origin[0]), float(g.origin[1]), float(g.resolution), rows, cols, self.bins)
        return out.reshape(poses.shape[:-1])

    def rows(self, keys: np.ndarray) -> np.ndarray:
        """The :attr:`table` row (...,) of each key (...,), computing those not seen before."""
        keys = np.asarray(keys, dtype=np.int64)
        flat = keys.ravel()
        wanted = np.unique(flat[flat >= 0])
        new = wanted[~np.isin(wanted, self._keys, assume_unique=True)]
        if new.size:
            self._compute(new)
        out = np.zeros(flat.shape, dtype=np.int64)
        inside = flat >= 0
        at = np.searchsorted(self._keys, flat[inside])
        out[inside] = self._rows[at]
        return out.reshape(keys.shape)

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
        self._preloaded += self.learn(keys, factors)

    def take_new(self) -> tuple[np.ndarray, np.ndarray]:
        """The keys computed here since the last call, and their factors (K, 3, 3): what a
        worker's copy of the table hands back to its parent's (:meth:`learn`). The first call
        starts the record and returns none: only a worker's copy keeps one."""
        keys = np.concatenate(self._new) if self._new else np.zeros(0, dtype=np.int64)
        self._new = []
        return keys, self.table[self.rows(keys)] if keys.size else np.zeros((0, 3, 3))

    def learn(self, keys: np.ndarray, factors: np.ndarray) -> int:
        """Take factors another copy of this table computed in this run (:meth:`take_new`) for
        the keys not known yet, and say how many; unlike :meth:`preload`, they count as
        :attr:`computed`."""
        keys = np.asarray(keys, dtype=np.int64)
        fresh = ~np.isin(keys, self._keys)
        self._add(keys[fresh], np.asarray(factors, dtype=float)[fresh])
        return int(fresh.sum())

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
        _factors(self.sdf, x0, y0, res, xs, ys, thetas, self.angles, self.params, G)
        self._add(keys, G)

    def _add(self, keys: np.ndarray, G: np.ndarray) -> None:
        """Rows for ``keys`` (none known yet) with their factors G (K, 3, 3)."""
        need = self.size + keys.size
        if need > self.table.shape[0]:
            grown = np.zeros((max(need, 2 * self.table.shape[0]), 3, 3))
            grown[: self.size] = self.table[: self.size]
            self.table = grown
        self.table[self.size : need] = G
        merged = np.concatenate([self._keys, keys])
        rows = np.concatenate([self._rows, np.arange(self.size, need)])
        order = np.argsort(merged, kind="stable")
        self._keys, self._rows = merged[order], rows[order]
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
