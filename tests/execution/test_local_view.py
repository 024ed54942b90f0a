"""What the simulated robots' costmaps give their controllers (tmpnav/execution/local_view.py):
the steering pose moved to where the lidar sees the nearest wall, and commands that keep the
footprint clear of what the robot sees whatever its estimate says."""

from __future__ import annotations

import math

import numpy as np

from tests.execution.test_site import WALL, corridor
from tmpnav.execution.local_view import COSTMAP_RESOLUTION, KEEP_CLEAR, LocalView, _rollouts
from tmpnav.execution.site import Site, SiteNoise

RADIUS = 0.25


def view(width: float = 2.0) -> LocalView:
    """A corridor of ``width`` m along x, its free space from y = WALL to WALL + width, the site the map."""
    return LocalView(Site(corridor(length=20.0, width=width), SiteNoise.none(), 0))


def test_the_steering_pose_moves_across_the_wall_to_where_the_lidar_sees_it() -> None:
    """The robot stands 0.3 m from the lower wall, its estimate says 0.6 m: it steers on a pose
    0.3 m from that wall, to the costmap's cell; along the wall the estimate is left as it is."""
    v = view()
    truth = np.array([10.0, WALL + 0.3, 0.0])
    est = np.array([10.4, WALL + 0.6, 0.1])
    steer = v.steering_pose(est, truth)
    assert abs(steer[1] - truth[1]) <= COSTMAP_RESOLUTION / 2 + 0.01
    assert steer[0] == est[0] and steer[2] == est[2]


def test_far_from_the_walls_or_seeing_something_else_the_estimate_steers() -> None:
    """In the middle of a wide hall no wall constrains the path; a surface much nearer than the
    mapped wall (clutter) is not taken for it."""
    wide = view(width=6.0)
    est = np.array([10.0, WALL + 3.0, 0.0])
    assert wide.steering_pose(est, est + np.array([0.0, 0.2, 0.0])) is est
    narrow = view()
    est = np.array([10.0, WALL + 0.9, 0.0])
    assert narrow.steering_pose(est, np.array([10.0, WALL + 0.25, 0.0])) is est  # 0.65 m off: past the gate


def test_a_command_that_stays_clear_is_kept_and_one_into_a_wall_is_turned_away() -> None:
    v = view()
    along = np.array([10.0, WALL + 1.0, 0.0])
    command = np.array([0.5, 0.0])
    assert v.safe_command(along, command, RADIUS, (0.5, 1.0)) is command
    assert v.safe_command(along, np.array([0.0, 1.0]), RADIUS, (0.5, 1.0))[0] == 0.0  # turning in place
    towards = np.array([10.0, WALL + 0.6, -math.pi / 3])  # 0.35 m of room, heading for the wall
    safe = v.safe_command(towards, command, RADIUS, (0.5, 1.0))
    assert safe[1] > 0.0  # it turns away from the lower wall
    field = v.site.field
    clear = _rollouts(field, v.x0, v.y0, v.res, towards, np.array([safe[0]]), np.array([safe[1]]))[0] - RADIUS
    assert clear >= KEEP_CLEAR
    straight = _rollouts(field, v.x0, v.y0, v.res, towards, np.array([0.5]), np.array([0.0]))[0] - RADIUS
    assert straight < 0.0  # the command itself would have hit within the horizon


def test_a_robot_boxed_in_stands_and_turns() -> None:
    """Facing a wall 0.3 m ahead with both sides blocked within the horizon: no arc keeps clear, so
    the robot stands (nav2 would stop and recover) rather than drive into it."""
    v = view(width=0.8)
    pose = np.array([10.0, WALL + 0.4, math.pi / 2])  # across the narrow corridor, the wall ahead
    safe = v.safe_command(pose, np.array([0.5, 0.0]), RADIUS, (0.5, 0.5))
    assert safe[0] == 0.0
