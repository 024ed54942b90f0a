"""One rollout through the production kernel and through the filterpy reference, on a
small two-robot corridor scene."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tmpnav.belief.controls import path_controls
from tmpnav.belief.reference import propagate_reference
from tmpnav.belief.rollout import ObservationNoise, Rollout, propagate_rollout, stack_paths
from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor

LANDMARKS = np.array([[0.5, 1.5], [1.5, -1.5]])  # near robot r's start only


def corridor_models(mode: ObservationMode = ObservationMode.NOISY, mutual: bool = True) -> Models:
    return Models(
        dt=0.1,
        motion_noise=(0.05, 0.01, 0.02, 0.05),
        landmark_sensor=RangeBearingSensor(3.0, 2 * np.pi, 0.1, 0.05),
        mutual_sensor=RangeBearingSensor(4.0, 2 * np.pi, 0.1, 0.05),
        mutual_observations=mutual,
        observations=mode,
        seed=42,
    )


def corridor_scene() -> tuple[Belief, Rollout]:
    """Robot r drives east along a corridor, robot r' west; they pass 1 m apart."""
    r = path_controls(np.array([[0.0, 0.0], [4.0, 0.0], [8.0, 0.5]]), 0.0, 1.0, 1.5, 0.1)
    r2 = path_controls(np.array([[8.0, 1.0], [3.0, 1.0]]), np.pi, 1.0, 1.5, 0.1)
    controls, poses, steps = stack_paths([r, r2])
    d_lm = np.linalg.norm(poses[:, :, None, :2] - LANDMARKS[None, None], axis=-1)
    d_mutual = np.linalg.norm(poses[0, :, :2] - poses[1, :, :2], axis=-1)
    mutual = np.zeros((2, 2, poses.shape[1]), dtype=bool)
    mutual[0, 1] = mutual[1, 0] = d_mutual < 4.0
    rollout = Rollout(controls, poses, steps, d_lm < 3.0, mutual)
    cov = np.diag([0.02, 0.02, 0.005, 0.02, 0.02, 0.005])
    return Belief(poses[:, 0].reshape(-1), cov), rollout


def test_stack_paths_pads_the_robot_that_arrives_first() -> None:
    _, rollout = corridor_scene()
    n, T, _ = rollout.controls.shape
    assert n == 2 and rollout.true_poses.shape == (2, T + 1, 3)
    assert rollout.active_steps.max() == T and rollout.active_steps.min() < T
    short = int(np.argmin(rollout.active_steps))
    np.testing.assert_array_equal(rollout.controls[short, rollout.active_steps[short] :], 0.0)


@pytest.mark.parametrize("mode", list(ObservationMode))
def test_the_kernel_matches_the_reference(mode: ObservationMode) -> None:
    belief, rollout = corridor_scene()
    models = corridor_models(mode)
    fast = propagate_rollout(belief, rollout, LANDMARKS, models)
    ref = propagate_reference(belief, rollout, LANDMARKS, models)
    np.testing.assert_allclose(fast.means, ref.means, rtol=0, atol=1e-9)
    np.testing.assert_allclose(fast.covs, ref.covs, rtol=0, atol=1e-9)
    for a, b in zip(fast.terms, ref.terms, strict=True):
        assert a.c_Sigma == pytest.approx(b.c_Sigma, abs=1e-9)
        assert a.c_G == pytest.approx(b.c_G, abs=1e-9)
        assert a.c_u == pytest.approx(b.c_u, abs=1e-12)
    assert fast.mutual_steps == ref.mutual_steps > 0
    np.testing.assert_array_equal(fast.final.mean, fast.means[-1])
    np.testing.assert_array_equal(fast.belief(3).cov, fast.covs[3])


def test_mutual_observations_help_the_robot_without_landmarks() -> None:
    belief, rollout = corridor_scene()
    with_mutual = propagate_rollout(belief, rollout, LANDMARKS, corridor_models())
    without = propagate_rollout(belief, rollout, LANDMARKS, corridor_models(mutual=False))
    assert without.mutual_steps == 0 and with_mutual.mutual_steps > 0
    assert with_mutual.terms[1].c_Sigma < without.terms[1].c_Sigma
    final = with_mutual.final
    assert np.abs(final.cov[:3, 3:]).max() > 0  # the robots' estimates are now correlated
    assert np.trace(final.marginal(1).cov) < np.trace(without.final.marginal(1).cov)


def test_models_mutual_flag_drops_the_mutual_observations() -> None:
    belief, rollout = corridor_scene()
    blind = replace(rollout, mutual_visible=np.zeros_like(rollout.mutual_visible))
    a = propagate_rollout(belief, rollout, LANDMARKS, corridor_models(mutual=False))
    b = propagate_rollout(belief, blind, LANDMARKS, corridor_models(mutual=True))
    np.testing.assert_array_equal(a.covs, b.covs)


def test_the_noise_comes_from_the_seed_unless_given() -> None:
    belief, rollout = corridor_scene()
    models = corridor_models()
    n, T, _ = rollout.controls.shape
    drawn = ObservationNoise.draw(models.seed, n, T, len(LANDMARKS))
    default = propagate_rollout(belief, rollout, LANDMARKS, models)
    explicit = propagate_rollout(belief, rollout, LANDMARKS, models, drawn)
    np.testing.assert_array_equal(default.means, explicit.means)
    other = propagate_rollout(belief, rollout, LANDMARKS, replace(models, seed=7))
    assert not np.array_equal(other.means, default.means)
