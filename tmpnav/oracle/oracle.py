"""The oracle: evaluations through the disk cache, misses on an executor."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tmpnav.errors import InputError, Problem, RoadmapError, ScenarioError
from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.evaluate import EvalStats, Request
from tmpnav.oracle.executors import OracleContext, Progress, SerialExecutor
from tmpnav.oracle.keys import context_digest, from_json, request_key, to_json
from tmpnav.roadmap.reach import roadmap_cuts
from tmpnav.scenario import display_path
from tmpnav.scenario.extent import plan_sizes
from tmpnav.types import MotionResult, Scenario


def check_plan_sizes(scenario: Scenario) -> None:
    """Raise ScenarioError when goal rooms x robots or the cost table's estimated entries
    pass their caps (tmpnav.scenario.limits) for this scenario, overrides included."""
    file = display_path(scenario.source)
    problems = [Problem(file, path, message, scenario.line_of(path)) for path, message in plan_sizes(scenario)]
    if problems:
        raise ScenarioError(problems)


def check_reachable(ctx: OracleContext) -> None:
    """Raise RoadmapError (exit 2) when the roadmap cuts a goal room off from the robot that
    must visit it though free space joins them, instead of costing every move and hearing
    "no plan" from ENHSP."""
    why = roadmap_cuts(ctx.scenario, ctx.world, ctx.roadmap)
    if why is not None:
        raise RoadmapError(why)


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
    """Evaluates actions (see :mod:`tmpnav.oracle.evaluate`) with caching and parallelism.

    Refuses a scenario whose cost table would pass the resource caps (ScenarioError), or
    whose goals the roadmap cannot serve (RoadmapError), before it computes anything. The
    scenario it is given is the one in force, with the command line's encoding and goals
    (``plan --encoding mixed``, the bench's goal draws), which validation never saw.
    """

    def __init__(self, ctx: OracleContext, cache: Any = None, executor: Any = None, progress: Progress | None = None):
        self.ctx = ctx
        self.cache = cache if cache is not None else NullCache()
        self.executor = executor if executor is not None else SerialExecutor()
        try:
            check_plan_sizes(ctx.scenario)
            check_reachable(ctx)
        except InputError:
            self.executor.close()
            self.cache.close()
            raise
        self.progress = progress
        self.context = context_digest(ctx.scenario, ctx.world, ctx.roadmap)
        self.stats = OracleStats()

    def evaluate(self, requests: list[Request]) -> list[MotionResult | None]:
        """Results in request order; None where the robots cannot reach their rooms.

        Raises InputError if a cost is not a finite number.
        """
        start = time.perf_counter()
        keys = [request_key(self.context, self.ctx.scenario, r) for r in requests]
        cached = self.cache.get_many(keys)
        missing = sorted({k: i for i, k in enumerate(keys) if k not in cached}.values())
        results: dict[str, MotionResult | None] = {k: from_json(v) for k, v in cached.items()}
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
        return [results[k] for k in keys]

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
