"""Relaxation (c) of :mod:`tmpnav.task.bound`: the plans' integer program, relaxed to a
linear program, tightened by cuts, and bounded through its dual.

Columns: every single move and every offered pair that a plan could make (each of its
robots can be at the origin and may enter the target), x between 0 and 1, at the table
cost. A plan sets x = 1 on its steps and 0 elsewhere, and its cost is c·x exactly. With
in(r, o) and out(r, o) the sums of x over the columns holding a move of r into / out of
o, every plan satisfies (F1-F3 of :mod:`tmpnav.task.bound`):

  - each room x of U: sum over r of in(r, x) = 1; each entry (r, x) of E: in(r, x) = 1;
  - each robot r: out(r, s_r) <= 1, and for every other location o: in(r, o) <= 1 and
    out(r, o) <= in(r, o) (a robot leaves only where it has arrived);
  - each location o that is not a start: the robots that do not target o enter it at most
    once in all (only an unvisited location admits them);
  - each two robots r, r': the pairs in which exactly one of them leaves its start sum to
    at most 1. Such a pair says which of the two moved first (the one still at its start
    had not); two such pairs with opposite answers cannot both be in a plan, and two with
    the same answer would make that robot leave its start twice;
  - connectivity (cuts): for a robot r, a set W of locations without s_r, and k in W,
    in(r, k) <= the flow of r's moves from outside W into W (a robot that reaches k has
    crossed into W on its way from s_r). These forbid the LP's closed loops away from the
    start, the weakness of (b). Each round separates them exactly from the LP solution
    (a maximum flow from s_r to every room r enters), adds the violated ones and drops
    those that stayed slack for a few rounds, until none is violated or ``rounds`` ran.

So min c·x over these constraints is at most every plan's cost. The value reported does
not trust the LP solver's optimality: for any multipliers y (y <= 0 on the <= rows),
weak duality with 0 <= x <= 1 gives c·x >= b·y + sum_j min(0, (c - Aᵀy)_j) for every
feasible x, and tmpnav evaluates this with the solver's duals. Inexact duals only make
the bound weaker, never wrong.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tmpnav.task.encodings import offered_pairs as _useful_pairs
from tmpnav.types import CostTable, Goals, MoveKey

if TYPE_CHECKING:
    from scipy.sparse import csc_array as SparseMatrix

    from tmpnav.task.linear import LpSolution

Floats = NDArray[np.float64]
Ints = NDArray[np.int64]
Bools = NDArray[np.bool_]

Row = tuple[str | None, str]
#: max-flow capacities are integers: LP flows are scaled by this before the cut search
FLOW_SCALE = 1_000_000
#: a cut is added when the LP's flow into W falls short of in(r, k) by more than this
VIOLATION = 1e-4
#: a cut that stayed slack for this many rounds in a row leaves the LP
SLACK_ROUNDS = 3
#: the LP starts with each robot's this many cheapest moves into each location
INITIAL_MOVES = 6
#: a column outside the LP joins it when its reduced cost is below minus this
PRICING_TOLERANCE = 1e-9


@dataclass(frozen=True)
class FlowBound:
    value: float  # the dual bound
    cuts: int  # connectivity cuts added over all rounds
    rounds: int  # LPs solved
    converged: bool  # the last LP violated no cut and left out no column of negative reduced cost
    stopped: bool = False  # its ``stop`` ended the rounds of cuts early


def flow_bound(
    table: CostTable,
    goals: Goals,
    min_gain: float,
    rows: list[Row],
    enter: dict[str, set[str]],
    rounds: int,
    stop: Callable[[], bool] | None = None,
) -> FlowBound | None:
    """The dual bound of the LP after up to ``rounds`` rounds of cuts, or fewer when ``stop``,
    asked after each LP, says so (every LP's dual bound holds); None when the solver returns
    no duals.

    The LP is solved over a subset of the columns (each robot's cheapest moves into each
    location, and the pairs of those), and a column joins when its reduced cost under
    the current duals is negative (column generation). The bound itself is computed over
    every column, so it holds whichever columns the LP saw.
    """
    lp = _Program(table, goals, min_gain, rows, enter)
    active = lp.initial_columns()
    last, total, solved, cut_rounds, converged, stopped = None, 0, 0, 0, False, False
    while True:
        a_ub, b_ub = lp.ub_matrix()
        res = _solve(lp, a_ub, b_ub, active)
        solved += 1
        if res.status == "infeasible" and not active.all():
            active[:] = True  # the subset admits no solution: give the LP every column
            continue
        if res.status != "optimal":
            break
        n_ub = a_ub.shape[0]
        y_eq, y_ub = res.duals[n_ub:], np.minimum(res.duals[:n_ub], 0.0)
        reduced = lp.cost - lp.a_eq.T @ y_eq - a_ub.T @ y_ub
        last = float(lp.b_eq @ y_eq + b_ub @ y_ub + np.minimum(reduced, 0.0).sum())
        entering = ~active & (reduced < -PRICING_TOLERANCE)
        if cut_rounds == rounds:
            break
        if stop is not None and stop():
            stopped = True
            break
        x = np.zeros(len(lp.cost))
        x[active] = res.x
        lp.drop_slack_cuts(x)
        added = lp.add_cuts(x)
        total, cut_rounds = total + added, cut_rounds + 1
        if added == 0 and not entering.any():
            converged = True
            break
        active |= entering
    return None if last is None else FlowBound(last, total, solved, converged, stopped)


def _solve(lp: _Program, a_ub: SparseMatrix, b_ub: Floats, active: Bools) -> LpSolution:
    """The LP over the ``active`` columns, 0 <= x <= 1, its rows the <= rows ``a_ub`` then the =
    rows (:func:`tmpnav.task.linear.minimise`)."""
    from scipy.sparse import csr_matrix, vstack

    from tmpnav.task.linear import minimise

    cols, n_ub = np.flatnonzero(active), a_ub.shape[0]
    return minimise(
        lp.cost[cols],
        np.zeros(len(cols)),
        np.ones(len(cols)),
        np.concatenate([np.full(n_ub, -np.inf), lp.b_eq]),
        np.concatenate([b_ub, lp.b_eq]),
        csr_matrix(vstack([a_ub[:, cols], lp.a_eq[:, cols]])),
    )


class _Program:
    """The LP: fixed rows built once, connectivity cuts added and dropped by rounds.

    A column's moves are kept as incidence arrays (column, robot, origin, target), with
    robots and locations as indices, so that cuts and flows are numpy operations.
    """

    def __init__(self, table: CostTable, goals: Goals, min_gain: float, rows: list[Row], enter: dict[str, set[str]]):
        self.robots, self.locs = table.robots, list(table.locations)
        for _, o, x in table.single:
            self.locs += [y for y in (o, x) if y not in self.locs]
        loc = {x: i for i, x in enumerate(self.locs)}
        self.start = np.array([loc[table.start_location[r]] for r in self.robots])
        self._columns(table, min_gain, enter, loc)
        self._equalities(rows, loc)
        self._inequalities(table, goals, loc)
        # cut (robot, k, W) -> its row's columns and values, and the rounds it has stayed slack
        self.cuts: dict[tuple[int, int, frozenset[int]], tuple[Ints, Floats, int]] = {}
        self._fixed_rows: SparseMatrix | None = None  # a_fixed by rows, made when first stacked

    def _columns(self, table: CostTable, min_gain: float, enter: dict[str, set[str]], loc: dict[str, int]) -> None:
        """The columns (single moves, then the useful pairs) and their incidence arrays."""

        def usable(m: MoveKey) -> bool:
            r, o, x = m
            return o != x and r in enter.get(x, ()) and (o == table.start_location[r] or r in enter.get(o, ()))

        columns: list[tuple[tuple[MoveKey, ...], float]] = [((m,), c) for m, c in table.single.items() if usable(m)]
        self.n_single = len(columns)
        columns += [(q, c) for q, c in _useful_pairs(table, min_gain).items() if usable(q[0]) and usable(q[1])]
        self.n_columns = len(columns)
        self.cost = np.array([c for _, c in columns], dtype=float)
        inc = [(j, self.robots.index(r), loc[o], loc[t]) for j, (moves, _) in enumerate(columns) for r, o, t in moves]
        self.col, self.rob, self.org, self.tgt = np.array(inc, dtype=np.int64).reshape(-1, 4).T
        single_index = {moves[0]: j for j, (moves, _) in enumerate(columns[: self.n_single])}
        self._move_single = np.array([single_index[m] for moves, _ in columns for m in moves], dtype=np.int64)

    def _equalities(self, rows: list[Row], loc: dict[str, int]) -> None:
        """One row per required entry."""
        from scipy.sparse import coo_array

        eq_index = {(None if r is None else self.robots.index(r), loc[x]): i for i, (r, x) in enumerate(rows)}
        hits = [
            (eq_index[key], j)
            for j, r, t in zip(self.col, self.rob, self.tgt, strict=True)
            for key in ((None, int(t)), (int(r), int(t)))
            if key in eq_index
        ]
        i_eq, j_eq = zip(*hits, strict=True) if hits else ((), ())
        self.a_eq = coo_array((np.ones(len(i_eq)), (i_eq, j_eq)), shape=(len(rows), self.n_columns)).tocsc()
        self.b_eq = np.ones(len(rows))

    def _inequalities(self, table: CostTable, goals: Goals, loc: dict[str, int]) -> None:
        """Flow (r, o) out - in <= [o is s_r]; in (r, o) <= 1; first visitors of o <= 1; and who
        moved first: a pair in which exactly one of its robots leaves its start."""
        from scipy.sparse import coo_array

        n_r, n_l = len(self.robots), len(self.locs)
        targets = {(self.robots.index(r), loc[x]) for r, x in goals.entries}
        starts = {loc[s] for s in table.start_location.values()}
        first = np.array(
            [
                (int(t) not in starts and (int(r), int(t)) not in targets)
                for r, t in zip(self.rob, self.tgt, strict=True)
            ],
            dtype=bool,
        )
        flow_out, flow_in = self.rob * n_l + self.org, self.rob * n_l + self.tgt
        i_ub = np.concatenate([flow_out, flow_in, n_r * n_l + flow_in, 2 * n_r * n_l + self.tgt[first]])
        j_ub = np.concatenate([self.col, self.col, self.col, self.col[first]])
        v_ub = np.concatenate(
            [np.ones(len(self.col)), -np.ones(len(self.col)), np.ones(len(self.col)), np.ones(int(first.sum()))]
        )
        a, b = np.flatnonzero(self.col >= self.n_single).reshape(-1, 2).T  # a pair's two incidences
        one_starts = (self.org[a] == self.start[self.rob[a]]) != (self.org[b] == self.start[self.rob[b]])
        i_ub = np.concatenate([i_ub, 2 * n_r * n_l + n_l + self.rob[a][one_starts] * n_r + self.rob[b][one_starts]])
        j_ub = np.concatenate([j_ub, self.col[a][one_starts]])
        v_ub = np.concatenate([v_ub, np.ones(int(one_starts.sum()))])
        n_ub = 2 * n_r * n_l + n_l + n_r * n_r
        self.a_fixed = coo_array((v_ub, (i_ub, j_ub)), shape=(n_ub, self.n_columns)).tocsc()
        self.b_fixed = np.concatenate([np.zeros(n_r * n_l), np.ones(n_r * n_l + n_l + n_r * n_r)])
        self.b_fixed[np.arange(n_r) * n_l + self.start] = 1.0

    def ub_matrix(self) -> tuple[SparseMatrix, Floats]:
        """The <= rows: the fixed ones, then the cuts (one sparse matrix, CSC for column slicing).
        Stacked by rows (a cut is a row's columns and values, each column once) and turned to
        CSC once: stacking CSC blocks went through coordinates, 1.8 s a round at 200 rooms."""
        from scipy.sparse import csr_array, vstack

        if self._fixed_rows is None:
            self._fixed_rows = self.a_fixed.tocsr()
        cuts = list(self.cuts.values())
        indptr = np.concatenate([[0], np.cumsum([len(c[0]) for c in cuts], dtype=np.int64)])
        cols = np.concatenate([c[0] for c in cuts]) if cuts else np.zeros(0, np.int64)
        vals = np.concatenate([c[1] for c in cuts]) if cuts else np.zeros(0)
        block = csr_array((vals, cols, indptr), shape=(len(cuts), len(self.cost)))
        matrix = vstack([self._fixed_rows, block], format="csr").tocsc()
        return matrix, np.concatenate([self.b_fixed, np.zeros(len(cuts))])

    def initial_columns(self) -> Bools:
        """Each robot's INITIAL_MOVES cheapest single moves into each location, and every
        pair whose two moves are among them."""
        single = self.col < self.n_single
        key = self.rob[single] * len(self.locs) + self.tgt[single]
        cols = self.col[single]
        order = np.lexsort((self.cost[cols], key))  # by (robot, target), then by cost
        key, cols = key[order], cols[order]
        rank = np.arange(len(key)) - np.searchsorted(key, key)  # position within its (robot, target)
        active = np.zeros(len(self.cost), dtype=bool)
        active[cols[rank < INITIAL_MOVES]] = True
        in_pair = ~single
        move_active = active[self._move_single[in_pair]]
        pair_cols = self.col[in_pair]
        both = np.ones(len(self.cost), dtype=bool)
        np.logical_and.at(both, pair_cols, move_active)
        active[self.n_single :] = both[self.n_single :]
        return active

    def drop_slack_cuts(self, x: Floats) -> None:
        """Forget the cuts that stayed slack for SLACK_ROUNDS rounds (they may come back)."""
        for key, (cols, vals, slack_rounds) in list(self.cuts.items()):
            slack_rounds = slack_rounds + 1 if -float(vals @ x[cols]) > VIOLATION else 0
            if slack_rounds >= SLACK_ROUNDS:
                del self.cuts[key]
            else:
                self.cuts[key] = (cols, vals, slack_rounds)

    def add_cuts(self, x: Floats) -> int:
        """Add the violated connectivity cuts of every robot; return how many."""
        added, n_l = 0, len(self.locs)
        for r in range(len(self.robots)):
            mine = self.rob == r
            flow = np.zeros((n_l, n_l))
            np.add.at(flow, (self.org[mine], self.tgt[mine]), x[self.col[mine]])
            inflow = flow.sum(axis=0)
            for k in np.flatnonzero(inflow > VIOLATION):
                for inside in self._short_cuts(int(self.start[r]), int(k), float(inflow[k]), flow):
                    mask = np.zeros(n_l, dtype=bool)
                    mask[list(inside)] = True
                    crossing = float(flow[~mask][:, mask].sum())
                    for k2 in inside:  # the same set cuts off every room in it that gets more
                        if inflow[k2] > crossing + VIOLATION and (r, k2, inside) not in self.cuts:
                            self.cuts[(r, k2, inside)] = (*self._cut_row(r, k2, mask), 0)
                            added += 1
        return added

    def _short_cuts(self, source: int, k: int, need: float, flow: Floats) -> list[frozenset[int]]:
        """Sets W (k in W, the start not) that the flow enters less than it enters k: the
        two sides of a minimum cut between the start and k; none when the flow suffices."""
        from scipy.sparse import csr_array
        from scipy.sparse.csgraph import maximum_flow

        cap = np.floor(flow * FLOW_SCALE).astype(np.int32)
        result = maximum_flow(csr_array(cap), source, k)
        if result.flow_value / FLOW_SCALE >= need - VIOLATION:
            return []
        residual = (cap - result.flow.toarray()) > 0
        from_source, to_sink = _reachable(residual, source), _reachable(residual.T, k)
        sides = [frozenset(i for i in range(len(cap)) if i not in from_source), frozenset(to_sink)]
        return [w for w in dict.fromkeys(sides) if k in w and source not in w]

    def _cut_row(self, r: int, k: int, mask: Bools) -> tuple[Ints, Floats]:
        """in(r, k) - (r's moves from outside W into W) <= 0: its columns and values."""
        mine = (self.rob == r) & mask[self.tgt]
        v = (self.tgt[mine] == k).astype(float) - (~mask[self.org[mine]]).astype(float)
        keep = v != 0.0
        return self.col[mine][keep], v[keep]


def _reachable(arcs: Ints, start: int) -> set[int]:
    """Nodes reachable from ``start`` along the True entries of a square boolean matrix."""
    reached, queue = {start}, deque([start])
    while queue:
        i = queue.popleft()
        for j in np.flatnonzero(arcs[i]):
            if int(j) not in reached:
                reached.add(int(j))
                queue.append(int(j))
    return reached
