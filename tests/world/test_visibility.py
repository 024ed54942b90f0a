"""Who sees what (world/visibility.py): landmark visibility polygons and robot-to-robot sight.

``LandmarkVisibility`` answers "is landmark l in line of sight from pose x" from 1440 rays
cast once per landmark. The reference it is checked against is the exact line of sight:
the segment sampled every 1/40 cell, ignoring the 1.5 cells at each end (a landmark mounted
on a wall still sees past its own cell). The rays approximate it: they must agree on almost
every pose, and on every pose whose answer does not hinge on grazing a cell corner.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tests.scenario.helpers import base_scenario, build_world
from tmpnav.world.build import World
from tmpnav.world.geometry import wrap_angle
from tmpnav.world.visibility import RAYS, LandmarkVisibility, MutualSensing, mutual_visible

RANGE = 4.0
FULL = 2 * math.pi


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> World:
    """The base world with landmarks in the open, in a corner, next to a door and on walls."""
    doc = base_scenario()
    doc["landmarks"] += [
        {"name": "on-wall", "position": [5.0, 4.0]},  # inside the wall between A and B
        {"name": "by-table", "position": [3.9, 1.5]},
        {"name": "by-door", "position": [0.5, 2.85]},
        {"name": "on-table-edge", "position": [6.0, 1.0]},  # the table's corner
    ]
    return build_world(tmp_path_factory.mktemp("vis"), doc)[1]


def exact_line_of_sight(world: World, a: np.ndarray, b: np.ndarray, margin: float | None = None) -> np.ndarray:
    """Segments a[k]-b[k] cross no occupied cell, sampled every 1/40 cell; the ``margin``
    (default 1.5 cells) at both ends is ignored, as everywhere in tmpnav."""
    r = world.grid.resolution
    margin = 1.5 * r if margin is None else margin
    length = np.linalg.norm(b - a, axis=1)
    t = np.linspace(0.0, 1.0, int(np.ceil(length.max() / (r / 40))) + 1)
    points = a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]
    along = t[None, :] * length[:, None]
    interior = (along > margin) & (along < length[:, None] - margin)
    return ~(world.grid.is_occupied(points) & interior).any(axis=1)


def random_poses(world: World, n: int, seed: int) -> np.ndarray:
    """n robot poses (n, 3) where a 0.25 m robot fits, uniformly over the map."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform((0.0, 0.0), (10.0, 6.0), size=(8 * n, 2))
    xy = xy[world.is_free(xy, 0.25)][:n]
    assert len(xy) == n
    return np.column_stack([xy, rng.uniform(-math.pi, math.pi, n)])


def test_landmark_visibility_matches_exact_line_of_sight(world: World) -> None:
    poses = random_poses(world, 600, seed=3)
    seen = LandmarkVisibility(world, RANGE).visible(poses, FULL).ravel()
    assert seen.shape == (600 * len(world.landmarks),)

    landmarks = np.repeat(world.landmark_xy[None], len(poses), axis=0).reshape(-1, 2)
    robots = np.repeat(poses[:, :2], len(world.landmarks), axis=0)
    distance = np.linalg.norm(robots - landmarks, axis=1)
    near = distance <= RANGE + 1.0  # the exact test is slow: only where range does not decide
    lm, rb, r = landmarks[near], robots[near], world.grid.resolution
    exact = distance <= RANGE
    exact[near] &= exact_line_of_sight(world, lm, rb)
    assert 0.15 < exact.mean() < 0.85  # a mix of seen and hidden
    assert (seen == exact).mean() > 0.98

    # Clear-cut pairs: the exact answer stays the same when the segment moves sideways by a
    # quarter cell either way (the rays are at most 0.9 cm off at 4 m) and when the end
    # margins grow or shrink by half a cell, and the robot is not within a cell of the sensor
    # range. There the rays must be exact (with 180 rays instead of 1440 they are not).
    normal = np.column_stack([lm[:, 1] - rb[:, 1], rb[:, 0] - lm[:, 0]]) / distance[near, None]
    answers = [
        exact_line_of_sight(world, lm + s * r / 4 * normal, rb + s * r / 4 * normal, margin)
        for s in (-1, 0, 1)
        for margin in (1.0 * r, 2.0 * r)
    ]
    clear_cut = np.abs(distance - RANGE) > r
    clear_cut[near] &= np.all([a == answers[0] for a in answers], axis=0)
    assert clear_cut.mean() > 0.6
    assert np.array_equal(seen[clear_cut], exact[clear_cut])


def rays_in_numpy(vis: LandmarkVisibility, poses: np.ndarray, fov: float, min_range: float) -> np.ndarray:
    """The ray model of :class:`LandmarkVisibility`, written in numpy as it was before it was
    compiled: range, field of view, and the free distance of the ray nearest the pose."""
    d = vis.landmarks[None, :, :] - poses[:, None, :2]
    dist = np.hypot(d[..., 0], d[..., 1])
    seen = (dist <= vis.range) & (dist >= min_range)
    if fov < FULL - 1e-9:
        seen &= np.abs(wrap_angle(np.arctan2(d[..., 1], d[..., 0]) - poses[:, None, 2])) <= fov / 2
    ray = np.round((np.arctan2(-d[..., 1], -d[..., 0]) + np.pi) / (2 * np.pi) * RAYS).astype(np.int64) % RAYS
    return seen & (dist <= np.take_along_axis(vis._free, ray.T, axis=1).T)


def test_compiled_landmark_visibility_is_the_ray_model(world: World) -> None:
    """The compiled check answers as the ray model in numpy on random poses, also outside the
    free space and with headings beyond [-pi, pi) (a pose exactly between two rays could
    differ: numpy's and the compiled arctangent may round its last bit apart)."""
    vis = LandmarkVisibility(world, RANGE)
    rng = np.random.default_rng(11)
    poses = np.column_stack([rng.uniform(-1.0, 11.0, (20000, 2)), rng.uniform(-7.0, 7.0, 20000)])
    for fov, min_range in ((FULL, 0.0), (math.radians(120), 0.25), (1.0, 0.5)):
        assert np.array_equal(vis.visible(poses, fov, min_range), rays_in_numpy(vis, poses, fov, min_range))


def test_landmark_visibility_range_min_range_and_field_of_view(world: World) -> None:
    vis = LandmarkVisibility(world, RANGE)
    plant = [lm.name for lm in world.landmarks].index("plant")  # at (9.5, 0.5), in the open hall
    poses = np.array(
        [
            [7.5, 0.5, 0.0],  # 2 m west of it, facing it
            [7.5, 0.5, math.pi],  # facing away
            [9.5, 4.7, -math.pi / 2],  # 4.2 m north, behind the wall of room B
            [9.1, 0.5, 0.0],  # 0.4 m away
        ]
    )
    assert vis.visible(poses, FULL)[:, plant].tolist() == [True, True, False, True]
    assert vis.visible(poses, math.radians(90))[:, plant].tolist() == [True, False, False, True]
    assert vis.visible(poses, FULL, min_range=0.5)[:, plant].tolist() == [True, True, False, False]
    assert LandmarkVisibility(world, 1.5).visible(poses, FULL)[:, plant].tolist() == [False, False, False, True]


def test_landmark_visibility_keeps_the_leading_shape(world: World) -> None:
    poses = random_poses(world, 6, seed=5).reshape(2, 3, 3)
    vis = LandmarkVisibility(world, RANGE)
    seen = vis.visible(poses, FULL)
    assert seen.shape == (2, 3, len(world.landmarks))
    assert np.array_equal(seen.reshape(6, -1), vis.visible(poses.reshape(6, 3), FULL))


def test_a_world_without_landmarks_sees_none(tmp_path: Path) -> None:
    doc = base_scenario()
    doc["landmarks"] = []
    _, bare = build_world(tmp_path, doc)
    seen = LandmarkVisibility(bare, RANGE).visible(random_poses(bare, 4, seed=1), FULL)
    assert seen.shape == (4, 0)


# --------------------------------------------------------------------------- robot to robot


def pose(x: float, y: float, heading_deg: float = 0.0) -> np.ndarray:
    return np.array([[x, y, math.radians(heading_deg)]])


@pytest.mark.parametrize(
    ("observer", "target", "kwargs", "expected"),
    [
        (pose(1.0, 1.5), pose(3.0, 1.5), {}, True),  # 2 m apart in the open hall
        (pose(1.0, 1.5), pose(3.0, 1.5), {"sensor_range": 1.5}, False),  # out of range
        (pose(1.0, 1.5), pose(3.0, 1.5), {"min_range": 2.5}, False),  # too close
        (pose(1.0, 1.5, 180), pose(3.0, 1.5), {"fov": math.radians(90)}, False),  # facing away
        (pose(1.0, 1.5, 40), pose(3.0, 1.5), {"fov": math.radians(90)}, True),  # 40 deg off-axis, fov +-45
        (pose(1.0, 1.5, 50), pose(3.0, 1.5), {"fov": math.radians(90)}, False),  # 50 deg off-axis
        (pose(3.0, 1.5), pose(7.0, 1.5), {"sensor_range": 5.0}, False),  # the table is in between
        (pose(2.5, 1.5), pose(2.5, 4.5), {}, True),  # through door-A
        (pose(1.0, 2.0), pose(1.0, 4.5), {}, False),  # through the wall of room A
        (pose(2.5, 4.5), pose(7.5, 4.5), {"sensor_range": 6.0}, False),  # from room A into room B
    ],
    ids=[
        "open",
        "out-of-range",
        "too-close",
        "facing-away",
        "fov-edge-in",
        "fov-edge-out",
        "table",
        "door",
        "wall",
        "room-to-room",
    ],
)
def test_mutual_visibility(
    world: World, observer: np.ndarray, target: np.ndarray, kwargs: dict[str, float], expected: bool
) -> None:
    args = {"sensor_range": RANGE, "fov": FULL, "min_range": 0.0, **kwargs}
    assert mutual_visible(world, observer, target, **args).tolist() == [expected]


def test_mutual_visibility_is_one_sided_with_a_narrow_field_of_view(world: World) -> None:
    a, b = pose(1.0, 1.5, 0), pose(3.0, 1.5, 0)  # both face east: a sees b's back, b sees nothing
    fov = math.radians(90)
    assert mutual_visible(world, a, b, RANGE, fov).tolist() == [True]
    assert mutual_visible(world, b, a, RANGE, fov).tolist() == [False]


def test_mutual_visibility_uses_the_same_line_of_sight_as_the_world(world: World) -> None:
    observers, targets = random_poses(world, 400, seed=11), random_poses(world, 400, seed=12)
    seen = mutual_visible(world, observers, targets, 20.0, FULL)
    assert np.array_equal(seen, world.line_of_sight(observers[:, :2], targets[:, :2]))


# --------------------------------------------------------------------------- mutual sensing


def test_mutual_sensing_between_two_robots(tmp_path: Path) -> None:
    """The one place that decides whether and how two robots observe each other."""
    doc = base_scenario()
    doc["robots"][0]["radius"] = 0.3
    doc["robots"][1]["radius"] = 0.2
    scenario, _ = build_world(tmp_path, doc)
    a, b = (r.name for r in scenario.robots)
    sensing = MutualSensing.between(scenario, a, b)
    assert sensing is not None
    sensor = scenario.models.mutual_sensor
    assert (sensing.range, sensing.fov, sensing.min_range) == (sensor.range, sensor.fov, 0.5)
    assert MutualSensing.between(scenario, b, a) == sensing
    off = replace(scenario, models=replace(scenario.models, mutual_observations=False))
    assert MutualSensing.between(off, a, b) is None
    assert MutualSensing.of_sensor(off, a, b) == MutualSensing.of_sensor(scenario, a, b) == sensing


def test_mutual_sensing_along_sequences_agrees_with_pose_pairs(world: World) -> None:
    """Whole simulations in trie order (shared prefixes copied) see what pose pairs see."""
    sensing = MutualSensing(RANGE, math.radians(200), 0.3)
    lengths = [6, 9, 4]
    poses = [random_poses(world, T + 1, seed=20 + k) for k, T in enumerate(lengths)]
    steps = np.array(lengths, dtype=np.int64)
    offset = np.concatenate([[0], np.cumsum(steps)[:-1]]).astype(np.int64)
    stacked = np.concatenate(poses)
    pairs = np.array([[0, 1], [0, 1], [1, 2], [2, 0]], dtype=np.int64)
    horizon = np.array([max(lengths[a], lengths[b]) for a, b in pairs], dtype=np.int64)
    rows = np.concatenate([[0], np.cumsum(horizon + 1)[:-1]]).astype(np.int64)
    restart = np.array([-1, 3, -1, -1], dtype=np.int64)  # the second copies steps 0..3 from the first
    out = np.zeros((int((horizon + 1).sum()), 2, 2), dtype=bool)
    first = sensing.sequences(world, (offset, steps, stacked), pairs, restart, horizon, rows, out)
    for c, (a, b) in enumerate(pairs):
        h = int(horizon[c])
        pa = np.array([poses[a][min(t, lengths[a])] for t in range(h + 1)])
        pb = np.array([poses[b][min(t, lengths[b])] for t in range(h + 1)])
        assert np.array_equal(out[rows[c] : rows[c] + h + 1, 0, 1], sensing.visible(world, pa, pb))
        assert np.array_equal(out[rows[c] : rows[c] + h + 1, 1, 0], sensing.visible(world, pb, pa))
        seen = np.nonzero(out[rows[c] : rows[c] + h + 1].any(axis=(1, 2)))[0]
        assert first[c] == (seen[0] if seen.size else -1)
    assert out[:, 0, 1].any() and not out[:, 0, 1].all()  # robots see each other at some steps only
