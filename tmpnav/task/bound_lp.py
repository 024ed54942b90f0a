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
    (a maximum flow from s_r to every room r enters; the sides of its minimum cut are the
    sets W), adds for each violated set the cut of the room in it the flow enters most,
    and drops those that stayed slack for a few rounds, until none is violated or
    ``rounds`` ran. An LP that violates no cut of the whole family has the family's
    optimum, whichever cuts it was given on the way.

So min c·x over these constraints is at most every plan's cost. The value reported does
not trust the LP solver's optimality: for any multipliers y (y <= 0 on the <= rows),
weak duality with 0 <= x <= 1 gives c·x >= b·y + sum_j min(0, (c - Aᵀy)_j) for every
feasible x, and tmpnav evaluates this with the solver's duals. Inexact duals only make
the bound weaker, never wrong.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from tmpnav.task.cuts import FLOW_SCALE, VIOLATION, Cuts, Rows, short_cuts
from tmpnav.task.encodings import offered_pairs as _useful_pairs
from tmpnav.types import CostTable, Goals, MoveKey

if TYPE_CHECKING:
    from tmpnav.task.linear import LpSolution

Floats = NDArray[np.float64]
Ints = NDArray[np.int64]
Bools = NDArray[np.bool_]

Row = tuple[str | None, str]
#: the LP starts with each robot's this many cheapest moves into each location
INITIAL_MOVES = 6
#: a column outside the LP joins it when its reduced cost is below minus this
PRICING_TOLERANCE = 1e-9
#: the rounds of cuts end when this many LPs in a row did not raise the best bound by more than
#: :data:`STALL_GAIN` of it. On the 100-room, 16-robot office the cost LP's bound stood at 49.033
#: from round 2 to 15 (55.288 by round 25), the makespan's work LP's at 655.5 (704.0): 20 LPs of
#: a quarter second each, for a bound 3.6% higher where the plan was 89% above it, and the
#: search waited 7 s for it. Where the cuts still bite the bound rises nearly every round: on
#: 3,000 generated tables of 2-4 robots and 6-12 rooms the rule changed one bound, by 0.1% (3
#: rounds changed 15, by up to 10%). Of the shipped configurations two bounds are 2.2% lower
#: (building-8robots, warehouse-8robots: gaps of 82.4% and 72.9% against 82.0% and 72.3%), the
#: others the same (benchmarks/README.md, "The bound's rounds of cuts")
STALL_ROUNDS = 4
STALL_GAIN = 1e-6


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
    """The best dual bound of the LPs over up to ``rounds`` rounds of cuts, or fewer when
    :data:`STALL_ROUNDS` LPs in a row did not raise it or ``stop``, asked after each LP, says so
    (every LP's dual bound holds); None when the solver returns no duals.

    The LP is solved over a subset of the columns (each robot's cheapest moves into each
    location, and the pairs of those), and a column joins when its reduced cost under
    the current duals is negative (column generation). The bound itself is computed over
    every column, so it holds whichever columns the LP saw.
    """
    lp = _Program(table, goals, min_gain, rows, enter)
    active = lp.initial_columns()
    last, total, solved, cut_rounds, converged, stopped = None, 0, 0, 0, False, False
    stalled = 0  # rounds in a row that did not raise the bound
    while True:
        res = _solve(lp, active)
        solved += 1
        if res.status == "infeasible" and not active.all():
            active[:] = True  # the subset admits no solution: give the LP every column
            continue
        if res.status != "optimal":
            break
        n_fixed, n_cuts = len(lp.b_fixed), len(lp.cuts)
        y_fixed = np.minimum(res.duals[:n_fixed], 0.0)
        y_cuts = np.minimum(res.duals[n_fixed : n_fixed + n_cuts], 0.0)
        y_eq = res.duals[n_fixed + n_cuts :]
        reduced = lp.cost - lp.a_eq.T @ y_eq - lp.a_fixed.T @ y_fixed - lp.cuts.block().T @ y_cuts
        value = float(lp.b_eq @ y_eq + lp.b_fixed @ y_fixed + np.minimum(reduced, 0.0).sum())
        stalled = 0 if last is None or value > last + STALL_GAIN * max(1.0, abs(last)) else stalled + 1
        last = value if last is None else max(last, value)  # each LP's dual bound holds: the best
        entering = ~active & (reduced < -PRICING_TOLERANCE)
        if cut_rounds == rounds or stalled >= STALL_ROUNDS:
            break
        if stop is not None and stop():
            stopped = True
            break
        x = np.zeros(len(lp.cost))
        x[active] = res.x
        lp.cuts.drop_slack(x)
        added = lp.add_cuts(x)
        total, cut_rounds = total + added, cut_rounds + 1
        if added == 0 and not entering.any():
            converged = True
            break
        active |= entering
    return None if last is None else FlowBound(last, total, solved, converged, stopped)


def _solve(lp: _Program, active: Bools) -> LpSolution:
    """The LP over the ``active`` columns, 0 <= x <= 1, its rows the fixed <= rows, the cuts,
    then the = rows (:func:`tmpnav.task.linear.minimise`). The rows are cut down to the active
    columns as they are stored, by rows, and stacked once: a matrix of every column, made
    each round and sliced, took most of a 200-room bound's time."""
    from scipy.sparse import csr_matrix

    from tmpnav.task.linear import minimise

    cols = np.flatnonzero(active)
    at = np.full(len(lp.cost), -1, dtype=np.int64)
    at[cols] = np.arange(len(cols))
    parts = [lp.fixed_rows, lp.cuts.rows, lp.eq_rows]
    rows = Rows.stack([part.restricted(at) for part in parts])
    n_ub = len(lp.b_fixed) + len(lp.cuts)
    return minimise(
        lp.cost[cols],
        np.zeros(len(cols)),
        np.ones(len(cols)),
        np.concatenate([np.full(n_ub, -np.inf), lp.b_eq]),
        np.concatenate([lp.b_fixed, np.zeros(len(lp.cuts)), lp.b_eq]),
        csr_matrix((rows.data, rows.indices, rows.indptr), shape=(rows.n_rows, len(cols))),
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
        self.cuts = Cuts(self.n_columns)  # cut (robot, k, W) -> its row, and the rounds it has stayed slack
        self.fixed_rows, self.eq_rows = Rows.of(self.a_fixed.tocsr()), Rows.of(self.a_eq.tocsr())
        # each robot's incidences (column, origin, target), for its cuts' rows
        self._mine = [np.flatnonzero(self.rob == r) for r in range(len(self.robots))]

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

    def add_cuts(self, x: Floats) -> int:
        """Add the violated connectivity cuts of every robot; return how many."""
        new: list[tuple[tuple[int, int, frozenset[int]], Ints, Floats]] = []
        seen: set[tuple[int, int, frozenset[int]]] = set()
        n_l = len(self.locs)
        for r, mine in enumerate(self._mine):
            flow = np.zeros((n_l, n_l))
            np.add.at(flow, (self.org[mine], self.tgt[mine]), x[self.col[mine]])
            inflow = flow.sum(axis=0)
            cap = np.floor(flow * FLOW_SCALE).astype(np.int64)
            for k in np.flatnonzero(inflow > VIOLATION):
                for inside in short_cuts(cap, int(self.start[r]), int(k), float(inflow[k])):
                    mask = np.zeros(n_l, dtype=bool)
                    mask[list(inside)] = True
                    crossing = float(flow[~mask][:, mask].sum())
                    # one cut per set, for the room in it the flow enters most (the most violated):
                    # a cut for each room of W converged no tighter, with rows 5-10 times as many
                    # (each lists every move into W) and 6-13 times the time at 200 rooms
                    k2 = max(sorted(inside), key=lambda q: inflow[q])
                    key = (r, k2, inside)
                    if inflow[k2] <= crossing + VIOLATION or key in self.cuts or key in seen:
                        continue
                    seen.add(key)
                    # in(r, k2) - (r's moves from outside W into W) <= 0
                    into = mine[mask[self.tgt[mine]]]
                    v = (self.tgt[into] == k2) - (~mask[self.org[into]]).astype(float)
                    keep = v != 0.0
                    new.append((key, self.col[into][keep], v[keep]))
        self.cuts.add(new)
        return len(new)
