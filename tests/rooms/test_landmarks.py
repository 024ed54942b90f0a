"""Landmark candidates: isolated obstacles, door frames, and a corner for rooms with neither."""

from __future__ import annotations

import numpy as np

from tmpnav.rooms.doors import DoorCandidate, find_doors
from tmpnav.rooms.landmarks import find_landmarks, room_corner
from tmpnav.rooms.polygon import outline
from tmpnav.rooms.segment import segment
from tmpnav.world.grid import OccupancyGrid


def building() -> OccupancyGrid:
    """Two 3 m rooms side by side (row 0 is the lowest y), a 1 m door, a pillar in the left room."""
    occ = np.zeros((64, 126), dtype=bool)
    occ[:2], occ[-2:], occ[:, :2], occ[:, -2:] = True, True, True, True
    occ[:, 62:64] = True
    occ[22:42, 62:64] = False
    occ[30:36, 20:26] = True  # a 0.3 m pillar centred at (1.15, 1.65)
    return OccupancyGrid(occ, (0.0, 0.0), 0.05)


def test_pillar_door_frame_and_no_corner_where_a_landmark_is() -> None:
    grid = building()
    seg = segment(grid)
    doors = {f"D{i}": d for i, d in enumerate(find_doors(seg), start=1)}
    outlines = {k: outline(seg.mask(k), grid) for k in range(1, seg.n_rooms + 1)}
    found = find_landmarks(seg, doors, outlines)
    kinds = [lm.kind for lm in found]
    assert kinds == ["pillar", "door-frame"]  # the door frame lies on both rooms' outlines
    pillar = found[0]
    assert np.allclose(pillar.position, (1.15, 1.65), atol=0.03)
    assert found[1].position == doors["D1"].segment[0]


def test_a_room_without_landmarks_gets_a_corner_away_from_its_door() -> None:
    grid = building()
    seg = segment(grid)
    outlines = {k: outline(seg.mask(k), grid) for k in range(1, seg.n_rooms + 1)}
    found = find_landmarks(seg, {}, outlines)  # doors left out: the right room has nothing
    corners = [lm for lm in found if lm.kind == "corner"]
    assert len(corners) == 1 and corners[0].room == 2


def test_room_corner_is_the_right_angle_farthest_from_the_doors() -> None:
    square = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [0.0, 3.0]])
    door = DoorCandidate((1, 2), ((0.0, 0.5), (0.0, 1.5)), 1.0)
    assert room_corner(square, [door]) == (4.0, 3.0)
    assert room_corner(square, []) == (0.0, 0.0)
    triangle = np.array([[0.0, 0.0], [4.0, 0.0], [2.0, 0.3]])  # no angle near 90 degrees
    assert room_corner(triangle, []) is None
