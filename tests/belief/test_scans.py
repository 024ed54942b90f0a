"""Range scans in the EKF: the compiled kernel against filterpy, and what a scan does to a belief."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.belief.support import DT, models, random_case
from tests.belief.test_kernel import assert_same_propagation
from tests.world.test_lidar import LIDAR
from tmpnav.belief.reference import propagate_reference
from tmpnav.belief.rollout import ObservationNoise, Rollout, propagate_rollout
from tmpnav.types import NAV2_AMCL, Belief, ScanModel
from tmpnav.world.grid import OccupancyGrid
from tmpnav.world.lidar import signed_distance
from tmpnav.world.scan_information import ScanInformation


def _with_scans(rng: np.random.Generator, rollout: Rollout) -> Rollout:
    """Random scan factors (n, T+1, 3, 3), some rank-deficient, some zero, repeated after arrival."""
    n, T1 = rollout.true_poses.shape[:2]
    scans = rng.normal(0.0, 1.0, (n, T1, 3, 3)) * rng.uniform(0.0, 30.0, (n, T1, 1, 1))
    scans[rng.random((n, T1)) < 0.3] = 0.0
    scans[..., 2, :] *= rng.random((n, T1, 1)) < 0.5
    for i in range(n):
        scans[i, rollout.active_steps[i] + 1 :] = scans[i, rollout.active_steps[i]]
    return replace(rollout, scans=scans)


#: the localiser models a scan may update with: every beam independent; nav2's AMCL (a scan per
#: update threshold, none standing) alone, and with the landmarks and partners fused too
LOCALISERS = (
    ScanModel(),
    NAV2_AMCL,
    replace(NAV2_AMCL, lidar_only=False),
    replace(NAV2_AMCL, prediction_noise=(0.2, 0.05, 0.3, 0.1)),  # predicting with AMCL's motion model
)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]), st.booleans(), st.sampled_from(LOCALISERS))
def test_kernel_matches_filterpy_with_range_scans(seed: int, n: int, ml: bool, localiser: ScanModel) -> None:
    rng = np.random.default_rng(seed)
    T, L = int(rng.integers(1, 12)), int(rng.integers(0, 3))
    belief, rollout, landmarks, noise = random_case(rng, n, T, L)
    rollout = _with_scans(rng, rollout)
    noise = ObservationNoise(noise.landmark, noise.mutual, rng.standard_normal((n, T + 1, 3)))
    m = replace(models(ml), range_sensor=replace(LIDAR, localiser=localiser))
    assert_same_propagation(
        propagate_rollout(belief, rollout, landmarks, m, noise),
        propagate_reference(belief, rollout, landmarks, m, noise),
    )


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_a_scan_never_adds_uncertainty_and_keeps_the_covariance_positive(seed: int) -> None:
    """Information never increases trace(Sigma); covariances stay symmetric positive semi-definite.
    (Maximum-likelihood mode: the means, hence the motion's Jacobians, do not depend on the scans.)"""
    rng = np.random.default_rng(seed)
    belief, rollout, landmarks, noise = random_case(rng, 2, 8, 0)
    rollout = replace(_with_scans(rng, rollout), mutual_visible=np.zeros_like(rollout.mutual_visible))
    with_scans = propagate_rollout(belief, rollout, landmarks, replace(models(True), range_sensor=LIDAR), noise)
    without = propagate_rollout(belief, rollout, landmarks, models(True, controller="rpp"), noise)  # same steps
    traces = np.trace(with_scans.covs, axis1=1, axis2=2)
    assert (traces <= np.trace(without.covs, axis1=1, axis2=2) + 1e-12).all()
    covs = with_scans.covs
    np.testing.assert_allclose(covs, np.swapaxes(covs, -1, -2), rtol=0, atol=1e-15)
    assert np.linalg.eigvalsh(covs).min() >= -1e-12


def corridor(length: float = 64.0, width: float = 2.0, res: float = 0.05) -> OccupancyGrid:
    """A straight corridor with no door, no feature: walls three cells thick all round."""
    rows, cols = round((width + 0.3) / res), round((length + 0.3) / res)
    occupied = np.zeros((rows, cols), dtype=bool)
    occupied[:3], occupied[-3:], occupied[:, :3], occupied[:, -3:] = True, True, True, True
    return OccupancyGrid(occupied, (0.0, 0.0), res)


def corridor_stds(
    length: float = 64.0, localiser: ScanModel | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A robot driving the corridor's length at 0.5 m/s with a 12 m lidar (localised as
    ``localiser`` says, else every beam independent): its x (m) and its position std along and
    across the corridor at every step (tmpnav's kernel, max-likelihood)."""
    grid = corridor(length)
    lidar = LIDAR if localiser is None else replace(LIDAR, localiser=localiser)
    table = ScanInformation(grid, signed_distance(grid), lidar)
    y = grid.extent[3] / 2
    T = int((length - 4.0) / (0.5 * DT))
    x = 2.0 + 0.5 * DT * np.arange(T + 1)
    poses = np.column_stack([x, np.full(T + 1, y), np.zeros(T + 1)])
    rows = table.rows(table.keys(poses))
    G = table.table[rows]
    controls = np.tile([0.5, 0.0], (1, T, 1))
    rollout = Rollout(
        controls, poses[None], np.array([T]), np.zeros((1, T + 1, 0), bool), np.zeros((1, 1, T + 1), bool), G[None]
    )
    m = replace(models(max_likelihood=True), range_sensor=lidar)
    belief = Belief(poses[0].copy(), np.diag([0.01, 0.01, 0.001]))
    run = propagate_rollout(belief, rollout, np.zeros((0, 2)), m)
    return x, np.sqrt(run.covs[:, 0, 0]), np.sqrt(run.covs[:, 1, 1])


def test_a_featureless_corridor_pins_the_robot_across_not_along() -> None:
    """60 m of corridor with no feature, a 12 m lidar: across the corridor the robot stays within
    centimetres; along it, once both ends are out of range, its uncertainty grows (the scan sees
    nothing along parallel walls) until the far end comes into range."""
    x, along, across = corridor_stds()
    assert across.max() <= 0.1 and across[1:].max() < 0.01
    middle = (x > 14.5) & (x < 49.5)  # both ends farther than the range
    assert along[middle][-1] > 5 * along[1] and np.all(np.diff(along[middle]) > 0)
    assert along[-1] < along[middle][-1] / 5  # the far end in range again


def test_nav2s_alphas_are_the_control_noise_of_its_odometry_model() -> None:
    """prediction_noise takes nav2's alpha1-4; per control step (d_trans = v dt, d_rot = w dt)
    nav2's odometry model draws the translation with variance alpha3 d_trans² + alpha4 d_rot²
    and the rotation with alpha1 d_rot² + alpha2 d_trans²: W(u) = diag(alpha3 v² + alpha4 w²,
    alpha2 v² + alpha1 w²). Without it, and for the beam model, the robot's own noise."""
    from tmpnav.belief.models import motion_noise_cov

    own = (0.01, 0.0, 0.02, 0.01)
    amcl = replace(NAV2_AMCL, prediction_noise=(0.2, 0.05, 0.3, 0.1))
    v, w, dt = 0.5, 0.4, DT
    W = motion_noise_cov(np.array([[v, w]]), amcl.belief_noise(own))[0] * dt**2
    assert W[0, 0] == pytest.approx(0.3 * (v * dt) ** 2 + 0.1 * (w * dt) ** 2)
    assert W[1, 1] == pytest.approx(0.2 * (w * dt) ** 2 + 0.05 * (v * dt) ** 2)
    assert NAV2_AMCL.belief_noise(own) == (0.03, 0.03, 0.03, 0.03)  # the default: the fitted alphas
    assert replace(NAV2_AMCL, prediction_noise=None).belief_noise(own) == own
    assert replace(ScanModel(), prediction_noise=(0.2, 0.2, 0.2, 0.2)).belief_noise(own) == own
    m = replace(models(), range_sensor=replace(LIDAR, localiser=amcl))
    assert m.belief_noise == (0.3, 0.1, 0.05, 0.2) and m.motion_noise == models().motion_noise


def test_the_prediction_noise_spreads_the_belief_along_a_corridor_not_across() -> None:
    """Predicting with nav2's alphas (0.2 each, the rate AMCL's particle cloud spreads at) or the
    fitted default (0.03 each) instead of a robot's odometry noise (0.01 each), the belief along a
    featureless corridor ends wider, the wider the larger the alphas, while across it the scans
    hold it within a few centimetres."""
    middle = None
    stds = {}
    odometry, nav2 = (0.01, 0.01, 0.01, 0.01), (0.2, 0.2, 0.2, 0.2)
    for name, alphas in (("odometry", odometry), ("fitted", NAV2_AMCL.prediction_noise), ("nav2", nav2)):
        x, along, across = corridor_stds(localiser=replace(NAV2_AMCL, prediction_noise=alphas))
        middle = (x > 14.5) & (x < 49.5)  # both ends farther than the range
        stds[name] = (along, across)
        assert across[middle].max() < 0.1
    for narrow, wide in (("odometry", "fitted"), ("fitted", "nav2")):
        (along, across), (along_w, across_w) = stds[narrow], stds[wide]
        assert along_w[middle][-1] > 1.5 * along[middle][-1]
        assert np.all(along_w >= along - 1e-12) and np.all(across_w >= across - 1e-12)  # more noise, never tighter


def test_the_amcl_models_belief_keeps_a_corridors_shape() -> None:
    """nav2's AMCL along a corridor: its error grows along it and stays at centimetres across it.
    The default AMCL model predicts that shape: along the corridor, once both ends are out of
    range, the belief is decimetres wide and many times wider than across it. With one small share
    of the likelihood field's information for every direction, no floor and the robot's own noise
    (the model before), it was as wide across the corridor as along it, within a factor of 2."""
    x, along, across = corridor_stds(localiser=NAV2_AMCL)
    middle = (x > 14.5) & (x < 49.5)
    assert np.all(along[middle] > 5 * across[middle]) and along[middle][-1] > 0.3
    assert across[middle].max() < 0.1
    flat = replace(NAV2_AMCL, information=0.000875, floor_beams=0.0, prediction_noise=None)
    _, along_flat, across_flat = corridor_stds(localiser=flat)
    assert np.all(along_flat[middle] < 2 * across_flat[middle]) and across_flat[middle].min() > 0.3
