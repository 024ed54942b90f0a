"""The collision bound (belief/risk.py) against Monte Carlo: it is never below the sampled rate.

Two small maps built in code: a straight corridor and an L-shaped corner, 5 cm cells. A robot
of radius 0.2 m drives along a wall, and around the corner's inner wall, by tmpnav's own
controls (``path_controls``) and EKF prediction without observations, at several noise levels
(the scenario's alphas and start covariance scaled together). True trajectories are sampled
four ways:

* ``independent``: x_k = mu_k + Sigma_k^(1/2) z_k, a fresh z at every step (the union bound's
  worst case: the steps fail independently);
* ``ar1``: the same marginals, z_k = rho z_{k-1} + sqrt(1 - rho²) xi_k correlated in time;
* ``walk``: the linearised error dynamics e_{k+1} = F_k e_k + V_k W_k^(1/2) w_k, a random walk
  whose marginals are exactly the EKF's Sigma_k;
* ``unicycle``: the nonlinear motion model with noisy controls, as ``tmpnav simulate`` moves a
  robot: the EKF's covariance is only an approximation of it (the bound's assumption, measured).

A case passes when the upper end of the sampled rate's 95% Clopper-Pearson interval is at most
the bound (and the rate itself when the bound is 1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from tmpnav.belief import ekf, risk
from tmpnav.belief.controls import PathControls, path_controls
from tmpnav.belief.models import motion, motion_jacobians, motion_noise_cov
from tmpnav.types import Belief
from tmpnav.world.grid import OccupancyGrid, clearance
from tmpnav.world.reach import REACH, SECTORS, SectorReach

RES = 0.05  # m per cell
RADIUS = 0.2  # m
DT = 0.1  # s
ALPHAS = (0.02, 0.0, 0.02, 0.01)  # scaled by the case's noise level
START_COV = np.diag([0.01, 0.01, 0.003])  # likewise
SAMPLES = 20_000


def grid_of(width: float, height: float, free: list[tuple[float, float, float, float]]) -> OccupancyGrid:
    """A grid occupied everywhere but the cells whose centres lie in the rectangles ``free``
    (x0, y0, x1, y1), m."""
    rows, cols = round(height / RES), round(width / RES)
    gx, gy = np.meshgrid((np.arange(cols) + 0.5) * RES, (np.arange(rows) + 0.5) * RES)
    occupied = np.ones((rows, cols), dtype=bool)
    for x0, y0, x1, y1 in free:
        occupied[(gx > x0) & (gx < x1) & (gy > y0) & (gy < y1)] = False
    return OccupancyGrid(occupied, (0.0, 0.0), RES)


STRAIGHT = grid_of(6.0, 1.6, [(0.1, 0.1, 5.9, 1.5)])  # a corridor 1.4 m wide
CORNER = grid_of(3.6, 4.0, [(0.1, 0.1, 3.3, 1.3), (2.1, 0.1, 3.3, 3.9)])  # east, then north
PATHS = {
    "straight": (STRAIGHT, [(0.5, 0.5), (5.5, 0.5)]),  # 0.4 m from the south wall's cells
    "corner": (CORNER, [(0.5, 0.5), (2.9, 0.5), (2.9, 3.5)]),  # 0.4 m from the outer walls, turning
    "inner": (CORNER, [(0.5, 0.85), (2.5, 0.85), (2.5, 3.5)]),  # around the inner corner (2.1, 1.3)
}


@dataclass(frozen=True)
class Drive:
    """A nominal drive and the EKF's covariances along it (no observations)."""

    grid: OccupancyGrid
    path: PathControls
    covs: np.ndarray  # (T+1, 3, 3)
    alphas: tuple[float, float, float, float]

    @property
    def bound(self) -> float:
        return risk.move_bound(self.path.poses, self.covs, self.grid, RADIUS)


def drive(case: str, noise: float) -> Drive:
    grid, points = PATHS[case]
    path = path_controls(np.array(points), 0.0, 0.5, 1.0, DT)
    alphas = (noise * ALPHAS[0], noise * ALPHAS[1], noise * ALPHAS[2], noise * ALPHAS[3])
    belief = Belief(path.poses[0].copy(), noise * START_COV)
    covs = [belief.cov]
    for u in path.controls:
        belief = ekf.predict(belief, u[None], DT, alphas)
        covs.append(belief.cov)
    return Drive(grid, path, np.array(covs), alphas)


def _chol(covs: np.ndarray) -> np.ndarray:
    """Cholesky factors of (..., n, n) PSD matrices (a zero variance stays zero)."""
    return np.linalg.cholesky(covs + 1e-15 * np.eye(covs.shape[-1]))


def sample(d: Drive, how: str, rng: np.random.Generator, n: int = SAMPLES) -> np.ndarray:
    """(n, T, 2) true positions after each control step, sampled as the module docstring says."""
    mu, T = d.path.poses, d.path.n_steps
    if how in ("independent", "ar1"):
        z = rng.standard_normal((n, T, 2))
        if how == "ar1":
            rho = 0.95
            for k in range(1, T):
                z[:, k] = rho * z[:, k - 1] + math.sqrt(1.0 - rho**2) * z[:, k]
        return mu[None, 1:, :2] + np.einsum("tij,ntj->nti", _chol(d.covs[1:, :2, :2]), z)
    if how == "walk":
        e = rng.standard_normal((n, 3)) @ _chol(d.covs[0]).T
        out = []
        for k in range(T):
            F, V = motion_jacobians(mu[k], d.path.controls[k], DT)
            w = rng.standard_normal((n, 2)) * np.sqrt(np.diag(motion_noise_cov(d.path.controls[k], d.alphas)))
            e = e @ F.T + w @ V.T
            out.append(mu[k + 1, :2] + e[:, :2])
        return np.stack(out, axis=1)
    x = mu[0] + rng.standard_normal((n, 3)) @ _chol(d.covs[0]).T  # unicycle
    out = []
    for u in d.path.controls:
        noisy = u + rng.standard_normal((n, 2)) * np.sqrt(np.diag(motion_noise_cov(u, d.alphas)))
        x = motion(x, noisy, DT)
        out.append(x[:, :2])
    return np.stack(out, axis=1)


def sampled_rate(d: Drive, how: str, seed: int = 0) -> tuple[float, float]:
    """The fraction of sampled trajectories with any step hitting a wall, and its 95% upper limit."""
    xs = sample(d, how, np.random.default_rng(seed))
    hits = int(risk.hits_wall(d.grid, clearance(d.grid), xs, RADIUS).any(axis=1).sum())
    return hits / xs.shape[0], risk.clopper_pearson(hits, xs.shape[0])[1]


#: (path, noise level) -> the bound as computed when this test was written (the informative
#: ones lie in (0.01, 0.5)); the sampled rates are in docs/models.md, "Collision bound". The
#: disc-only bound of stop 26 was 15 to 30 times larger (straight 0.04: 0.4643, corner 0.05:
#: 0.3816, inner 0.045: 0.9152)
CASES = {
    ("straight", 0.025): 0.0018,
    ("straight", 0.035): 0.0154,
    ("straight", 0.04): 0.0311,
    ("straight", 0.06): 0.1766,
    ("straight", 0.09): 0.6299,
    ("corner", 0.03): 0.0007,
    ("corner", 0.04): 0.0052,
    ("corner", 0.05): 0.0184,
    ("corner", 0.07): 0.0842,
    ("corner", 0.1): 0.2936,
    ("inner", 0.02): 0.0003,
    ("inner", 0.035): 0.0127,
    ("inner", 0.045): 0.0436,
    ("inner", 0.07): 0.2279,
}
HOW = ("independent", "ar1", "walk", "unicycle")


@pytest.mark.parametrize(("case", "noise"), list(CASES))
def test_the_bound_is_as_recorded(case: str, noise: float) -> None:
    assert drive(case, noise).bound == pytest.approx(CASES[(case, noise)], abs=5e-5)


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize(("case", "noise"), list(CASES))
def test_the_bound_is_never_below_the_sampled_rate(case: str, noise: float, how: str) -> None:
    d = drive(case, noise)
    rate, upper = sampled_rate(d, how)
    bound = d.bound
    assert rate <= bound
    if bound < 1.0:
        assert upper <= bound, f"{case} at noise {noise}, {how}: sampled {rate:.4f} (upper {upper:.4f}) > {bound:.4f}"


def test_some_cases_are_informative_and_some_hit() -> None:
    """The cases test something: bounds between 0.01 and 0.5 where walls are hit in samples."""
    informative = [(c, n) for (c, n), b in CASES.items() if 0.01 < b < 0.5]
    assert len(informative) >= 4
    assert sampled_rate(drive("straight", 0.04), "independent")[0] > 0.01


# ---------------------------------------------------------------- one step


def test_a_step_without_reach_is_certain_to_be_bounded_by_one() -> None:
    cov = np.diag([1e-6, 1e-6])
    assert risk.step_bound(cov, np.zeros(SECTORS)) == 1.0
    assert risk.step_bound(cov, np.r_[1.0, np.zeros(SECTORS - 1)]) == 1.0  # one sector touches
    reach = np.stack([np.zeros(SECTORS), np.full(SECTORS, 1e-9), np.ones(SECTORS)])
    assert np.all(risk.step_bound(np.zeros((3, 2, 2)), reach) == [1.0, 0.0, 0.0])


@pytest.mark.parametrize("sigma", [0.05, 0.08, 0.12])
def test_one_step_near_a_wall_against_sampling(sigma: float) -> None:
    """One step 0.4 m from the straight corridor's wall cells, isotropic: the step bound alone
    (no union over steps), against 200,000 samples."""
    grid, _ = PATHS["straight"]
    clear = clearance(grid)
    mu, cov = np.array([3.025, 0.525]), sigma**2 * np.eye(2)
    x = mu + sigma * np.random.default_rng(3).standard_normal((200_000, 2))
    hits = int(risk.hits_wall(grid, clear, x, RADIUS).sum())
    bound = float(risk.step_bound(cov, SectorReach(grid, clear, RADIUS).at(mu)))
    assert risk.clopper_pearson(hits, x.shape[0])[1] <= bound


def test_a_step_with_zero_covariance_never_hits() -> None:
    grid, _ = PATHS["straight"]
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
    assert risk.clopper_pearson(outside, e.shape[0])[1] <= bound < math.exp(-0.09 / (2 * lam))


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
    grid, _ = PATHS["straight"]
    clear = clearance(grid)
    mu = np.array([[3.01, 0.51], [-1.0, 0.5], [3.0, 1.55]])  # a free cell, off the grid, a wall cell
    d = risk.margins(grid, mu, RADIUS, clear)
    i, j, _ = grid.cells(mu[0])
    assert d[0] == pytest.approx(clear[i, j] - RADIUS - math.sqrt(2) * RES)
    assert d[1] == -math.inf and d[2] < 0.0
    assert list(risk.hits_wall(grid, clear, mu, RADIUS)) == [False, True, True]


def test_no_point_within_the_margin_hits_a_wall() -> None:
    """The lemma behind the margin: ||x - mu|| < d(mu) implies C[cell(x)] > r, at every free cell
    of the corner, for points all around the disc of radius d."""
    grid, _ = PATHS["corner"]
    clear = clearance(grid)
    rng = np.random.default_rng(1)
    mu = rng.uniform((0.0, 0.0), (3.6, 4.0), (4000, 2))
    d = risk.margins(grid, mu, RADIUS, clear)
    mu, d = mu[d > 0], d[d > 0]
    angle = rng.uniform(0, 2 * np.pi, (mu.shape[0], 64))
    reach = d[:, None] * np.sqrt(rng.uniform(0.0, 1.0, angle.shape)) * 0.999999
    x = mu[:, None, :] + reach[..., None] * np.stack([np.cos(angle), np.sin(angle)], -1)
    assert not risk.hits_wall(grid, clear, x, RADIUS).any()


def test_a_move_sums_its_steps_after_the_start_and_stops_at_one() -> None:
    grid, _ = PATHS["straight"]
    positions = np.array([[3.0, 0.3], [3.0, 0.5], [3.0, 0.5]])  # the start has no margin
    covs = np.repeat(np.diag([0.004, 0.004, 0.001])[None], 3, axis=0)
    p = risk.step_bounds(positions, covs, grid, RADIUS)
    assert p[0] == 1.0 and 0.0 < p[1] < 0.5
    assert risk.move_bound(positions, covs, grid, RADIUS) == pytest.approx(2 * p[1])
    assert risk.move_bound(positions, 100 * covs, grid, RADIUS) == 1.0
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
    s = risk.separation(delta, 0.25, 0.3, si, sj)
    mu_i, mu_j = np.array([1.0, 2.0]), np.array([1.0, 2.0]) + s * np.array([0.6, 0.8])
    cross = correlation * _chol(cov_i) @ _chol(cov_j).T  # a valid joint covariance for |c| <= 1
    joint = np.block([[cov_i, cross], [cross.T, cov_j]])
    x = np.random.default_rng(2).multivariate_normal(np.concatenate([mu_i, mu_j]), joint, 100_000)
    touch = np.hypot(*(x[:, :2] - x[:, 2:]).T) < 0.25 + 0.3
    _, upper = risk.clopper_pearson(int(touch.sum()), touch.size)
    assert risk.pair_bound(mu_i, mu_j, cov_i, cov_j, 0.25, 0.3) == pytest.approx(delta)
    assert upper <= delta


def test_robots_closer_than_their_radii_are_bounded_by_one_and_still_ones_never_touch() -> None:
    cov = np.diag([0.01, 0.01])
    assert risk.pair_bound(np.zeros(2), np.array([0.4, 0.0]), cov, cov, 0.25, 0.25) == 1.0
    assert risk.pair_bound(np.zeros(2), np.array([0.6, 0.0]), 0 * cov, 0 * cov, 0.25, 0.25) == 0.0


def test_clopper_pearson() -> None:
    assert risk.clopper_pearson(0, 25) == (0.0, pytest.approx(0.1372, abs=1e-4))
    lo, hi = risk.clopper_pearson(5, 100)
    assert (round(lo, 4), round(hi, 4)) == (0.0164, 0.1128)
    assert risk.clopper_pearson(3, 3)[1] == 1.0
