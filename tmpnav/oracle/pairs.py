"""Two-robot requests: every combination of the robots' goal instantiations, evaluated jointly.

Requests whose robots start from the same states form a group; a group's combinations are
simulated in trie order (:func:`tmpnav.belief.trie.joint_lex_order`). Before any joint
simulation, mutual visibility is checked along every combination: one whose robots never
see each other (from uncorrelated starts) is factorised into its two single runs, and a
request that provably cannot save its ``min_gain`` is pruned (:mod:`tmpnav.oracle.bounds`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tmpnav.belief.sequences import Sequences
from tmpnav.belief.trie import joint_lex_order
from tmpnav.oracle.bounds import cannot_save, combination_bounds, cutoff, skippable
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.motionsets import GroupStart, MotionSet, MotionTable, SetKey, chain_restarts, row_offsets
from tmpnav.oracle.requests import EvalStats, Request, mutual_seed
from tmpnav.oracle.results import block_diagonal, motion_result, pick, pruned_result
from tmpnav.oracle.singles import SingleRuns
from tmpnav.types import CostTerms, MotionResult
from tmpnav.world.visibility import MutualSensing


@dataclass
class _Layout:
    """Every combination of every group laid out for the kernel, groups one after another."""

    table: MotionTable
    bounds: np.ndarray  # (G+1,) first combination of each group
    horizon: list[np.ndarray]  # per group: last step of each combination
    motions: np.ndarray  # (C, 2) table rows of the two robots' motions
    row_offset: np.ndarray  # (C,) first row of each combination's steps in ``visible``
    visible: np.ndarray  # (rows, 2, 2): robot i sees robot j at a step of a combination


class PairCombos:
    """The two-robot combinations of all pair requests of one evaluation."""

    def __init__(self, lib: MotionLibrary, sets: dict[SetKey, MotionSet], requests: list[Request], priced: bool = True):
        self.lib, self.requests, self.priced = lib, requests, priced
        self.groups: list[tuple[MotionSet, MotionSet, Request]] = []
        self.a: list[np.ndarray] = []  # per group: motions of robot 1, in trie order
        self.b: list[np.ndarray] = []  # per group: motions of robot 2
        self.of_request: dict[int, tuple[int, np.ndarray]] = {}  # request -> (group, combo positions)
        self.pruned: dict[int, float] = {}  # request -> lower bound, for pairs not simulated
        self.skipped: dict[int, tuple[float, float]] = {}  # request -> (its cutoff, least bound it skipped)
        for g, wanted in self._group_requests(sets).items():
            self._order(g, wanted)

    def _group_requests(self, sets: dict[SetKey, MotionSet]) -> dict[int, list[tuple[int, list[tuple[int, int]]]]]:
        """Group the pair requests by start states; per group, each request's combinations
        (motion positions), in the product order of the rooms' instantiations."""
        inst = self.lib.roadmap.instantiations
        group_of: dict[tuple, int] = {}
        raw: dict[int, list[tuple[int, list[tuple[int, int]]]]] = {}
        for i, req in enumerate(self.requests):
            if req.n != 2:
                continue
            k1, k2 = (req.robots[0], req.starts[0]), (req.robots[1], req.starts[1])
            if k1 not in sets or k2 not in sets:
                continue
            s1, s2 = sets[k1], sets[k2]
            gkey = (req.robots, req.starts, req.joint_cov)
            if gkey not in group_of:
                group_of[gkey] = len(self.groups)
                self.groups.append((s1, s2, req))
            mine = [
                (s1.by_goal[g1], s2.by_goal[g2])
                for g1 in inst[req.rooms[0]]
                for g2 in inst[req.rooms[1]]
                if g1 != g2 and g1 in s1.by_goal and g2 in s2.by_goal  # two robots cannot end on one pose
            ]
            raw.setdefault(group_of[gkey], []).append((i, mine))
        return {g: raw.get(g, []) for g in range(len(self.groups))}

    def _order(self, g: int, wanted: list[tuple[int, list[tuple[int, int]]]]) -> None:
        """Put group g's combinations in trie order and note where each request's are."""
        s1, s2, _ = self.groups[g]
        combos = sorted({c for _, mine in wanted for c in mine})
        a = np.array([c[0] for c in combos], dtype=np.int64)
        b = np.array([c[1] for c in combos], dtype=np.int64)
        order = joint_lex_order(a, b, s1.prefix, s2.prefix) if len(combos) else np.zeros(0, dtype=np.int64)
        a, b = a[order], b[order]
        position = {pair: k for k, pair in enumerate(zip(a.tolist(), b.tolist(), strict=True))}
        self.a.append(a)
        self.b.append(b)
        for i, mine in wanted:
            self.of_request[i] = (g, np.array([position[c] for c in mine], dtype=np.int64))

    def singles_needed(self) -> list[tuple[MotionSet, np.ndarray]]:
        """Every motion the combos use, simulated alone: factorised combos are sums of these,
        and their running c_Sigma bounds the joint cost (:mod:`tmpnav.oracle.bounds`)."""
        out = []
        for g, (s1, s2, _) in enumerate(self.groups):
            out.append((s1, self.a[g]))
            out.append((s2, self.b[g]))
        return out

    def run(self, stats: EvalStats, singles: SingleRuns) -> None:
        """Mutual visibility of every combo, factorisation, pruning, then the joint simulations."""
        G = len(self.groups)
        self.seen = [np.zeros(a.shape[0], dtype=bool) for a in self.a]  # per group: do its robots ever meet?
        self.kept_row = [np.full(a.shape[0], -1, dtype=np.int64) for a in self.a]  # row of the joint run, or -1
        if G == 0 or not any(a.shape[0] for a in self.a):
            return
        layout = self._layout()
        first = self._first_sight(layout)
        self.seen = [f >= 0 for f in first]
        needed = self._prune(first, singles, stats)
        self._joint_runs(layout, needed, stats)
        self._settle_skipped(singles, stats)

    def _layout(self) -> _Layout:
        lib = self.lib
        sets = [ms for s1, s2, _ in self.groups for ms in (s1, s2)]
        table = MotionTable.of_sets(sets, lib, self.priced)
        horizon = [
            np.maximum(s1.steps[a], s2.steps[b]) for (s1, s2, _), a, b in zip(self.groups, self.a, self.b, strict=True)
        ]
        ids1 = [table.ids(s1, a) for (s1, _, _), a in zip(self.groups, self.a, strict=True)]
        ids2 = [table.ids(s2, b) for (_, s2, _), b in zip(self.groups, self.b, strict=True)]
        c_horizon = np.concatenate(horizon)
        return _Layout(
            table=table,
            bounds=np.cumsum([0] + [a.shape[0] for a in self.a]),
            horizon=horizon,
            motions=np.column_stack([np.concatenate(ids1), np.concatenate(ids2)]),
            row_offset=row_offsets(c_horizon),
            visible=np.zeros((int((c_horizon + 1).sum()), 2, 2), dtype=bool),
        )

    def _restarts(self, g: int, k: np.ndarray | slice) -> np.ndarray:
        """Steps each of group g's combinations ``k`` shares with the one before it."""
        s1, s2, _ = self.groups[g]
        a, b = self.a[g][k], self.b[g][k]
        return chain_restarts(s1.prefix, a, np.maximum(s1.steps[a], s2.steps[b]), s2.prefix, b)

    def _first_sight(self, layout: _Layout) -> list[np.ndarray]:
        """Fills ``layout.visible``; returns per group the first step at which the robots of
        each combination see each other (-1: never, or mutual observations are off)."""
        G = len(self.groups)
        first_all = np.full(layout.motions.shape[0], -1, dtype=np.int64)
        sensing = [MutualSensing.between(self.lib.scenario, s1.robot, s2.robot) for s1, s2, _ in self.groups]
        kinds = list(dict.fromkeys(s for s in sensing if s is not None))  # teams mostly share one size
        if not kinds:
            return [first_all[layout.bounds[g] : layout.bounds[g + 1]] for g in range(G)]
        # a group's first combination starts from scratch; the others copy the steps they share
        chains = [self._restarts(g, slice(None)) for g in range(G)]
        restart = np.concatenate([np.concatenate([[-1], r[1:]]) if r.shape[0] else r for r in chains])
        kind = np.repeat([kinds.index(s) if s is not None else -1 for s in sensing], np.diff(layout.bounds))
        horizon = np.concatenate(layout.horizon)
        t = layout.table.arrays
        for k, sense in enumerate(kinds):
            sel = np.nonzero(kind == k)[0]
            st = restart[sel].copy()
            st[1:][np.diff(sel) != 1] = -1  # a gap breaks the chain of shared prefixes
            first_all[sel] = sense.sequences(
                self.lib.world,
                (t.offset, t.steps, t.poses),
                layout.motions[sel],
                st,
                horizon[sel],
                layout.row_offset[sel],
                layout.visible,
            )
        return [first_all[layout.bounds[g] : layout.bounds[g + 1]] for g in range(G)]

    def _prune(self, first: list[np.ndarray], singles: SingleRuns, stats: EvalStats) -> list[np.ndarray]:
        """Prune the requests that provably cannot save ``min_gain``; returns, per group,
        the combos still worth simulating jointly."""
        weights = self.lib.scenario.cost
        needed = [np.zeros(a.shape[0], dtype=bool) for a in self.a]
        self.pruned, self.skipped = {}, {}
        for i, (g, positions) in self.of_request.items():
            req = self.requests[i]
            s1, s2, _ = self.groups[g]
            bounded = req.min_gain is not None or req.bound_only
            if not bounded or req.joint_cov is not None or positions.size == 0:
                needed[g][positions] = True
                continue
            a, b, sight = self.a[g][positions], self.b[g][positions], first[g][positions]
            bounds = combination_bounds(singles, s1, s2, a, b, sight, weights)
            bound = float(bounds.min(initial=np.inf))
            alone = singles.best_cost(s1, req.rooms[0]) + singles.best_cost(s2, req.rooms[1])
            if req.bound_only or cannot_save(bound, alone, req.min_gain or 0.0):
                self.pruned[i] = bound
                stats.pairs_pruned += 1
                continue
            skip = np.zeros(positions.size, dtype=bool)
            if req.max_risk is None:  # (tmpnav.oracle.bounds: not under a threshold on the collision bound)
                limit = cutoff(bounds, sight < 0, alone, req.min_gain or 0.0)
                skip = skippable(bounds, sight >= 0, limit)
                if skip.any():
                    self.skipped[i] = (limit, float(bounds[skip].min()))
            needed[g][positions[~skip]] = True
        return needed

    def _settle_skipped(self, singles: SingleRuns, stats: EvalStats) -> None:
        """A request that skipped combinations is exact when its cheapest other combination is
        within its cutoff; otherwise none of its combinations can save ``min_gain``: pruned."""
        for i, (limit, skipped) in self.skipped.items():
            g, positions = self.of_request[i]
            cheapest = float(self._costs(g, positions, singles)[0].min(initial=np.inf))
            if cheapest > limit:
                self.pruned[i] = min(cheapest, skipped)
                stats.pairs_pruned += 1

    def _joint_runs(self, layout: _Layout, needed: list[np.ndarray], stats: EvalStats) -> None:
        """Simulate jointly what cannot be factorised and is not pruned."""
        groups: list[GroupStart] = []
        cg, cm, cs, ch, co = [], [], [], [], []
        rows = 0
        for g, (_, _, req) in enumerate(self.groups):
            correlated = req.joint_cov is not None  # correlated starts never factorise
            keep = (self.seen[g] | correlated) & needed[g]
            stats.joint_factorized += 0 if correlated else int((~self.seen[g] & needed[g]).sum())
            k = np.nonzero(keep)[0]
            if k.size == 0:
                continue
            groups.append(GroupStart(req.mean0(), req.cov0(), mutual_seed(self.lib, req.robots, req.starts)))
            cg.append(np.full(k.size, len(groups) - 1, dtype=np.int64))
            cm.append(layout.motions[layout.bounds[g] + k])
            cs.append(self._restarts(g, k))
            ch.append(layout.horizon[g][k])
            co.append(layout.row_offset[layout.bounds[g] + k])
            self.kept_row[g][k] = rows + np.arange(k.size)
            rows += k.size
        stats.joint_sims += rows
        if rows == 0:
            return
        seqs = Sequences(*(np.concatenate(x) for x in (cg, cm, cs, ch, co)))
        run = layout.table.propagate(self.lib, 2, groups, seqs, layout.visible)
        self.mean, self.cov, self.mutual = run.mean, run.cov, run.mutual_steps
        goal_xy = layout.table.goal_xy(seqs.motions)  # (rows, 2, 2)
        self.c_u = layout.table.c_u[seqs.motions]
        self.c_g = np.hypot(run.arrival_xy[..., 0] - goal_xy[..., 0], run.arrival_xy[..., 1] - goal_xy[..., 1])
        self.c_sigma = run.c_sigma
        self.risk = run.risk
        self.cost = self.lib.scenario.cost.combine(self.c_u, self.c_g, self.c_sigma).sum(axis=1)
        stats.count_steps(seqs.horizon, seqs.restart)

    def _costs(self, g: int, positions: np.ndarray, singles: SingleRuns) -> tuple[np.ndarray, np.ndarray]:
        """The costs and collision bounds of group g's combinations at ``positions``: simulated
        jointly, factorised (the sum of the singles), or skipped (robots that meet, not
        simulated: cost inf, see :meth:`_prune`)."""
        s1, s2, _ = self.groups[g]
        costs, risks = np.empty(positions.size), np.empty((positions.size, 2))
        for k, p in enumerate(positions):
            row = self.kept_row[g][p]
            if row >= 0:
                costs[k], risks[k] = self.cost[row], self.risk[row]
            elif self.seen[g][p]:
                costs[k], risks[k] = np.inf, np.inf
            else:
                r1, r2 = singles.index(s1, int(self.a[g][p])), singles.index(s2, int(self.b[g][p]))
                costs[k], risks[k] = singles.cost[r1] + singles.cost[r2], (singles.risk[r1], singles.risk[r2])
        return costs, risks

    def best(self, i: int, singles: SingleRuns) -> MotionResult | None:
        """The cheapest combination of pair request i (the first in the request's own
        product order on a tie), its bound if it was pruned, or None if there is none."""
        if i not in self.of_request or self.of_request[i][1].size == 0:
            return None
        req = self.requests[i]
        if i in self.pruned:
            return pruned_result(req.robots, self.pruned[i])
        g, positions = self.of_request[i]
        s1, s2, _ = self.groups[g]
        costs, risks = self._costs(g, positions, singles)
        p = positions[pick(costs, risks, req.max_risk)]
        a, b = int(self.a[g][p]), int(self.b[g][p])
        motions = (s1.motions[a], s2.motions[b])
        weights = self.lib.scenario.cost
        priced = req.max_risk is not None
        row = self.kept_row[g][p]
        if row >= 0:
            terms = tuple(
                CostTerms(float(self.c_u[row, j]), float(self.c_g[row, j]), float(self.c_sigma[row, j]))
                for j in range(2)
            )
            risk = (float(self.risk[row, 0]), float(self.risk[row, 1])) if priced else ()
            mean, cov, mutual = self.mean[row], self.cov[row], int(self.mutual[row])
            return motion_result(req.robots, terms, mean, cov, mutual, motions, weights, risk)
        r1, r2 = singles.index(s1, a), singles.index(s2, b)
        mean, cov = block_diagonal(singles.mean[r1], singles.cov[r1], singles.mean[r2], singles.cov[r2])
        terms = (singles.terms(r1), singles.terms(r2))
        risk = (float(singles.risk[r1]), float(singles.risk[r2])) if priced else ()
        return motion_result(req.robots, terms, mean, cov, 0, motions, weights, risk)
