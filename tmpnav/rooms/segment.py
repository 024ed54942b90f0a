"""An occupancy grid -> rooms: labelled regions of free space, split at narrow passages.

The method is the distance-transform watershed of the ROS room-segmentation packages,
followed by a merge that decides which passages are doors:

1. Free space, with *isolated* obstacles filled in and pinholes in walls closed: speckles of
   sensor noise, tables and pillars that touch no wall must not split a room (they are kept as
   landmark candidates), and a wall a laser saw through in places is still a wall.
2. The clearance D (distance to the nearest occupied cell, m) of every free cell. A room is a
   hill of D; a door between two rooms is a saddle of D, about half the door's width.
3. The watershed of -D from every regional maximum: many small basins.
4. Basins are merged while the passage between two of them is not a constriction: the saddle
   between basins a and b is the widest point of their common border, and they merge when
   ``saddle >= merge_ratio * min(peak_a, peak_b)`` (the passage is nearly as wide as the
   narrower of the two spaces). Basins smaller than ``min_area`` then join the neighbour they
   share the widest passage with, and with ``max_rooms`` the least constricted passages are
   opened until no more rooms than that remain.

A corridor joined to offices by 0.9 m doors stays apart from them (saddle 0.45 m against a
corridor half-width of 0.9 m or more); an open hall with pillars and shelving stays one room
(its bays are joined by passages as wide as the bays). A door at least about a quarter
narrower than the spaces it joins is found; a wider opening joins them into one room.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from tmpnav.rooms import MAX_AREA
from tmpnav.world.grid import OccupancyGrid

EIGHT = np.ones((3, 3), dtype=bool)
MAX_WALL_THICKNESS = 0.3  # m: an isolated obstacle mostly thinner than this ...
MIN_WALL_LENGTH = 0.6  # m: ... and longer than this is a piece of wall, not furniture or noise
SPECKLE_AREA = 0.02  # m²: an occupied blob this small is sensor noise
GAP = 0.2  # m: gaps in walls up to about this wide are closed before segmenting


@dataclass(frozen=True)
class SegmentParams:
    """Choices of the segmentation; the defaults suit office and warehouse maps."""

    min_area: float = 3.0  # m²: a region smaller than this joins its neighbour (or is dropped if alone)
    max_area: float = MAX_AREA  # m²: a larger room is a hall, split into places (tmpnav.rooms.places)
    max_rooms: int | None = None  # merge the least separated rooms until at most this many remain
    merge_ratio: float = 0.7  # see the module docstring
    fill_area: float = 1.5  # m²: isolated obstacles up to this size do not split rooms


@dataclass(frozen=True, eq=False)
class Segmentation:
    """Rooms as a label image over the grid: 0 is not a room, k is the k-th room (reading order)."""

    grid: OccupancyGrid
    labels: np.ndarray  # (rows, cols) int32
    clearance: np.ndarray  # (rows, cols) m, of the free space with isolated obstacles filled in
    filled: np.ndarray  # (rows, cols) bool: isolated obstacles that were filled in

    @property
    def n_rooms(self) -> int:
        return int(self.labels.max(initial=0))

    def mask(self, k: int) -> np.ndarray:
        """Cells of room k (1-based)."""
        return self.labels == k


def segment(grid: OccupancyGrid, params: SegmentParams | None = None) -> Segmentation:
    """Split the free space of ``grid`` into rooms (see the module docstring)."""
    params = params or SegmentParams()
    cell_area = grid.resolution**2
    filled = removable(grid, params.fill_area)
    free = ~close_gaps(grid.occupied & ~filled, grid.resolution)
    clear = ndimage.distance_transform_edt(np.pad(free, 1, constant_values=False))[1:-1, 1:-1] * grid.resolution
    labels = basins(free, clear, grid.resolution)
    labels = merge(labels, clear, params, cell_area)
    labels = reading_order(labels)
    return Segmentation(grid, labels, clear, filled)


def removable(grid: OccupancyGrid, max_area: float) -> np.ndarray:
    """Occupied cells that are no wall: speckles of noise, and isolated obstacles of at most
    ``max_area`` m² (decided after the gaps in walls are closed, so a wall a laser saw through
    in places is not taken for a row of obstacles)."""
    cell_area = grid.resolution**2
    occupied = grid.occupied
    noise = speckles(occupied, SPECKLE_AREA / cell_area)
    walls = close_gaps(occupied & ~noise, grid.resolution)
    return noise | (occupied & isolated_obstacles(walls, max_area / cell_area, grid.resolution))


def close_gaps(occupied: np.ndarray, resolution: float) -> np.ndarray:
    """Occupied cells with gaps up to about ``GAP`` wide closed (a morphological closing).

    A laser that missed a few cells of a wall leaves a pinhole no robot passes; closed, the wall
    stays one obstacle (and is not mistaken for a row of isolated ones) and the pinhole no
    passage between rooms.
    """
    cells = max(1, round(GAP / 2 / resolution))
    square = np.ones((2 * cells + 1, 2 * cells + 1), dtype=bool)  # a disc would leave a thin wall's gap open
    return occupied | ndimage.binary_closing(occupied, structure=square)


def speckle_cells(resolution: float) -> float:
    """``SPECKLE_AREA`` in cells, rounded so that 0.02 m² are 2 cells of 0.1 m (not 1.9999...).
    The segmentation itself keeps the unrounded figure, with which its results were measured."""
    return round(SPECKLE_AREA / resolution**2, 6)


def speckles(occupied: np.ndarray, max_cells: float) -> np.ndarray:
    """Occupied components (8-connected) of at most ``max_cells`` cells, not at the grid's border:
    sensor noise. Removed first, so that closing the gaps in walls does not glue them to a wall."""
    comp, n = ndimage.label(occupied, structure=EIGHT)
    small = np.bincount(comp.ravel(), minlength=n + 1) <= max_cells
    small[0] = False
    small[np.unique(np.concatenate([comp[0], comp[-1], comp[:, 0], comp[:, -1]]))] = False
    return small[comp]


def isolated_obstacles(occupied: np.ndarray, max_fill_cells: float, resolution: float) -> np.ndarray:
    """The cells of isolated obstacles, which the segmentation treats as free.

    An obstacle is isolated when its occupied component (8-connected) does not touch the border
    of the grid (the unknown surroundings of a building are occupied and reach it), has at most
    ``max_fill_cells`` cells and is not a piece of wall (:func:`wall_like`; a wall between two
    doors is a component of its own, and filling it in would join the doors into one opening).
    """
    comp, n = ndimage.label(occupied, structure=EIGHT)
    if n == 0:
        return np.zeros_like(occupied)
    sizes = np.bincount(comp.ravel(), minlength=n + 1)[1:]
    fill = (sizes <= max_fill_cells) & ~wall_like(occupied, comp, n, resolution)
    edge = np.unique(np.concatenate([comp[0], comp[-1], comp[:, 0], comp[:, -1]]))
    fill[edge[edge > 0] - 1] = False
    return np.concatenate([[False], fill])[comp]


def wall_like(occupied: np.ndarray, comp: np.ndarray, n: int, resolution: float) -> np.ndarray:
    """Which components 1..n are pieces of wall: mostly thinner than ``MAX_WALL_THICKNESS`` (a
    morphological opening of that width removes most of their cells) and longer than
    ``MIN_WALL_LENGTH`` (the diagonal of their bounding box). A straight, L- or T-shaped run of
    wall is; a table, a pillar or a cluster of sensor speckles is not."""
    side = int(MAX_WALL_THICKNESS / resolution) + 1
    opened = ndimage.binary_opening(occupied, structure=np.ones((side, side), dtype=bool))
    sizes = np.bincount(comp.ravel(), minlength=n + 1)[1:]
    thick = np.bincount(comp[opened], minlength=n + 1)[1:]
    boxes = ndimage.find_objects(comp, n)
    diagonal = np.array([np.hypot(b[0].stop - b[0].start, b[1].stop - b[1].start) for b in boxes]) * resolution
    return (thick < 0.5 * sizes) & (diagonal > MIN_WALL_LENGTH)


def basins(free: np.ndarray, clear: np.ndarray, resolution: float) -> np.ndarray:
    """Watershed of -clearance from its regional maxima (higher than their surroundings by a cell)."""
    from skimage.morphology import h_maxima
    from skimage.segmentation import watershed

    peaks = h_maxima(np.where(free, clear, 0.0), resolution) & free
    markers, _ = ndimage.label(peaks, structure=EIGHT)
    return np.asarray(watershed(-clear, markers, mask=free), dtype=np.int32)


def saddles(labels: np.ndarray, clear: np.ndarray) -> dict[tuple[int, int], float]:
    """(a, b) with a < b -> the widest point (clearance, m) of the border between regions a and b."""
    keys, values = [], []
    for a, b, ca, cb in (
        (labels[:, :-1], labels[:, 1:], clear[:, :-1], clear[:, 1:]),
        (labels[:-1], labels[1:], clear[:-1], clear[1:]),
    ):
        m = (a != b) & (a > 0) & (b > 0)
        lo, hi = np.minimum(a[m], b[m]).astype(np.int64), np.maximum(a[m], b[m]).astype(np.int64)
        keys.append(lo * (int(labels.max()) + 1) + hi)
        values.append(np.minimum(ca[m], cb[m]))
    key, value = np.concatenate(keys), np.concatenate(values)
    if key.size == 0:
        return {}
    uniq, inverse = np.unique(key, return_inverse=True)
    best = np.full(uniq.shape, -np.inf)
    np.maximum.at(best, inverse, value)
    base = int(labels.max()) + 1
    return {(int(k // base), int(k % base)): float(v) for k, v in zip(uniq, best, strict=True)}


class _Regions:
    """Regions being merged: peak clearance, area and the saddle to each neighbour."""

    def __init__(self, labels: np.ndarray, clear: np.ndarray, cell_area: float):
        n = int(labels.max())
        index = np.arange(1, n + 1)
        self.peak = dict(zip(index.tolist(), ndimage.maximum(clear, labels, index).tolist(), strict=True))
        self.area = dict(
            zip(index.tolist(), (np.bincount(labels.ravel(), minlength=n + 1)[1:] * cell_area).tolist(), strict=True)
        )
        self.nbr: dict[int, dict[int, float]] = {k: {} for k in index.tolist()}
        for (a, b), s in saddles(labels, clear).items():
            self.nbr[a][b] = s
            self.nbr[b][a] = s
        self.parent = {k: k for k in index.tolist()}

    def ratio(self, a: int, b: int) -> float:
        return self.nbr[a][b] / max(min(self.peak[a], self.peak[b]), 1e-9)

    def least_separated(self) -> tuple[float, int, int] | None:
        """The pair of neighbours whose passage is the least constriction, with its ratio."""
        best = None
        for a, others in self.nbr.items():
            for b in others:
                if a < b and (best is None or self.ratio(a, b) > best[0]):
                    best = (self.ratio(a, b), a, b)
        return best

    def join(self, a: int, b: int) -> None:
        """Merge region a into region b."""
        for c, s in self.nbr.pop(a).items():
            del self.nbr[c][a]
            if c != b:
                self.nbr[b][c] = self.nbr[c][b] = max(self.nbr[b].get(c, -np.inf), s)
        self.peak[b] = max(self.peak[b], self.peak.pop(a))
        self.area[b] += self.area.pop(a)
        self.parent[a] = b

    def root(self, a: int) -> int:
        while self.parent[a] != a:
            a = self.parent[a]
        return a


def merge(labels: np.ndarray, clear: np.ndarray, params: SegmentParams, cell_area: float) -> np.ndarray:
    """Merge basins into rooms (steps 4 of the module docstring); returns the new label image."""
    if labels.max(initial=0) == 0:
        return labels
    regions = _Regions(labels, clear, cell_area)
    while True:
        best = regions.least_separated()
        if best is not None and best[0] >= params.merge_ratio:
            regions.join(best[1], best[2])
            continue
        small = [a for a in regions.area if regions.area[a] < params.min_area and regions.nbr[a]]
        if small:
            a = min(small, key=lambda k: regions.area[k])
            regions.join(a, max(regions.nbr[a], key=lambda c: regions.nbr[a][c]))
            continue
        if params.max_rooms is not None and len(regions.area) > params.max_rooms and best is not None:
            regions.join(best[1], best[2])
            continue
        break
    keep = {a for a, area in regions.area.items() if area >= params.min_area}
    lookup = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    for a in regions.parent:
        r = regions.root(a)
        lookup[a] = r if r in keep else 0
    return lookup[labels]


def reading_order(labels: np.ndarray) -> np.ndarray:
    """Relabel rooms 1..n in reading order: rows of rooms from the top of the map down, each
    row left to right. A room belongs to the current row when its centroid lies within the
    vertical extent of the row's first room, so the order is stable under small changes."""
    ids = [int(k) for k in np.unique(labels) if k > 0]
    if not ids:
        return labels
    objects = ndimage.find_objects(labels)
    centre = dict(zip(ids, ndimage.center_of_mass(np.ones_like(labels), labels, ids), strict=True))
    pending = sorted(ids, key=lambda k: -centre[k][0])
    order: list[int] = []
    while pending:
        head = pending[0]
        rows = objects[head - 1][0]
        row = [k for k in pending if rows.start <= centre[k][0] < rows.stop]
        order += sorted(row, key=lambda k: centre[k][1])
        pending = [k for k in pending if k not in row]
    lookup = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    for new, old in enumerate(order, start=1):
        lookup[old] = new
    return lookup[labels]
