"""The pipeline: the only module that knows the order of the stages, and times each one.

::

    scenario -> world      load_world        scenario/, world/ (the command line's overrides
                                             applied, tmpnav.options; everything checked once)
    -> roadmap             roadmap_for       roadmap/ (grown, or read from the cache directory)
    -> task plan           plan_stage        planning/: the search and costs of tmpnav.choices,
                                             task/ on attachment/'s cost models (oracle/ inside)
    -> re-simulation       resimulate        the plan run with beliefs carried step to step
    -> PlanReport                            report/ writes it (JSON, text, figure)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from tmpnav import scenario as scenario_stage
from tmpnav import world as world_stage
from tmpnav.cachedir import CacheDir
from tmpnav.deadline import Deadline, run_started
from tmpnav.errors import (
    ConflictError,
    PlannerTimeoutError,
    RiskError,
    ScenarioError,
    TimeLimitError,
)
from tmpnav.heap import long_lived_frozen
from tmpnav.options import NO_THRESHOLD as NO_THRESHOLD
from tmpnav.options import Execution as Execution
from tmpnav.options import Overrides as Overrides
from tmpnav.options import PlanOptions as PlanOptions
from tmpnav.options import Reporters as Reporters
from tmpnav.options import apply_options as apply_options
from tmpnav.options import in_force as in_force
from tmpnav.options import size_problems
from tmpnav.results import CacheUse, PlanReport, SearchProgress, StageTimes
from tmpnav.types import Roadmap, Scenario
from tmpnav.world import MapImageError, World

if TYPE_CHECKING:
    from tmpnav.oracle.oracle import Oracle
    from tmpnav.oracle.table import Origin
    from tmpnav.roadmap.store import RoadmapStore
    from tmpnav.task.encode import EncodedTask


def load_world(path: str | Path, overrides: Overrides | None = None) -> tuple[Scenario, World]:
    """Stages 1-2: the scenario in force (``overrides`` applied) and its world, every input
    problem reported at once (ScenarioError), the caps on the plan's size included."""
    scenario, problems = scenario_stage.load_partial(path)
    if scenario is None:
        raise ScenarioError(problems)
    scenario = apply_options(scenario, overrides or Overrides())
    try:
        world = world_stage.build(scenario)
    except MapImageError as err:
        raise ScenarioError([*problems, err.problem]) from None
    problems += world_stage.check(scenario, world) + size_problems(scenario)
    if problems:
        raise ScenarioError(problems)
    return scenario, world


def roadmap_for(
    scenario: Scenario, world: World, store: RoadmapStore | None, base: Roadmap | None = None
) -> tuple[Roadmap, bool]:
    """The scenario's roadmap: ``base`` with the robots' starts added (a replan's), else read
    from ``store`` when it holds it, else grown (and stored); returns it and whether it was
    read or added to."""
    from tmpnav.roadmap import build_roadmap, with_starts
    from tmpnav.roadmap.store import roadmap_key

    if base is not None and (added := with_starts(base, world, scenario.robots, scenario.roadmap)) is not None:
        return added, True
    if store is None:
        return build_roadmap(world, scenario.robots, scenario.roadmap), False
    key = roadmap_key(world, scenario.robots, scenario.roadmap)
    found = store.load(key)
    if found is not None:
        return found, True
    roadmap = build_roadmap(world, scenario.robots, scenario.roadmap)
    store.save(key, roadmap)
    return roadmap, False


def _roadmap_stored(scenario: Scenario, world: World, store: RoadmapStore | None, base: Roadmap | None) -> bool:
    """Whether :func:`roadmap_for` will find the roadmap rather than grow it (a guess for a
    replan's: its starts are joined to ``base``)."""
    from tmpnav.roadmap.store import roadmap_key

    if base is not None:
        return True
    return store is not None and store.cache.roadmap(roadmap_key(world, scenario.robots, scenario.roadmap)).exists()


def warm_site(scenario: Scenario, world: World, options: PlanOptions) -> bool:
    """Compute ahead what every plan and revision of a loaded site asks for first (``tmpnav
    serve``): its roadmap, read from the cache (never grown here), and the shortest-path trees,
    walks and motion floors from every room's pose instantiations, which
    :mod:`tmpnav.roadmap.graph` keeps for the process. Whether the roadmap was there to warm."""
    from tmpnav.attachment.carried import room_floors
    from tmpnav.oracle.executors import OracleContext, library
    from tmpnav.roadmap.store import RoadmapStore

    run = options.execution
    store = RoadmapStore(CacheDir.at(run.cache_dir)) if run.use_cache else None
    if not _roadmap_stored(scenario, world, store, None):
        return False
    roadmap, _ = roadmap_for(scenario, world, store)
    room_floors(scenario, library(OracleContext(scenario, world, roadmap)), [r.name for r in scenario.robots])
    return True


def make_oracle(
    scenario: Scenario, world: World, roadmap: Roadmap, execution: Execution, progress: Reporters | None = None
) -> Oracle:
    """The cost oracle of this world and roadmap: its cache (the cost database, or none) and executor."""
    from tmpnav.oracle.cache import DiskCache, NullCache
    from tmpnav.oracle.executors import OracleContext, make_executor
    from tmpnav.oracle.oracle import Oracle

    cache = DiskCache(CacheDir.at(execution.cache_dir).root) if execution.use_cache else NullCache()
    executor = make_executor(execution.executor, execution.workers, execution.ray_address)
    return Oracle(OracleContext(scenario, world, roadmap), cache, executor, progress.oracle if progress else None)


@dataclass(frozen=True)
class Prepared:
    """The stages before the task plan, shared by ``plan`` and ``export-pddl``."""

    scenario: Scenario
    world: World
    roadmap: Roadmap
    roadmap_hit: bool
    cache: CacheDir | None
    roadmap_warnings: tuple[str, ...]
    oracle: Oracle  # open: the caller closes it


def prepare(
    path: str | Path,
    options: PlanOptions,
    times: StageTimes,
    loaded: tuple[Scenario, World] | None = None,
    on_loaded: Callable[[Scenario, bool], None] | None = None,
) -> Prepared:
    """Load (or take ``loaded``, the overrides applied), tell ``on_loaded`` the scenario and
    whether its roadmap is at hand (read from the cache or added to a replan's: the stages
    up to the plan will be quick), grow or read the roadmap, open the oracle. The caller must
    close ``prepared.oracle`` (executor and cache)."""
    from tmpnav.roadmap.reach import check_reachable
    from tmpnav.roadmap.store import RoadmapStore, SafeWeightStore, ScanStore

    run = options.execution
    with times.timed("load"):
        if loaded is None:
            scenario, world = load_world(path, options.overrides)
        else:
            scenario, world = in_force(loaded[0], options.overrides), loaded[1]
    cache = CacheDir.at(run.cache_dir) if run.use_cache else None
    if cache is not None:
        cache.ensure()  # an unusable cache directory fails now, not after the roadmap
    store = RoadmapStore(cache) if cache is not None else None
    if on_loaded is not None:
        on_loaded(scenario, _roadmap_stored(scenario, world, store, options.overrides.roadmap_base))
    with times.timed("roadmap"):
        roadmap, roadmap_hit = roadmap_for(scenario, world, store, options.overrides.roadmap_base)
        check_reachable(scenario, world, roadmap)
        if cache is not None and store is not None and scenario.models.range_sensor is not None:
            # before the oracle's workers fork: they start with the table too
            ScanStore(cache, store).load(world, scenario.models.range_sensor)
        if cache is not None and store is not None and scenario.roadmap.clearance:
            radius = max(r.radius for r in scenario.robots)  # the motions' (tmpnav.oracle.motions)
            SafeWeightStore(cache, store).ensure(roadmap, world, radius, scenario.roadmap.clearance)
    with times.timed("oracle"):
        oracle = make_oracle(scenario, world, roadmap, run, options.reporters)
    warnings = tuple(store.warnings) if store is not None else ()
    return Prepared(scenario, world, roadmap, roadmap_hit, cache, warnings, oracle)


def searches_over() -> None:
    """A command's planning is done: ENHSP's JVM is let go before the figures are drawn or the
    sessions executed (tmpnav.task.enhsp_jvm.release; a planning service keeps it)."""
    from tmpnav.task import enhsp_jvm

    enhsp_jvm.release()


def export_problem(path: str | Path, options: PlanOptions) -> EncodedTask:
    """The encoded task problem with its computed costs (``tmpnav export-pddl``)."""
    from tmpnav.planning.table import full_table
    from tmpnav.task.stage import TaskProblem

    times = StageTimes()
    deadline = Deadline(started=run_started(times.started))

    def loaded_now(scenario: Scenario, _roadmap_stored: bool) -> None:
        deadline.seconds = scenario.planner.time_limit

    with _named_stage(times, deadline):
        prep = prepare(path, options.but(progress=deadline.watch(options.reporters.oracle)), times, None, loaded_now)
        try:
            deadline.check()
            table = full_table(prep.scenario, prep.world, prep.oracle, times)
        finally:
            prep.oracle.close()
    return TaskProblem.of(prep.scenario, table).encode()


def plan(
    path: str | Path, options: PlanOptions | None = None, loaded: tuple[Scenario, World] | None = None
) -> PlanReport:
    """Plan a scenario end to end: the task-level optimal plan for the roadmap, with its
    motions and beliefs. ``loaded`` skips loading when the caller already has the world.
    Raises RiskError when the plan breaks the chance constraint (:func:`check_risk`) and
    ConflictError when it leaves robots in each other's way (:func:`check_conflicts`), unless
    the options accept that (``accept_risk``)."""
    options = options or PlanOptions()
    report = _planned(path, options, loaded)
    if not options.overrides.accept_risk:
        check_risk(path, options, report)
        check_conflicts(report)
    return report


def check_conflicts(report: PlanReport) -> None:
    """Raise ConflictError when, under a chance constraint (planner.max_risk), robots asked to be
    kept apart (planner.keep_apart) are still in each other's way on the plan's trajectories (the
    independent checker, tmpnav.belief.conflicts) at the same planned instant. Without a
    constraint (the paper's model) no plan claims to be safe: its conflicts are reported, not
    refused; nor are robots that keep apart on the plan's clock but not within the time
    windows of planner.clock_drift: the plan's warnings name them."""
    from tmpnav.planning.safety import conflicts_left

    planner = report.scenario.planner
    if planner.max_risk is None or not planner.keep_apart or not (left := conflicts_left(report, drift=0.0)):
        return
    first = left[0]
    more = f" (and {len(left) - 1} more)" if len(left) > 1 else ""
    raise ConflictError(
        f"the plan leaves robots in each other's way: {' and '.join(first.robots)} at {first.t_from:.1f} s, "
        f"{first.closest_distance:.2f} m apart where {first.required_separation:.2f} m are needed{more}; no wait, "
        "detour or sidestep clears them (--accept-risk takes the plan as it is, --no-keep-apart plans without "
        "keeping robots apart)"
    )


def in_own_units(progress: SearchProgress | None, scenario: Scenario) -> SearchProgress | None:
    """The search's progress told in the objective's own units (the makespan's seconds for
    ``makespan``, :meth:`tmpnav.task.objectives.Objective.own`): the best plan and the bound."""
    from tmpnav.task.objectives import OBJECTIVES

    objective = OBJECTIVES[scenario.planner.objective]
    if progress is None or objective.units == "cost":
        return progress
    dt, tell = scenario.models.dt, progress

    def told(seconds: float, best: float, bound: float | None, what: str) -> None:
        tell(seconds, objective.own(best, dt), None if bound is None else objective.own(bound, dt), what)

    return told


def _planned(path: str | Path, options: PlanOptions, loaded: tuple[Scenario, World] | None) -> PlanReport:
    """The plan, whether or not it keeps within the chance constraint."""
    from tmpnav.attachment.apart import keep_apart
    from tmpnav.planning import TaskRun, get_ready, plan_stage
    from tmpnav.resimulate import resimulate
    from tmpnav.task.search_run import SearchRun

    times = StageTimes()
    deadline = Deadline(started=run_started(times.started))

    def loaded_now(scenario: Scenario, roadmap_stored: bool) -> None:
        deadline.seconds = scenario.planner.time_limit
        if not roadmap_stored:
            # ENHSP readied while the roadmap and the first costs are computed. With the roadmap
            # at hand the plan is often remembered too, and needs no JVM: the search, if it runs,
            # readies ENHSP itself (tmpnav.planning.anytime) as it starts
            get_ready(scenario)

    options = options.but(progress=deadline.watch(options.reporters.oracle))  # the limit, between blocks
    with long_lived_frozen(), _named_stage(times, deadline):  # tmpnav.heap
        prep = prepare(path, options, times, loaded, on_loaded=loaded_now)
        try:
            deadline.check()
            store = prep.oracle.cache if options.execution.use_cache else None
            progress = in_own_units(options.reporters.search, prep.scenario)
            watch = SearchRun(times, progress, deadline=deadline)
            origin = _origins(options.overrides, prep)
            scenario = _within(prep.scenario, deadline)
            run = TaskRun.of(scenario, prep.world, prep.oracle, store, options.execution.replan, watch, origin)
            run = replace(run, incumbent=options.overrides.incumbent)
            planned = plan_stage(run)
            deadline.disarm()  # the plan is found: its re-simulation and report follow
            task, apart = planned.task, None
            with times.timed("resimulate"):
                resim = resimulate(run.carried, task)
                if prep.scenario.planner.keep_apart:  # the search's own resolution, if it priced this plan
                    delta = prep.scenario.planner.max_risk
                    kept = keep_apart(run.carried, task, delta, resim.cost, resim.schedule.makespan)
                    if kept is not None:
                        task, apart = kept.task, kept.apart
                        resim = resimulate(run.carried, task, kept.delays, kept.detours)
        finally:
            with times.timed("oracle"):  # its workers end
                prep.oracle.close()
            with times.timed("roadmap"):  # the scans' information stored with the roadmap
                _keep_scans(prep)
    times.close()
    report = PlanReport(
        scenario=prep.scenario,
        world=prep.world,
        roadmap=prep.roadmap,
        table=planned.table,
        task=task,
        actions=tuple(resim.actions),
        trajectories=resim.trajectories,
        schedule=resim.schedule,
        times=times,
        cache=_cache_use(prep, planned.task.plan_hit, options.execution.use_cache),
        oracle=prep.oracle.stats.counts(),
        apart=apart,
    )
    return report


@contextmanager
def _named_stage(times: StageTimes, deadline: Deadline) -> Iterator[None]:
    """TimeLimitError, and an exact search's ENHSP timeout cut short by the time limit, completed
    with the stage that took the time: the stage of most seconds so far."""
    try:
        yield
    except PlannerTimeoutError as err:
        if not isinstance(err, TimeLimitError) and not deadline.passed():
            raise
        limit = deadline.seconds or 0.0
        raise TimeLimitError(f"no plan within --time-limit {limit:g} s: {_took(times)}", limit) from None


def _took(times: StageTimes) -> str:
    spent = {k: v for k, v in times.seconds.items() if k != "total"}
    if not spent:
        return "the run took the time before its first stage ended"
    stage = max(spent, key=lambda k: spent[k])
    others = ", ".join(f"{k} {v:.1f} s" for k, v in spent.items() if k != stage)
    return f"the {stage} stage took the time ({spent[stage]:.1f} s{'; ' + others if others else ''})"


def _within(scenario: Scenario, deadline: Deadline) -> Scenario:
    """The scenario as the task stage runs it: an exact search's ENHSP run (planner.timeout) ends
    by the time limit at the latest."""
    left = deadline.left()
    if not math.isfinite(left):
        return scenario
    timeout = max(0.1, min(scenario.planner.timeout, left))
    return replace(scenario, planner=replace(scenario.planner, timeout=timeout))


def _origins(overrides: Overrides, prep: Prepared) -> dict[str, Origin]:
    """A replan's origins (Overrides.origins) on the roadmap it grew from, for the robots it plans."""
    from tmpnav.oracle.table import origins

    base = overrides.roadmap_base
    if base is None or prep.roadmap.grown != base.fingerprint:
        return {}
    names = {r.name for r in prep.scenario.robots}
    return origins(tuple(r for r in overrides.origins if r.name in names and r.name in base.starts), prep.world, base)


def _keep_scans(prep: Prepared) -> None:
    """Store the range sensor's scan information this run computed, for the next (tmpnav.roadmap.store)."""
    from tmpnav.roadmap.store import RoadmapStore, ScanStore

    sensor = prep.scenario.models.range_sensor
    if prep.cache is not None and sensor is not None:
        ScanStore(prep.cache, RoadmapStore(prep.cache)).save(prep.world, sensor)


#: re-plans at the threshold the plan of least risk meets, before tmpnav names it (each under
#: it: the named threshold is one that a plan was found for)
RISK_RETRIES = 3


def check_risk(path: str | Path, options: PlanOptions, report: PlanReport) -> None:
    """Raise RiskError when a move of ``report``'s plan exceeds the chance constraint: the
    planner found no plan within it (a move over it costs more than any plan within it,
    tmpnav.types.RISK_PENALTY). The error names the least threshold tmpnav found a plan for:
    the plan's largest move bound, rounded up, verified by planning at it (the plan found
    there is remembered, so that the rerun the message suggests takes no search)."""
    delta = report.scenario.planner.max_risk
    worst = report.worst_risk
    if delta is None or worst <= delta:
        return
    asked = delta
    limit = report.scenario.planner.time_limit
    for _ in range(RISK_RETRIES):
        least = min(1.0, _round_up(worst))
        left = None if limit is None else limit - (time.perf_counter() - report.times.started)
        if least >= 1.0 or (left is not None and left <= 0.0):
            break  # no least threshold found within the run's --time-limit: the plain error
        try:
            again = _planned(path, options.but(max_risk=least, replan=False, time_limit=left), None)
        except TimeLimitError:
            break
        worst = again.worst_risk
        if worst <= least:
            from tmpnav.planning.safety import conflicts_left, speck_hint

            apart = again.scenario.planner.keep_apart and conflicts_left(again, drift=0.0)
            raise RiskError(
                f"no plan keeps every move's collision bound within max_risk {asked:g}: the least "
                f"tmpnav found is {least:g} (rerun with --max-risk {least:g}, or set planner.max_risk"
                + ("; its plan leaves robots in each other's way: add --accept-risk to take it)" if apart else ")")
                + speck_hint(report),
                least,
            )
    from tmpnav.planning.safety import speck_hint

    raise RiskError(
        f"no plan keeps every move's collision bound within max_risk {asked:g} "
        f"({report.scenario.planner.max_risk_from or 'planner.max_risk'}): {_worst_move(report)} "
        "(--accept-risk takes the plan as it is)" + speck_hint(report),
        1.0,
    )


def _worst_move(report: PlanReport) -> str:
    """The plan's riskiest move, where its bound is made, and what would help there, in words."""
    from tmpnav.planning.safety import riskiest_point, what_would_help

    point = riskiest_point(report)
    return "every plan has a move at 1" if point is None else what_would_help(report, point)


def _round_up(p: float) -> float:
    """``p`` rounded up to two significant digits."""
    if p <= 0.0:
        return 0.0
    scale = 10.0 ** (math.floor(math.log10(p)) - 1)
    return math.ceil(p / scale - 1e-9) * scale


def pddl_texts(report: PlanReport) -> tuple[str, str]:
    """The PDDL domain and problem behind a report's plan (encoded again when the planner's
    own problem is not at hand: a remembered plan, a search over sub-problems)."""
    from tmpnav.task.export import pddl_texts as texts
    from tmpnav.task.stage import TaskProblem

    if report.task.pddl is not None:
        return report.task.pddl()
    return texts(TaskProblem.of(report.scenario, report.table).encode())


def _cache_use(prep: Prepared, plan_hit: bool, enabled: bool) -> CacheUse:
    stats = prep.oracle.stats
    return CacheUse(
        enabled=enabled,
        directory=prep.cache.root if prep.cache is not None else None,
        hits=stats.cache_hits,
        misses=stats.cache_misses,
        roadmap_hit=prep.roadmap_hit,
        table_hit=stats.table_hit,
        plan_hit=plan_hit,
        warnings=(*prep.roadmap_warnings, *prep.oracle.cache.stats.warnings),
    )
