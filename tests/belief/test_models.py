"""The model equations: values, batching, and every Jacobian against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.belief.models import (
    joint_block_diag,
    landmark_obs,
    landmark_obs_jacobian,
    motion,
    motion_jacobians,
    motion_noise_cov,
    mutual_obs,
    mutual_obs_jacobian,
    noisy_observation,
    observation_residual,
    process_noise,
    wrap_angle,
)

coord = st.floats(-20.0, 20.0)
heading = st.floats(-np.pi, np.pi, exclude_max=True)
pose = st.tuples(coord, coord, heading).map(np.array)
control = st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0)).map(np.array)
offset = st.tuples(st.floats(-10.0, 10.0), st.floats(-10.0, 10.0)).filter(
    lambda d: np.hypot(*d) > 0.5  # away from the range-bearing singularity at d = 0
)

EPS = 1e-6


def numeric_jacobian(fn, x: np.ndarray, angle_rows: tuple[int, ...]) -> np.ndarray:
    """Central differences of fn at x; rows listed in angle_rows are wrapped differences."""
    columns = []
    for c in range(x.shape[0]):
        step = np.zeros_like(x)
        step[c] = EPS
        diff = fn(x + step) - fn(x - step)
        for r in angle_rows:
            diff[r] = wrap_angle(diff[r])
        columns.append(diff / (2 * EPS))
    return np.stack(columns, axis=-1)


# --------------------------------------------------------------------------- motion


def test_motion_drives_along_the_heading_and_wraps_theta() -> None:
    x = np.array([1.0, 2.0, np.pi / 2])
    np.testing.assert_allclose(motion(x, np.array([2.0, 0.0]), 0.5), [1.0, 3.0, np.pi / 2], atol=1e-15)
    turned = motion(np.array([0.0, 0.0, 3.0]), np.array([0.0, 1.0]), 0.5)
    np.testing.assert_allclose(turned, [0.0, 0.0, 3.5 - 2 * np.pi])


def test_models_work_on_batches_like_on_single_poses() -> None:
    def same(a: np.ndarray, b: np.ndarray) -> None:  # vectorised loops may round differently
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-14)

    rng = np.random.default_rng(1)
    xs = np.column_stack([rng.uniform(-5, 5, (4, 3, 2)).reshape(-1, 2), rng.uniform(-3, 3, 12)])
    xs = xs.reshape(4, 3, 3)
    us = rng.uniform(-1, 1, (4, 3, 2))
    lm = np.array([7.0, -8.0])
    F, V = motion_jacobians(xs, us, 0.1)
    H = landmark_obs_jacobian(xs, lm)
    Hm = mutual_obs_jacobian(xs[:, 0], xs[:, 1])
    assert F.shape == (4, 3, 3, 3) and V.shape == (4, 3, 3, 2) and H.shape == (4, 3, 2, 3)
    for b in range(4):
        for r in range(3):
            x, u = xs[b, r], us[b, r]
            same(motion(xs, us, 0.1)[b, r], motion(x, u, 0.1))
            same(F[b, r], motion_jacobians(x, u, 0.1)[0])
            same(V[b, r], motion_jacobians(x, u, 0.1)[1])
            same(landmark_obs(xs, lm)[b, r], landmark_obs(x, lm))
            same(H[b, r], landmark_obs_jacobian(x, lm))
        same(Hm[b], mutual_obs_jacobian(xs[b, 0], xs[b, 1]))
        same(mutual_obs(xs[:, 0], xs[:, 1])[b], mutual_obs(xs[b, 0], xs[b, 1]))


@settings(max_examples=60)
@given(pose, control, st.floats(0.01, 0.5), st.booleans())
def test_motion_jacobians_equal_finite_differences(x: np.ndarray, u: np.ndarray, dt: float, midpoint: bool) -> None:
    F, V = motion_jacobians(x, u, dt, midpoint)
    np.testing.assert_allclose(F, numeric_jacobian(lambda s: motion(s, u, dt, midpoint), x, (2,)), atol=1e-7)
    np.testing.assert_allclose(V, numeric_jacobian(lambda c: motion(x, c, dt, midpoint), u, (2,)), atol=1e-7)


def test_the_midpoint_step_follows_the_arc_and_equals_euler_where_a_step_only_turns_or_drives() -> None:
    """The midpoint step lands within O(dt³) of the arc a command held for dt drives (the Euler
    step within O(dt²)); on a step that either turns or drives the two steps are the same pose."""
    x, u, dt = np.array([1.0, 2.0, 0.3]), np.array([0.5, 0.8]), 0.5
    r = u[0] / u[1]  # the exact arc's radius
    end = x[2] + u[1] * dt
    arc = np.array([x[0] + r * (np.sin(end) - np.sin(x[2])), x[1] - r * (np.cos(end) - np.cos(x[2]))])
    mid_error = np.hypot(*(motion(x, u, dt, midpoint=True)[:2] - arc))
    euler_error = np.hypot(*(motion(x, u, dt)[:2] - arc))
    assert mid_error < 0.002 < 0.04 < euler_error
    for only in (np.array([0.5, 0.0]), np.array([0.0, 0.8])):
        np.testing.assert_array_equal(motion(x, only, dt, midpoint=True), motion(x, only, dt))
        F, _ = motion_jacobians(x, only, dt, midpoint=True)
        np.testing.assert_array_equal(F, motion_jacobians(x, only, dt)[0])


def test_motion_noise_is_zero_when_standing_still() -> None:
    alphas = (0.1, 0.2, 0.3, 0.4)
    np.testing.assert_array_equal(motion_noise_cov(np.zeros(2), alphas), np.zeros((2, 2)))
    W = motion_noise_cov(np.array([2.0, 0.5]), alphas)
    np.testing.assert_allclose(W, np.diag([0.1 * 4 + 0.2 * 0.25, 0.3 * 4 + 0.4 * 0.25]))
    x = np.array([0.0, 0.0, 0.0])
    R = process_noise(x, np.array([1.0, 0.0]), 0.1, alphas)
    # V at theta = 0 maps the speed noise onto x and the turn-rate noise onto theta
    np.testing.assert_allclose(R, np.diag([0.01 * 0.1, 0.0, 0.01 * 0.3]))


def test_joint_block_diag_places_each_robot_on_the_diagonal() -> None:
    blocks = np.stack([np.full((3, 3), 1.0), np.full((3, 3), 2.0)])
    J = joint_block_diag(blocks)
    assert J.shape == (6, 6)
    np.testing.assert_array_equal(J[:3, :3], 1.0)
    np.testing.assert_array_equal(J[3:, 3:], 2.0)
    np.testing.assert_array_equal(J[:3, 3:], 0.0)


# --------------------------------------------------------------------------- observations


def test_landmark_obs_range_and_bearing() -> None:
    z = landmark_obs(np.array([1.0, 1.0, np.pi / 2]), np.array([4.0, 5.0]))
    np.testing.assert_allclose(z, [5.0, np.arctan2(4.0, 3.0) - np.pi / 2])
    behind = landmark_obs(np.array([0.0, 0.0, 0.1]), np.array([-1.0, -1e-12]))
    assert -np.pi <= behind[1] < np.pi


@settings(max_examples=60)
@given(pose, offset)
def test_landmark_jacobian_equals_finite_differences(x: np.ndarray, d: tuple[float, float]) -> None:
    lm = x[:2] + np.array(d)
    H = landmark_obs_jacobian(x, lm)
    np.testing.assert_allclose(H, numeric_jacobian(lambda s: landmark_obs(s, lm), x, (1,)), atol=1e-6)


@settings(max_examples=60)
@given(pose, offset, heading)
def test_mutual_jacobian_equals_finite_differences(x_r: np.ndarray, d: tuple[float, float], theta_s: float) -> None:
    x_s = np.array([x_r[0] + d[0], x_r[1] + d[1], theta_s])
    joint = np.concatenate([x_r, x_s])
    H = mutual_obs_jacobian(x_r, x_s)
    numeric = numeric_jacobian(lambda s: mutual_obs(s[:3], s[3:]), joint, (1,))
    np.testing.assert_allclose(H, numeric, atol=1e-6)


def test_paper_printed_mutual_jacobian_has_swapped_entries() -> None:
    """The paper's eq. (15) prints -dx/d², dy/d² for the bearing row's x_s, y_s entries."""
    x_r, x_s = np.array([0.0, 0.0, 0.3]), np.array([3.0, 1.0, -1.0])
    dx, dy, d2 = 3.0, 1.0, 10.0
    H = mutual_obs_jacobian(x_r, x_s)
    np.testing.assert_allclose(H[1, 3:5], [-dy / d2, dx / d2])
    assert not np.allclose(H[1, 3:5], [-dx / d2, dy / d2])
    # the bearing depends on x_r and x_s only through their difference
    np.testing.assert_allclose(H[:, :2], -H[:, 3:5])


def test_noisy_observation_adds_correlated_noise_and_wraps() -> None:
    Q = np.array([[0.04, 0.0], [0.0, 0.01]])
    L = np.linalg.cholesky(Q)
    z0 = np.array([2.0, np.pi - 0.05])
    np.testing.assert_array_equal(noisy_observation(z0, L, np.zeros(2)), z0)
    z = noisy_observation(z0, L, np.array([1.0, 1.0]))
    np.testing.assert_allclose(z, [2.2, np.pi - 0.05 + 0.1 - 2 * np.pi])
    y = observation_residual(np.array([1.0, -np.pi + 0.01]), np.array([1.5, np.pi - 0.01]))
    np.testing.assert_allclose(y, [-0.5, 0.02])


@pytest.mark.parametrize("fn", [landmark_obs, landmark_obs_jacobian])
def test_landmark_models_broadcast_landmarks_against_poses(fn) -> None:
    poses = np.zeros((5, 3))
    poses[:, 0] = np.arange(5)
    lms = np.array([[10.0, 1.0], [-3.0, 4.0]])
    out = fn(poses[:, None, :], lms[None, :, :])
    assert out.shape[:2] == (5, 2)
    np.testing.assert_array_equal(out[3, 1], fn(poses[3], lms[1]))
