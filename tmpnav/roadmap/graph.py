"""Shortest paths on a :class:`~tmpnav.types.Roadmap` with scipy's compiled Dijkstra.

Edges weigh their length, as in the paper; under a chance constraint they weigh more where
they pass close to obstacles (:func:`safe_weights`), so that paths keep clear of walls.
"""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Callable
from functools import cached_property

import numba as nb
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
    grown = grown_edges(roadmap)
    known = grown_safe_weights(roadmap, world, radius, clearance)
    if not roadmap.sources:
        return known.copy()
    out = np.empty(roadmap.edges.shape[0])
    out[grown] = known  # a replan's roadmap: only its sources' edges are new
    e = roadmap.edges[~grown]
    margin = segment_margins(roadmap.nodes[e[:, 0]], roadmap.nodes[e[:, 1]], world, radius)
    out[~grown] = _safe(roadmap.weights[~grown], margin, clearance)
    return out


def grown_safe_weights(roadmap: Roadmap, world: World, radius: float, clearance: float) -> np.ndarray:
    """:func:`safe_weights` of the grown roadmap's edges alone (a replan's sources left out), in
    the order of ``roadmap.edges``; kept in the process (and read from the cache by
    tmpnav.roadmap.store.SafeWeightStore): a replan adds a few edges to a roadmap whose other
    weights are known. Do not write to the array."""
    grown = grown_edges(roadmap)
    key = (roadmap.grown, world.fingerprint, radius, clearance)
    known = _GROWN_WEIGHTS.get(key)
    if known is None or known.shape[0] != int(grown.sum()):
        # the grown roadmap's edges on their own: their margins are sampled as without sources
        e = roadmap.edges[grown]
        margin = segment_margins(roadmap.nodes[e[:, 0]], roadmap.nodes[e[:, 1]], world, radius)
        known = _safe(roadmap.weights[grown], margin, clearance)
        if roadmap.grown:  # a roadmap built by hand has no fingerprint to know it by
            keep_safe_weights(roadmap, world, radius, clearance, known)
    return known


def keep_safe_weights(roadmap: Roadmap, world: World, radius: float, clearance: float, weights: np.ndarray) -> None:
    """Keep ``weights`` as the grown roadmap's safe weights (:func:`grown_safe_weights`)."""
    _GROWN_WEIGHTS[(roadmap.grown, world.fingerprint, radius, clearance)] = weights
    while len(_GROWN_WEIGHTS) > 4:
        _GROWN_WEIGHTS.pop(next(iter(_GROWN_WEIGHTS)))


#: the safe weights of grown roadmaps' edges (:func:`safe_weights`), by roadmap, world, radius and
#: clearance: a replan adds a few edges to a roadmap whose other weights are known
_GROWN_WEIGHTS: dict[tuple[str, str, float, float], np.ndarray] = {}


def _safe(weights: np.ndarray, margin: np.ndarray, clearance: float) -> np.ndarray:
    g = (np.clip(clearance - margin, 0.0, clearance) / clearance) ** 2
    return np.asarray(weights * (1.0 + SAFE_PENALTY * g), dtype=float)


def grown_edges(roadmap: Roadmap) -> np.ndarray:
    """Which of the roadmap's edges are the grown roadmap's (no end at a replan's source)."""
    return ~_touches(roadmap.edges, roadmap.sources)


def _touches(edges: np.ndarray, nodes: tuple[int, ...]) -> np.ndarray:
    """Which edges have an end among ``nodes``."""
    if not nodes:
        return np.zeros(edges.shape[0], dtype=bool)
    return np.asarray(np.isin(edges, np.asarray(nodes)).any(axis=1))


def edge_margins(roadmap: Roadmap, world: World, radius: float) -> np.ndarray:
    """Each edge's smallest footprint margin (m; World.margins of a disc of ``radius``) at points
    a grid cell apart along it."""
    return segment_margins(roadmap.nodes[roadmap.edges[:, 0]], roadmap.nodes[roadmap.edges[:, 1]], world, radius)


def segment_margins(a: np.ndarray, b: np.ndarray, world: World, radius: float) -> np.ndarray:
    """The smallest footprint margin (m) along each segment a[k] -> b[k] ((E, 2) each), at points
    a grid cell apart: the points a + s (b - a) for ``s`` the same fractions on every segment (as
    many as the longest one needs), their margins those of World.margins. Computed point by
    point in one compiled loop (the points and their cells by the same operations as numpy's,
    so the same bits); the margin's constant part is taken off the smallest clearance, which
    gives the same number as the smallest margin (rounding is monotone)."""
    a = np.ascontiguousarray(a, dtype=float).reshape(-1, 2)
    b = np.ascontiguousarray(b, dtype=float).reshape(-1, 2)
    length = np.hypot(*(b - a).T)
    grid = world.grid
    samples = max(2, int(np.ceil(length.max(initial=0.0) / grid.resolution)) + 1)
    s = np.linspace(0.0, 1.0, samples)
    x0, y0 = (float(v) for v in grid.origin)
    least = _least_clearance(a, b, s, x0, y0, float(grid.resolution), world.clearance)
    return least - radius - np.sqrt(2.0) * grid.resolution


@nb.njit(cache=True)
def _least_clearance(
    a: np.ndarray, b: np.ndarray, s: np.ndarray, x0: float, y0: float, res: float, clear: np.ndarray
) -> np.ndarray:  # pragma: no cover - compiled
    """The least clearance of the cells of the points a[k] + s (b[k] - a[k]) (-inf for a point off the grid).

    ``s`` rising, each coordinate of a point's cell is a monotone function of s (every operation
    that computes it is), so the points of one cell follow one another: where a segment has many
    points a cell (the longest segment sets how many every segment has), the first point of the
    next cell is searched for, doubling the step then halving it, and the points between are
    not computed. The cells found, and their least clearance, are those of every point."""
    rows, cols = clear.shape
    out = np.empty(a.shape[0])
    n = s.shape[0]
    for k in range(a.shape[0]):
        ax, ay = a[k, 0], a[k, 1]
        dx = b[k, 0] - ax
        dy = b[k, 1] - ay
        # a segment's points fall in about |dx| / res + |dy| / res + 1 cells: search where it has many points a cell
        per_cell = n / ((abs(dx) + abs(dy)) / res + 1.0)
        search = per_cell > 8.0
        first = max(1, int(0.5 * per_cell))  # the first step of the search: half a cell's points
        least = np.inf
        m = 0
        while m < n:
            i, j = _sample_cell(ax, ay, dx, dy, s[m], x0, y0, res)
            if i < 0 or i >= rows or j < 0 or j >= cols:
                least = -np.inf
                break
            c = clear[int(i), int(j)]
            if c < least:
                least = c
            if not search:
                m += 1
                continue
            # the first point after m in another cell: gallop, then bisect (lo: same cell, hi: another)
            lo, step = m, first
            hi = n
            while lo + step < n:
                u, v = _sample_cell(ax, ay, dx, dy, s[lo + step], x0, y0, res)
                if u != i or v != j:
                    hi = lo + step
                    break
                lo += step
                step *= 2
            while hi - lo > 1:
                mid = (lo + hi) // 2
                u, v = _sample_cell(ax, ay, dx, dy, s[mid], x0, y0, res)
                if u != i or v != j:
                    hi = mid
                else:
                    lo = mid
            m = hi
        out[k] = least
    return out


@nb.njit(cache=True, inline="always")
def _sample_cell(ax, ay, dx, dy, t, x0, y0, res):  # pragma: no cover - compiled
    """The cell (row, column, as floats) of the point a + t d of a segment."""
    return np.floor(((ay + t * dy) - y0) / res), np.floor(((ax + t * dx) - x0) / res)


def _base_edges(roadmap: Roadmap) -> int:
    """How many of the roadmap's edges are its base's (a source's edges come after them)."""
    return int((roadmap.edges < roadmap.base_nodes).all(axis=1).sum())


def _padded(dist: np.ndarray, pred: np.ndarray, shared: int, pad: int) -> tuple[np.ndarray, np.ndarray]:
    """A tree over the first ``shared`` nodes, with ``pad`` unreached nodes (sources) after them."""
    if not pad and len(dist) == shared:
        return dist, pred
    return (
        np.concatenate([dist[:shared], np.full(pad, np.inf)]),
        np.concatenate([pred[:shared], np.full(pad, -9999, dtype=pred.dtype)]),
    )


#: the most bytes of shortest-path trees (and what is derived from them) :class:`_Shared` keeps
SHARED_BYTES = 128 * 2**20


class _Shared:
    """The shortest-path trees from the nodes of grown roadmaps, and arrays derived from them,
    shared by every :class:`RoadmapGraph` of the same grown roadmap and weights in this process:
    a planning service revises plan after plan of one site, each revision's roadmap the site's
    with other sources (Roadmap.sources), and no path between the grown roadmap's nodes passes
    through a source. Least recently used first out, past :data:`SHARED_BYTES`."""

    def __init__(self, limit: int):
        self.limit, self.size = limit, 0
        self.items: OrderedDict[tuple[object, ...], tuple[np.ndarray, ...]] = OrderedDict()

    def get(self, key: tuple[object, ...]) -> tuple[np.ndarray, ...] | None:
        found = self.items.get(key)
        if found is not None:
            self.items.move_to_end(key)
        return found

    def put(self, key: tuple[object, ...], arrays: tuple[np.ndarray, ...]) -> None:
        if key in self.items:
            return
        self.items[key] = arrays
        self.size += sum(a.nbytes for a in arrays)
        while self.size > self.limit and len(self.items) > 1:
            _, gone = self.items.popitem(last=False)
            self.size -= sum(a.nbytes for a in gone)


_SHARED = _Shared(SHARED_BYTES)


class RoadmapGraph:
    """Shortest-path queries on a roadmap; one Dijkstra run per source node, memoised (from
    the grown roadmap's nodes, for every graph of that roadmap in this process: :class:`_Shared`).
    ``weights`` replace the roadmap's edge lengths (:func:`safe_weights`)."""

    def __init__(self, roadmap: Roadmap, weights: np.ndarray | None = None):
        self.roadmap = roadmap
        self.weights = roadmap.weights if weights is None else weights
        self._trees: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @cached_property
    def _key(self) -> tuple[str, str] | None:
        """What decides the trees from the grown roadmap's nodes: its fingerprint and the weights
        of its edges (None: a roadmap built by hand, which has no fingerprint)."""
        rm = self.roadmap
        if not rm.grown:
            return None
        base = np.ascontiguousarray(self.weights[: _base_edges(rm)], dtype=float)
        return rm.grown, hashlib.blake2b(base.tobytes(), digest_size=16).hexdigest()

    def memo(
        self, tag: tuple[object, ...], nodes: tuple[int, ...], make: Callable[[], tuple[np.ndarray, ...]]
    ) -> tuple[np.ndarray, ...]:
        """What ``make`` computes from the paths out of the grown roadmap's ``nodes`` alone
        (``tag`` names it and everything else it depends on), for every graph of that roadmap
        in this process; computed afresh where a node is a source."""
        return self._kept("memo", tag, nodes, make)

    def derived(self, source: int, tag: tuple[object, ...], make: Callable[[], np.ndarray]) -> np.ndarray:
        """What ``make`` computes from the tree of ``source`` (``tag`` names it and its
        parameters), as :meth:`memo` keeps it, for graphs with as many nodes."""
        return self._kept("derived", (*tag, self.roadmap.n_nodes), (source,), lambda: (make(),))[0]

    def _kept(
        self, kind: str, tag: tuple[object, ...], nodes: tuple[int, ...], make: Callable[[], tuple[np.ndarray, ...]]
    ) -> tuple[np.ndarray, ...]:
        if self._key is None or max(nodes, default=0) >= self.roadmap.base_nodes:
            return make()
        key = (kind, *self._key, nodes, *tag)
        found = _SHARED.get(key)
        if found is None:
            found = make()
            _SHARED.put(key, found)
        return found

    @cached_property
    def matrix(self) -> csr_matrix:
        """The weighted adjacency: both ways along every edge, out only from the roadmap's
        ``sources`` (Roadmap)."""
        rm = self.roadmap
        n = rm.n_nodes
        rows = np.concatenate([rm.edges[:, 0], rm.edges[:, 1]])
        cols = np.concatenate([rm.edges[:, 1], rm.edges[:, 0]])
        w = np.concatenate([self.weights, self.weights])
        if rm.sources:
            into = np.isin(cols, np.asarray(rm.sources))
            rows, cols, w = rows[~into], cols[~into], w[~into]
        return csr_matrix((w, (rows, cols)), shape=(n, n))

    def inherit(self, other: RoadmapGraph) -> None:
        """Take ``other``'s shortest-path trees from the nodes both share, when both are the
        same roadmap with other sources (Roadmap.sources, a replan's starts): no path between
        those nodes passes through a source, so each tree is the same on them; the sources of
        this roadmap are unreached from there."""
        mine, theirs = self.roadmap, other.roadmap
        shared = mine.base_nodes
        if mine.grown != theirs.grown or theirs.base_nodes != shared:
            return
        if not np.array_equal(self.weights[: _base_edges(mine)], other.weights[: _base_edges(theirs)]):
            return
        for s, (dist, pred) in other._trees.items():
            if s < shared and s not in self._trees:
                self._trees[s] = _padded(dist, pred, shared, len(mine.sources))

    @cached_property
    def base_matrix(self) -> csr_matrix:
        """The adjacency of the roadmap without its sources: the matrix of the roadmap they
        were added to, entry for entry (its edges come first)."""
        rm = self.roadmap
        kept = _base_edges(rm)
        edges, w = rm.edges[:kept], self.weights[:kept]
        rows = np.concatenate([edges[:, 0], edges[:, 1]])
        cols = np.concatenate([edges[:, 1], edges[:, 0]])
        return csr_matrix((np.concatenate([w, w]), (rows, cols)), shape=(rm.base_nodes, rm.base_nodes))

    def prepare(self, sources: list[int]) -> None:
        """Run Dijkstra from many sources in one compiled call. From a node of a roadmap with
        sources that is not one of them: on the roadmap without them (undirected, as it was
        searched before the sources were added: the same trees, ties included), the sources
        unreached; from a source: directed, never into another source."""
        todo = sorted({s for s in sources if s not in self._trees})
        if not todo:
            return
        rm = self.roadmap
        shared = rm.base_nodes
        base = []
        for s in todo:
            if s >= shared:
                continue
            known = _SHARED.get(("tree", *self._key, s)) if self._key else None
            if known is None:
                base.append(s)
            else:
                self._trees[s] = _padded(known[0], known[1], shared, len(rm.sources))
        if base:
            matrix = self.base_matrix if rm.sources else self.matrix
            dist, pred = dijkstra(matrix, directed=False, indices=base, return_predecessors=True)
            for k, s in enumerate(base):
                if self._key:
                    _SHARED.put(("tree", *self._key, s), (dist[k, :shared].copy(), pred[k, :shared].copy()))
                self._trees[s] = _padded(dist[k], pred[k], shared, len(rm.sources))
        added = [s for s in todo if s >= shared]
        if added:
            dist, pred = dijkstra(self.matrix, directed=True, indices=added, return_predecessors=True)
            for k, s in enumerate(added):
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
        """The positions (len(path), 2) of the nodes of ``path``."""
        return self.roadmap.nodes.take(path, axis=0)
