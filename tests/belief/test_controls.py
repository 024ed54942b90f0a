"""Roadmap paths to turn-then-drive controls."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tmpnav.belief.controls import pad, path_controls
from tmpnav.belief.models import motion

point = st.tuples(st.floats(-20.0, 20.0), st.floats(-20.0, 20.0))


def test_straight_edge_along_the_heading_needs_no_turn() -> None:
    path = path_controls(np.array([[0.0, 0.0], [1.0, 0.0]]), 0.0, speed=0.3, turn_rate=1.0, dt=0.1)
    n_drive = math.ceil(1.0 / 0.03)
    assert path.n_steps == n_drive
    np.testing.assert_allclose(path.controls[:, 0], 1.0 / (n_drive * 0.1))
    np.testing.assert_array_equal(path.controls[:, 1], 0.0)
    np.testing.assert_array_equal(path.node_steps, [0, n_drive])
    np.testing.assert_allclose(path.poses[-1], [1.0, 0.0, 0.0], atol=1e-12)


def test_quarter_turn_then_drive() -> None:
    path = path_controls(np.array([[0.0, 0.0], [0.0, 2.0]]), 0.0, speed=1.0, turn_rate=np.pi / 2, dt=0.1)
    # 90 degrees at 90 deg/s takes 1 s = 10 steps, then 2 m at 1 m/s = 20 steps
    assert path.n_steps == 30
    np.testing.assert_allclose(path.controls[:10], [[0.0, np.pi / 2]] * 10)
    np.testing.assert_allclose(path.controls[10:], [[1.0, 0.0]] * 20)
    np.testing.assert_allclose(path.poses[10], [0.0, 0.0, np.pi / 2], atol=1e-12)
    np.testing.assert_allclose(path.poses[-1], [0.0, 2.0, np.pi / 2], atol=1e-12)


def test_a_turn_below_the_threshold_is_skipped() -> None:
    # found by hypothesis: the second edge bends by 1e-9 rad, too little to turn for
    pts = np.array([[1.0, 1e-9], [0.0, 0.0], [-2.0, 0.0]])
    path = path_controls(pts, 0.0, speed=1.0, turn_rate=1.0, dt=0.05)
    assert np.all(path.controls[path.node_steps[1] :, 1] == 0.0)
    assert np.hypot(*(path.poses[-1, :2] - pts[-1])) <= 2e-9  # 2 m x 1e-9 rad


def test_repeated_points_produce_no_steps() -> None:
    pts = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [1.0, 0.0]])
    path = path_controls(pts, 0.0, speed=1.0, turn_rate=1.0, dt=0.1)
    np.testing.assert_array_equal(path.node_steps, [0, 0, 10, 10])
    assert path.n_steps == 10
    single = path_controls(pts[:1], 0.3, speed=1.0, turn_rate=1.0, dt=0.1)
    assert single.n_steps == 0 and single.controls.shape == (0, 2)
    np.testing.assert_allclose(single.poses, [[0.0, 0.0, 0.3]])


@settings(max_examples=30, deadline=None)
@given(
    st.lists(point, min_size=1, max_size=6),
    st.floats(-np.pi, np.pi),
    st.floats(0.1, 2.0),
    st.floats(0.2, 3.0),
    st.sampled_from([0.05, 0.1, 0.25]),
)
def test_nominal_poses_follow_the_path(
    points: list[tuple[float, float]], theta0: float, speed: float, turn_rate: float, dt: float
) -> None:
    pts = np.array(points)
    path = path_controls(pts, theta0, speed, turn_rate, dt)
    T = path.n_steps
    assert path.controls.shape == (T, 2) and path.poses.shape == (T + 1, 3)
    # the poses are the motion model applied exactly to the controls
    pose = path.poses[0]
    np.testing.assert_array_equal(pose[:2], pts[0])
    for k in range(T):
        pose = motion(pose, path.controls[k], dt)
        np.testing.assert_array_equal(pose, path.poses[k + 1])
    # every path point is reached at its node step, the last one at the end
    assert path.node_steps[0] == 0 and path.node_steps[-1] == T
    assert np.all(np.diff(path.node_steps) >= 0)
    # a turn below 1e-9 rad is skipped, which may miss a point by up to 1e-9 x edge length
    edge = np.concatenate([[0.0], np.hypot(*np.diff(pts, axis=0).T)])
    miss = np.hypot(*(path.poses[path.node_steps, :2] - pts).T)
    assert np.all(miss <= 1e-9 * np.maximum(1.0, edge)), miss
    # each step either turns on the spot or drives straight, within the robot's limits
    v, omega = path.controls[:, 0], path.controls[:, 1]
    assert np.all((v == 0.0) | (omega == 0.0))
    assert np.all(np.abs(omega) <= turn_rate * (1 + 1e-12))
    assert np.all((v >= 0.0) & (v <= speed * (1 + 1e-12)))


def test_pad_waits_at_the_goal() -> None:
    path = path_controls(np.array([[0.0, 0.0], [1.0, 1.0]]), 0.0, 1.0, 1.0, 0.1)
    controls, poses = pad(path.controls, path.poses, path.n_steps + 5)
    assert controls.shape == (path.n_steps + 5, 2) and poses.shape == (path.n_steps + 6, 3)
    np.testing.assert_array_equal(controls[path.n_steps :], 0.0)
    np.testing.assert_array_equal(poses[path.n_steps :], np.repeat(path.poses[-1:], 6, axis=0))
    same_controls, same_poses = pad(path.controls, path.poses, path.n_steps)
    np.testing.assert_array_equal(same_controls, path.controls)
    np.testing.assert_array_equal(same_poses, path.poses)
    with pytest.raises(ValueError):
        pad(path.controls, path.poses, path.n_steps - 1)
