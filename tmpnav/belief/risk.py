"""The collision bound: how likely a robot's footprint leaves free space, from its belief.

The numpy reference of the bound stated and proved in docs/models.md ("Collision bound");
the compiled kernel computes the same formula. Robot i is a disc of radius r; the map's
clearance C (:func:`tmpnav.world.grid.clearance`, m) is the distance from each free cell's
centre to the nearest occupied cell's centre (0 on occupied cells), and cell(p) is the cell
that contains p (:meth:`tmpnav.world.grid.OccupancyGrid.cells`).

* A true position x **hits a wall** when C[cell(x)] <= r, or x lies outside the grid (an
  occupied or unknown cell has C = 0): :func:`hits_wall`, what ``tmpnav simulate`` counts.
* The **margin** at a nominal (mean) position mu is d(mu) = C[cell(mu)] - r - sqrt(2) res:
  ||x - mu|| < d implies that x does not hit a wall (:func:`margins`; the roadmap's safe
  weights use it).
* The **sector reach** R_k(mu) (:mod:`tmpnav.world.reach`): x - mu in sector k and
  ||x - mu|| < R_k imply that x does not hit a wall.
* A **step** with position covariance Sigma (2x2): P(hit) <= 1 if some R_k = 0, else the
  smaller of the disc's chi-square(2) tail exp(-R² / (2 lambda_max(Sigma))), R = min_k R_k,
  and the Gaussian's mass beyond R_k summed over the sectors (:func:`step_bound`).
* A **move** of T control steps: P(any hit) <= min(1, sum_{k=1..T} p_k), Boole's inequality
  (:func:`move_bound`); a plan sums its moves the same way.
* Two **robots** at one instant touch when ||x_i - x_j|| < r_i + r_j; with
  m = ||mu_i - mu_j|| - r_i - r_j and sigma = sqrt(lambda_max(Sigma_xy)) of each,
  P(touch) <= exp(-m² / (2 (sigma_i + sigma_j)²)) (1 if m <= 0) (:func:`pair_bound`), so the
  separation r_i + r_j + k(delta) (sigma_i + sigma_j), k(delta) = sqrt(2 ln(1/delta)), keeps it
  at most delta (:func:`separation`, :func:`k_of`).

Every bound assumes the true position error is Gaussian with the EKF's covariance (a
consistent filter); tests/belief/test_risk.py measures the bound against sampled
trajectories, and ``tmpnav simulate`` against executions. :func:`clopper_pearson` gives the
confidence interval both report for a sampled rate.
"""

from __future__ import annotations

import math

import numpy as np

from tmpnav.world.grid import OccupancyGrid, clearance, footprint_margins
from tmpnav.world.reach import SectorReach

SQRT2 = math.sqrt(2.0)
#: below this the disc's bound is used as it is (the sectors would not change a sum that matters)
TINY = 1e-12
#: Sigma with det <= DET_FLOOR lambda_max² is nearly singular: the disc's bound alone
DET_FLOOR = 1e-9


def k_of(delta: float) -> float:
    """k(delta) = sqrt(2 ln(1/delta)): the multiple of a standard deviation whose Gaussian tail
    bound exp(-k²/2) is delta. delta in (0, 1]."""
    if not 0.0 < delta <= 1.0:
        raise ValueError(f"delta must be in (0, 1], not {delta}")
    return math.sqrt(2.0 * math.log(1.0 / delta))


def lambda_max(cov_xy: np.ndarray) -> np.ndarray:
    """Largest eigenvalue of each symmetric 2x2 block (..., 2, 2) -> (...,), m².

    lambda_max = (a + c)/2 + sqrt(((a - c)/2)² + b²) for [[a, b], [b, c]] (the mean of the two
    off-diagonal entries is used, so a slightly asymmetric covariance is read as its symmetric part).
    """
    cov = np.asarray(cov_xy, dtype=float)
    a, c = cov[..., 0, 0], cov[..., 1, 1]
    b = 0.5 * (cov[..., 0, 1] + cov[..., 1, 0])
    return np.maximum(0.5 * (a + c) + np.hypot(0.5 * (a - c), b), 0.0)


def position_std(cov: np.ndarray) -> np.ndarray:
    """sigma = sqrt(lambda_max(Sigma_xy)) (m): the largest standard deviation of the position,
    from a pose covariance (..., 3, 3) or its position block (..., 2, 2)."""
    return np.sqrt(lambda_max(np.asarray(cov, dtype=float)[..., :2, :2]))


def hits_wall(grid: OccupancyGrid, clear: np.ndarray, points: np.ndarray, radius: float | np.ndarray) -> np.ndarray:
    """Whether a disc of ``radius`` (m; a scalar, or one per point) at each position (..., 2)
    hits a wall: C[cell(x)] <= radius, or x outside the grid. ``clear`` is the grid's clearance."""
    i, j, inside = grid.cells(np.asarray(points, dtype=float))
    return ~inside | (clear[i, j] <= radius)


def margins(grid: OccupancyGrid, positions: np.ndarray, radius: float, clear: np.ndarray | None = None) -> np.ndarray:
    """d(mu) = C[cell(mu)] - r - sqrt(2) res (m) at each nominal position (..., 2) -> (...,).

    Any x with ||x - mu|| < d(mu) has C[cell(x)] > r (docs/models.md, "Collision bound"). A
    position outside the grid gets -inf. ``clear`` is ``clearance(grid)``, computed when not given.
    """
    clear = clearance(grid) if clear is None else clear
    return footprint_margins(grid, clear, np.asarray(positions, dtype=float), radius)


def step_bound(cov_xy: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Upper bound on P(the true position hits a wall) at one step -> (...,).

    ``reach``: (..., K) the sector reach R_k at the nominal position (:mod:`tmpnav.world.reach`,
    m), ``cov_xy``: (..., 2, 2) position covariance, m² (a pose covariance is cut to it). With
    R = min_k R_k, the smaller of two bounds (docs/models.md, "Collision bound"):

    * the disc: exp(-R² / (2 lambda_max)): ||x - mu||² <= lambda_max ||z||², chi²(2) tail;
    * the sectors: sum_k w exp(-R_k² q_k / 2) / (2 pi sqrt(det Sigma) q_k), where q_k is the least
      of q(theta) = u(theta)^T Sigma^-1 u(theta) over sector k: the Gaussian's mass beyond R_k in
      the sector, with q at its least (exp(-R² q / 2) / q falls as q grows).

    1 when R <= 0; the disc alone when it is below :data:`TINY` or Sigma is nearly singular.
    """
    cov = np.asarray(cov_xy, dtype=float)[..., :2, :2]
    R = np.asarray(reach, dtype=float)
    a, c = cov[..., 0, 0], cov[..., 1, 1]
    b = 0.5 * (cov[..., 0, 1] + cov[..., 1, 0])
    lam = lambda_max(cov)
    r_min = R.min(axis=-1)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        disc = np.where(lam > 0.0, np.exp(-(r_min**2) / (2.0 * lam)), 0.0)
        det = a * c - b * b
        sectors = _sector_sum(a[..., None], b[..., None], c[..., None], det[..., None], R)
        use = (disc >= TINY) & (det > DET_FLOOR * lam * lam)
        p = np.where(use, np.minimum(disc, sectors), disc)
    return np.where(r_min <= 0.0, 1.0, np.minimum(p, 1.0))


def _sector_sum(a: np.ndarray, b: np.ndarray, c: np.ndarray, det: np.ndarray, R: np.ndarray) -> np.ndarray:
    """sum_k of the sector terms of :func:`step_bound` (the kernel's loop, vectorised).

    q(theta) = v(theta + pi/2) / det with v(phi) = a cos² phi + 2 b cos phi sin phi + c sin² phi the
    variance along phi; over a sector it is least at an edge, or at the major axis of Sigma
    (q = 1 / lambda_max) when the sector holds it."""
    K = R.shape[-1]
    w = 2.0 * math.pi / K
    edges = w * np.arange(K + 1)
    s, co = np.sin(edges), np.cos(edges)
    q_edge = (a * s * s - 2.0 * b * s * co + c * co * co) / det  # (..., K+1)
    q = np.minimum(q_edge[..., :-1], q_edge[..., 1:])
    major = 0.5 * np.arctan2(2.0 * b, a - c)
    holds = np.mod(major - edges[:-1], math.pi) <= w
    lam = 0.5 * (a + c) + np.hypot(0.5 * (a - c), b)
    q = np.where(holds, 1.0 / lam, q)
    terms = w * np.exp(-(R**2) * q / 2.0) / (2.0 * math.pi * np.sqrt(det) * q)
    return terms.sum(axis=-1)


def step_bounds(
    positions: np.ndarray, covs: np.ndarray, grid: OccupancyGrid, radius: float, clear: np.ndarray | None = None
) -> np.ndarray:
    """The per-step bounds p_k along a path: positions (T+1, 2) m, covariances (T+1, 3, 3) or
    (T+1, 2, 2) -> (T+1,) (entry 0 is the start, which :func:`move_bound` leaves out)."""
    table = SectorReach(grid, clearance(grid) if clear is None else clear, radius)
    return step_bound(np.asarray(covs, dtype=float)[..., :2, :2], table.at(np.asarray(positions, dtype=float)))


def move_bound(
    positions: np.ndarray, covs: np.ndarray, grid: OccupancyGrid, radius: float, clear: np.ndarray | None = None
) -> float:
    """P_move = min(1, sum_{k=1..T} p_k): an upper bound on the probability that the robot hits
    a wall at any of the move's control steps (Boole's inequality over the steps after each control).

    positions: (T+1, 2) nominal positions, the start first (a (T+1, 3) pose array is cut to them);
    covs: (T+1, 3, 3) or (T+1, 2, 2) covariances at the same steps; radius: m.
    """
    p = step_bounds(positions, covs, grid, radius, clear)
    return float(min(1.0, float(np.sum(p[1:]))))


def plan_bound(moves: list[float]) -> float:
    """A plan's bound: min(1, sum of its moves' bounds) (Boole again)."""
    return float(min(1.0, math.fsum(moves)))


def pair_bound(
    mu_i: np.ndarray,
    mu_j: np.ndarray,
    cov_i: np.ndarray,
    cov_j: np.ndarray,
    r_i: float,
    r_j: float,
) -> np.ndarray:
    """Upper bound on P(robots i and j touch) at one instant: ||x_i - x_j|| < r_i + r_j.

    m = ||mu_i - mu_j|| - r_i - r_j; P <= 1 if m <= 0, else exp(-m² / (2 (sigma_i + sigma_j)²)),
    sigma = sqrt(lambda_max(Sigma_xy)). Touching needs ||e|| > m for the relative error
    e = (x_i - x_j) - (mu_i - mu_j), whose largest standard deviation is at most
    sigma_i + sigma_j whatever the cross-covariance (std(u·e_i - u·e_j) <= std(u·e_i) + std(u·e_j)).

    mu: (..., 2) m; cov: (..., 3, 3) or (..., 2, 2) m²; radii m. Returns (...,).
    """
    gap = np.asarray(mu_i, dtype=float)[..., :2] - np.asarray(mu_j, dtype=float)[..., :2]
    m = np.hypot(gap[..., 0], gap[..., 1]) - r_i - r_j
    s = position_std(cov_i) + position_std(cov_j)
    with np.errstate(divide="ignore", invalid="ignore"):
        tail = np.where(s > 0.0, np.exp(-(m**2) / (2.0 * s**2)), 0.0)
    return np.where(m <= 0.0, 1.0, tail)


def separation(delta: float, r_i: float, r_j: float, sigma_i: float, sigma_j: float) -> float:
    """s_ij = r_i + r_j + k(delta) (sigma_i + sigma_j) (m): planned means at least this far apart
    keep :func:`pair_bound` at most delta."""
    return r_i + r_j + k_of(delta) * (sigma_i + sigma_j)


def clopper_pearson(hits: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper-Pearson) confidence interval of a rate seen ``hits`` times in ``n``
    trials: (lower, upper), from the beta distribution's quantiles; (0, 1) when n = 0."""
    from scipy import stats  # imported here: the clock imports this module, and scipy.stats is slow to load

    if n <= 0:
        return 0.0, 1.0
    a = 0.5 * (1.0 - level)
    lo = 0.0 if hits <= 0 else float(stats.beta.ppf(a, hits, n - hits + 1))
    hi = 1.0 if hits >= n else float(stats.beta.ppf(1.0 - a, hits + 1, n - hits))
    return lo, hi
