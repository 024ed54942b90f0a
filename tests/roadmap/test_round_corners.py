"""A path's corners rounded before RPP drives it (tmpnav.roadmap.shortcut.round_corners): arcs
tangent to the segments, no nearer to the walls than the corners they replace, and driven by RPP
at full speed where a sharp corner slows it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.belief.test_pursuit import DT, RES, follow_without_noise, open_floor, walled
from tmpnav.belief.pursuit import RppParams, pursuit_controls
from tmpnav.belief.pursuit_path import Rounding
from tmpnav.execution.rpp import RppFollower
from tmpnav.roadmap.shortcut import CORNER_RADIUS, least_clearance, round_corners

L_TURN = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]])


def test_a_right_angle_in_the_open_becomes_an_arc_of_the_full_radius() -> None:
    clear, origin = open_floor()
    out, at = round_corners(L_TURN, 0.8, clear, origin, RES)
    assert at[0] == 0 and at[-1] == len(out) - 1
    assert np.allclose(out[0], L_TURN[0]) and np.allclose(out[-1], L_TURN[-1])
    arc = out[1:-1]
    centre = np.array([4.0 - CORNER_RADIUS, CORNER_RADIUS])
    assert np.allclose(np.hypot(*(arc - centre).T), CORNER_RADIUS)
    assert np.allclose(arc[0], [4.0 - CORNER_RADIUS, 0.0]) and np.allclose(arc[-1], [4.0, CORNER_RADIUS])
    # the corner's own index is its arc's middle, nearest the corner
    assert np.argmin(np.hypot(*(out - L_TURN[1]).T)) == at[1]
    assert np.max(np.hypot(*np.diff(arc, axis=0).T)) <= 0.05 + 1e-9


def test_short_segments_take_a_smaller_radius_and_leave_the_neighbours_their_half() -> None:
    clear, origin = open_floor()
    points = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.6], [2.0, 0.6]])
    out, at = round_corners(points, 0.8, clear, origin, RES)
    first, second = out[1 : at[1] + 1], out[at[2] : -1]
    # each arc ends within its half of the shared 0.6 m segment
    assert first[:, 1].max() <= 0.3 + 1e-9 and second[:, 1].min() >= 0.3 - 1e-9


@pytest.mark.parametrize("points", [[[0.0, 0.0], [2.0, 0.0], [4.0, 0.0]], [[0.0, 0.0], [2.0, 0.0], [0.0, 0.0]]])
def test_straight_on_and_turning_back_stay_as_they_are(points: list) -> None:
    clear, origin = open_floor()
    out, at = round_corners(np.array(points), 0.8, clear, origin, RES)
    assert np.allclose(out, points) and at.tolist() == [0, 1, 2]


def test_around_a_wall_the_arc_keeps_the_clearance_of_the_corner_it_replaces() -> None:
    # a block inside the turn, 0.5 m from the corner's two segments
    clear, origin = walled(slice(200 + 10, 200 + 70), slice(200 + 10, 200 + 70))
    points = np.array([[-3.0, 0.0], [4.0, 0.0], [4.0, 5.0]])
    points[:, 0] -= 0.5  # the corner at (3.5, 0), the block from (0.5, 0.5) to (3.5, 3.5)
    out, _ = round_corners(points, 0.8, clear, origin, RES)
    assert len(out) > 3  # rounded, with a smaller radius than the open floor's
    kept = least_clearance(points, clear, origin, RES)
    assert least_clearance(out, clear, origin, RES) >= min(kept, 0.8) - 1e-9
    # random polylines among the blocks: never nearer than the polyline or the clearance asked
    # (to the cells a line sampled a cell apart meets: a part of a segment may meet one more)
    rng = np.random.default_rng(3)
    for _ in range(200):
        poly = rng.uniform(-6.0, 6.0, size=(rng.integers(3, 8), 2))
        required = float(rng.uniform(0.2, 1.0))
        out, at = round_corners(poly, required, clear, origin, RES)
        floor = min(least_clearance(poly, clear, origin, RES), required)
        assert least_clearance(out, clear, origin, RES) >= floor - RES
        assert np.allclose(out[at[0]], poly[0]) and np.allclose(out[at[-1]], poly[-1])


def test_rpp_drives_a_rounded_corner_at_full_speed_and_a_sharp_one_slowed() -> None:
    clear, origin = open_floor()
    args = (L_TURN, 0.0, 0.5, 1.0, DT, RppParams(), clear, origin, RES)
    sharp, rounded = pursuit_controls(*args), pursuit_controls(*args, required=0.8)
    assert sharp is not None and rounded is not None
    least = RppParams().regulated_linear_scaling_min_speed
    assert sharp.controls[:-4, 0].min() < least + 0.05  # the corner's tight arc, slowed to near the least speed
    assert rounded.controls[:-4, 0].min() > 0.45  # on the arc of 0.9 m, at (about) full speed
    assert rounded.n_steps < sharp.n_steps


def test_the_follower_drives_the_rounded_path_the_plan_drove() -> None:
    clear, origin = open_floor()
    points = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [1.0, 5.0]])
    pc = pursuit_controls(points, 0.3, 0.5, 1.0, DT, RppParams(), clear, origin, RES, required=0.8, substeps=1)
    assert pc is not None
    f = RppFollower(points, RppParams(), 0.5, 1.0, DT, rounding=Rounding(0.8, clear, origin, RES))
    pose = follow_without_noise(f, pc, np.array([0.0, 0.0, 0.3]))
    assert f.at_goal(pose)
    assert math.hypot(*(pose[:2] - points[-1])) <= RppParams().xy_goal_tolerance
