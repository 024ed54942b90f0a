"""Regulated Pure Pursuit as the planner drives a path with it (models.controller: rpp), and the
shortcut of a roadmap path before it is driven."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from tmpnav.belief.controls import path_controls
from tmpnav.belief.models import motion
from tmpnav.belief.pursuit import PLAN_SUBSTEPS, RppParams, pursuit_controls
from tmpnav.execution.rpp import RppFollower
from tmpnav.roadmap.shortcut import shortcut

DT = 0.5
RES = 0.05


def open_floor(size: float = 20.0) -> tuple[np.ndarray, tuple[float, float]]:
    """A clearance grid of open floor (every cell 5 m from an obstacle), origin at (-size/2, -size/2)."""
    n = int(size / RES)
    return np.full((n, n), 5.0), (-size / 2, -size / 2)


def walled(rows: slice, cols: slice, size: float = 20.0) -> tuple[np.ndarray, tuple[float, float]]:
    """The clearance grid of open floor with a block of occupied cells."""
    from scipy import ndimage

    n = int(size / RES)
    free = np.ones((n, n), dtype=bool)
    free[rows, cols] = False
    return ndimage.distance_transform_edt(free) * RES, (-size / 2, -size / 2)


def unicycle(pose: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The pose after one control step of DT without noise (the midpoint step the planner's
    rollout takes), its heading wrapped."""
    x, y, theta = pose
    mid = theta + 0.5 * u[1] * DT
    after = np.array([x + u[0] * DT * math.cos(mid), y + u[0] * DT * math.sin(mid), theta + u[1] * DT])
    after[2] = (after[2] + math.pi) % (2 * math.pi) - math.pi
    return after


def follow_without_noise(f: RppFollower, pc, start: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Drive the follower ``f`` from ``start`` on its own commands, without noise and with every
    obstacle 5 m away, checking each pose and command against the planner's rollout ``pc``; the
    pose it ends at."""
    pose = start
    for k in range(pc.n_steps):
        assert np.allclose(pose, pc.poses[k])
        u = f.command(pose, 5.0)
        assert np.allclose(u, pc.controls[k])
        pose = unicycle(pose, u)
    return pose


def drive(
    points: list[list[float]],
    theta: float = 0.0,
    speed: float = 0.5,
    turn_rate: float = 1.0,
    dt: float = DT,
    substeps: int = PLAN_SUBSTEPS,
):  # type: ignore[no-untyped-def]
    clear, origin = open_floor()
    pc = pursuit_controls(
        np.array(points, float), theta, speed, turn_rate, dt, RppParams(), clear, origin, RES, substeps=substeps
    )
    assert pc is not None
    return pc


def test_a_straight_path_is_driven_at_speed_then_slowed_on_the_approach() -> None:
    pc = drive([[0.0, 0.0], [5.0, 0.0]])
    v = pc.controls[:, 0]
    assert np.allclose(pc.controls[:, 1], 0.0)
    assert np.isclose(v.max(), 0.5)
    assert v[-1] < 0.5  # nav2's approach scaling
    end = pc.poses[-1]
    assert math.hypot(end[0] - 5.0, end[1]) <= RppParams().xy_goal_tolerance
    # 4.75 m at 0.5 m/s is 9.5 s; the approach adds a little
    assert 9.5 <= pc.n_steps * DT <= 11.0


def test_a_corner_is_turned_while_driving_within_the_robot_limits() -> None:
    pc = drive([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]], turn_rate=1.0)
    v, w = pc.controls[:, 0], pc.controls[:, 1]
    assert np.any((v > 0.2) & (np.abs(w) > 0.1))  # v and omega together at the corner
    assert v.max() <= 0.5 + 1e-12 and np.abs(w).max() <= 1.0 + 1e-12
    # the curvature regulation slows the robot on the bend
    assert v[np.abs(w) > 0.1].min() < 0.5
    # it never turns on the spot: the start is aligned and the corner is cut
    assert not np.any((v == 0.0) & (np.abs(w) > 0.0))
    # turn-then-drive takes longer: it stops to turn at the corner
    ttd = path_controls(np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]]), 0.0, 0.5, 1.0, DT)
    assert pc.n_steps < ttd.n_steps


def test_the_poses_follow_the_motion_model_step_by_step() -> None:
    """Each step is the motion model's midpoint step: it translates along the heading at the
    step's middle, theta + omega dt / 2."""
    pc = drive([[0.0, 0.0], [3.0, 1.0], [2.0, 4.0], [-1.0, 4.0]], theta=2.0)
    x, u = pc.poses[:-1], pc.controls
    mid = x[:, 2] + 0.5 * u[:, 1] * DT
    expected = np.column_stack(
        [x[:, 0] + u[:, 0] * DT * np.cos(mid), x[:, 1] + u[:, 0] * DT * np.sin(mid), x[:, 2] + u[:, 1] * DT]
    )
    wrapped = (expected[:, 2] + np.pi) % (2 * np.pi) - np.pi
    assert np.allclose(pc.poses[1:, :2], expected[:, :2])
    assert np.allclose(np.cos(pc.poses[1:, 2] - wrapped), 1.0)
    assert np.allclose(pc.poses[1:], motion(x, u, DT, midpoint=True))
    assert np.any(u[:, 0] * u[:, 1] != 0.0)  # steps that turn while they drive, where the two steps differ


def test_the_plan_step_drives_as_the_law_at_nav2s_rate() -> None:
    """At the plan's 0.5 s the law's commands held for a step drive the bends as the law run at
    20 Hz does: no longer, and in no more time than a step's grain (with the Euler step the robot
    went on along its heading before each turn, weaved about the path and took 3% longer in the
    median over office-ros' motions, benchmarks/rpp/controller_rate.txt)."""
    points = [[0.0, 0.0], [3.0, 1.0], [2.0, 4.0], [-1.0, 4.0]]  # Euler's steps: 20.0 s against 18.75 s
    coarse = drive(points, theta=0.0)
    fine = drive(points, theta=0.0, dt=DT / 10)
    length = [float(np.hypot(*np.diff(p.poses[:, :2], axis=0).T).sum()) for p in (coarse, fine)]
    assert length[0] <= 1.01 * length[1]
    assert coarse.n_steps * DT <= fine.n_steps * DT / 10 + DT


def test_a_turn_on_the_spot_ramps_up_as_at_nav2s_rate() -> None:
    """A short move that starts with a turn on the spot (a robot leaving a dock or a room the way
    it came): at 20 Hz the turn ramps up within max_angular_accel, 0.3 s to full rate. The law
    once per 0.5 s step reached full rate at once and planned a step less than 20 Hz drives on
    the plan's grid (building-4robots' r4 out of its dock: 5.5 s where 20 Hz drives 6.2 s);
    run twice a step it plans what 20 Hz drives."""
    for points in ([[0.0, 0.0], [0.0, -0.5], [0.0, -2.5]], [[0.0, 0.0], [-0.5, -0.2], [-2.5, -0.2]]):
        fine = drive(points, theta=0.0, dt=DT / 10, substeps=1).n_steps * DT / 10
        grid = math.ceil(fine / DT - 1e-9) * DT
        assert drive(points, theta=0.0, substeps=1).n_steps * DT == grid - DT
        assert drive(points, theta=0.0).n_steps * DT == grid


def test_a_start_facing_away_turns_on_the_spot_first() -> None:
    pc = drive([[0.0, 0.0], [3.0, 0.0]], theta=math.pi)
    first = pc.controls[0]
    assert first[0] == 0.0 and abs(first[1]) > 0.0
    assert np.all(np.diff(pc.node_steps) >= 0)


def test_the_planner_rollout_is_the_follower_driven_without_noise() -> None:
    """simulate --follower rpp steers with the same compiled law: driven on its own poses with the
    same obstacle distances, it gives the planner's controls (the planner's rollout with the law
    once per step, as RppFollower.command gives it)."""
    points = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [1.0, 5.0]])
    pc = drive(points.tolist(), theta=0.3, substeps=1)
    f = RppFollower(points, RppParams(), 0.5, 1.0, DT)
    pose = follow_without_noise(f, pc, np.array([0.0, 0.0, 0.3]))
    assert f.at_goal(pose)


def test_near_walls_the_robot_slows_as_nav2_does() -> None:
    # a wall 0.3 m beside the path: cost regulation v * d / 0.6
    clear, origin = walled(slice(200 - 8, 200 - 6), slice(0, 400))
    pc = pursuit_controls(np.array([[-5.0, 0.0], [5.0, 0.0]]), 0.0, 0.5, 1.0, DT, RppParams(), clear, origin, RES)
    assert pc is not None
    cruising = pc.controls[5:-5, 0]
    assert np.all(cruising < 0.5) and np.all(cruising >= RppParams().regulated_linear_scaling_min_speed)


def test_a_zig_zag_in_the_open_is_cut_to_its_ends() -> None:
    clear, origin = open_floor()
    points = np.array([[0.0, 0.0], [1.0, 0.3], [2.0, -0.2], [3.0, 0.4], [4.0, 0.0]])
    assert shortcut(points, 0.8, clear, origin, RES).tolist() == [0, 4]


def test_a_shortcut_keeps_the_corner_round_a_wall() -> None:
    # a wall along x in [-10, 0.5] at y in [0.9, 1.1]: the path goes round its end
    clear, origin = walled(slice(218, 222), slice(0, 210))
    points = np.array([[-2.0, 0.0], [0.0, 0.0], [1.5, 0.0], [1.5, 2.0], [0.0, 2.0], [-2.0, 2.0]])
    keep = shortcut(points, 0.6, clear, origin, RES)
    assert keep[0] == 0 and keep[-1] == 5
    assert 2 in keep.tolist() or 3 in keep.tolist()  # it does not cut through the wall's end
    for a, b in itertools.pairwise(keep):
        n = 200
        seg = points[a] + (points[b] - points[a]) * np.linspace(0, 1, n)[:, None]
        i = np.floor((seg[:, 1] - origin[1]) / RES).astype(int)
        j = np.floor((seg[:, 0] - origin[0]) / RES).astype(int)
        assert clear[i, j].min() >= 0.6 - 1e-9


@pytest.mark.parametrize("n", [0, 1, 2])
def test_short_paths_are_kept_as_they_are(n: int) -> None:
    clear, origin = open_floor()
    assert shortcut(np.zeros((n, 2)) + np.arange(n)[:, None], 0.5, clear, origin, RES).tolist() == list(range(n))


def test_a_shortcut_keeps_the_middle_of_a_door() -> None:
    # a wall along y = 0 with a door at x in [-0.5, 0.5]: the path's node in the door stays
    clear, origin = walled(slice(198, 202), slice(0, 190))
    right = walled(slice(198, 202), slice(210, 400))[0]
    clear = np.minimum(clear, right)
    points = np.array([[-3.0, -3.0], [-1.5, -1.5], [0.0, 0.0], [1.5, 1.5], [3.0, 3.0]])
    keep = shortcut(points, 1.0, clear, origin, RES).tolist()
    assert 2 in keep and keep[0] == 0 and keep[-1] == 4


def test_at_a_goal_pose_it_stops_within_the_tolerance_and_turns_to_the_heading() -> None:
    """nav2 given a goal pose: RPP drives until within the goal checker's 0.25 m, then turns on
    the spot to the pose's heading until within 0.25 rad of it; it does not close in on the pose."""
    clear, origin = open_floor()
    points, params = np.array([[0.0, 0.0], [5.0, 0.0]]), RppParams()
    plain = pursuit_controls(points, 0.0, 0.5, 1.0, DT, params, clear, origin, RES, substeps=1)
    posed = pursuit_controls(
        points, 0.0, 0.5, 1.0, DT, params, clear, origin, RES, goal_heading=math.pi / 2, substeps=1
    )
    assert plain is not None and posed is not None
    # the same drive, then the turn: about pi / 2 at 1 rad/s, no step driven
    n = plain.n_steps
    assert np.array_equal(posed.controls[:n], plain.controls)
    turn = posed.controls[n:]
    assert len(turn) and np.all(turn[:, 0] == 0.0) and np.all(turn[:, 1] > 0.0)
    assert 1.0 <= len(turn) * DT <= 2.5
    end = posed.poses[-1]
    assert math.hypot(end[0] - 5.0, end[1]) > 0.05  # left where the goal checker stopped it
    assert math.hypot(end[0] - 5.0, end[1]) <= params.xy_goal_tolerance
    assert abs(end[2] - math.pi / 2) <= params.yaw_goal_tolerance
    # a heading it already points within the tolerance of adds nothing
    near = pursuit_controls(points, 0.0, 0.5, 1.0, DT, params, clear, origin, RES, goal_heading=0.2, substeps=1)
    assert near is not None and near.n_steps == n


def test_the_follower_turns_to_a_goal_pose_as_the_planner_rollout_does() -> None:
    points = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0]])
    clear, origin = open_floor()
    pc = pursuit_controls(points, 0.0, 0.5, 1.0, DT, RppParams(), clear, origin, RES, goal_heading=-2.5, substeps=1)
    assert pc is not None
    f = RppFollower(points, RppParams(), 0.5, 1.0, DT, goal_heading=-2.5)
    pose = np.array([0.0, 0.0, 0.0])
    for k in range(pc.n_steps):
        assert np.allclose(pose, pc.poses[k])
        assert not f.at_goal(pose)
        u = f.command(pose, 5.0)
        assert np.allclose(u, pc.controls[k])
        pose = unicycle(pose, u)
    assert f.at_goal(pose)
