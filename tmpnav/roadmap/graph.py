"""Shortest paths on a :class:`~tmpnav.types.Roadmap` with scipy's compiled Dijkstra.

Edges weigh their length, as in the paper; under a chance constraint they weigh more where
they pass close to obstacles (:func:`safe_weights`), so that paths keep clear of walls.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from tmpnav.types import SAFE_MARGIN, Roadmap
from tmpnav.world import World

#: :func:`safe_weights`: an edge whose footprint margin falls to 0 weighs (1 + SAFE_PENALTY)
#: times its length; the penalty falls quadratically to nothing at the clearance asked for
SAFE_PENALTY = 4.0


def safe_weights(roadmap: Roadmap, world: World, radius: float, clearance: float = SAFE_MARGIN) -> np.ndarray:
    """Edge weights that keep paths clear of obstacles, as nav2's inflation layer does: length x
    (1 + SAFE_PENALTY g), where g = (max(0, c - m) / c)^2 for the ``clearance`` c (m) and m is the
    smallest footprint margin (World.margins of a disc of ``radius``) at points a grid cell apart
    along the edge. A path that hugs a wall leaves its robot no room for its uncertainty: its
    collision bound is near 1 whatever the belief (docs/models.md, "Collision bound"), so the
    shortest path is the wrong one to bound; a detour of a few per cent through the free middle
    makes the bound useful."""
    margin = edge_margins(roadmap, world, radius)
    g = (np.clip(clearance - margin, 0.0, clearance) / clearance) ** 2
    return np.asarray(roadmap.weights * (1.0 + SAFE_PENALTY * g), dtype=float)


def edge_margins(roadmap: Roadmap, world: World, radius: float) -> np.ndarray:
    """Each edge's smallest footprint margin (m; World.margins of a disc of ``radius``) at points
    a grid cell apart along it."""
    return segment_margins(roadmap.nodes[roadmap.edges[:, 0]], roadmap.nodes[roadmap.edges[:, 1]], world, radius)


def segment_margins(a: np.ndarray, b: np.ndarray, world: World, radius: float) -> np.ndarray:
    """The smallest footprint margin (m) along each segment a[k] -> b[k] ((E, 2) each), at points
    a grid cell apart."""
    length = np.hypot(*(b - a).T)
    samples = max(2, int(np.ceil(length.max(initial=0.0) / world.grid.resolution)) + 1)
    s = np.linspace(0.0, 1.0, samples)
    margin = np.empty(length.shape[0])
    for lo in range(0, length.shape[0], 2048):  # a few MB at a time
        e = slice(lo, lo + 2048)
        points = a[e, None, :] + s[None, :, None] * (b[e] - a[e])[:, None, :]
        margin[e] = world.margins(points, radius).min(axis=1)
    return margin


class RoadmapGraph:
    """Shortest-path queries on a roadmap; one Dijkstra run per source node, memoised.
    ``weights`` replace the roadmap's edge lengths (:func:`safe_weights`)."""

    def __init__(self, roadmap: Roadmap, weights: np.ndarray | None = None):
        self.roadmap = roadmap
        self.weights = roadmap.weights if weights is None else weights
        self._trees: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @cached_property
    def matrix(self) -> csr_matrix:
        rm = self.roadmap
        n = rm.n_nodes
        rows = np.concatenate([rm.edges[:, 0], rm.edges[:, 1]])
        cols = np.concatenate([rm.edges[:, 1], rm.edges[:, 0]])
        w = np.concatenate([self.weights, self.weights])
        return csr_matrix((w, (rows, cols)), shape=(n, n))

    def prepare(self, sources: list[int]) -> None:
        """Run Dijkstra from many sources in one compiled call."""
        todo = sorted({s for s in sources if s not in self._trees})
        if not todo:
            return
        dist, pred = dijkstra(self.matrix, directed=False, indices=todo, return_predecessors=True)
        for k, s in enumerate(todo):
            self._trees[s] = (dist[k], pred[k])

    def tree(self, source: int) -> tuple[np.ndarray, np.ndarray]:
        """The shortest-path tree from ``source``: distances and predecessors of every node."""
        self.prepare([source])
        return self._trees[source]

    def distance(self, source: int, target: int) -> float:
        self.prepare([source])
        return float(self._trees[source][0][target])

    def path(self, source: int, target: int) -> tuple[int, ...] | None:
        """Node indices of a shortest path source -> target, or None if unreachable."""
        self.prepare([source])
        dist, pred = self._trees[source]
        if not np.isfinite(dist[target]):
            return None
        nodes = [target]
        while nodes[-1] != source:
            nodes.append(int(pred[nodes[-1]]))
        return tuple(reversed(nodes))

    def points(self, path: tuple[int, ...]) -> np.ndarray:
        return self.roadmap.nodes[list(path)]
