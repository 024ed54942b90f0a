"""The oracle: evaluations through the disk cache, misses on an executor.

It only computes costs: the scenario it is given has been checked by the load stage (its
sizes against the caps, tmpnav.scenario.extent) and its roadmap by the roadmap stage (every
goal room reachable, tmpnav.roadmap.reach), both in :mod:`tmpnav.pipeline`.
"""

from __future__ import annotations

import math
import time
from collections import OrderedDict
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from tmpnav.errors import InputError
from tmpnav.oracle.cache import CacheStats, NullCache
from tmpnav.oracle.evaluate import EvalStats, Request
from tmpnav.oracle.executors import OracleContext, Outcome, Progress, SerialExecutor
from tmpnav.oracle.keys import context_digest, from_json, request_key, source_bytes, to_json
from tmpnav.oracle.results import penalised
from tmpnav.results import OracleCounts
from tmpnav.types import MotionResult

#: results kept in memory for the run (each a few kB: paths and a joint belief)
MAX_SEEN = 50_000


class CostCache(Protocol):
    """Where the oracle's results are kept between runs: ``DiskCache`` (the cost database of the
    cache directory) or ``NullCache`` (none), in :mod:`tmpnav.oracle.cache`."""

    stats: CacheStats

    def get_many(self, keys: Iterable[str]) -> dict[str, Any]: ...

    def put_many(self, items: dict[str, Any]) -> None: ...

    def close(self) -> None: ...


class Executor(Protocol):
    """Where the evaluations the cache misses run: in this process, in local worker processes,
    or on Ray (:mod:`tmpnav.oracle.executors`); every executor gives bit-identical results."""

    def run(self, ctx: OracleContext, requests: list[Request], progress: Progress | None = None) -> Outcome: ...

    def let_go(self) -> None: ...

    def close(self) -> None: ...


@dataclass
class OracleStats:
    requests: int = 0
    cache_hits: int = 0
    cache_misses: int = 0
    seconds: float = 0.0
    sims: EvalStats = field(default_factory=EvalStats)
    table_hit: bool = False  # the whole cost table came from the cache

    def counts(self) -> OracleCounts:
        """The counters as the run's report holds them."""
        return OracleCounts(
            table_cache_hit=self.table_hit,
            requests=self.requests,
            cache_hits=self.cache_hits,
            cache_misses=self.cache_misses,
            single_simulations=self.sims.single_sims,
            joint_simulations=self.sims.joint_sims,
            joint_factorized=self.sims.joint_factorized,
            pairs_pruned=self.sims.pairs_pruned,
        )


class Oracle:
    """Evaluates actions (see :mod:`tmpnav.oracle.evaluate`) with caching and parallelism."""

    def __init__(
        self,
        ctx: OracleContext,
        cache: CostCache | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ):
        self.ctx = ctx
        self.cache: CostCache = cache if cache is not None else NullCache()
        self.executor: Executor = executor if executor is not None else SerialExecutor()
        self.progress = progress
        self.context = context_digest(ctx.scenario, ctx.world, ctx.roadmap)
        self.sources = source_bytes(ctx.roadmap)
        self.stats = OracleStats()
        #: results of this run, by key: the searches ask the same questions again (with --no-cache too)
        self._seen: OrderedDict[str, MotionResult | None] = OrderedDict()

    def let_go_of_workers(self) -> None:
        """Let local workers go now, when no wave of requests is near (a later one forks new
        workers; tmpnav.oracle.executors.ProcessExecutor)."""
        self.executor.let_go()

    def close(self) -> None:
        """Stop the executor and close the cache."""
        self.executor.close()
        self.cache.close()

    def evaluate(self, requests: list[Request]) -> list[MotionResult | None]:
        """Results in request order; None where the robots cannot reach their rooms, or may not
        enter them (a room whose job, ``goals.jobs``, is for other robots).

        Raises InputError if a cost is not a finite number. Every request is answered under
        the scenario's chance constraint (``planner.max_risk``, :class:`Request`): a move over
        it costs its penalty more (tmpnav.oracle.results.penalised; the cache keeps the bare
        result).
        """
        goals = self.ctx.scenario.goals
        allowed = [
            not goals.jobs or all(goals.may_visit(r, x) for r, x in zip(q.robots, q.rooms, strict=True))
            for q in requests
        ]
        if not all(allowed):
            # a move into a room whose job is for other robots is no move at all: answered None
            # (as a room the robot cannot reach), neither computed nor cached
            answers = iter(self.evaluate([q for q, ok in zip(requests, allowed, strict=True) if ok]))
            return [next(answers) if ok else None for ok in allowed]
        start = time.perf_counter()
        delta = self.ctx.scenario.planner.max_risk
        if delta is not None:
            requests = [r if r.max_risk == delta else replace(r, max_risk=delta) for r in requests]
        keys = [request_key(self.context, self.ctx.scenario, r, self.sources) for r in requests]
        results: dict[str, MotionResult | None] = {k: self._seen[k] for k in keys if k in self._seen}
        cached = self.cache.get_many([k for k in keys if k not in results])
        missing = sorted({k: i for i, k in enumerate(keys) if k not in cached and k not in results}.values())
        results.update({k: from_json(v) for k, v in cached.items()})
        if missing:
            todo = [requests[i] for i in missing]
            computed, sims = self.executor.run(self.ctx, todo, self.progress)
            for request, result in zip(todo, computed, strict=True):
                self._check_finite(request, result)
            self.stats.sims.add(sims)
            fresh = {keys[i]: res for i, res in zip(missing, computed, strict=True)}
            if not isinstance(self.cache, NullCache):
                self.cache.put_many({k: to_json(v) for k, v in fresh.items()})
            results.update(fresh)
        self.stats.requests += len(requests)
        self.stats.cache_hits += len(cached)
        self.stats.cache_misses += len(missing)
        self.stats.seconds += time.perf_counter() - start
        for k in keys:
            self._seen[k] = results[k]
            self._seen.move_to_end(k)
        while len(self._seen) > MAX_SEEN:
            self._seen.popitem(last=False)
        return [penalised(results[k], delta) for k in keys]

    def _check_finite(self, request: Request, result: MotionResult | None) -> None:
        """Refuse a cost that is not a finite number (NaN or infinity: the EKF overflowed,
        from an extreme covariance or noise) before it reaches the cache or the planner."""
        if result is None or math.isfinite(result.cost):
            return
        terms = "; ".join(
            f"{robot}: c_u {t.c_u:g}, c_G {t.c_G:g}, c_Sigma {t.c_Sigma:g}"
            for robot, t in zip(result.robots, result.terms, strict=True)
        )
        keys = " and ".join(f"robots.{robot}.covariance" for robot in request.robots)
        raise InputError(
            f"the cost of {self._move(request)} is {result.cost} ({terms or 'a lower bound'}), not a finite number: "
            f"the EKF overflowed; expected {keys} and the models' noise small enough for finite beliefs"
        )

    def _move(self, request: Request) -> str:
        """The move in words: ``r1 moving from roadmap node 9 (room A) to room B``."""
        world, nodes = self.ctx.world, self.ctx.roadmap.nodes
        parts = []
        for robot, start, room in zip(request.robots, request.starts, request.rooms, strict=True):
            x, y = (float(v) for v in nodes[start.node])
            where = world.room_of(np.array([x, y]))
            origin = f"room {where}" if where is not None else f"({x:g}, {y:g})"
            parts.append(f"{robot} moving from roadmap node {start.node} ({origin}) to room {room}")
        return " with ".join(parts)
