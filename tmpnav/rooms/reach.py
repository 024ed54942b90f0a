"""Which rooms a robot reaches from its start, as ``tmpnav validate`` will see the scenario.

Free space is what ``validate`` tests on the world the scenario builds (doors carved free,
clearance at least radius plus one cell, 8-connected), with ``LEEWAY`` to spare. Validate is
content with one reachable cell inside a room's polygon; here at least half of the room's free
cells must be reachable (a doorway's share of a room is not the room). A speck of noise just
before a doorway can block it for the robot; a door carved ``DEEP_DOOR`` deep clears it, and is
used only where that makes a room reachable that was not.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy import ndimage

from tmpnav.rooms.doors import DOOR_THICKNESS, DoorCandidate
from tmpnav.rooms.segment import EIGHT
from tmpnav.world.geometry import points_in_polygon
from tmpnav.world.grid import OccupancyGrid, clearance, fill_segment

DEEP_DOOR = 1.2  # m: a door carved this deep also clears noise just before and after the doorway
#: m: a passage counts when a robot this much wider fits through: validate accepts a path one cell
#: wide between specks of noise, but the roadmap's random samples would hardly ever find it
LEEWAY = 0.05


def reachable_rooms(
    grid: OccupancyGrid,
    polygons: Mapping[int, np.ndarray],
    doors: Mapping[str, DoorCandidate],
    start: tuple[int, int],
    radius: float,
) -> tuple[set[int], set[str], np.ndarray]:
    """The rooms (keys of ``polygons``) a robot of ``radius`` reaches from the cell ``start``, the
    doors that must be carved ``DEEP_DOOR`` deep for that, and the cells it reaches."""
    inside = {label: polygon_cells(grid, polygon) for label, polygon in polygons.items()}

    def reachable(deep: set[str]) -> tuple[set[int], np.ndarray]:
        free, component = free_from(grid, doors, deep, start, radius)
        out = set()
        for label, (rows, cols) in inside.items():
            room_free = np.count_nonzero(free[rows, cols])
            if room_free and np.count_nonzero(component[rows, cols]) >= 0.5 * room_free:
                out.add(label)
        return out, component

    usual, component = reachable(set())
    deep = {name for name, d in doors.items() if not set(d.rooms) <= usual}
    if deep:
        found, _ = reachable(deep)
        deep = {name for name in deep if set(doors[name].rooms) <= found}
    if not deep:
        return usual, deep, component
    rooms, component = reachable(deep)
    return rooms, deep, component


def polygon_cells(grid: OccupancyGrid, polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the cells whose centres lie inside ``polygon`` (k, 2), m."""
    xs, ys = grid.cell_centers()
    cols = np.nonzero((xs >= polygon[:, 0].min()) & (xs <= polygon[:, 0].max()))[0]
    rows = np.nonzero((ys >= polygon[:, 1].min()) & (ys <= polygon[:, 1].max()))[0]
    gi, gj = np.meshgrid(rows, cols, indexing="ij")
    inside = points_in_polygon(np.column_stack([xs[gj.ravel()], ys[gi.ravel()]]), polygon)
    return gi.ravel()[inside], gj.ravel()[inside]


def free_from(
    grid: OccupancyGrid,
    doors: Mapping[str, DoorCandidate],
    deep: set[str],
    start: tuple[int, int],
    radius: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Cells where a robot of ``radius`` fits with ``LEEWAY`` to spare, and those of them it
    reaches from ``start``, with the doors carved as world.build carves them."""
    occupied = grid.occupied.copy()
    xs, ys = grid.cell_centers()
    for name, door in doors.items():
        thickness = (DEEP_DOOR if name in deep else DOOR_THICKNESS) + 2 * grid.resolution  # as world.build carves
        a, b = (np.array(p) for p in door.segment)
        fill_segment(occupied, xs, ys, a, b, thickness, False, flat_caps=True)
    clear = clearance(OccupancyGrid(occupied, grid.origin, grid.resolution))
    free = clear >= radius + grid.resolution + LEEWAY
    comp, _ = ndimage.label(free, structure=EIGHT)
    return free, (comp == comp[start] if comp[start] > 0 else np.zeros(grid.shape, dtype=bool))
