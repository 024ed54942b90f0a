"""Shortest paths on a :class:`~tmpnav.types.Roadmap` with scipy's compiled Dijkstra."""

from __future__ import annotations

from functools import cached_property

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from tmpnav.types import Roadmap


class RoadmapGraph:
    """Shortest-path queries on a roadmap; one Dijkstra run per source node, memoised."""

    def __init__(self, roadmap: Roadmap):
        self.roadmap = roadmap
        self._trees: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @cached_property
    def matrix(self) -> csr_matrix:
        rm = self.roadmap
        n = rm.n_nodes
        rows = np.concatenate([rm.edges[:, 0], rm.edges[:, 1]])
        cols = np.concatenate([rm.edges[:, 1], rm.edges[:, 0]])
        w = np.concatenate([rm.weights, rm.weights])
        return csr_matrix((w, (rows, cols)), shape=(n, n))

    def prepare(self, sources: list[int]) -> None:
        """Run Dijkstra from many sources in one compiled call."""
        todo = sorted({s for s in sources if s not in self._trees})
        if not todo:
            return
        dist, pred = dijkstra(self.matrix, directed=False, indices=todo, return_predecessors=True)
        for k, s in enumerate(todo):
            self._trees[s] = (dist[k], pred[k])

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
