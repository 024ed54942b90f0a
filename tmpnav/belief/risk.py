"""The collision bound: how likely a robot's footprint leaves free space along a move, from its
beliefs.

The numpy reference of the bound stated and proved in docs/models.md ("Collision bound"); the
compiled kernel (:mod:`tmpnav.belief.kernel_bound`) computes the same formulas while it propagates
beliefs, and tests/belief/test_collision_bound.py holds the two together. In short:

* :func:`hits_wall` is what ``tmpnav simulate`` counts; :func:`margins` and the sector reach
  (:mod:`tmpnav.world.reach`) say how far a position may move before it hits;
* :func:`step_bound`: p_t >= P(hit at step t), from the position covariance and the reach;
* :func:`crossing_bound`: X_t >= P(no hit at step t-1, hit at step t), from the covariances
  of both steps and their cross-covariance Cov(e_t, e_{t-1}) (the filter's error is
  Gauss-Markov along a path), at most p_t;
* :func:`move_bound`: P(a hit at any step of a move) <= min(p_1, p_0 + X_1) + sum_{t>=2} X_t
  (first passage), instead of Boole's sum of the p_t over steps that are strongly correlated;
* two robots touching: :mod:`tmpnav.belief.pair_risk`, on the same steps.

Every bound assumes the true position errors are jointly Gaussian with the EKF's covariances
and cross-covariances (a consistent filter). :mod:`tmpnav.belief.intervals` gives the confidence
intervals that the tests, ``tmpnav simulate`` and ``tmpnav calibrate`` report for sampled rates.
"""

from __future__ import annotations

import math

import numpy as np

from tmpnav.world.grid import OccupancyGrid, clearance, footprint_margins
from tmpnav.world.reach import SECTORS, SectorReach

SQRT2 = math.sqrt(2.0)
#: below this the disc's bound is used as it is (the sectors would not change a sum that matters)
TINY = 1e-12
#: Sigma with det <= DET_FLOOR lambda_max² is nearly singular: the disc's bound alone
DET_FLOOR = 1e-9
#: the share of a step's sector sum left for the previous error outside the ball that the
#: crossing bound looks at (its radius follows from it)
ESCAPE = 0.01
#: sectors whose own mass is below this share of the step's sector sum keep it as their
#: crossing term (it bounds that too): the crossing is worked out for the ones that matter
SIGNIFICANT = 1e-2
#: the sector angle (rad), the edges' directions (cos, sin; edge k at k w, edge K is edge 0)
WIDTH = 2.0 * math.pi / SECTORS
EDGE_COS = np.cos(WIDTH * np.arange(SECTORS + 1))
EDGE_SIN = np.sin(WIDTH * np.arange(SECTORS + 1))
#: cos of d sector widths, 0 from a right angle on: how far a sector reaches along an edge's
#: direction, for a sector whose nearer edge is d widths from it
CONE_COS = np.where(np.arange(SECTORS) < SECTORS // 4, np.cos(WIDTH * np.arange(SECTORS)), 0.0)


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


# ---------------------------------------------------------------- one step


def step_bound(cov_xy: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """p_t: an upper bound on P(the true position hits a wall) at one step -> (...,).

    ``reach``: (..., K) the sector reach R_k at the nominal position (:mod:`tmpnav.world.reach`,
    m), ``cov_xy``: (..., 2, 2) position covariance, m² (a pose covariance is cut to it). With
    R = min_k R_k, the smaller of two bounds (docs/models.md, "Collision bound"):

    * the disc: exp(-R² / (2 lambda_max)): ||x - mu||² <= lambda_max ||z||², chi²(2) tail;
    * the sectors: sum_k w exp(-R_k² q_k / 2) / (2 pi sqrt(det Sigma) q_k), where q_k is the least
      of q(theta) = u(theta)^T Sigma^-1 u(theta) over sector k: the Gaussian's mass beyond R_k in
      the sector, with q at its least (exp(-R² q / 2) / q falls as q grows).

    1 when R <= 0; the disc alone when it is below :data:`TINY`, Sigma is nearly singular, or the
    reach has other than :data:`~tmpnav.world.reach.SECTORS` sectors (as in the kernel).
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
        if R.shape[-1] != SECTORS:
            return np.where(r_min <= 0.0, 1.0, np.minimum(disc, 1.0))
        sectors = _sector_sum(a[..., None], b[..., None], c[..., None], det[..., None], R)
        use = (disc >= TINY) & (det > DET_FLOOR * lam * lam)
        p = np.where(use, np.minimum(disc, sectors), disc)
    return np.where(r_min <= 0.0, 1.0, np.minimum(p, 1.0))


def _sector_sum(a: np.ndarray, b: np.ndarray, c: np.ndarray, det: np.ndarray, R: np.ndarray) -> np.ndarray:
    """sum_k of the sector terms of :func:`step_bound` (the kernel's loop, vectorised).

    q(theta) = v(theta + pi/2) / det with v(phi) = a cos² phi + 2 b cos phi sin phi + c sin² phi the
    variance along phi; over a sector it is least at an edge, or at the major axis of Sigma
    (q = 1 / lambda_max) when the sector holds it."""
    s, co = EDGE_SIN, EDGE_COS
    q_edge = (a * s * s - 2.0 * b * s * co + c * co * co) / det  # (..., K+1)
    q = np.minimum(q_edge[..., :-1], q_edge[..., 1:])
    major = 0.5 * np.arctan2(2.0 * b, a - c)
    holds = np.mod(major - WIDTH * np.arange(SECTORS), math.pi) <= WIDTH
    lam = 0.5 * (a + c) + np.hypot(0.5 * (a - c), b)
    q = np.where(holds, 1.0 / lam, q)
    terms = WIDTH * np.exp(-(R**2) * q / 2.0) / (2.0 * math.pi * np.sqrt(det) * q)
    return terms.sum(axis=-1)


# ---------------------------------------------------------------- two steps


def crossing_bound(
    cov_prev: np.ndarray, cov: np.ndarray, cross: np.ndarray, reach_prev: np.ndarray, reach: np.ndarray
) -> np.ndarray:
    """X_t: an upper bound on P(no hit at step t-1, a hit at step t), at most p_t -> (...,).

    ``cov_prev``, ``cov``: (..., 2, 2) position covariances of steps t-1 and t (pose covariances
    are cut to them); ``cross``: (..., 2, 2) Cov(e_t, e_{t-1}) of the position errors, m²;
    ``reach_prev``, ``reach``: (..., K) the sector reach of the two nominal positions, m.

    The hit set of step t is covered sector by sector (U_t^k: x - mu_t in sector k, at least R_k
    from mu_t), the safe set of step t-1 by its star of reaches, cut to a ball that e_{t-1}
    leaves with probability at most eps = ESCAPE sum_k m_k; given e_t, the error's projection on
    a wall's normal n at step t-1 is Gaussian (the filter's error is Gauss-Markov), so

        X_t <= eps + sum_k min(m_k, min_n w/(2 pi sqrt(det Sigma_t)) I(R_k, q_k, c_k(n), b(n), s(n)))

    with b(n) how far the safe star reaches along n, c_k(n) and s(n) the regression of
    n.e_{t-1} on e_t, I the radial integral of the Gaussian tail times the probability of
    having been on the safe side (docs/models.md, "Collision bound", for the proof; the normals
    n tried are the edges around the nearest wall point each sector looks at). The crossing is
    worked out only for the sectors with at least :data:`SIGNIFICANT` of the sum; X_t is p_t
    where p_t takes the disc's bound, or either position has no reach in some sector.
    """
    cp = np.asarray(cov_prev, dtype=float)[..., :2, :2]
    c = np.asarray(cov, dtype=float)[..., :2, :2]
    x = np.asarray(cross, dtype=float)[..., :2, :2]
    rp, r = np.asarray(reach_prev, dtype=float), np.asarray(reach, dtype=float)
    shape = np.broadcast_shapes(cp.shape[:-2], c.shape[:-2], x.shape[:-2], rp.shape[:-1], r.shape[:-1])
    cp, c, x = (np.broadcast_to(m, (*shape, 2, 2)).reshape(-1, 2, 2) for m in (cp, c, x))
    rp, r = (np.broadcast_to(m, (*shape, m.shape[-1])).reshape(-1, m.shape[-1]) for m in (rp, r))
    p = step_bound(c, r)
    out = np.array([_crossing(cp[k], c[k], x[k], rp[k], r[k], float(p[k])) for k in range(p.shape[0])])
    return out.reshape(shape)


def _crossing(Sp: np.ndarray, S: np.ndarray, C: np.ndarray, Rp: np.ndarray, R: np.ndarray, p: float) -> float:
    """X_t of one step (:func:`crossing_bound`), in the kernel's order of operations."""
    K = R.shape[0]
    a, b, c = float(S[0, 0]), 0.5 * float(S[0, 1] + S[1, 0]), float(S[1, 1])
    lam = 0.5 * (a + c) + math.sqrt(0.25 * (a - c) * (a - c) + b * b)
    det = a * c - b * b
    r_min = float(R.min())
    if K != SECTORS or r_min <= 0.0 or float(Rp.min()) <= 0.0 or lam <= 0.0:
        return p
    if math.exp(-r_min * r_min / (2.0 * lam)) < TINY or not det > DET_FLOOR * lam * lam:
        return p
    masses, qs = _sector_masses(a, b, c, det, lam, R)
    total = 0.0
    for m in masses:
        total += m
    escape = ESCAPE * total
    if escape >= p:
        return p
    ap, bp, cpp = float(Sp[0, 0]), 0.5 * float(Sp[0, 1] + Sp[1, 0]), float(Sp[1, 1])
    lam_p = 0.5 * (ap + cpp) + math.sqrt(0.25 * (ap - cpp) * (ap - cpp) + bp * bp)
    ball = math.sqrt(-2.0 * math.log(escape) * max(lam_p, 0.0))
    # G = Sigma_t^-1 C: E[n.e_{t-1} | e_t = y] = (G n).y; the residual Lambda = Sigma_{t-1} - Cᵀ G
    C00, C01, C10, C11 = float(C[0, 0]), float(C[0, 1]), float(C[1, 0]), float(C[1, 1])
    G00, G01 = (c * C00 - b * C10) / det, (c * C01 - b * C11) / det
    G10, G11 = (a * C10 - b * C00) / det, (a * C11 - b * C01) / det
    L00 = ap - (C00 * G00 + C10 * G10)
    L01 = bp - (C00 * G01 + C10 * G11)
    L11 = cpp - (C01 * G01 + C11 * G11)
    scale = WIDTH / (2.0 * math.pi * math.sqrt(det))
    support = np.full(K, -1.0)
    out = escape
    for k in range(K):
        best = masses[k]
        if best >= SIGNIFICANT * total:
            # of the normals around the wall's foot, the one where the previous step's safe side
            # ends nearest the sector's reach, in standard deviations of n.e_{t-1} given e_t
            foot, pick, z_pick, c_pick, s_pick = _foot(R, k), -1, math.inf, 0.0, 0.0
            for o in (-1, 0, 1, 2):
                n = (foot + o) % K
                nx, ny = float(EDGE_COS[n]), float(EDGE_SIN[n])
                gx, gy = G00 * nx + G01 * ny, G10 * nx + G11 * ny
                lo = min(gx * EDGE_COS[k] + gy * EDGE_SIN[k], gx * EDGE_COS[k + 1] + gy * EDGE_SIN[k + 1])
                if lo <= 0.0:
                    continue
                if support[n] < 0.0:
                    support[n] = _support(Rp, ball, n)
                s = math.sqrt(max(L00 * nx * nx + 2.0 * L01 * nx * ny + L11 * ny * ny, 0.0))
                gap = float(support[n]) - float(lo) * float(R[k])
                z = gap / s if s > 0.0 else (math.inf if gap > 0.0 else -math.inf)
                if pick < 0 or z < z_pick:
                    pick, z_pick, c_pick, s_pick = n, z, float(lo), s
            if pick >= 0:
                tail = best * qs[k] / scale  # exp(-R_k² q_k / 2)
                best = min(best, scale * _passage(float(R[k]), qs[k], c_pick, float(support[pick]), s_pick, tail))
        out += best
    return min(p, out)


def _sector_masses(
    a: float, b: float, c: float, det: float, lam: float, R: np.ndarray
) -> tuple[list[float], list[float]]:
    """The sector terms m_k of :func:`step_bound` and each sector's least q_k, one at a time."""
    K = R.shape[0]
    major = 0.5 * math.atan2(2.0 * b, a - c)
    root = math.sqrt(det)
    s0, c0 = float(EDGE_SIN[0]), float(EDGE_COS[0])
    q0 = (a * s0 * s0 - 2.0 * b * s0 * c0 + c * c0 * c0) / det
    masses, qs = [], []
    for k in range(K):
        s1, c1 = float(EDGE_SIN[k + 1]), float(EDGE_COS[k + 1])
        q1 = (a * s1 * s1 - 2.0 * b * s1 * c1 + c * c1 * c1) / det
        q = 1.0 / lam if (major - WIDTH * k) % math.pi <= WIDTH else min(q0, q1)
        masses.append(WIDTH * math.exp(-float(R[k]) * float(R[k]) * q / 2.0) / (2.0 * math.pi * root * q))
        qs.append(q)
        q0 = q1
    return masses, qs


def _foot(R: np.ndarray, k: int) -> int:
    """The sector where the reach, followed downhill from sector k (at most a quarter turn), is
    least, or the middle one of a level stretch there: the foot of the wall that sector k looks
    at (a wall's nearest cells give a level stretch of reach around its normal)."""
    K = R.shape[0]
    at = k
    if min(R[(k - 1) % K], R[(k + 1) % K]) < R[k]:
        step = -1 if R[(k - 1) % K] < R[(k + 1) % K] else 1
        for _ in range(K // 4):
            nxt = (at + step) % K
            if R[nxt] > R[at]:
                break
            at = nxt
    lo, hi = at, at
    for _ in range(K // 4):
        if R[(lo - 1) % K] != R[at]:
            break
        lo = (lo - 1) % K
    for _ in range(K // 4):
        if R[(hi + 1) % K] != R[at]:
            break
        hi = (hi + 1) % K
    return (lo + ((hi - lo) % K + 1) // 2) % K


def _support(Rp: np.ndarray, ball: float, n: int) -> float:
    """b(n): how far the star of reaches ``Rp`` cut to the ball of radius ``ball`` reaches along
    edge n's direction: max over the sectors of min(R_i, ball) times the cos of the angle from
    edge n to the sector's nearer edge (sectors a quarter turn away or more reach nothing)."""
    K = Rp.shape[0]
    out = 0.0
    for o in range(-(K // 4), K // 4):
        i = (n + o) % K
        d = o if o >= 0 else -o - 1
        out = max(out, min(float(Rp[i]), ball) * float(CONE_COS[d]))
    return out


def _passage(R: float, q: float, c: float, b: float, s: float, tail: float) -> float:
    """I = int_R^inf rho exp(-q rho²/2) Phi((b - c rho)/s) d rho (c > 0; s = 0: Phi a step);
    ``tail`` is exp(-q R²/2).

    By parts: (exp(-q R²/2) Phi((b - c R)/s) - c/(s sqrt(P)) exp(-q b²/(2 (q s² + c²)))
    Q(sqrt(P) (R - m))) / q, with P = q + c²/s² and m = b c / (s² P); Q = 1 - Phi."""
    if s <= 0.0 or c > 1e8 * s:
        top = max(R, b / c)
        return max(tail - math.exp(-q * top * top / 2.0), 0.0) / q
    z = c / s
    P = q + z * z
    m = b * z / (s * P)
    first = tail * 0.5 * math.erfc((c * R - b) / (s * SQRT2))
    second = z / math.sqrt(P) * math.exp(-q * b * b / (2.0 * (q * s * s + c * c)))
    second *= 0.5 * math.erfc(math.sqrt(P) * (R - m) / SQRT2)
    return max(first - second, 0.0) / q


# ---------------------------------------------------------------- a move, a plan


def step_bounds(
    positions: np.ndarray, covs: np.ndarray, grid: OccupancyGrid, radius: float, clear: np.ndarray | None = None
) -> np.ndarray:
    """The per-step bounds p_t along a path: positions (T+1, 2) m, covariances (T+1, 3, 3) or
    (T+1, 2, 2) -> (T+1,) (entry 0 is the start)."""
    table = SectorReach(grid, clearance(grid) if clear is None else clear, radius)
    return step_bound(np.asarray(covs, dtype=float)[..., :2, :2], table.at(np.asarray(positions, dtype=float)))


def move_bound(
    positions: np.ndarray,
    covs: np.ndarray,
    cross: np.ndarray,
    grid: OccupancyGrid,
    radius: float,
    clear: np.ndarray | None = None,
    hazard: float = 0.0,
) -> float:
    """P_move = min(1, min(p_1, p_0 + X_1) + sum_{t=2..T} X_t): an upper bound on the probability
    that the robot hits a wall at any of the move's control steps (first passage: the first hit
    is at step 1, or at a step t whose step before was free).

    positions: (T+1, 2) nominal positions, the start first (a (T+1, 3) pose array is cut to them);
    covs: (T+1, 3, 3) or (T+1, 2, 2) covariances at the same steps; cross: (T+1, 2, 2)
    Cov(e_t, e_{t-1}) of the position errors (row 0 unused); radius: m; ``hazard``: the
    localiser's failures per metre driven, each step's share f_t = hazard |mu_t - mu_{t-1}|
    added to its p_t and X_t (:func:`failure_shares`).
    """
    table = SectorReach(grid, clearance(grid) if clear is None else clear, radius)
    positions = np.asarray(positions, dtype=float)[..., :2]
    reach = table.at(positions)
    covs = np.asarray(covs, dtype=float)[..., :2, :2]
    return first_passage(covs, np.asarray(cross, dtype=float), reach, failure_shares(positions, hazard))


def step_lengths(positions: np.ndarray) -> np.ndarray:
    """|mu_t - mu_{t-1}| (T,) m of each step t = 1..T along positions (T+1, 2) (a pose array is cut to them)."""
    positions = np.asarray(positions, dtype=float)[..., :2]
    return np.hypot(*np.diff(positions, axis=0).T)


def failure_shares(positions: np.ndarray, hazard: float) -> np.ndarray:
    """f_t = hazard |mu_t - mu_{t-1}| of each step t = 1..T (T,) along nominal positions (T+1, 2):
    the chance that the localiser fails (a Poisson rate ``hazard`` per metre driven) on that
    step, at most its length times the rate (docs/models.md, "Localisation failures")."""
    return hazard * step_lengths(positions)


def first_passage(covs: np.ndarray, cross: np.ndarray, reach: np.ndarray, fail: np.ndarray | None = None) -> float:
    """min(1, min(p_1, p_0 + X_1) + sum_{t>=2} X_t) of an error with covariances ``covs`` (T+1,
    2, 2), cross-covariances ``cross`` (T+1, 2, 2; row 0 unused) and sector reach ``reach`` (T+1,
    K) at each step; ``fail`` (T,): each step's localisation failure share, added to its p_t and
    X_t. The first-passage sum of :func:`move_bound` (and of two robots' passing bound)."""
    if covs.shape[0] < 2:
        return 0.0
    p = step_bound(covs, reach)
    x = crossing_bound(covs[:-1], covs[1:], cross[1:], reach[:-1], reach[1:])
    if fail is not None:
        p = np.concatenate([p[:1], np.minimum(1.0, p[1:] + fail)])
        x = x + fail
    return float(min(1.0, min(p[1], p[0] + x[0]) + math.fsum(x[1:])))


def local_errors(steps: int, var: float, rho: float) -> tuple[np.ndarray, np.ndarray]:
    """The error the bound prices where a robot keeps clear of the walls its lidar sees
    (ScanModel.local_walls): a stationary Gauss-Markov process e_t = rho e_{t-1} + w_t, isotropic,
    of variance ``var`` per axis -> its covariances (steps, 2, 2), var I, and the cross-covariances
    Cov(e_t, e_{t-1}) (steps, 2, 2), rho var I, as :func:`move_bound` takes them."""
    eye = np.broadcast_to(np.eye(2), (steps, 2, 2))
    return var * eye, rho * var * eye


def running_bound(terms: np.ndarray, drove: np.ndarray) -> np.ndarray:
    """A robot's collision bound summed over the rows it drove into, as the kernel sums it:
    ``terms`` (h+1, 2) holds p_t and X_t of each row (the kernel's ``step_risk``), ``drove``
    (h+1,) whether the robot drove into each row (row 0: whether it drove into the row before
    the first). Row t adds X_t after a row it drove into, min(p_t, p_{t-1} + X_t) after one it
    stood in (a move's first step), 0 where it stands -> (h+1,) running sums, 0 at row 0."""
    p, x = terms[:, 0], terms[:, 1]
    first = np.minimum(p[1:], p[:-1] + x[1:])
    add = np.where(drove[1:], np.where(drove[:-1], x[1:], first), 0.0)
    return np.concatenate([[0.0], np.cumsum(add)])


def plan_bound(moves: list[float]) -> float:
    """A plan's bound: min(1, sum of its moves' bounds) (Boole's inequality over the moves)."""
    return float(min(1.0, math.fsum(moves)))
