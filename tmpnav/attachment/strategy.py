"""Stage 6 as the pipeline runs it: which task search, on which costs, from which start.

=================  ========================================================================
``--costs table``  ``exact``: every cost of the table first, one optimal ENHSP search
                   (:func:`tmpnav.task.stage.plan_task`); ``anytime``: the large-neighbourhood
                   search on lazily computed costs, with the certified lower bound of the
                   table (:func:`tmpnav.task.stage.plan_anytime`).
``--costs carried`` ``exact``: the belief space unfolded and searched by ENHSP
                   (:mod:`tmpnav.attachment.unfold`, :func:`tmpnav.task.stage.plan_unfolded`);
                   ``anytime``: the same search as above, every plan costed with carried-over
                   beliefs, started from the cheapest of OR-Tools' routes and (where it is
                   quick) the exact plan of the cost table.
=================  ========================================================================

``auto`` picks ``exact`` where it finishes quickly (:func:`tmpnav.task.modes.exact_fits`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from tmpnav.attachment.canonical import CanonicalCosts
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.floors import motion_floors
from tmpnav.attachment.remember import recall, remember, search_key
from tmpnav.attachment.unfold import unfold
from tmpnav.errors import InputError
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import build_table, start_locations
from tmpnav.results import StageTimes, TaskResult
from tmpnav.task.bound import Bound, lower_bound
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.memo import EntryStore
from tmpnav.task.modes import exact_fits, time_budget
from tmpnav.task.plans import Plan, Rules
from tmpnav.task.search import Progress
from tmpnav.task.solve import engine_class, reads_pddl_text
from tmpnav.task.stage import TaskProblem, plan_anytime, plan_task, plan_unfolded
from tmpnav.types import CostTable, Scenario
from tmpnav.world import World

#: paired moves beyond which the bound of the table gives way to the motion floors: bounding
#: each pair without joint simulation takes about 0.2 ms (20 rooms and 2 robots: 130,000 pairs)
MAX_BOUND_PAIRS = 25_000


@dataclass(frozen=True)
class Planned:
    """The task stage's result and the costs behind it."""

    table: CostTable  # the table costs the planner saw (the lazily computed ones for anytime)
    task: TaskResult


def search_mode(scenario: Scenario) -> str:
    """``exact`` or ``anytime``: the scenario's choice, or for ``auto`` exact where it fits."""
    sp = scenario.planner
    if sp.encoding == "paper":
        return "exact"  # with table costs (tmpnav.pipeline.apply_options)
    if sp.search != "auto":
        return sp.search
    fits = exact_fits(len(scenario.goals.all_rooms), len(scenario.robots), sp.costs)
    return "exact" if fits else "anytime"


def full_table(scenario: Scenario, world: World, oracle: Oracle, times: StageTimes) -> CostTable:
    """Every cost the encoding may need, before the exact planner runs (stage ``oracle``)."""
    with times.timed("oracle"):
        sp = scenario.planner
        want = ENCODINGS[sp.encoding].table_request(scenario.goals, start_locations(scenario, world), sp.pair_min_gain)
        return build_table(
            oracle,
            world,
            want.destinations,
            want.pair_filter,
            filter_key=want.filter_key,
            pair_min_gain=want.pair_min_gain,
        )


def plan_scenario(
    scenario: Scenario,
    world: World,
    canonical: CanonicalCosts,
    carried: CarriedCosts,
    store: EntryStore | None,
    replan: bool,
    times: StageTimes,
    progress: Progress | None,
) -> Planned:
    """The task plan of ``scenario`` (see the module docstring)."""
    sp, oracle = scenario.planner, canonical.oracle
    mode = search_mode(scenario)
    if not (mode == "exact" and sp.costs == "table"):
        _check_engine(sp.name)
    if mode == "exact" and sp.costs == "table":
        table = full_table(scenario, world, oracle, times)
        return Planned(table, plan_task(TaskProblem.of(scenario, table), store, replan, times))
    run = _Run(scenario, world, canonical, carried, store, replan, times, progress)
    key = search_key(scenario, oracle.context)
    model = carried if sp.costs == "carried" else canonical
    if store is not None and not replan:
        with times.timed("planner"):
            found = recall(store, key, model, scenario.goals, run.budget)
        if found is not None:
            return Planned(canonical.seen(), found)
    task = _search(run, mode)
    if store is not None:
        remember(store, key, task, run.budget)
    return Planned(canonical.seen(), task)


@dataclass(frozen=True)
class _Run:
    """What a search of the task stage works with."""

    scenario: Scenario
    world: World
    canonical: CanonicalCosts
    carried: CarriedCosts
    store: EntryStore | None
    replan: bool
    times: StageTimes
    progress: Progress | None

    @property
    def budget(self) -> float:
        """The anytime search's time budget for the whole run."""
        sp, goals = self.scenario.planner, self.scenario.goals
        return time_budget(len(goals.all_rooms), len(self.scenario.robots), sp.time_budget)


def _search(run: _Run, mode: str) -> TaskResult:
    """The unfolded search (exact, carried costs) or the anytime search."""
    scenario, canonical, carried, times = run.scenario, run.canonical, run.carried, run.times
    sp, goals = scenario.planner, scenario.goals
    if mode == "exact":
        with times.timed("oracle"):
            graph = unfold(carried, goals, sp.pair_min_gain)
        if graph is not None:
            locations = tuple(dict.fromkeys([*goals.all_rooms, *canonical.start_location.values()]))
            rules = Rules(canonical.start_location, goals)
            return plan_unfolded(graph, canonical.robots, locations, rules, sp, times)
        if sp.search == "exact":
            raise InputError(
                f"the belief space of {len(goals.all_rooms)} goal rooms and {len(scenario.robots)} robots is too "
                "large to unfold; plan it with --search anytime (or auto)"
            )
    bound = lambda: certified_bound(scenario, canonical)  # noqa: E731
    if sp.costs == "table":
        return plan_anytime(canonical, goals, sp, bound, times, run.progress, "table")
    return _carried_anytime(run, bound)


def _carried_anytime(run: _Run, bound: Callable[[], Bound]) -> TaskResult:
    """The anytime search with carried costs, in two phases: first with table costs (each
    computed once and shared by every sub-problem) for up to half the budget, then with
    carried costs from the cheapest of its plan, OR-Tools' routes and (where quick) the
    exact plan of the table, every plan costed as executed."""
    scenario, times = run.scenario, run.times
    sp, goals = scenario.planner, scenario.goals
    seeds: dict[str, Plan] = {}
    if exact_fits(len(goals.all_rooms), len(scenario.robots), "table"):
        table = full_table(scenario, run.world, run.canonical.oracle, times)
        seeds["the exact plan of the cost table"] = plan_task(
            TaskProblem.of(scenario, table), run.store, run.replan, times
        ).steps
    left = run.budget - sum(v for k, v in times.seconds.items() if k not in ("load", "total"))
    labelled = _labelled(run.progress, "table costs")
    first = plan_anytime(run.canonical, goals, sp, None, times, labelled, "table", budget=left / 2)
    assert first.search is not None
    seeds["the anytime search's plan with table costs"] = first.steps
    task = plan_anytime(run.carried, goals, sp, bound, times, run.progress, "carried", seeds)
    assert task.search is not None
    search = replace(
        task.search,
        start=f"{task.search.start}; before it, the search with table costs: "
        f"{first.search.subproblems} sub-problems, stopped: {first.search.stopped}",
        subproblems=task.search.subproblems + first.search.subproblems,
    )
    return replace(task, search=search)


def _labelled(progress: Progress | None, label: str) -> Progress | None:
    if progress is None:
        return None
    report = progress

    def show(t: float, best: float, bound: float | None, what: str) -> None:
        report(t, best, bound, f"{what}; {label}")

    return show


def _check_engine(planner: str) -> None:
    """The unfolded and the anytime search give ENHSP tmpnav's own PDDL text: they need an
    ENHSP engine (an unknown name is the planner's error, exit code 4)."""
    if not reads_pddl_text(planner):
        engine_class(planner)  # raises PlannerUnavailableError for a name unified-planning does not know
        raise InputError(
            f"planner {planner!r} is not an ENHSP engine; the anytime search and carried costs run ENHSP "
            "(enhsp-blind, enhsp-opt, enhsp): use one of them, or --costs table --search exact for other engines"
        )


def certified_bound(scenario: Scenario, canonical: CanonicalCosts) -> Bound:
    """A lower bound on the cost of every plan of the anytime search's plan space.

    With table costs and at most :data:`MAX_BOUND_PAIRS` paired moves possible, the bound of
    the table with every pair at its cost or its lower bound (:func:`tmpnav.task.bound.lower_bound`);
    otherwise, and with carried costs (where a move's cost depends on the beliefs it starts
    from), the bound of the moves' motion floors (:mod:`tmpnav.attachment.floors`), which
    hold in every context and for every paired move."""
    sp, goals = scenario.planner, scenario.goals
    if sp.costs == "table":
        table = canonical.bound_table(goals, MAX_BOUND_PAIRS)
        if table is not None:
            if sp.encoding != "mixed":
                table = replace(table, pair={})
            return lower_bound(table, goals, sp.pair_min_gain)
    floors = motion_floors(scenario, canonical.oracle.ctx.roadmap, canonical.start_location, goals)
    bound = lower_bound(floors, goals, 0.0)
    return replace(bound, relaxation=f"motion floors, {bound.relaxation}")
