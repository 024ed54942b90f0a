"""Doors: the passages between two rooms of a segmentation, as segments from jamb to jamb.

Two rooms touch along one or more stretches of border; each stretch (8-connected) is one
passage. The watershed draws that border across the doorway, and rooms touch only where both
sides are free, so the stretch runs from jamb to jamb: its extent along its principal axis is
the door leaf the scenario format wants (``doors[].segment``), and its length the door's width.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy import ndimage

from tmpnav.rooms.segment import EIGHT, Segmentation
from tmpnav.world.grid import OccupancyGrid, fill_segment

Point = tuple[float, float]
MIN_DOOR_WIDTH = 0.5  # m: narrower passages (a gap a laser saw through) are not doors
DOOR_THICKNESS = 0.15  # m: the scenario format's default door thickness on a ROS map


@dataclass(frozen=True)
class DoorCandidate:
    """A passage between rooms ``rooms`` (1-based labels, ascending)."""

    rooms: tuple[int, int]
    segment: tuple[Point, Point]  # jamb to jamb, m
    width: float  # m

    @property
    def centre(self) -> Point:
        (x0, y0), (x1, y1) = self.segment
        return ((x0 + x1) / 2, (y0 + y1) / 2)


def find_doors(
    seg: Segmentation,
    min_width: float = MIN_DOOR_WIDTH,
    solid: np.ndarray | None = None,
    pairs: Callable[[tuple[int, int]], bool] | None = None,
) -> list[DoorCandidate]:
    """Every passage at least ``min_width`` wide between two rooms, ordered by rooms then position.

    ``pairs``, if given, says which pairs of rooms to look at. ``solid``, if given, marks cells a
    door must not be carved through (racks, pillars): a border is cut where it crosses them, and
    a door is shortened until the strip world.build carves for it misses them (or dropped). A
    door between rooms runs along a doorway, free by definition; a connection between two places
    of a hall runs across open floor, where a pillar may stand on it, and may meet a wall at a
    slant.
    """
    doors = []
    for pair, cells in borders(seg.labels).items():
        if pairs is not None and not pairs(pair):
            continue
        if solid is not None:
            cells = cells[~solid[cells[:, 0], cells[:, 1]]]
        for part in _stretches(cells):
            door: DoorCandidate | None = _door(seg, pair, part)
            if door is not None and solid is not None:
                door = _kept_clear(door, solid, seg.grid, min_width)
            if door is not None and door.width >= min_width:
                doors.append(door)
    return sorted(doors, key=lambda d: (d.rooms, d.centre[1], d.centre[0]))


def _stretches(cells: np.ndarray) -> list[np.ndarray]:
    """``cells`` (m, 2) split into 8-connected stretches, in the order ndimage.label finds them."""
    if cells.size == 0:
        return []
    lo = cells.min(axis=0)
    mask = np.zeros(tuple(cells.max(axis=0) - lo + 1), dtype=bool)
    mask[cells[:, 0] - lo[0], cells[:, 1] - lo[1]] = True
    parts, n = ndimage.label(mask, structure=EIGHT)
    found = parts[cells[:, 0] - lo[0], cells[:, 1] - lo[1]]
    order = np.lexsort((cells[:, 1], cells[:, 0]))  # row-major, as np.argwhere lists them
    return [cells[order][found[order] == k] for k in range(1, n + 1)]


def borders(labels: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """(a, b) with a < b -> the cells (m, 2) of either room that have a 4-neighbour in the other."""
    base = int(labels.max()) + 1
    keys, cells = [], []
    rows, cols = labels.shape
    for di, dj in ((0, 1), (1, 0)):
        a = labels[: rows - di, : cols - dj]
        b = labels[di:, dj:]
        ij = np.argwhere((a != b) & (a > 0) & (b > 0))
        la, lb = a[ij[:, 0], ij[:, 1]].astype(np.int64), b[ij[:, 0], ij[:, 1]].astype(np.int64)
        key = np.minimum(la, lb) * base + np.maximum(la, lb)
        keys += [key, key]
        cells += [ij, ij + np.array([di, dj])]
    key, cell = np.concatenate(keys), np.concatenate(cells)
    if key.size == 0:
        return {}
    order = np.argsort(key, kind="stable")
    key, cell = key[order], cell[order]
    uniq, start = np.unique(key, return_index=True)
    groups = np.split(cell, start[1:])
    return {(int(k // base), int(k % base)): np.unique(g, axis=0) for k, g in zip(uniq, groups, strict=True)}


def _kept_clear(door: DoorCandidate, solid: np.ndarray, grid: OccupancyGrid, min_width: float) -> DoorCandidate | None:
    """``door`` (its ends to the centimetre, as the scenario has them) shortened a cell at a time
    at whichever end the strip world.build carves for it touches a ``solid`` cell, or None when
    it is narrower than ``min_width`` before that strip comes clear."""
    a, b = (np.round(np.array(p, dtype=float), 2) for p in door.segment)
    while (width := float(np.hypot(*(b - a)))) >= min_width:
        hits = _solid_in_strip(a, b, solid, grid)
        if hits.size == 0:
            return replace(door, segment=((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))), width=width)
        along = (hits - a) @ (b - a) / width**2
        step = grid.resolution * (b - a) / width
        a = np.round(a + step, 2) if (along < 0.5).any() else a
        b = np.round(b - step, 2) if (along >= 0.5).any() else b
    return None


def _solid_in_strip(a: np.ndarray, b: np.ndarray, solid: np.ndarray, grid: OccupancyGrid) -> np.ndarray:
    """Centres (m, 2) of the ``solid`` cells in the strip world.build carves for an open door
    from a to b (``DOOR_THICKNESS`` and a cell either side, flat caps)."""
    r = grid.resolution
    thickness = DOOR_THICKNESS + 2 * r
    i0, j0, _ = grid.cells(np.minimum(a, b) - thickness)
    i1, j1, _ = grid.cells(np.maximum(a, b) + thickness)
    window = slice(int(i0), int(i1) + 1), slice(int(j0), int(j1) + 1)
    xs, ys = grid.cell_centers()
    strip = np.zeros(solid[window].shape, dtype=bool)
    fill_segment(strip, xs[window[1]], ys[window[0]], a, b, thickness, True, flat_caps=True)
    i, j = np.nonzero(strip & solid[window])
    return np.column_stack([xs[window[1]][j], ys[window[0]][i]])


def _door(seg: Segmentation, pair: tuple[int, int], part: np.ndarray) -> DoorCandidate:
    """The door across one stretch of border (cells ``part``, row and column)."""
    axis = _principal_axis(part)
    t = (part - part.mean(axis=0)) @ axis
    # the faces of the jambs: half a cell beyond the outermost cells of the stretch
    ends = part[np.argmin(t)] - 0.5 * axis, part[np.argmax(t)] + 0.5 * axis
    r, (x0, y0) = seg.grid.resolution, seg.grid.origin
    (i0, j0), (i1, j1) = ends
    a = (float(x0 + (j0 + 0.5) * r), float(y0 + (i0 + 0.5) * r))
    b = (float(x0 + (j1 + 0.5) * r), float(y0 + (i1 + 0.5) * r))
    return DoorCandidate(pair, (a, b), float(np.hypot(b[0] - a[0], b[1] - a[1])))


def _principal_axis(part: np.ndarray) -> np.ndarray:
    """Unit vector (row, col) along which the cells ``part`` (m, 2) spread most: across the doorway."""
    if part.shape[0] < 2:
        return np.array([0.0, 1.0])
    axis = np.linalg.svd(part - part.mean(axis=0), full_matrices=False)[2][0]
    return axis if axis[np.argmax(np.abs(axis))] > 0 else -axis
