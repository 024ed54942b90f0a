"""The reference EKF (filterpy) on immutable beliefs."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.belief.ekf import predict, update_landmark, update_mutual
from tmpnav.belief.models import (
    landmark_obs,
    landmark_obs_jacobian,
    motion,
    motion_jacobians,
    mutual_obs,
    process_noise,
    wrap_angle,
)
from tmpnav.types import Belief

ALPHAS = (0.05, 0.01, 0.02, 0.05)
Q = np.diag([0.1**2, 0.05**2])


def random_belief(rng: np.random.Generator, n: int, correlated: bool = True) -> Belief:
    mean = np.concatenate([[4.0 * i, 0.0, 0.0] for i in range(n)]) + rng.normal(0, 0.5, 3 * n)
    mean[2::3] = wrap_angle(mean[2::3])
    if correlated:
        A = rng.normal(0, 0.2, (3 * n, 3 * n))
        cov = A @ A.T + 1e-3 * np.eye(3 * n)
    else:
        cov = np.diag(rng.uniform(1e-3, 0.1, 3 * n))
    return Belief(mean, cov)


def block_traces(cov: np.ndarray) -> np.ndarray:
    return np.diagonal(cov).reshape(-1, 3).sum(-1)


def test_predict_is_the_joint_model_of_eq_11() -> None:
    rng = np.random.default_rng(0)
    b = random_belief(rng, 2)
    u = np.array([[0.5, 0.2], [1.0, -0.4]])
    out = predict(b, u, 0.1, ALPHAS)
    poses = b.mean.reshape(2, 3)
    np.testing.assert_allclose(out.mean.reshape(2, 3), motion(poses, u, 0.1))
    F, _ = motion_jacobians(poses, u, 0.1)
    R = process_noise(poses, u, 0.1, ALPHAS)
    for i in range(2):
        for j in range(2):
            block = F[i] @ b.cov[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] @ F[j].T
            if i == j:
                block = block + R[i]
            np.testing.assert_allclose(out.cov[3 * i : 3 * i + 3, 3 * j : 3 * j + 3], block)


def test_predict_keeps_independent_robots_independent() -> None:
    b = random_belief(np.random.default_rng(1), 2, correlated=False)
    out = predict(b, np.array([[0.5, 0.2], [1.0, -0.4]]), 0.1, ALPHAS)
    np.testing.assert_array_equal(out.cov[:3, 3:], 0.0)


def test_functions_return_new_beliefs_and_leave_inputs_alone() -> None:
    b = random_belief(np.random.default_rng(2), 2)
    mean, cov = b.mean.copy(), b.cov.copy()
    lm = np.array([3.0, 4.0])
    outs = [
        predict(b, np.ones((2, 2)), 0.1, ALPHAS),
        update_landmark(b, 0, lm, landmark_obs(b.mean[:3], lm) + 0.1, Q),
        update_mutual(b, 0, 1, mutual_obs(b.mean[:3], b.mean[3:]) + 0.1, Q),
    ]
    np.testing.assert_array_equal(b.mean, mean)
    np.testing.assert_array_equal(b.cov, cov)
    assert all(o is not b and o.mean is not b.mean for o in outs)


def test_landmark_update_matches_the_textbook_ekf_of_eq_9() -> None:
    rng = np.random.default_rng(3)
    b = random_belief(rng, 2)
    lm = np.array([2.0, 5.0])
    z = landmark_obs(b.mean[3:], lm) + np.array([0.05, -0.02])
    out = update_landmark(b, 1, lm, z, Q)
    H = np.zeros((2, 6))
    H[:, 3:] = landmark_obs_jacobian(b.mean[3:], lm)
    K = b.cov @ H.T @ np.linalg.inv(H @ b.cov @ H.T + Q)
    y = z - landmark_obs(b.mean[3:], lm)
    np.testing.assert_allclose(out.mean, b.mean + K @ y, atol=1e-12)
    np.testing.assert_allclose(out.cov, (np.eye(6) - K @ H) @ b.cov, atol=1e-12)


def test_bearing_innovation_is_wrapped() -> None:
    b = Belief(np.array([0.0, 0.0, 0.0]), np.diag([0.01, 0.01, 0.01]))
    lm = np.array([-5.0, 1e-3])  # predicted bearing just below pi
    z = np.array([5.0, -np.pi + 1e-3])  # measured just above -pi: a tiny innovation
    out = update_landmark(b, 0, lm, z, Q)
    assert abs(out.mean[2]) < 1e-2


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]))
def test_landmark_update_never_increases_uncertainty(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    b = random_belief(rng, n)
    i = int(rng.integers(n))
    lm = b.mean[3 * i : 3 * i + 2] + rng.uniform(1.0, 6.0) * np.array([1.0, rng.uniform(-1, 1)])
    z = landmark_obs(b.mean[3 * i : 3 * i + 3], lm) + rng.normal(0, 0.1, 2)
    out = update_landmark(b, i, lm, z, Q)
    assert np.trace(out.cov) <= np.trace(b.cov) + 1e-12
    assert np.all(block_traces(out.cov) <= block_traces(b.cov) + 1e-12)
    np.testing.assert_array_equal(out.cov, out.cov.T)
    assert np.linalg.eigvalsh(out.cov).min() > -1e-12


def test_mutual_update_correlates_the_two_robots() -> None:
    b = random_belief(np.random.default_rng(4), 3, correlated=False)
    z = mutual_obs(b.mean[:3], b.mean[6:]) + np.array([0.1, 0.05])
    out = update_mutual(b, 0, 2, z, Q)
    assert np.abs(out.cov[:3, 6:]).max() > 1e-6
    np.testing.assert_array_equal(out.cov[3:6, [0, 1, 2, 6, 7, 8]], 0.0)  # robot 1 untouched
    np.testing.assert_array_equal(out.cov[3:6, 3:6], b.cov[3:6, 3:6])
    assert block_traces(out.cov)[0] < block_traces(b.cov)[0]
    assert block_traces(out.cov)[2] < block_traces(b.cov)[2]
    # robot 0 only measures robot 2's position: the observed robot's heading stays put
    assert out.cov[8, 8] == pytest.approx(b.cov[8, 8])


def test_a_robot_cannot_observe_itself() -> None:
    b = random_belief(np.random.default_rng(5), 2)
    with pytest.raises(ValueError):
        update_mutual(b, 1, 1, np.zeros(2), Q)
    with pytest.raises(ValueError):
        predict(b, np.zeros((3, 2)), 0.1, ALPHAS)
