"""The lower bound's connectivity cuts (tmpnav.task.cuts): the minimum cut against scipy's
maximum flow, and the rows cut down and kept against scipy's own slicing."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse import csr_array
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from tmpnav.task.cuts import Rows, min_cut


@pytest.mark.parametrize("seed", range(20))
def test_the_minimum_cut_is_scipys(seed: int) -> None:
    """The same flow value, and the same sides: the nodes the residual graph reaches from the
    source, and those that reach the sink (the same for every maximum flow)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 40))
    cap = np.where(rng.random((n, n)) < 0.15, rng.integers(1, 1_000_000, (n, n)), 0).astype(np.int64)
    np.fill_diagonal(cap, 0)
    source, sink = 0, n - 1
    value, from_source, to_sink = min_cut(cap, source, sink)
    flow = maximum_flow(csr_array(cap.astype(np.int32)), source, sink)
    residual = csr_array((cap - flow.flow.toarray()) > 0)
    assert value == flow.flow_value
    reached = np.zeros(n, dtype=bool)
    reached[breadth_first_order(residual, source, return_predecessors=False)] = True
    reaching = np.zeros(n, dtype=bool)
    reaching[breadth_first_order(residual.T, sink, return_predecessors=False)] = True
    assert np.array_equal(from_source, reached) and np.array_equal(to_sink, reaching)
    assert not (from_source & to_sink).any()  # a node on both sides would carry more flow


def test_rows_cut_down_to_columns_and_kept_by_rows_are_scipys() -> None:
    rng = np.random.default_rng(3)
    dense = np.where(rng.random((30, 50)) < 0.2, rng.normal(size=(30, 50)), 0.0)
    matrix = csr_array(dense)
    rows = Rows.of(matrix)
    cols = np.flatnonzero(rng.random(50) < 0.4)
    at = np.full(50, -1, dtype=np.int64)
    at[cols] = np.arange(len(cols))
    cut = rows.restricted(at)
    assert np.array_equal(
        csr_array((cut.data, cut.indices, cut.indptr), shape=(30, len(cols))).toarray(), dense[:, cols]
    )
    keep = rng.random(30) < 0.5
    kept = rows.kept(keep)
    assert np.array_equal(
        csr_array((kept.data, kept.indices, kept.indptr), shape=(int(keep.sum()), 50)).toarray(), dense[keep]
    )
    both = Rows.stack([rows, kept])
    assert np.array_equal(
        csr_array((both.data, both.indices, both.indptr), shape=(30 + int(keep.sum()), 50)).toarray(),
        np.vstack([dense, dense[keep]]),
    )
