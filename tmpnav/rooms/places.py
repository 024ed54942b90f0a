"""Halls -> places: where a robot is sent in a region too large to be one room.

Rooms come from walls and doors (:mod:`tmpnav.rooms.segment`); an open hall with racks and
pillars is one room, and one room is one goal. A room larger than ``max_area`` is a *hall*,
split into places:

1. The space where a robot's centre may go: the hall's cells with a clearance of at least the
   robot's radius (isolated pillars and pallets filled in, as for rooms). Every place is cut
   around a part of it, so every place has room for the robot, clear of the racks.
2. Its medial axis (:mod:`tmpnav.rooms.medial`): the centre line of every aisle, the passages
   through gaps in rack rows, the ridges of open areas; spurs into corners pruned.
3. Every branch of the axis, less its ends inside a junction's disc (a crossing), seeds a
   place. The hall's cells are flooded from the seeds down the clearance (the watershed of
   -clearance), so that a cell joins the branch it faces across its aisle: an aisle between
   two racks becomes a place that ends on the line between the racks' ends, and a cross aisle
   splits into the fronts of the aisles that open onto it.
4. A place smaller than ``max_area / PLACE_SHARE`` (a gap in a rack row, a corner) joins the
   neighbour it shares the longest border with.
5. A place larger than ``max_area`` (an open area with nothing in it has one ridge) is split
   into ``ceil(area / max_area)`` places by geodesic k-means: Lloyd's algorithm, each step a
   compact watershed from the seeds over the place's cells, so that the pieces wrap around
   obstacles instead of reaching through them.

Why the medial axis: it is where a hall's structure is (an aisle is a branch, a crossing a
junction), so places follow aisles and rack ends as a warehouse's staff name them. Clustering
alone (k-means over the hall) cuts aisles at arbitrary points, and a grid of tiles cuts through
racks; clustering is used only where the axis says nothing, to keep places below ``max_area``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from tmpnav.rooms import MAX_AREA
from tmpnav.rooms.medial import Axis, medial_axis
from tmpnav.rooms.segment import Segmentation

PLACE_SHARE = 16.0  # a place smaller than max_area / PLACE_SHARE (and min_area) joins a neighbour
LLOYD_STEPS = 8  # k-means steps when a place is larger than max_area ...
LLOYD_CELLS = 10_000  # ... on at most about this many of its cells


@dataclass(frozen=True)
class PlaceParams:
    """Choices of the split of halls into places."""

    max_area: float = MAX_AREA  # m²: a larger room is a hall; no place is larger (but see merge_small)
    min_area: float = 3.0  # m²: no place is smaller than this (nor than max_area / PLACE_SHARE)
    radius: float = 0.25  # m: the robot's; places are cut around where its centre may go

    @property
    def min_place(self) -> float:
        """m²: a smaller place joins a neighbour."""
        return max(self.min_area, self.max_area / PLACE_SHARE)


def split_halls(seg: Segmentation, params: PlaceParams) -> np.ndarray:
    """A label image of places (1..n, 0 where no room is): a room up to ``params.max_area``
    is one place with all its cells, a hall is split (see the module docstring)."""
    cell_area = seg.grid.resolution**2
    out = np.zeros_like(seg.labels)
    count = 0
    for k, box in enumerate(ndimage.find_objects(seg.labels), start=1):
        if box is None:
            continue
        mask = seg.labels[box] == k
        if np.count_nonzero(mask) * cell_area > params.max_area:
            local = split_hall(mask, seg.clearance[box], seg.grid.resolution, params)
        else:
            local = mask.astype(out.dtype)
        view = out[box]
        view[mask] = local[mask] + count
        count += int(local.max())
    return out


def split_hall(mask: np.ndarray, clear: np.ndarray, resolution: float, params: PlaceParams) -> np.ndarray:
    """Places 1..m of one hall (cells ``mask``; ``clear`` in m), 0 outside it."""
    space = mask & (clear >= params.radius + resolution)
    if np.count_nonzero(space) < 2:
        return mask.astype(np.int32)
    cell_area = resolution**2
    labels = flood(mask, medial_axis(space, clear, resolution), clear, resolution)
    labels = merge_small(labels, params.min_place / cell_area, params.max_area / cell_area)
    labels = split_large(labels, space, params.max_area / cell_area)
    lookup = np.zeros(int(labels.max()) + 1, dtype=np.int32)
    used = np.unique(labels[labels > 0])
    lookup[used] = np.arange(1, used.size + 1)  # 0 stays 0: outside the hall, in its box
    return lookup[labels]


def flood(mask: np.ndarray, axis: Axis, clear: np.ndarray, resolution: float) -> np.ndarray:
    """Step 3 of the module docstring: the cells of ``mask`` labelled by the branch of the
    medial axis ``axis`` they face."""
    from scipy.spatial import cKDTree
    from skimage.segmentation import watershed

    seeds = axis.branch.copy()
    crossing = axis.junction > 0
    if crossing.any():  # a crossing belongs to no branch yet: its cells go to the branches around
        junctions = axis.cells[crossing]
        distance, nearest = cKDTree(junctions).query(axis.cells)
        seeds[distance * resolution < clear[junctions[nearest, 0], junctions[nearest, 1]]] = 0
    if not seeds.any():  # the axis is all crossings
        seeds = np.ones(len(axis.cells), dtype=np.int64)
    markers = np.zeros(mask.shape, dtype=np.int32)
    markers[axis.cells[:, 0], axis.cells[:, 1]] = seeds
    labels = np.asarray(watershed(-clear, markers, mask=mask), dtype=np.int32)
    missing = mask & (labels == 0)
    if missing.any():  # a part of the hall no branch's flood reaches: the nearest place's
        _, (i, j) = ndimage.distance_transform_edt(labels == 0, return_indices=True)
        labels[missing] = labels[i[missing], j[missing]]
    return labels


def borders(labels: np.ndarray) -> dict[tuple[int, int], int]:
    """(a, b) with a < b -> how many pairs of 4-neighbouring cells the two regions share."""
    base = int(labels.max()) + 1
    keys = []
    for a, b in ((labels[:, :-1], labels[:, 1:]), (labels[:-1], labels[1:])):
        m = (a != b) & (a > 0) & (b > 0)
        keys.append(np.minimum(a[m], b[m]).astype(np.int64) * base + np.maximum(a[m], b[m]))
    uniq, counts = np.unique(np.concatenate(keys), return_counts=True)
    return {(int(k // base), int(k % base)): int(c) for k, c in zip(uniq, counts, strict=True)}


def merge_small(labels: np.ndarray, min_cells: float, max_cells: float) -> np.ndarray:
    """Regions of fewer than ``min_cells`` cells join, smallest first, the neighbour they share
    the longest border with among those that stay within ``max_cells`` (any neighbour when none
    does, so that no splinter is left); returns the new label image."""
    size = dict(enumerate(np.bincount(labels.ravel()).tolist()))
    size.pop(0, None)
    nbr: dict[int, dict[int, int]] = {k: {} for k in size if size[k]}
    for (a, b), n in borders(labels).items():
        nbr[a][b] = nbr[b][a] = n
    parent = {k: k for k in nbr}
    while True:
        small = [k for k in nbr if size[k] < min_cells and nbr[k]]
        if not small:
            break
        a = min(small, key=lambda k: (size[k], k))
        fits = [c for c in nbr[a] if size[a] + size[c] <= max_cells] or list(nbr[a])
        b = max(fits, key=lambda c: (nbr[a][c], -c))
        for c, n in nbr.pop(a).items():
            del nbr[c][a]
            if c != b:
                nbr[b][c] = nbr[c][b] = nbr[b].get(c, 0) + n
        size[b] += size.pop(a)
        parent[a] = b
    lookup = np.arange(int(labels.max()) + 1, dtype=labels.dtype)
    for k in parent:
        root = k
        while parent[root] != root:
            root = parent[root]
        lookup[k] = root
    return lookup[labels]


def split_large(labels: np.ndarray, space: np.ndarray, max_cells: float) -> np.ndarray:
    """Step 5 of the module docstring: every region of more than ``max_cells`` cells split into
    equal parts by geodesic k-means, seeded where a robot fits (``space``)."""
    out = labels.copy()
    count = int(labels.max())
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            continue
        region = labels[box] == k
        parts = math.ceil(np.count_nonzero(region) / max_cells)
        if parts < 2:
            continue
        local = lloyd(region, region & space[box], parts)
        view = out[box]
        moved = region & (local > 1)
        view[moved] = local[moved] - 1 + count  # part 1 keeps label k
        count += parts - 1
    return out


def lloyd(region: np.ndarray, where: np.ndarray, k: int) -> np.ndarray:
    """``region`` split into k parts (labels 1..k) by geodesic k-means with seeds in ``where``.

    The steps run on every ``step``-th cell of a large region (``LLOYD_CELLS`` of them at most):
    where the seeds settle does not need every cell, and the parts are drawn on all of them.
    """
    from skimage.segmentation import watershed

    where = where if where.any() else region
    step = max(1, math.isqrt(int(np.count_nonzero(region) // LLOYD_CELLS)))
    coarse, coarse_where = region[::step, ::step], where[::step, ::step]
    if not coarse_where.any():
        step, coarse, coarse_where = 1, region, where
    seeds = farthest(np.argwhere(coarse_where), k)
    flat = np.zeros(coarse.shape)
    for _ in range(LLOYD_STEPS):
        labels = np.asarray(watershed(flat, _markers(coarse.shape, seeds), mask=coarse, compactness=1.0))
        moved = centres(labels, coarse_where, len(seeds))
        if np.array_equal(moved, seeds):
            break
        seeds = moved
    markers = _markers(region.shape, seeds * step)
    return np.asarray(watershed(np.zeros(region.shape), markers, mask=region, compactness=1.0), dtype=np.int32)


def _markers(shape: tuple[int, int], seeds: np.ndarray) -> np.ndarray:
    markers = np.zeros(shape, dtype=np.int32)
    markers[seeds[:, 0], seeds[:, 1]] = np.arange(1, len(seeds) + 1)
    return markers


def farthest(cells: np.ndarray, k: int) -> np.ndarray:
    """k of ``cells`` (m, 2) spread out: the one farthest from their centroid, then each time
    the one farthest from those chosen (farthest-point sampling)."""
    first = int(np.argmax(((cells - cells.mean(axis=0)) ** 2).sum(axis=1)))
    chosen = [first]
    gap = ((cells - cells[first]) ** 2).sum(axis=1)
    while len(chosen) < min(k, len(cells)):
        nxt = int(np.argmax(gap))
        chosen.append(nxt)
        gap = np.minimum(gap, ((cells - cells[nxt]) ** 2).sum(axis=1))
    return cells[chosen]


def centres(labels: np.ndarray, where: np.ndarray, k: int) -> np.ndarray:
    """For each part 1..k, the cell of ``where`` in it nearest to the part's centroid (any of
    its cells when none is in ``where``), (k, 2)."""
    index = np.arange(1, k + 1)
    centroid = np.array(ndimage.center_of_mass(np.ones(labels.shape), labels, index)).reshape(-1, 2)
    ii, jj = np.indices(labels.shape)
    own = np.vstack([[np.inf, np.inf], centroid])[labels]
    d2 = (ii - own[..., 0]) ** 2 + (jj - own[..., 1]) ** 2
    d2 = np.where(where, d2, d2 + 1e12)
    return np.array(ndimage.minimum_position(d2, labels, index), dtype=np.int64).reshape(-1, 2)
