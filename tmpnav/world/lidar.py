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
independent): tmpnav.world.scan_information sums it per pose and keeps it per grid cell.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np
from scipy import ndimage

from tmpnav.types import RangeSensor, ScanModelKind
from tmpnav.world.grid import OccupancyGrid

#: march at least this share of a cell per step near a wall
MIN_STEP = 0.25
#: bisection steps that bracket a hit (a quarter cell / 2**6: 0.2 mm on a 5 cm grid) before a secant step
BISECTIONS = 6


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
    return _bilinear(f00, f01, f10, f11, fx, fy, res)


@nb.njit(cache=True, inline="always")
def _bilinear(f00, f01, f10, f11, fx, fy, res):
    """(phi, gx, gy) between the four centres f00 (lower left) .. f11 at (fx, fy) of a cell from f00."""
    a = f00 + (f01 - f00) * fx
    b = f10 + (f11 - f10) * fx
    phi = a + (b - a) * fy
    gx = ((f01 - f00) * (1.0 - fy) + (f11 - f10) * fy) / res
    gy = (b - a) / res
    return phi, gx, gy


def ringed(sdf: np.ndarray, resolution: float) -> np.ndarray:
    """The field (rows + 2, cols + 2) inside one ring of its value off the grid, -res/2, as
    :func:`ringed_field` reads it."""
    return np.pad(sdf, 1, constant_values=-0.5 * resolution)


@nb.njit(cache=True, inline="always")
def ringed_field(ring, x0, y0, res, x, y):
    """:func:`_field` read off the field inside its ring (:func:`ringed`): the same values to the
    bit for one bounds check rather than four, since a cell whose four corners are not all in
    the ringed array has all four off the grid."""
    u = (x - x0) / res - 0.5
    v = (y - y0) / res - 0.5
    j = math.floor(u)
    i = math.floor(v)
    fx, fy = u - j, v - i
    R, C = ring.shape
    if i >= -1 and i + 2 < R and j >= -1 and j + 2 < C:  # grid cell (i, j) is the ring's (i + 1, j + 1)
        return _bilinear(ring[i + 1, j + 1], ring[i + 1, j + 2], ring[i + 2, j + 1], ring[i + 2, j + 2], fx, fy, res)
    out = -0.5 * res
    return _bilinear(out, out, out, out, fx, fy, res)


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
    return bracketed_hit(sdf, x0, y0, res, x, y, dx, dy, t_prev, t, f_prev, phi, r_max)


@nb.njit(cache=True, inline="always")
def bracketed_hit(sdf, x0, y0, res, x, y, dx, dy, lo, hi, f_lo, f_hi, r_max):
    """:func:`cast`'s hit along direction (dx, dy) from (x, y) between ranges ``lo``, where the
    field is f_lo >= 0, and ``hi``, where it is f_hi < 0: bisection, then a secant step;
    (range m, gx, gy), range inf beyond ``r_max``."""
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


#: the length of :func:`sensor_params`' vector (a placeholder without a sensor has as many zeros)
SENSOR_PARAMS = 10


def sensor_params(sensor: RangeSensor, resolution: float = 0.0) -> np.ndarray:
    """The sensor as the compiled functions take it: (min_range m, range m, cos of the largest
    incidence, sigma_range m, divergence rad), then its localiser's scan model on a map of
    ``resolution`` m: (1 for the likelihood field else 0, its endpoint variance
    sigma_lf² = sigma_hit² + resolution²/12 m², the information share times the mixture factor
    eta, the cloud's heading spread squared rad², and the information of ``floor_beams`` head-on
    beams kappa eta floor_beams / sigma_lf² m^-2 that each direction of a scan loses;
    docs/models.md, "What a localiser achieves")."""
    model = sensor.localiser
    field = model.kind is ScanModelKind.AMCL
    var_lf = model.sigma_hit**2 + resolution**2 / 12.0
    share = model.information * model.mixture_factor(sensor.range)
    params = np.array(
        [
            sensor.min_range,
            sensor.range,
            math.cos(sensor.max_incidence),
            sensor.sigma_range,
            sensor.divergence,
            1.0 if field else 0.0,
            var_lf,
            share,
            model.heading_blur**2 if field else 0.0,
            model.floor_beams * share / var_lf if field else 0.0,
        ]
    )
    assert params.shape == (SENSOR_PARAMS,)
    return params


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
    of its range) (:func:`returned`)."""
    r, gx, gy = cast(sdf, x0, y0, res, x, y, psi, params[1])
    return returned(r, gx, gy, psi, params)


@nb.njit(cache=True, inline="always")
def returned(r, gx, gy, psi, params):
    """Whether beam psi cast to range r, field gradient (gx, gy) at its hit (:func:`cast`),
    returns, its range r, its Jacobian h0, h1, h2 and the variance of its range. It returns with
    a hit within range, beyond the blind zone, on a surface met at most the largest incidence
    beta from head-on; its variance is sigma^2 + (r div tan beta)^2, the spot's spread along the
    surface (docs/models.md, "Range sensor")."""
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
