"""The connectivity cuts of the lower bound's LP (:mod:`tmpnav.task.bound_lp`): their rows,
kept by rows as they come and go, and their separation from an LP solution by minimum cuts.

A cut of robot r, set W and room k in W reads in(r, k) - (r's moves from outside W into W)
<= 0. The sets come from a maximum flow of r's LP flow from its start s_r to k: the nodes the
residual graph does not reach from s_r, and those that reach k in it, are the two sides of
minimum cuts, the same for every maximum flow.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba as nb
import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from scipy.sparse import csr_array as SparseMatrix

Floats = NDArray[np.float64]
Ints = NDArray[np.int64]
Bools = NDArray[np.bool_]

#: max-flow capacities are integers: LP flows are scaled by this before the cut search
FLOW_SCALE = 1_000_000
#: a cut is added when the LP's flow into W falls short of in(r, k) by more than this
VIOLATION = 1e-4
#: a cut that stayed slack for this many rounds in a row leaves the LP
SLACK_ROUNDS = 3


@dataclass(frozen=True)
class Rows:
    """Sparse rows as CSR's three arrays (each row's columns ascending)."""

    indptr: Ints
    indices: Ints
    data: Floats

    @property
    def n_rows(self) -> int:
        return len(self.indptr) - 1

    @staticmethod
    def of(matrix: SparseMatrix) -> Rows:
        """The rows of a CSR matrix."""
        return Rows(matrix.indptr.astype(np.int64), matrix.indices.astype(np.int64), matrix.data)

    @staticmethod
    def stack(parts: list[Rows]) -> Rows:
        """The rows of ``parts``, one after the other."""
        offsets = np.cumsum([0] + [len(p.indices) for p in parts[:-1]])
        indptr = np.concatenate([[0]] + [p.indptr[1:] + o for p, o in zip(parts, offsets, strict=True)])
        return Rows(indptr, np.concatenate([p.indices for p in parts]), np.concatenate([p.data for p in parts]))

    def restricted(self, at: Ints) -> Rows:
        """The rows on the columns ``at`` maps to a new index (-1: left out)."""
        new = at[self.indices]
        keep = new >= 0
        kept_before = np.concatenate([[0], np.cumsum(keep)])  # entries kept before each entry
        return Rows(kept_before[self.indptr], new[keep], self.data[keep])

    def kept(self, rows: Bools) -> Rows:
        """The ``rows`` marked True."""
        counts = np.diff(self.indptr)
        entries = np.repeat(rows, counts)
        return Rows(np.concatenate([[0], np.cumsum(counts[rows])]), self.indices[entries], self.data[entries])


class Cuts:
    """The connectivity cuts in the LP, in the order they came, as the rows of one sparse
    block (:class:`Rows`), each with the rounds it has stayed slack."""

    def __init__(self, n_columns: int):
        self.n_columns = n_columns
        self.keys: list[tuple[int, int, frozenset[int]]] = []
        self.slack = np.zeros(0, dtype=np.int64)
        self.rows = Rows(np.zeros(1, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))
        self._known: set[tuple[int, int, frozenset[int]]] = set()
        self._block: SparseMatrix | None = None  # :meth:`block` of these rows, once made

    def __len__(self) -> int:
        return len(self.keys)

    def __contains__(self, key: tuple[int, int, frozenset[int]]) -> bool:
        return key in self._known

    def add(self, new: list[tuple[tuple[int, int, frozenset[int]], Ints, Floats]]) -> None:
        """Add cuts (key, columns ascending, values) after the others, none slack yet."""
        if not new:
            return
        parts = [self.rows] + [Rows(np.array([0, len(c)], dtype=np.int64), c, v) for _, c, v in new]
        self.rows, self._block = Rows.stack(parts), None
        self.keys += [key for key, _, _ in new]
        self._known.update(key for key, _, _ in new)
        self.slack = np.concatenate([self.slack, np.zeros(len(new), dtype=np.int64)])

    def block(self) -> SparseMatrix:
        """The cuts' rows over every column (CSR), made once for a round's pricing and its
        dropping of slack cuts."""
        from scipy.sparse import csr_array

        if self._block is None:
            r = self.rows
            self._block = csr_array((r.data, r.indices, r.indptr), shape=(len(self.keys), self.n_columns))
        return self._block

    def drop_slack(self, x: Floats) -> None:
        """Forget the cuts that stayed slack for SLACK_ROUNDS rounds (they may come back)."""
        if not self.keys:
            return
        self.slack = np.where(-(self.block() @ x) > VIOLATION, self.slack + 1, 0)
        keep = self.slack < SLACK_ROUNDS
        if keep.all():
            return
        self._known.difference_update(k for k, kept in zip(self.keys, keep, strict=True) if not kept)
        self.keys = [k for k, kept in zip(self.keys, keep, strict=True) if kept]
        self.rows, self.slack, self._block = self.rows.kept(keep), self.slack[keep], None


def short_cuts(cap: NDArray[np.int64], source: int, k: int, need: float) -> list[frozenset[int]]:
    """Sets W (k in W, the start not) that the flow (its capacities ``cap``, scaled to integers)
    enters less than it enters k: the two sides of a minimum cut between the start and k (the
    nodes the residual graph reaches from the start, and those that reach k in it: the same for
    every maximum flow); none when the flow suffices."""
    value, from_source, to_sink = min_cut(cap, source, k)
    if value / FLOW_SCALE >= need - VIOLATION:
        return []
    sides = [
        frozenset(int(i) for i in np.flatnonzero(~from_source)),
        frozenset(int(i) for i in np.flatnonzero(to_sink)),
    ]
    return [w for w in dict.fromkeys(sides) if k in w and source not in w]


@nb.njit(cache=True)
def min_cut(cap: NDArray[np.int64], source: int, sink: int) -> tuple[int, Bools, Bools]:  # pragma: no cover
    """A maximum flow from ``source`` to ``sink`` on the dense integer capacities ``cap``
    (Edmonds-Karp: shortest augmenting paths), its value, and which nodes the residual graph
    reaches from the source and which reach the sink in it. The LP's flows have a few hundred
    arcs among a few hundred locations: a dense breadth-first search per path is quicker
    than building sparse matrices for each of the thousands of flows a round asks for."""
    n = cap.shape[0]
    res = cap.copy()
    parent = np.empty(n, dtype=np.int64)
    queue = np.empty(n, dtype=np.int64)
    total = 0
    while True:
        parent[:] = -1
        parent[source] = source
        head, tail = 0, 1
        queue[0] = source
        while head < tail and parent[sink] < 0:
            i = queue[head]
            head += 1
            for j in range(n):
                if parent[j] < 0 and res[i, j] > 0:
                    parent[j] = i
                    queue[tail] = j
                    tail += 1
        if parent[sink] < 0:
            break
        least = res[parent[sink], sink]
        j = sink
        while j != source:
            least = min(least, res[parent[j], j])
            j = parent[j]
        j = sink
        while j != source:
            i = parent[j]
            res[i, j] -= least
            res[j, i] += least
            j = i
        total += least
    from_source = parent >= 0
    to_sink = np.zeros(n, dtype=np.bool_)
    to_sink[sink] = True
    head, tail = 0, 1
    queue[0] = sink
    while head < tail:
        j = queue[head]
        head += 1
        for i in range(n):
            if not to_sink[i] and res[i, j] > 0:
                to_sink[i] = True
                queue[tail] = i
                tail += 1
    return total, from_source, to_sink
