"""The medial axis of a hall's free space as a graph: junctions, and the branches between them.

A hall's free space (where a robot's centre may go) is thinned to its skeleton, one cell wide:
the generalised Voronoi diagram of the racks, walls and pillars around it. Along an aisle it is
the aisle's centre line; where aisles cross, branches meet at a *junction*. Every corner of
the free space grows a *spur*, a short branch from a junction to the corner; spurs carry no
structure and are pruned (:func:`medial_axis`), so that what is left are the aisles, the
passages through gaps in rack rows, and the ridges of open areas.

The graph is kept as the skeleton's cells and a label per cell, not as images: a skeleton has
a few cells in a hundred, and pruning it round after round stays cheap on a large map.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

#: an end branch shorter than this many times the clearance of its junction is a spur: a
#: 90-degree corner's runs sqrt(2) times the junction's clearance from it; an aisle that ends
#: in a wall is longer than that
SPUR = 1.5
PRUNE_ROUNDS = 6  # spurs of spurs: each round removes one generation
NEIGHBOURS = [(di, dj) for di in (-1, 0, 1) for dj in (-1, 0, 1) if (di, dj) != (0, 0)]


@dataclass(frozen=True, eq=False)
class Axis:
    """A skeleton as a graph: its cells, and for each the branch or junction it belongs to."""

    cells: np.ndarray  # (n, 2) row, column
    branch: np.ndarray  # (n,) 1..b: the branch of a cell that is no junction, else 0
    junction: np.ndarray  # (n,) 1..j: the junction cluster of a cell with 3 or more neighbours, else 0
    degree: np.ndarray  # (n,) skeleton neighbours of each cell (8-connected)
    edges: np.ndarray  # (m, 2) indices of neighbouring cells, both ways

    @property
    def n_branches(self) -> int:
        return int(self.branch.max(initial=0))

    @property
    def n_junctions(self) -> int:
        return int(self.junction.max(initial=0))


def axis_graph(cells: np.ndarray, shape: tuple[int, int]) -> Axis:
    """The graph of the skeleton cells ``cells`` (n, 2) of an image of ``shape``."""
    n = len(cells)
    index = np.full(shape, -1, dtype=np.int64)
    index[cells[:, 0], cells[:, 1]] = np.arange(n)
    src, dst = [], []
    for di, dj in NEIGHBOURS:
        i, j = cells[:, 0] + di, cells[:, 1] + dj
        inside = (i >= 0) & (i < shape[0]) & (j >= 0) & (j < shape[1])
        other = np.full(n, -1, dtype=np.int64)
        other[inside] = index[i[inside], j[inside]]
        src.append(np.nonzero(other >= 0)[0])
        dst.append(other[other >= 0])
    edges = np.column_stack([np.concatenate(src), np.concatenate(dst)]).astype(np.int64)
    degree = np.bincount(edges[:, 0], minlength=n)
    at_junction = degree >= 3
    return Axis(cells, _components(edges, ~at_junction), _components(edges, at_junction), degree, edges)


def _components(edges: np.ndarray, members: np.ndarray) -> np.ndarray:
    """Connected components 1..k of the cells ``members`` (n,) along ``edges``; 0 elsewhere."""
    n = len(members)
    keep = members[edges[:, 0]] & members[edges[:, 1]]
    graph = coo_matrix((np.ones(int(keep.sum())), (edges[keep, 0], edges[keep, 1])), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    out = np.zeros(n, dtype=np.int64)
    if members.any():
        out[members] = np.unique(labels[members], return_inverse=True)[1] + 1
    return out


def medial_axis(space: np.ndarray, clear: np.ndarray, resolution: float) -> Axis:
    """The skeleton of ``space`` (bool) with its spurs pruned (see the module docstring);
    ``clear`` is the clearance (m) of every cell."""
    from skimage.morphology import skeletonize

    cells = np.argwhere(skeletonize(space))
    axis = axis_graph(cells, space.shape)
    for _ in range(PRUNE_ROUNDS):
        spurs = _spurs(axis, clear[cells[:, 0], cells[:, 1]], resolution)
        if not spurs.any():
            break
        cells = cells[~spurs]
        axis = axis_graph(cells, space.shape)
    return axis


def _spurs(axis: Axis, clear: np.ndarray, resolution: float) -> np.ndarray:
    """Which cells (n,) to prune: those of branches with a free end that touch one junction and
    are shorter than ``SPUR`` times its clearance (``clear`` (n,): of each cell, m). Of the
    branches of a junction that are all spurs (the centre of a square room), the longest stays."""
    n_branches, n_junctions = axis.n_branches, axis.n_junctions
    if n_junctions == 0 or n_branches == 0:
        return np.zeros(len(axis.cells), dtype=bool)
    a, b = axis.edges[:, 0], axis.edges[:, 1]
    across = (axis.branch[a] > 0) & (axis.junction[b] > 0)
    pairs = np.unique(np.column_stack([axis.branch[a[across]], axis.junction[b[across]]]), axis=0)
    n_touched = np.bincount(pairs[:, 0], minlength=n_branches + 1)
    free_end = np.zeros(n_branches + 1, dtype=bool)
    free_end[axis.branch[(axis.degree == 1) & (axis.branch > 0)]] = True
    length = np.bincount(axis.branch, minlength=n_branches + 1) * resolution
    reach = np.zeros(n_junctions + 1)
    np.maximum.at(reach, axis.junction, clear)
    spur = {int(br): int(j) for br, j in pairs if free_end[br] and n_touched[br] == 1 and length[br] < SPUR * reach[j]}
    for j in set(spur.values()):
        mine = pairs[pairs[:, 1] == j, 0]
        if all(int(br) in spur for br in mine):
            del spur[int(max(mine, key=lambda br: length[br]))]
    return np.isin(axis.branch, list(spur))
