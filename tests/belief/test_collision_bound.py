"""The collision bound as the compiled kernel computes it, and the oracle's choice under a threshold.

The bound itself (its validity against Monte Carlo) is tested in tests/belief/test_risk.py; here:
the kernel's p_t and X_t of every step equal the numpy reference's (tmpnav.belief.risk.step_bound
and crossing_bound, with the cross-covariances of the filter's error worked out in numpy), with
landmarks, partners and range scans; a move's bound is min(p_1, p_0 + X_1) + sum X_t over its
driving steps, the same from a restart; running_bound sums it the same way over any driving rows;
the oracle picks the cheapest instantiation within max_risk.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.belief import risk_paths
from tests.belief.test_kernel import _batch
from tmpnav.belief import risk
from tmpnav.belief.models import motion_jacobians
from tmpnav.belief.sequences import MotionArrays, propagate_sequences
from tmpnav.oracle.results import pick
from tmpnav.types import RISK_PENALTY, risk_penalty
from tmpnav.world.grid import clearance
from tmpnav.world.reach import SECTORS, SectorReach

#: a weak scan's information factor (J = Gᵀ G), so that the bounds stay informative
SCAN = np.array([[3.0, 1.0, 0.0], [0.0, 2.0, 0.5], [0.0, 0.0, 4.0]])


def _reach(margins: np.ndarray) -> np.ndarray:
    """(T+1, K) reach: each step's margin in the sectors facing +y (a wall along the path), far
    elsewhere, so that both the disc and the sectors decide some steps."""
    far = np.full((margins.shape[0], SECTORS), 0.8 if np.isfinite(margins).any() else np.inf)
    far[:, 4:12] = np.maximum(margins, 0.0)[:, None]
    return far


def _motion(T: int, L: int, margins: np.ndarray, turn: float = 0.0) -> MotionArrays:
    ctrl = np.column_stack([np.full(T, 0.5), np.full(T, turn)])
    poses = np.column_stack([0.1 * np.arange(T + 1), np.zeros(T + 1), np.zeros(T + 1)])
    vis = np.zeros((T + 1, L), dtype=bool)
    return MotionArrays.of([ctrl], [poses], [vis], np.zeros(1, dtype=np.int64), L, [_reach(margins)])


def _expected(means: np.ndarray, covs: np.ndarray, controls: np.ndarray, reach: np.ndarray) -> tuple[np.ndarray, ...]:
    """p_t, X_t and the move's bound of the reference along a drive without observations, where
    Cov(e_t, e_{t-1}) = F_t Sigma_{t-1}."""
    T = controls.shape[0]
    F = np.array([motion_jacobians(means[k], controls[k], 0.2)[0] for k in range(T)])
    cross = (F @ covs[:T])[:, :2, :2]
    p = risk.step_bound(covs[:, :2, :2], reach)
    x = risk.crossing_bound(covs[:T, :2, :2], covs[1:, :2, :2], cross, reach[:-1], reach[1:])
    return p, x, min(p[1], p[0] + x[0]) + x[1:].sum()


@pytest.mark.parametrize("low", [0.4, 0.1, 0.0, -0.2])
def test_the_kernel_computes_the_reference_step_by_step(low: float) -> None:
    T, L = 12, 2
    margins = np.linspace(0.6, low, T + 1)
    motion = _motion(T, L, margins, turn=0.2)
    out = propagate_sequences(_batch(motion, [0], [0], T, L))
    p, x, move = _expected(out.last_means, out.last_covs, motion.controls, _reach(margins))
    np.testing.assert_allclose(out.step_risk[:, 0, 0], p, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(out.step_risk[1:, 0, 1], x, rtol=1e-12, atol=1e-300)
    assert out.risk[0, 0] == pytest.approx(move, rel=1e-12)
    assert np.all(x <= p[1:]) and out.risk[0, 0] <= p[1:].sum() * (1.0 + 1e-12)  # never above Boole's


@pytest.mark.parametrize("scan", [False, True])
@pytest.mark.parametrize("name", ["corner", "door", "passing"])
def test_with_landmarks_partners_and_scans_the_kernel_computes_the_reference(name: str, scan: bool) -> None:
    """The cross-covariance the kernel carries through landmark, scan and mutual updates is the
    filter's error transition's (risk_paths.drive works it out in numpy)."""
    G = SCAN if scan else None
    d = risk_paths.drive(risk_paths.path(name), 1.0, G)
    out = propagate_sequences(risk_paths.kernel_batch(d, 1.0, scan=G))
    table = SectorReach(d.grid, clearance(d.grid), risk_paths.RADIUS)
    for i in range(d.poses.shape[0]):
        T, b = int(d.steps[i]), slice(3 * i, 3 * i + 2)
        reach = table.at(d.poses[i, : T + 1, :2])
        p = risk.step_bound(d.covs[: T + 1, b, b], reach)
        x = risk.crossing_bound(d.covs[:T, b, b], d.covs[1 : T + 1, b, b], d.cross(i)[1 : T + 1], reach[:-1], reach[1:])
        assert x.sum() > 1e-5  # informative
        np.testing.assert_allclose(out.step_risk[: T + 1, i, 0], p, rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(out.step_risk[1 : T + 1, i, 1], x, rtol=1e-9, atol=1e-15)
        move = risk.move_bound(
            d.poses[i, : T + 1], d.covs[: T + 1, b, b], d.cross(i)[: T + 1], d.grid, risk_paths.RADIUS
        )
        assert min(out.risk[0, i], 1.0) == pytest.approx(move, rel=1e-9)


def test_a_restart_from_a_shared_prefix_gives_the_same_bound() -> None:
    T, L = 10, 2
    margins = np.linspace(0.5, 0.1, T + 1)
    one = _motion(T, L, margins)
    two = MotionArrays.of(
        [one.controls, one.controls.copy()],
        [one.poses, one.poses.copy()],
        [one.lm_visible] * 2,
        np.zeros(2, dtype=np.int64),
        L,
        [_reach(margins)] * 2,
    )
    shared = propagate_sequences(_batch(two, [0, 1], [0, 6], T, L))
    alone = propagate_sequences(_batch(two, [1], [0], T, L))
    assert shared.risk[1, 0] == alone.risk[0, 0] > 0.0


def test_no_margins_no_bound_and_a_robot_that_waits_adds_nothing() -> None:
    T, L = 8, 2
    free = np.full(T + 1, np.inf)
    out = propagate_sequences(_batch(_motion(T, L, free), [0], [0], T, L))
    assert out.risk[0, 0] == 0.0
    short = _motion(4, L, np.linspace(0.3, 0.2, 5))
    out = propagate_sequences(_batch(short, [0], [0], T, L))  # drives 4 steps, then stands 4
    _, _, move = _expected(out.last_means[:5], out.last_covs[:5], short.controls, _reach(np.linspace(0.3, 0.2, 5)))
    assert out.risk[0, 0] == pytest.approx(move, rel=1e-12)
    assert np.all(out.step_risk[5:, 0] == 0.0)


def test_the_running_bound_starts_each_move_at_its_first_step() -> None:
    """Rows driven after a row stood in add min(p_t, p_{t-1} + X_t), rows after a driven row X_t."""
    terms = np.array([[0.1, 0.0], [0.2, 0.05], [0.3, 0.02], [0.4, 0.3], [0.05, 0.01], [0.06, 0.02]])
    drove = np.array([False, True, True, False, True, True])
    got = risk.running_bound(terms, drove)
    want = np.cumsum([0.0, min(0.2, 0.1 + 0.05), 0.02, 0.0, min(0.05, 0.4 + 0.01), 0.02])
    np.testing.assert_allclose(got, want)
    assert risk.running_bound(terms, np.r_[True, drove[1:]])[1] == pytest.approx(0.05)  # a move going on


def test_the_oracle_picks_the_cheapest_within_the_threshold_else_the_least_risky() -> None:
    cost = np.array([1.0, 2.0, 3.0, 4.0])
    risks = np.array([0.5, 0.04, 0.01, 0.01])
    assert pick(cost, risks, None) == 0
    assert pick(cost, risks, 0.05) == 1
    assert pick(cost, risks, 0.02) == 2
    assert pick(cost, risks, 0.001) == 2  # none within: the least risky, the cheaper of a tie
    pairs = np.array([[0.01, 0.2], [0.03, 0.03], [0.0, 0.0], [0.1, 0.0]])
    assert pick(cost, pairs, 0.05) == 1  # each robot's bound within it


def test_a_move_over_the_threshold_costs_more_than_any_plan_within_it() -> None:
    assert risk_penalty(0.3, None) == 0.0
    assert risk_penalty(0.05, 0.05) == 0.0
    assert risk_penalty(0.051, 0.05) == pytest.approx(RISK_PENALTY * 0.001)
    assert risk_penalty(0.05 + 1e-6, 0.05) > 1e5


@pytest.mark.parametrize("low", [0.3, 0.1, 0.0])
def test_against_the_walls_a_robot_sees_the_kernel_prices_the_local_error(low: float) -> None:
    """models.range_sensor.localiser.walls: local: the kernel's p_t and X_t are the reference's
    for the stationary Gauss-Markov error of risk.local_errors, whatever the belief (the move's
    beliefs are the same as without it), and the bound falls as local_std does."""
    T, L = 12, 2
    margins = np.linspace(0.6, low, T + 1)
    motion = _motion(T, L, margins, turn=0.2)
    batch = _batch(motion, [0], [0], T, L)
    var, rho = 0.04**2, 0.8
    local = propagate_sequences(replace(batch, ekf=batch.ekf._replace(local_var=var, local_rho=rho)))
    belief = propagate_sequences(batch)
    np.testing.assert_array_equal(local.last_covs, belief.last_covs)
    covs, cross = risk.local_errors(T + 1, var, rho)
    reach = _reach(margins)
    p = risk.step_bound(covs, reach)
    x = risk.crossing_bound(covs[:T], covs[1:], cross[1:], reach[:-1], reach[1:])
    np.testing.assert_allclose(local.step_risk[:, 0, 0], p, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(local.step_risk[1:, 0, 1], x, rtol=1e-12, atol=1e-300)
    assert local.risk[0, 0] == pytest.approx(min(p[1], p[0] + x[0]) + x[1:].sum(), rel=1e-12)
    tighter = propagate_sequences(replace(batch, ekf=batch.ekf._replace(local_var=0.02**2, local_rho=rho)))
    assert tighter.risk[0, 0] <= local.risk[0, 0]


@pytest.mark.parametrize("local", [False, True])
def test_the_localisers_failures_add_their_rate_along_the_path_driven(local: bool) -> None:
    """localiser.failure_rate: each driving step's p_t and X_t grow by hazard times its length
    (risk.failure_shares), so a move's bound by hazard times the path it drives; the kernel's
    are the reference's, the beliefs are untouched."""
    T, L, hazard = 12, 2, 2e-3
    margins = np.linspace(0.6, 0.1, T + 1)
    motion = _motion(T, L, margins, turn=0.2)
    batch = _batch(motion, [0], [0], T, L)
    if local:
        batch = replace(batch, ekf=batch.ekf._replace(local_var=0.04**2, local_rho=0.8))
    without = propagate_sequences(batch)
    out = propagate_sequences(replace(batch, ekf=batch.ekf._replace(hazard=hazard)))
    np.testing.assert_array_equal(out.last_covs, without.last_covs)
    f = risk.failure_shares(motion.poses[:, :2], hazard)
    np.testing.assert_allclose(f, hazard * 0.1)  # 0.1 m a step
    np.testing.assert_allclose(out.step_risk[1:, 0, 0], np.minimum(1.0, without.step_risk[1:, 0, 0] + f), rtol=1e-12)
    np.testing.assert_allclose(out.step_risk[1:, 0, 1], without.step_risk[1:, 0, 1] + f, rtol=1e-12)
    assert out.risk[0, 0] == pytest.approx(without.risk[0, 0] + hazard * 0.1 * T, rel=1e-9)
    drove = np.ones(T + 1, dtype=bool)
    drove[0] = False
    assert risk.running_bound(out.step_risk[:, 0], drove)[-1] == pytest.approx(out.risk[0, 0], rel=1e-12)
    if not local:  # the reference move bound takes the same rate
        p, x, _ = _expected(out.last_means, out.last_covs, motion.controls, _reach(margins))
        p, x = np.concatenate([p[:1], np.minimum(1.0, p[1:] + f)]), x + f
        assert out.risk[0, 0] == pytest.approx(min(p[1], p[0] + x[0]) + x[1:].sum(), rel=1e-12)
