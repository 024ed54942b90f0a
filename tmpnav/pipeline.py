"""The pipeline: the only module that knows the order of the stages, and times each one.

scenario -> world -> roadmap -> oracle (belief + cache) -> task (encode, solve, decode)
  -> re-simulation -> report
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from tmpnav import scenario as scenario_stage
from tmpnav import world as world_stage
from tmpnav.errors import InputError, ScenarioError
from tmpnav.types import Goals, PlanStatus, Roadmap, Scenario, StageTimes
from tmpnav.world import MapImageError, World


@contextmanager
def timed(times: StageTimes, stage: str) -> Iterator[None]:
    start = time.perf_counter()
    try:
        yield
    finally:
        times.add(stage, time.perf_counter() - start)


def load_world(path: str | Path) -> tuple[Scenario, World]:
    """Stages 1-2 with every input problem reported at once (ScenarioError)."""
    scenario, problems = scenario_stage.load_partial(path)
    if scenario is None:
        raise ScenarioError(problems)
    try:
        world = world_stage.build(scenario)
    except MapImageError as err:
        raise ScenarioError([*problems, err.problem]) from None
    problems += world_stage.check(scenario, world)
    if problems:
        raise ScenarioError(problems)
    return scenario, world


@dataclass(frozen=True)
class PlanOptions:
    """Command-line choices that override the scenario, and how to run the oracle."""

    encoding: str | None = None
    planner: str | None = None
    timeout: float | None = None
    pair_min_gain: float | None = None
    mutual_observations: bool | None = None
    goals: Goals | None = None
    cache_dir: Path | None = None  # None: the default (XDG) cache directory
    use_cache: bool = True
    replan: bool = False  # run the task planner even when the cache remembers its plan
    executor: str = "processes"
    workers: int | None = None
    ray_address: str | None = None
    progress: Callable[[int, int], None] | None = None


@dataclass
class PlanReport:
    """Everything ``tmpnav plan`` reports (see report/plan_json.py for the JSON schema)."""

    scenario: Scenario
    world: World
    roadmap: Roadmap
    encoding: str
    planner: str
    status: PlanStatus
    planner_cost: float
    resimulated_cost: float
    actions: list[Any]
    trajectories: dict[str, list[Any]]
    times: StageTimes
    cache: dict[str, Any]
    oracle: dict[str, Any]
    task: dict[str, Any]
    encoded: Any = field(repr=False, default=None)  # None when the plan came from the cache
    table: Any = field(repr=False, default=None)

    def pddl_texts(self) -> tuple[str, str]:
        """The PDDL domain and problem behind the plan (encoded again after a cache hit)."""
        from tmpnav.task.encode import encode
        from tmpnav.task.export import pddl_texts

        encoded = self.encoded
        if encoded is None:
            sc = self.scenario
            encoded = encode(self.table, sc.goals, sc.planner.encoding, name=sc.name, min_gain=sc.planner.pair_min_gain)
        return pddl_texts(encoded)


def apply_options(scenario: Scenario, options: PlanOptions) -> Scenario:
    """The scenario with the command line's overrides."""
    planner = scenario.planner
    planner = replace(
        planner,
        encoding=options.encoding or planner.encoding,
        name=options.planner or planner.name,
        timeout=options.timeout if options.timeout is not None else planner.timeout,
        pair_min_gain=options.pair_min_gain if options.pair_min_gain is not None else planner.pair_min_gain,
    )
    models = scenario.models
    if options.mutual_observations is not None:
        models = replace(models, mutual_observations=options.mutual_observations)
    goals = options.goals or scenario.goals
    return replace(scenario, planner=planner, models=models, goals=goals)


def build_roadmap(scenario: Scenario, world: World, cache_dir: Path | None) -> tuple[Roadmap, bool]:
    """The roadmap, from the store when possible; returns it and whether it was stored."""
    from tmpnav.roadmap import build_roadmap as grow
    from tmpnav.roadmap import store

    if cache_dir is None:
        return grow(world, scenario.robots, scenario.roadmap), False
    key = store.roadmap_key(world, scenario.robots, scenario.roadmap)
    found = store.load(cache_dir, key)
    if found is not None:
        return found, True
    roadmap = grow(world, scenario.robots, scenario.roadmap)
    store.save(cache_dir, key, roadmap)
    return roadmap, False


def make_oracle(scenario: Scenario, world: World, roadmap: Roadmap, options: PlanOptions) -> Any:
    from tmpnav.oracle.cache import DiskCache, NullCache, default_cache_dir
    from tmpnav.oracle.executors import OracleContext, make_executor
    from tmpnav.oracle.oracle import Oracle

    cache = DiskCache(options.cache_dir or default_cache_dir()) if options.use_cache else NullCache()
    executor = make_executor(options.executor, options.workers, options.ray_address)
    return Oracle(OracleContext(scenario, world, roadmap), cache, executor, options.progress)


@dataclass
class Prepared:
    """The stages up to the cost table, shared by ``plan`` and ``export-pddl``."""

    scenario: Scenario
    world: World
    roadmap: Roadmap
    roadmap_hit: bool
    cache_dir: Path | None
    oracle: Any
    table: Any


def prepare(
    path: str | Path, options: PlanOptions, times: StageTimes, loaded: tuple[Scenario, World] | None = None
) -> Prepared:
    """Load, grow (or fetch) the roadmap, and compute the cost table the encoding needs.

    The caller must close ``prepared.oracle`` (executor and cache).
    """
    from tmpnav.oracle.cache import default_cache_dir
    from tmpnav.oracle.table import build_table, start_locations
    from tmpnav.task.encode import ENCODINGS, pair_filter

    with timed(times, "load"):
        scenario, world = loaded if loaded is not None else load_world(path)
        scenario = apply_options(scenario, options)
        _check_goals(scenario)
    encoding = ENCODINGS[scenario.planner.encoding]
    cache_dir = (options.cache_dir or default_cache_dir()) if options.use_cache else None
    with timed(times, "roadmap"):
        roadmap, roadmap_hit = build_roadmap(scenario, world, cache_dir)
    oracle = make_oracle(scenario, world, roadmap, options)
    try:
        with timed(times, "oracle"):
            starts = start_locations(scenario, world)
            pairs = pair_filter(encoding.name, scenario.goals, starts) if encoding.pairs else None
            # only the mixed encoding drops pairs that save little, so only it may prune them
            prune = (
                scenario.planner.pair_min_gain
                if encoding.name == "mixed" and scenario.planner.pair_min_gain > 0
                else None
            )
            table = build_table(
                oracle,
                world,
                encoding.destinations,
                pairs,
                filter_key=repr((encoding.name, scenario.goals)),
                pair_min_gain=prune,
            )
    except BaseException:
        close(oracle)
        raise
    return Prepared(scenario, world, roadmap, roadmap_hit, cache_dir, oracle, table)


def close(oracle: Any) -> None:
    oracle.executor.close()
    oracle.cache.close()


def encode_only(path: str | Path, options: PlanOptions) -> Any:
    """The encoded task problem with its computed costs (``tmpnav export-pddl``)."""
    from tmpnav.task.encode import encode

    prep = prepare(path, options, StageTimes())
    close(prep.oracle)
    sc = prep.scenario
    return encode(prep.table, sc.goals, sc.planner.encoding, name=sc.name, min_gain=sc.planner.pair_min_gain)


def plan(
    path: str | Path, options: PlanOptions | None = None, loaded: tuple[Scenario, World] | None = None
) -> PlanReport:
    """Plan a scenario end to end: the task-level optimal plan for the roadmap, with its
    motions and beliefs. ``loaded`` skips loading when the caller already has the world."""
    from tmpnav.oracle.executors import library
    from tmpnav.resimulate import resimulate
    from tmpnav.task.decode import canonical_order, decode, step_cost
    from tmpnav.task.encode import encode
    from tmpnav.task.memo import Memo, from_json, memo_key
    from tmpnav.task.memo import to_json as memo_to_json
    from tmpnav.task.solve import solve

    options = options or PlanOptions()
    times = StageTimes()
    prep = prepare(path, options, times, loaded)
    scenario, oracle, table = prep.scenario, prep.oracle, prep.table
    try:
        memo, key, encoded = None, None, None
        if options.use_cache:
            with timed(times, "planner"):
                sp = scenario.planner
                key = memo_key(table, scenario.goals, sp.encoding, sp.pair_min_gain, sp.name, scenario.name)
                found = None if options.replan else oracle.cache.get_many([key]).get(key)
                memo = from_json(found, table) if found is not None else None
        if memo is None:
            with timed(times, "encode"):
                encoded = encode(
                    table,
                    scenario.goals,
                    scenario.planner.encoding,
                    name=scenario.name,
                    min_gain=scenario.planner.pair_min_gain,
                )
            with timed(times, "planner"):
                solved = solve(encoded.problem, scenario.planner.name, scenario.planner.timeout)
            memo = Memo(
                status=solved.status,
                engine=solved.engine,
                actions=solved.actions,
                steps=tuple(decode(solved, encoded)),
                task={
                    "actions": encoded.n_actions,
                    "pair_actions": len(encoded.pair_actions),
                    "reshaped_rooms": len(encoded.potentials),
                },
            )
            if key is not None:
                oracle.cache.put_many({key: memo_to_json(memo)})
        else:
            times.seconds.setdefault("encode", 0.0)
        plan_hit = encoded is None
        order = canonical_order(list(memo.steps), table.robots)
        steps = [memo.steps[i] for i in order]
        names = [memo.actions[i][0] for i in order]
        planner_costs = [step_cost(table, s) for s in steps]
        with timed(times, "resimulate"):
            resim = resimulate(library(oracle.ctx), oracle, scenario, steps, planner_costs, names)
    finally:
        close(oracle)
    times.seconds["total"] = sum(v for k, v in times.seconds.items() if k != "load")
    stats = oracle.stats
    return PlanReport(
        scenario=scenario,
        world=prep.world,
        roadmap=prep.roadmap,
        encoding=scenario.planner.encoding,
        planner=scenario.planner.name,
        status=memo.status,
        planner_cost=float(sum(planner_costs)),
        resimulated_cost=resim.cost,
        actions=resim.actions,
        trajectories=resim.trajectories,
        times=times,
        cache={
            "enabled": options.use_cache,
            "directory": str(prep.cache_dir) if prep.cache_dir else None,
            "hits": stats.cache_hits,
            "misses": stats.cache_misses,
            "roadmap_hit": prep.roadmap_hit,
            "plan_hit": plan_hit,
            "warnings": list(getattr(oracle.cache.stats, "warnings", [])),
        },
        oracle=stats.as_dict(),
        task={"single_moves": len(table.single), "pair_moves_evaluated": len(table.pair), **memo.task},
        encoded=encoded,
        table=table,
    )


def _check_goals(scenario: Scenario) -> None:
    """Goals must name rooms of the scenario (the bench may override them)."""
    rooms = {r.name for r in scenario.rooms}
    unknown = [g for g in scenario.goals.all_rooms if g not in rooms]
    if unknown:
        raise InputError(f"goal rooms {', '.join(unknown)} are not rooms of scenario {scenario.name!r}")
