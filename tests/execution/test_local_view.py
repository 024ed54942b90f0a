"""What the simulated robots' costmaps give their controllers (tmpnav/execution/local_view.py):
the steering pose placed among the walls by the lidar's nearby returns, and commands that keep
the footprint clear of what the robot sees whatever its estimate says."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.execution.test_site import LIDAR, WALL, _box_distance, corridor
from tmpnav.execution.local_view import KEEP_CLEAR, LocalView, _rollouts
from tmpnav.execution.site import Site, SiteNoise

RADIUS = 0.25


def view(width: float = 2.0, pillar: bool = False) -> LocalView:
    """A corridor of ``width`` m along x, its free space from y = WALL to WALL + width, the site the map."""
    return LocalView(Site(corridor(length=20.0, width=width, pillar=pillar), SiteNoise.none(), 0), LIDAR)


def test_the_steering_pose_is_where_the_lidar_places_the_robot_among_the_walls() -> None:
    """The robot stands 0.3 m from the lower wall of a corridor, its estimate 0.3 m farther out and
    0.4 m along: it steers on a pose at the right distance from the walls; along the corridor,
    where the walls say nothing, the estimate is kept; the heading is the estimate's."""
    v = view()
    truth = np.array([10.0, WALL + 0.3, 0.0])
    est = np.array([10.4, WALL + 0.6, 0.05])
    steer = v.steering_pose(est, truth)
    assert abs(steer[1] - truth[1]) < 0.03
    assert abs(steer[0] - est[0]) < 0.05 and steer[2] == est[2]


def test_beside_a_pillar_the_lidar_places_the_robot_both_ways() -> None:
    """Beside the pillar (x 10-11.5 m, y 2.85-3.85 m) the returns fix the position along the
    corridor as well: an estimate 0.3 m off in x and y steers from where the robot is."""
    v = view(width=8.0, pillar=True)
    truth = np.array([9.4, 3.3, 0.0])
    est = truth + np.array([0.3, -0.3, 0.0])
    steer = v.steering_pose(est, truth)
    assert float(np.hypot(*(steer[:2] - truth[:2]))) < 0.05


def test_with_nothing_near_the_estimate_steers_alone() -> None:
    """In the middle of a wide hall no return lies within reach: the estimate steers."""
    wide = view(width=6.0)
    est = np.array([10.0, WALL + 3.0, 0.0])
    assert wide.steering_pose(est, est + np.array([0.0, 0.2, 0.0])) is est


def test_a_command_that_stays_clear_is_kept_and_one_into_a_wall_is_turned_away() -> None:
    v = view()
    along = np.array([10.0, WALL + 1.0, 0.0])
    command = np.array([0.5, 0.0])
    assert v.safe_command(along, command, RADIUS, (0.5, 1.0), 5.0) is command
    assert v.safe_command(along, np.array([0.0, 1.0]), RADIUS, (0.5, 1.0), 5.0)[0] == 0.0  # turning in place
    towards = np.array([10.0, WALL + 0.6, -math.pi / 3])  # 0.35 m of room, heading for the wall
    safe = v.safe_command(towards, command, RADIUS, (0.5, 1.0), 5.0)
    assert safe[1] > 0.0  # it turns away from the lower wall
    clear = _rollouts(v.clearance, towards, np.array([safe[0]]), np.array([safe[1]]))[0] - RADIUS
    assert clear >= KEEP_CLEAR
    straight = _rollouts(v.clearance, towards, np.array([0.5]), np.array([0.0]))[0] - RADIUS
    assert straight < 0.0  # the command itself would have hit within the horizon


def test_a_robot_boxed_in_gets_no_command() -> None:
    """Facing a wall 0.3 m ahead with both sides blocked within the horizon: no arc keeps clear, so
    the controller fails (None: nav2's recoveries take over) rather than drive into it; backing
    away keeps clear, driving on does not."""
    v = view(width=0.8)
    pose = np.array([10.0, WALL + 0.4, math.pi / 2])  # across the narrow corridor, the wall ahead
    assert v.safe_command(pose, np.array([0.5, 0.0]), RADIUS, (0.5, 0.5), 5.0) is None
    assert v.clear_path(pose, -0.05, RADIUS, 2.0)
    assert not v.clear_path(pose, 0.5, RADIUS, 2.0)


def test_a_robot_stopping_short_of_a_wall_may_drive_up_to_it() -> None:
    """A waypoint 0.3 m short of the wall ahead: the check ends where the robot stops, so it drives
    there; a waypoint past the wall is refused."""
    v = view()
    pose = np.array([10.0, WALL + 1.0, math.pi / 2])  # 1 m from the upper wall, heading for it
    command = np.array([0.5, 0.0])
    assert v.safe_command(pose, command, RADIUS, (0.5, 1.0), 0.4) is command
    assert v.safe_command(pose, command, RADIUS, (0.5, 1.0), 2.0) is not command
    goal = pose[:2] + np.array([0.0, 0.65])  # a goal 0.1 m from the wall: the robot may drive up to it
    assert v.safe_command(pose, command, RADIUS, (0.5, 1.0), 0.65, goal) is command


def test_the_room_beside_clutter_is_the_exact_distance_not_the_sites_lower_bound() -> None:
    """The site's field, which its ray casts march on, is exact only near a box and a lower bound
    (at least 0.3 m) beyond: a robot on a path kept 0.6 m from every box would read 0.3 m of it,
    no more than a 0.25 m robot needs with 5 cm to spare, and see every command refused. The
    local view measures the walls and the boxes exactly."""
    world = corridor()
    noise = SiteNoise(clutter=4, wall_offset=0, people=0)
    path = np.column_stack([np.arange(1.0, 59.0, 0.2), np.full(290, WALL + 4.0)])
    v = LocalView(Site(world, noise, 1, keep_clear=path), LIDAR)
    x, y = path.T  # the free space is x in [WALL, 60 + WALL], y in [WALL, 8 + WALL]
    walls = np.min([x - WALL, 60.0 + WALL - x, y - WALL, 8.0 + WALL - y], axis=0)
    exact = np.minimum(walls, np.min([_box_distance(path, box, noise.clutter_size) for box in v.site.boxes], axis=0))
    np.testing.assert_allclose(v.clearance(path), exact, atol=0.03)
    rows, cols, _ = world.grid.cells(path)
    lower = v.site.field[rows, cols]
    assert (lower <= exact + 0.04).all() and (lower < exact - 0.1).any()  # the field is looser (at cell centres)
    for pose in np.column_stack([path[::10], np.zeros(29)]):  # driving along the path is never refused
        assert v.safe_command(pose, np.array([0.5, 0.0]), RADIUS, (0.5, 1.0), 5.0) is not None


def test_another_robot_in_sight_is_kept_clear_of_like_a_wall() -> None:
    """Another robot standing 0.6 m ahead in an open corridor: driving on is refused or turned
    away from it; with nobody there the same command is kept."""
    v = view(width=6.0)
    pose = np.array([10.0, WALL + 3.0, 0.0])
    command = np.array([0.5, 0.0])
    assert v.safe_command(pose, command, RADIUS, (0.5, 1.0), 5.0) is command
    v.robots = np.array([[10.6, WALL + 3.0, RADIUS]])
    safe = v.safe_command(pose, command, RADIUS, (0.5, 1.0), 5.0)
    assert safe is None or abs(safe[1]) > 0.0
    assert float(v.clearance(pose[None, :2])[0]) == pytest.approx(0.6 - RADIUS)
