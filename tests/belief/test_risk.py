"""The collision bound's parts (belief/risk.py) against Monte Carlo: one step, two steps, one instant
of two robots; and the small rules around them.

One step: the step bound p_t against sampled positions near the walls of a corridor. Two steps:
the crossing bound X_t against sampled pairs (e_{t-1}, e_t) of a Gauss-Markov error, near the
walls and door frames of a corridor with a door, in seeded random cases (the bound is a theorem
under that assumption: a case below its rate would be a bug). Whole paths are tested in
tests/belief/test_monte_carlo.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.belief import risk_paths
from tmpnav.belief import intervals, pair_risk, risk
from tmpnav.world.grid import clearance
from tmpnav.world.reach import REACH, SECTORS, SectorReach

RADIUS = 0.2  # m
#: name -> (grid, waypoints) of the paths driven without observations (risk_paths.OPEN_LOOP):
#: a corridor 1.4 m wide, and an L (tests/world/test_reach.py samples their reach too)
PATHS = {name.removeprefix("open-"): (grid, list(points[0])) for name, (grid, points) in risk_paths.OPEN_LOOP.items()}
STRAIGHT, CORNER = PATHS["straight"][0], PATHS["corner"][0]
DOOR = risk_paths.path("door").grid  # a corridor and a room, a door 0.9 m wide between them


def _factor(cov: np.ndarray) -> np.ndarray:
    w, V = np.linalg.eigh(0.5 * (cov + cov.T))
    return V * np.sqrt(np.maximum(w, 0.0))


# ---------------------------------------------------------------- one step


# ---------------------------------------------------------------- one step


def test_a_step_without_reach_is_certain_to_be_bounded_by_one() -> None:
    cov = np.diag([1e-6, 1e-6])
    assert risk.step_bound(cov, np.zeros(SECTORS)) == 1.0
    assert risk.step_bound(cov, np.r_[1.0, np.zeros(SECTORS - 1)]) == 1.0  # one sector touches
    reach = np.stack([np.zeros(SECTORS), np.full(SECTORS, 1e-9), np.ones(SECTORS)])
    assert np.all(risk.step_bound(np.zeros((3, 2, 2)), reach) == [1.0, 0.0, 0.0])


@pytest.mark.parametrize("sigma", [0.05, 0.08, 0.12])
def test_one_step_near_a_wall_against_sampling(sigma: float) -> None:
    """One step 0.4 m from the straight corridor's wall cells (0.225 m from the cells where the
    footprint hits), isotropic: the step bound alone against 200,000 samples, and against the
    exact half-plane probability Q(0.225 / sigma) (the nearest wall is straight)."""
    from scipy.stats import norm

    grid = STRAIGHT
    clear = clearance(grid)
    mu, cov = np.array([3.025, 0.525]), sigma**2 * np.eye(2)
    x = mu + sigma * np.random.default_rng(3).standard_normal((200_000, 2))
    hits = int(risk.hits_wall(grid, clear, x, RADIUS).sum())
    bound = float(risk.step_bound(cov, SectorReach(grid, clear, RADIUS).at(mu)))
    exact = float(norm.sf(0.225 / sigma))
    assert hits / x.shape[0] <= bound and exact <= bound <= 3.0 * exact


def test_a_step_with_zero_covariance_never_hits() -> None:
    grid = STRAIGHT
    mu = np.array([[3.0, 0.8], [3.0, 0.5]])
    reach = SectorReach(grid, clearance(grid), RADIUS).at(mu)
    assert np.all(reach > 0.0)
    assert np.all(risk.step_bound(np.zeros((2, 3, 3)), reach) == 0.0)


def test_with_the_same_reach_all_round_an_isotropic_step_is_the_chi_square_tail() -> None:
    """The sectors' sum of an isotropic Sigma and equal R_k is exp(-R² / (2 sigma²)), the disc's:
    q = 1/sigma² everywhere. For an anisotropic one the sectors' is the smaller, and still at
    least the sampled P(||e|| >= R)."""
    reach = np.full(SECTORS, 0.3)
    assert risk.step_bound(0.01 * np.eye(2), reach) == pytest.approx(math.exp(-0.09 / 0.02), rel=1e-12)
    cov = np.array([[0.02, 0.01], [0.01, 0.01]])
    lam = np.linalg.eigvalsh(cov)[-1]
    assert risk.lambda_max(cov) == pytest.approx(lam, rel=1e-12)
    bound = float(risk.step_bound(cov, reach))
    e = np.random.default_rng(4).multivariate_normal(np.zeros(2), cov, 200_000)
    outside = int((np.hypot(*e.T) >= 0.3).sum())
    assert intervals.clopper_pearson(outside, e.shape[0])[1] <= bound < math.exp(-0.09 / (2 * lam))


@pytest.mark.parametrize("sigma", [(0.1, 0.1), (0.05, 0.2), (0.2, 0.05)])
@pytest.mark.parametrize("normal", [0.0, 0.7, 2.0])
def test_facing_one_wall_the_sectors_give_the_half_plane_probability(sigma: tuple[float, float], normal: float) -> None:
    """A wall (a half-plane) at distance d along ``normal`` (sigma[0] along the normal, sigma[1]
    along the wall): R_k is the least distance to it within sector k (REACH where it is farther).
    Then the sum over sectors is at least the exact probability of the half-plane,
    P(n . e > d) = Phi(-d / sigma_n), and close to it: as the sectors narrow it is Craig's
    formula for the Gaussian tail (docs/models.md)."""
    from scipy.stats import norm

    d = 2.33 * sigma[0]  # the exact probability near 0.01
    w = 2 * math.pi / SECTORS
    edges = w * np.arange(SECTORS + 1)
    off = np.mod(np.stack([edges[:-1], edges[1:]], -1) - normal + math.pi, 2 * math.pi) - math.pi
    nearest = np.where(off[:, 0] * off[:, 1] <= 0, 0.0, np.minimum(abs(off[:, 0]), abs(off[:, 1])))
    facing = (np.abs(off) < math.pi / 2).all(axis=1) | (off[:, 0] * off[:, 1] <= 0)
    with np.errstate(divide="ignore"):
        reach = np.where(facing, np.minimum(d / np.cos(np.minimum(nearest, 1.5707)), REACH), REACH)
    rot = np.array([[math.cos(normal), -math.sin(normal)], [math.sin(normal), math.cos(normal)]])
    cov = rot @ np.diag(np.square(sigma)) @ rot.T
    exact = float(norm.sf(d / sigma[0]))  # sigma[0] lies along the normal
    bound = float(risk.step_bound(cov, reach))
    assert exact <= bound <= (1.3 if sigma[0] == sigma[1] else 3.0) * exact


def test_margins_follow_the_clearance_and_are_minus_infinity_off_the_grid() -> None:
    grid = STRAIGHT
    clear = clearance(grid)
    mu = np.array([[3.01, 0.51], [-1.0, 0.5], [3.0, 1.55]])  # a free cell, off the grid, a wall cell
    d = risk.margins(grid, mu, RADIUS, clear)
    i, j, _ = grid.cells(mu[0])
    assert d[0] == pytest.approx(clear[i, j] - RADIUS - math.sqrt(2) * risk_paths.RES)
    assert d[1] == -math.inf and d[2] < 0.0
    assert list(risk.hits_wall(grid, clear, mu, RADIUS)) == [False, True, True]


def test_no_point_within_the_margin_hits_a_wall() -> None:
    """The lemma behind the margin: ||x - mu|| < d(mu) implies C[cell(x)] > r, at every free cell
    of the corner, for points all around the disc of radius d."""
    grid = CORNER
    clear = clearance(grid)
    rng = np.random.default_rng(1)
    mu = rng.uniform((0.0, 0.0), (3.6, 4.0), (4000, 2))
    d = risk.margins(grid, mu, RADIUS, clear)
    mu, d = mu[d > 0], d[d > 0]
    angle = rng.uniform(0, 2 * np.pi, (mu.shape[0], 64))
    reach = d[:, None] * np.sqrt(rng.uniform(0.0, 1.0, angle.shape)) * 0.999999
    x = mu[:, None, :] + reach[..., None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    assert not risk.hits_wall(grid, clear, x, RADIUS).any()


# ---------------------------------------------------------------- two steps


def _two_steps(rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """A random step near the door's walls and frames: nominal positions mu_{t-1}, mu_t (both
    free, 0.05-0.6 m from the walls' footprint), Sigma_{t-1}, and the error's transition
    e_t = A e_{t-1} + nu, nu ~ N(0, N): a drive (A near I), a turn on the spot (A = I, N = 0), or
    an update (A shrinks the error)."""
    clear = clearance(DOOR)
    while True:
        mu_prev = rng.uniform((0.3, 0.3), (9.7, 5.8))
        mu = mu_prev + rng.uniform(-0.3, 0.3, 2) * (rng.random() < 0.8)
        margins = risk.margins(DOOR, np.stack([mu_prev, mu]), RADIUS, clear)
        if np.all((margins > 0.05) & (margins < 0.6)):
            break
    L = rng.normal(0.0, 1.0, (2, 2)) * rng.uniform(0.02, 0.15)
    cov_prev = L @ L.T + 1e-4 * np.eye(2)
    kind = rng.integers(3)
    if kind == 1:
        return mu_prev, mu, cov_prev, np.eye(2), np.zeros((2, 2))
    A = np.eye(2) + rng.normal(0.0, 0.05, (2, 2)) if kind == 0 else rng.uniform(0.3, 0.9) * np.eye(2)
    M = rng.normal(0.0, 1.0, (2, 2)) * rng.uniform(0.005, 0.05)
    return mu_prev, mu, cov_prev, A, M @ M.T


@pytest.mark.parametrize("seed", range(24))
def test_a_step_s_crossing_bound_is_never_below_its_sampled_rate(seed: int) -> None:
    """X_t against P(no hit at t-1, a hit at t) sampled from the Gauss-Markov pair, near the
    walls and door frames; X_t never above p_t."""
    rng = np.random.default_rng(seed)
    mu_prev, mu, cov_prev, A, N = _two_steps(rng)
    cov, cross = A @ cov_prev @ A.T + N, A @ cov_prev
    table = SectorReach(DOOR, clearance(DOOR), RADIUS)
    reach_prev, reach = table.at(mu_prev), table.at(mu)
    x = float(risk.crossing_bound(cov_prev, cov, cross, reach_prev, reach))
    p = float(risk.step_bound(cov, reach))
    e_prev = rng.standard_normal((200_000, 2)) @ _factor(cov_prev).T
    e = e_prev @ A.T + rng.standard_normal((200_000, 2)) @ _factor(N).T
    clear = clearance(DOOR)
    crossed = ~risk.hits_wall(DOOR, clear, mu_prev + e_prev, RADIUS) & risk.hits_wall(DOOR, clear, mu + e, RADIUS)
    assert crossed.mean() <= x <= p


def test_standing_still_less_crosses_and_independent_steps_cross_as_often_as_they_hit() -> None:
    """The same pose and error at both steps (a turn on the spot): X_t below p_t, though not 0
    (the sectors' edges: docs/models.md). Independent errors (no cross-covariance): X_t near
    p_t, as Boole's inequality counts the step."""
    mu = np.array([3.0, 0.6])
    cov = np.diag([0.01, 0.02])
    reach = SectorReach(DOOR, clearance(DOOR), RADIUS).at(mu)
    p = float(risk.step_bound(cov, reach))
    frozen = float(risk.crossing_bound(cov, cov, cov, reach, reach))
    independent = float(risk.crossing_bound(cov, cov, np.zeros((2, 2)), reach, reach))
    assert p > 0.01 and frozen < 0.8 * p and 0.9 * p <= independent <= p


def test_without_reach_the_crossing_is_the_step_bound() -> None:
    cov, reach = 0.01 * np.eye(2), np.full(SECTORS, 0.3)
    none = np.r_[0.0, np.full(SECTORS - 1, 0.3)]
    assert risk.crossing_bound(cov, cov, cov, reach, none) == 1.0
    assert risk.crossing_bound(cov, cov, cov, none, reach) == risk.step_bound(cov, reach)
    assert risk.crossing_bound(cov, cov, cov, reach, np.full(SECTORS, 5.0)) == risk.step_bound(
        cov, np.full(SECTORS, 5.0)
    )


def test_a_move_is_its_first_step_and_its_crossings_and_stops_at_one() -> None:
    positions = np.array([[3.0, 0.3], [3.0, 0.5], [3.1, 0.5], [3.2, 0.5]])  # the start has no margin
    covs = np.repeat(np.diag([0.004, 0.004])[None], 4, axis=0)
    cross = 0.9 * covs
    table = SectorReach(STRAIGHT, clearance(STRAIGHT), RADIUS)
    reach = table.at(positions)
    p = risk.step_bound(covs, reach)
    x = risk.crossing_bound(covs[:-1], covs[1:], cross[1:], reach[:-1], reach[1:])
    assert p[0] == 1.0 and 0.0 < p[1] < 0.5 and np.all(x <= p[1:])
    move = risk.move_bound(positions, covs, cross, STRAIGHT, RADIUS)
    assert move == pytest.approx(min(p[1], p[0] + x[0]) + x[1] + x[2]) and move < p[1:].sum()
    assert risk.move_bound(positions, 100 * covs, 0 * cross, STRAIGHT, RADIUS) == 1.0  # independent steps
    assert risk.move_bound(positions[:1], covs[:1], cross[:1], STRAIGHT, RADIUS) == 0.0
    assert risk.plan_bound([0.2, 0.3]) == pytest.approx(0.5) and risk.plan_bound([0.7, 0.6]) == 1.0


# ---------------------------------------------------------------- two robots


def test_k_of_delta() -> None:
    assert risk.k_of(1.0) == 0.0
    assert risk.k_of(0.01) == pytest.approx(math.sqrt(2 * math.log(100)))
    assert math.exp(-(risk.k_of(0.05) ** 2) / 2) == pytest.approx(0.05)
    with pytest.raises(ValueError):
        risk.k_of(0.0)


@pytest.mark.parametrize("correlation", [-0.9, 0.0, 0.9])
@pytest.mark.parametrize("delta", [0.01, 0.1, 0.3])
def test_robots_at_the_separation_touch_at_most_delta(delta: float, correlation: float) -> None:
    """Two robots whose positions are correlated Gaussians (anisotropic, with a cross-covariance
    of either sign), their means the separation apart: the sampled touching rate is at most delta."""
    cov_i = np.array([[0.010, 0.004], [0.004, 0.006]])
    cov_j = np.array([[0.003, -0.001], [-0.001, 0.008]])
    si, sj = float(risk.position_std(cov_i)), float(risk.position_std(cov_j))
    s = pair_risk.separation(delta, 0.25, 0.3, si, sj)
    mu_i, mu_j = np.array([1.0, 2.0]), np.array([1.0, 2.0]) + s * np.array([0.6, 0.8])
    cross = correlation * _factor(cov_i) @ _factor(cov_j).T  # a valid joint covariance for |c| <= 1
    joint = np.block([[cov_i, cross], [cross.T, cov_j]])
    x = np.random.default_rng(2).multivariate_normal(np.concatenate([mu_i, mu_j]), joint, 100_000)
    touch = np.hypot(*(x[:, :2] - x[:, 2:]).T) < 0.25 + 0.3
    _, upper = intervals.clopper_pearson(int(touch.sum()), touch.size)
    assert pair_risk.pair_bound(mu_i, mu_j, cov_i, cov_j, 0.25, 0.3) == pytest.approx(delta)
    assert upper <= delta


@pytest.mark.parametrize("correlation", [-0.9, 0.0, 0.9])
@pytest.mark.parametrize("gap", [0.1, 0.25])
def test_the_contact_bound_of_the_relative_error_against_sampling(gap: float, correlation: float) -> None:
    """One instant, two correlated robots: the bound from the covariance of their relative
    position is at least the sampled touching rate, and within a few times it."""
    cov_i = np.array([[0.010, 0.004], [0.004, 0.006]])
    cov_j = np.array([[0.003, -0.001], [-0.001, 0.008]])
    cross = correlation * _factor(cov_i) @ _factor(cov_j).T
    rel = cov_i + cov_j - cross - cross.T
    mu_i, mu_j = np.array([1.0, 2.0]), np.array([1.0, 2.0]) + (0.55 + gap) * np.array([0.6, 0.8])
    joint = np.block([[cov_i, cross], [cross.T, cov_j]])
    x = np.random.default_rng(5).multivariate_normal(np.concatenate([mu_i, mu_j]), joint, 200_000)
    hits = int((np.hypot(*(x[:, :2] - x[:, 2:]).T) < 0.55).sum())
    bound = float(pair_risk.contact_bound(mu_i, mu_j, rel, 0.25, 0.3))
    assert hits >= 20 and hits / x.shape[0] <= bound <= 3.0 * hits / x.shape[0]
    assert bound < float(pair_risk.pair_bound(mu_i, mu_j, cov_i, cov_j, 0.25, 0.3))


def test_a_disc_s_reach_is_its_distance_in_every_sector_that_meets_it() -> None:
    reach = pair_risk.disc_reach(np.array([1.0, 0.0]), 0.5)  # the disc spans -30..30 degrees
    angles = (np.arange(SECTORS) + 0.5) * 2 * math.pi / SECTORS
    meets = np.abs(np.mod(angles + math.pi, 2 * math.pi) - math.pi) < math.pi / 6 - math.pi / SECTORS
    assert (
        reach[0] == pytest.approx(0.5)
        and np.all(reach[meets] >= 0.5)
        and np.all(reach[~meets & (angles > 1.0) & (angles < 5.0)] == REACH)
    )
    ray = np.hypot(np.cos(angles[2]) - 1.0, np.sin(angles[2]))  # a point of the disc's edge lies beyond reach[2]
    assert (reach[2] <= 1.0 and ray <= 0.5 + 1e-9) or reach[2] == REACH
    assert np.all(pair_risk.disc_reach(np.array([0.1, 0.0]), 0.5) == 0.0)


def test_robots_closer_than_their_radii_are_bounded_by_one_and_still_ones_never_touch() -> None:
    cov = np.diag([0.01, 0.01])
    assert pair_risk.pair_bound(np.zeros(2), np.array([0.4, 0.0]), cov, cov, 0.25, 0.25) == 1.0
    assert pair_risk.pair_bound(np.zeros(2), np.array([0.6, 0.0]), 0 * cov, 0 * cov, 0.25, 0.25) == 0.0


def test_clopper_pearson() -> None:
    assert intervals.clopper_pearson(0, 25) == (0.0, pytest.approx(0.1372, abs=1e-4))
    lo, hi = intervals.clopper_pearson(5, 100)
    assert (round(lo, 4), round(hi, 4)) == (0.0164, 0.1128)
    assert intervals.clopper_pearson(3, 3)[1] == 1.0
