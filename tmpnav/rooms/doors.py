"""Doors: the passages between two rooms of a segmentation, as segments from jamb to jamb.

Two rooms touch along one or more stretches of border; each stretch (8-connected) is one
passage. The watershed draws that border across the doorway, and rooms touch only where both
sides are free, so the stretch runs from jamb to jamb: its extent along its principal axis is
the door leaf the scenario format wants (``doors[].segment``), and its length the door's width.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from tmpnav.rooms.segment import EIGHT, Segmentation

Point = tuple[float, float]
MIN_DOOR_WIDTH = 0.5  # m: narrower passages (a gap a laser saw through) are not doors


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


def find_doors(seg: Segmentation, min_width: float = MIN_DOOR_WIDTH) -> list[DoorCandidate]:
    """Every passage at least ``min_width`` wide between two rooms, ordered by rooms then position."""
    doors = []
    for pair, cells in borders(seg.labels).items():
        mask = np.zeros(seg.labels.shape, dtype=bool)
        mask[cells[:, 0], cells[:, 1]] = True
        parts, n = ndimage.label(mask, structure=EIGHT)
        for k in range(1, n + 1):
            part = np.argwhere(parts == k)
            door = _door(seg, pair, part)
            if door.width >= min_width:
                doors.append(door)
    return sorted(doors, key=lambda d: (d.rooms, d.centre[1], d.centre[0]))


def borders(labels: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """(a, b) with a < b -> the cells (m, 2) of either room that have a 4-neighbour in the other."""
    cells: dict[tuple[int, int], list[np.ndarray]] = {}
    rows, cols = labels.shape
    for di, dj in ((0, 1), (1, 0)):
        a = labels[: rows - di, : cols - dj]
        b = labels[di:, dj:]
        ij = np.argwhere((a != b) & (a > 0) & (b > 0))
        la, lb = a[ij[:, 0], ij[:, 1]], b[ij[:, 0], ij[:, 1]]
        for (x, y), p, q in zip(ij, la, lb, strict=True):
            key = (int(min(p, q)), int(max(p, q)))
            cells.setdefault(key, []).append(np.array([[x, y], [x + di, y + dj]]))
    return {k: np.unique(np.concatenate(v), axis=0) for k, v in sorted(cells.items())}


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
