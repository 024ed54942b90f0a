"""The pipeline: the only module that knows the order of the stages, and times each one.

::

    scenario -> world      load_world        scenario/, world/
    -> roadmap             roadmap_for       roadmap/ (grown, or read from the cache directory)
    -> cost table          prepare           oracle/ (belief/ inside), what the encoding asks for
    -> task plan           plan_task         task/ (memo lookup, encode, solve, decode)
    -> re-simulation       resimulate        the plan run with beliefs carried step to step
    -> PlanReport                            report/ writes it (JSON, text, figure)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from tmpnav import scenario as scenario_stage
from tmpnav import world as world_stage
from tmpnav.cachedir import CacheDir
from tmpnav.errors import InputError, ScenarioError
from tmpnav.results import CacheUse, PlanReport, StageTimes, TaskResult
from tmpnav.types import CostTable, Goals, Roadmap, Scenario
from tmpnav.world import MapImageError, World

#: progress of the anytime search: (seconds, best plan cost, lower bound or None, what happened)
SearchProgress = Callable[[float, float, float | None, str], None]

if TYPE_CHECKING:
    from tmpnav.oracle.oracle import Oracle
    from tmpnav.roadmap.store import RoadmapStore
    from tmpnav.task.encode import EncodedTask


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
    cache_dir: Path | None = None  # None: the default cache directory (tmpnav.cachedir)
    use_cache: bool = True
    replan: bool = False  # run the task planner even when the cache remembers its plan
    executor: str = "processes"
    workers: int | None = None
    ray_address: str | None = None
    progress: Callable[[int, int], None] | None = None
    search: str | None = None  # exact | anytime | auto
    time_budget: float | None = None
    costs: str | None = None  # table | carried
    search_progress: SearchProgress | None = None  # (seconds, best cost, bound, what happened)


def apply_options(scenario: Scenario, options: PlanOptions) -> Scenario:
    """The scenario with the command line's overrides."""
    planner = scenario.planner
    planner = replace(
        planner,
        encoding=options.encoding or planner.encoding,
        name=options.planner or planner.name,
        timeout=options.timeout if options.timeout is not None else planner.timeout,
        pair_min_gain=options.pair_min_gain if options.pair_min_gain is not None else planner.pair_min_gain,
        search=options.search or planner.search,
        time_budget=options.time_budget if options.time_budget is not None else planner.time_budget,
        costs=options.costs or planner.costs,
    )
    if planner.encoding == "paper":
        # the paper's encoding is the paper's model: every action costed from canonical states
        if options.costs == "carried" or options.search == "anytime":
            raise InputError(
                "the paper's encoding is planned exactly with table costs; "
                "use --encoding mixed for --search anytime or --costs carried"
            )
        planner = replace(planner, costs="table", search="exact")
    models = scenario.models
    if options.mutual_observations is not None:
        models = replace(models, mutual_observations=options.mutual_observations)
    goals = options.goals or scenario.goals
    return replace(scenario, planner=planner, models=models, goals=goals)


def roadmap_for(scenario: Scenario, world: World, store: RoadmapStore | None) -> tuple[Roadmap, bool]:
    """The scenario's roadmap, read from ``store`` when it holds it, else grown (and stored);
    returns it and whether it was read."""
    from tmpnav.roadmap import build_roadmap
    from tmpnav.roadmap.store import roadmap_key

    if store is None:
        return build_roadmap(world, scenario.robots, scenario.roadmap), False
    key = roadmap_key(world, scenario.robots, scenario.roadmap)
    found = store.load(key)
    if found is not None:
        return found, True
    roadmap = build_roadmap(world, scenario.robots, scenario.roadmap)
    store.save(key, roadmap)
    return roadmap, False


def make_oracle(scenario: Scenario, world: World, roadmap: Roadmap, options: PlanOptions) -> Oracle:
    """The cost oracle of this world and roadmap: its cache (the cost database, or none) and executor."""
    from tmpnav.oracle.cache import DiskCache, NullCache
    from tmpnav.oracle.executors import OracleContext, make_executor
    from tmpnav.oracle.oracle import Oracle

    cache = DiskCache(CacheDir.at(options.cache_dir).root) if options.use_cache else NullCache()
    executor = make_executor(options.executor, options.workers, options.ray_address)
    return Oracle(OracleContext(scenario, world, roadmap), cache, executor, options.progress)


@dataclass(frozen=True)
class Prepared:
    """The stages up to the cost table, shared by ``plan`` and ``export-pddl``."""

    scenario: Scenario
    world: World
    roadmap: Roadmap
    roadmap_hit: bool
    cache: CacheDir | None
    roadmap_warnings: tuple[str, ...]
    oracle: Oracle  # open: the caller closes it (see close)
    table: CostTable | None  # None when prepared without it (the anytime search costs lazily)


def prepare(
    path: str | Path,
    options: PlanOptions,
    times: StageTimes,
    loaded: tuple[Scenario, World] | None = None,
    with_table: bool = True,
) -> Prepared:
    """Load, grow (or read) the roadmap, and (``with_table``) compute the cost table the
    encoding asks for; without it, ``prepared.table`` is None.

    The caller must close ``prepared.oracle`` (executor and cache), see :func:`close`.
    """
    from tmpnav.attachment.strategy import full_table
    from tmpnav.roadmap.store import RoadmapStore

    with times.timed("load"):
        scenario, world = loaded if loaded is not None else load_world(path)
        scenario = apply_options(scenario, options)
        _check_goals(scenario)
    cache = CacheDir.at(options.cache_dir) if options.use_cache else None
    if cache is not None:
        cache.ensure()  # an unusable cache directory fails now, not after the roadmap
    store = RoadmapStore(cache) if cache is not None else None
    with times.timed("roadmap"):
        roadmap, roadmap_hit = roadmap_for(scenario, world, store)
    oracle = make_oracle(scenario, world, roadmap, options)
    try:
        table = full_table(scenario, world, oracle, times) if with_table else None
    except BaseException:
        close(oracle)
        raise
    warnings = tuple(store.warnings) if store is not None else ()
    return Prepared(scenario, world, roadmap, roadmap_hit, cache, warnings, oracle, table)


def close(oracle: Oracle) -> None:
    """Stop the oracle's executor and close its cache."""
    oracle.executor.close()
    oracle.cache.close()


def export_problem(path: str | Path, options: PlanOptions) -> EncodedTask:
    """The encoded task problem with its computed costs (``tmpnav export-pddl``)."""
    from tmpnav.task.stage import TaskProblem

    prep = prepare(path, options, StageTimes())
    close(prep.oracle)
    assert prep.table is not None
    return TaskProblem.of(prep.scenario, prep.table).encode()


def plan(
    path: str | Path, options: PlanOptions | None = None, loaded: tuple[Scenario, World] | None = None
) -> PlanReport:
    """Plan a scenario end to end: the task-level optimal plan for the roadmap, with its
    motions and beliefs. ``loaded`` skips loading when the caller already has the world."""
    from tmpnav.attachment.canonical import CanonicalCosts
    from tmpnav.attachment.carried import CarriedCosts
    from tmpnav.attachment.strategy import plan_scenario
    from tmpnav.resimulate import resimulate

    options = options or PlanOptions()
    times = StageTimes()
    prep = prepare(path, options, times, loaded, with_table=False)
    scenario, oracle = prep.scenario, prep.oracle
    try:
        canonical = CanonicalCosts(oracle, prep.world, scenario.planner.pair_min_gain)
        carried = CarriedCosts(oracle, canonical)
        store = oracle.cache if options.use_cache else None
        planned = plan_scenario(
            scenario, prep.world, canonical, carried, store, options.replan, times, options.search_progress
        )
        table, task = planned.table, planned.task
        with times.timed("resimulate"):
            resim = resimulate(carried, list(task.steps), list(task.step_costs), list(task.action_names))
    finally:
        close(oracle)
    times.close()
    return PlanReport(
        scenario=scenario,
        world=prep.world,
        roadmap=prep.roadmap,
        table=table,
        task=task,
        actions=tuple(resim.actions),
        trajectories=resim.trajectories,
        times=times,
        cache=_cache_use(prep, task, options.use_cache),
        oracle=oracle.stats,
    )


def pddl_texts(report: PlanReport) -> tuple[str, str]:
    """The PDDL domain and problem behind a report's plan (encoded again when it was remembered)."""
    from tmpnav.task.export import pddl_texts as texts
    from tmpnav.task.stage import TaskProblem, encoded_problem

    return texts(encoded_problem(TaskProblem.of(report.scenario, report.table), report.task))


def _cache_use(prep: Prepared, task: TaskResult, enabled: bool) -> CacheUse:
    stats = prep.oracle.stats
    return CacheUse(
        enabled=enabled,
        directory=prep.cache.root if prep.cache is not None else None,
        hits=stats.cache_hits,
        misses=stats.cache_misses,
        roadmap_hit=prep.roadmap_hit,
        table_hit=stats.table_hit,
        plan_hit=task.plan_hit,
        warnings=(*prep.roadmap_warnings, *prep.oracle.cache.stats.warnings),
    )


def _check_goals(scenario: Scenario) -> None:
    """Goals must name rooms of the scenario (the bench may override them)."""
    rooms = {r.name for r in scenario.rooms}
    unknown = [g for g in scenario.goals.all_rooms if g not in rooms]
    if unknown:
        raise InputError(f"goal rooms {', '.join(unknown)} are not rooms of scenario {scenario.name!r}")
