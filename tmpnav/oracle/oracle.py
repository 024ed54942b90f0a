"""The oracle: evaluations through the disk cache, misses on an executor."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.evaluate import EvalStats, Request
from tmpnav.oracle.executors import OracleContext, Progress, SerialExecutor
from tmpnav.oracle.keys import context_digest, from_json, request_key, to_json
from tmpnav.types import MotionResult


@dataclass
class OracleStats:
    requests: int = 0
    cache_hits: int = 0
    cache_misses: int = 0
    seconds: float = 0.0
    sims: EvalStats = field(default_factory=EvalStats)
    table_hit: bool = False  # the whole cost table came from the cache

    def as_dict(self) -> dict[str, Any]:
        return {
            "table_cache_hit": self.table_hit,
            "requests": self.requests,
            "cache_hits": self.cache_hits,
            "cache_misses": self.cache_misses,
            "single_simulations": self.sims.single_sims,
            "joint_simulations": self.sims.joint_sims,
            "joint_factorized": self.sims.joint_factorized,
            "pairs_pruned": self.sims.pairs_pruned,
        }


class Oracle:
    """Evaluates actions (see :mod:`tmpnav.oracle.evaluate`) with caching and parallelism."""

    def __init__(self, ctx: OracleContext, cache: Any = None, executor: Any = None, progress: Progress | None = None):
        self.ctx = ctx
        self.cache = cache if cache is not None else NullCache()
        self.executor = executor if executor is not None else SerialExecutor()
        self.progress = progress
        self.context = context_digest(ctx.scenario, ctx.world, ctx.roadmap)
        self.stats = OracleStats()

    def evaluate(self, requests: list[Request]) -> list[MotionResult | None]:
        """Results in request order; None where the robots cannot reach their rooms."""
        start = time.perf_counter()
        keys = [request_key(self.context, self.ctx.scenario, r) for r in requests]
        cached = self.cache.get_many(keys)
        missing = sorted({k: i for i, k in enumerate(keys) if k not in cached}.values())
        results: dict[str, MotionResult | None] = {k: from_json(v) for k, v in cached.items()}
        if missing:
            todo = [requests[i] for i in missing]
            computed, sims = self.executor.run(self.ctx, todo, self.progress)
            self.stats.sims.add(sims)
            fresh = {keys[i]: res for i, res in zip(missing, computed, strict=True)}
            if not isinstance(self.cache, NullCache):
                self.cache.put_many({k: to_json(v) for k, v in fresh.items()})
            results.update(fresh)
        self.stats.requests += len(requests)
        self.stats.cache_hits += len(cached)
        self.stats.cache_misses += len(missing)
        self.stats.seconds += time.perf_counter() - start
        return [results[k] for k in keys]
