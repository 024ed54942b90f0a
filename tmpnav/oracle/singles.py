"""Single-robot simulations: one robot moving alone along each motion it may need.

They answer single-robot requests, and they are the building blocks of pairs: a factorised
pair costs exactly the sum of its two singles, and the running c_Sigma of a single bounds
the joint cost of a pair until its robots first see each other (:mod:`tmpnav.oracle.bounds`).
"""

from __future__ import annotations

import numpy as np

from tmpnav.belief.sequences import Sequences
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.motionsets import GroupStart, MotionSet, MotionTable, SetKey, chain_restarts, row_offsets
from tmpnav.oracle.requests import EvalStats, Request
from tmpnav.oracle.results import motion_result, pick
from tmpnav.types import CostTerms, MotionResult


class SingleRuns:
    """The single-robot simulations of one evaluation, each motion set's in trie order.

    After :meth:`run`, row r (:meth:`index`) has the robot's final belief ``mean[r]``,
    ``cov[r]``, its cost terms ``c_u[r]``, ``c_g[r]``, ``c_sigma[r]``, its weighted
    ``cost[r]`` and its running c_Sigma after every step, ``csig_hist[r]``.
    """

    def __init__(self, lib: MotionLibrary, sets: dict[SetKey, MotionSet], priced: bool = True):
        self.lib, self.sets, self.priced = lib, sets, priced
        self.wanted: dict[int, set[int]] = {}
        self.by_id = {id(ms): ms for ms in sets.values()}
        self.results: dict[tuple[int, int], int] = {}

    def need(self, ms: MotionSet, local: list[int] | np.ndarray) -> None:
        """Ask for the motions at positions ``local`` of ``ms`` to be simulated."""
        self.wanted.setdefault(id(ms), set()).update(int(k) for k in local)

    def run(self, stats: EvalStats) -> None:
        """Simulate every motion asked for, in one kernel call."""
        if not self.wanted:
            return
        sets = [self.by_id[k] for k in self.wanted]
        table = MotionTable.of_sets(sets, self.lib, self.priced)
        groups, cg, cm, cs, ch = [], [], [], [], []
        for g, ms in enumerate(sets):
            local = np.array(sorted(self.wanted[id(ms)]), dtype=np.int64)
            groups.append(GroupStart(np.array(ms.start.mean), np.array(ms.start.cov), 0))
            horizon = ms.steps[local]
            cg.append(np.full(local.shape[0], g, dtype=np.int64))
            cm.append(table.ids(ms, local))
            cs.append(chain_restarts(ms.prefix, local, horizon))
            ch.append(horizon)
            for k in local:
                self.results[(id(ms), int(k))] = len(self.results)
        group, motion, restart, horizon = (np.concatenate(x) for x in (cg, cm, cs, ch))
        seqs = Sequences(group, motion[:, None], restart, horizon, row_offsets(horizon))
        nobody = np.zeros((int((horizon + 1).sum()), 1, 1), dtype=bool)  # one robot sees no other
        run = table.propagate(self.lib, 1, groups, seqs, nobody, c_sigma_history=True)
        assert run.c_sigma_history is not None
        self.mean, self.cov = run.mean, run.cov
        self.csig_hist = run.c_sigma_history[:, :, 0]  # running c_Sigma after each step: the bound of pruned pairs
        goal_xy = np.concatenate([ms.goal_xy[sorted(self.wanted[id(ms)])] for ms in sets])
        self.c_u = np.concatenate([ms.c_u[sorted(self.wanted[id(ms)])] for ms in sets])
        self.c_sigma = run.c_sigma[:, 0]
        self.risk = run.risk[:, 0]
        self.c_g = np.hypot(*(run.arrival_xy[:, 0] - goal_xy).T)
        self.cost = self.lib.scenario.cost.combine(self.c_u, self.c_g, self.c_sigma)
        stats.single_sims += group.shape[0]
        stats.count_steps(horizon, restart)

    def index(self, ms: MotionSet, k: int) -> int:
        """The row of the simulation of motion k of set ``ms``."""
        return self.results[(id(ms), k)]

    def rows(self, ms: MotionSet, local: np.ndarray) -> np.ndarray:
        """The rows of the simulations of the motions at positions ``local`` of set ``ms``."""
        key = id(ms)
        return np.array([self.results[(key, k)] for k in local.tolist()], dtype=np.int64)

    def best_cost(self, ms: MotionSet, room: str) -> float:
        """The single-robot optimum of moving to ``room`` (its table cost)."""
        return float(min(self.cost[self.index(ms, k)] for k in ms.goals_in(self.lib, room)))

    def terms(self, r: int) -> CostTerms:
        """The cost terms of row r."""
        return CostTerms(float(self.c_u[r]), float(self.c_g[r]), float(self.c_sigma[r]))

    def best(self, req: Request) -> MotionResult | None:
        """The cheapest instantiation of a single-robot request (the first on a tie), or
        None if the robot reaches none of the room's instantiations."""
        ms = self.sets.get((req.robots[0], req.starts[0]))
        if ms is None:
            return None
        rows = [(k, self.index(ms, k)) for k in ms.goals_in(self.lib, req.rooms[0])]
        if not rows:
            return None
        idx = np.array([r for _, r in rows])
        k, r = rows[pick(self.cost[idx], self.risk[idx], req.max_risk)]
        weights = self.lib.scenario.cost
        motion = (ms.motions[k],)
        risk = (float(self.risk[r]),) if req.max_risk is not None else ()
        return motion_result(req.robots, (self.terms(r),), self.mean[r], self.cov[r], 0, motion, weights, risk)
