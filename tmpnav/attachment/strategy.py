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

from dataclasses import dataclass

from tmpnav.attachment.canonical import CanonicalCosts
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.unfold import unfold
from tmpnav.errors import InputError
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import build_table, start_locations
from tmpnav.results import StageTimes, TaskResult
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.memo import EntryStore
from tmpnav.task.modes import exact_fits
from tmpnav.task.plans import Plan, Rules
from tmpnav.task.search import Progress
from tmpnav.task.stage import TaskProblem, plan_anytime, plan_task, plan_unfolded
from tmpnav.types import CostTable, Scenario
from tmpnav.world import World


@dataclass(frozen=True)
class Planned:
    """The task stage's result and the costs behind it."""

    table: CostTable  # the table costs the planner saw (the lazily computed ones for anytime)
    task: TaskResult


def search_mode(scenario: Scenario) -> str:
    """``exact`` or ``anytime``: the scenario's choice, or for ``auto`` exact where it fits."""
    sp = scenario.planner
    if sp.encoding == "paper":
        if sp.search == "anytime" or sp.costs == "carried":
            raise InputError(
                "the paper's encoding is planned exactly with table costs only; "
                "use --encoding mixed for --search anytime or --costs carried"
            )
        return "exact"
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
    sp, goals, oracle = scenario.planner, scenario.goals, canonical.oracle
    mode = search_mode(scenario)
    if mode == "exact" and sp.costs == "table":
        table = full_table(scenario, world, oracle, times)
        return Planned(table, plan_task(TaskProblem.of(scenario, table), store, replan, times))
    if mode == "exact":
        with times.timed("oracle"):
            graph = unfold(carried, goals, sp.pair_min_gain)
        if graph is not None:
            locations = tuple(dict.fromkeys([*goals.all_rooms, *canonical.start_location.values()]))
            rules = Rules(canonical.start_location, goals)
            task = plan_unfolded(graph, canonical.robots, locations, rules, sp, times)
            return Planned(canonical.seen(), task)
        if sp.search == "exact":
            raise InputError(
                f"the belief space of {len(goals.all_rooms)} goal rooms and {len(scenario.robots)} robots is too "
                "large to unfold; plan it with --search anytime (or auto)"
            )
    seeds: dict[str, Plan] = {}
    if sp.costs == "carried" and exact_fits(len(goals.all_rooms), len(scenario.robots), "table"):
        table = full_table(scenario, world, oracle, times)
        exact = plan_task(TaskProblem.of(scenario, table), store, replan, times)
        seeds["the exact plan of the cost table"] = exact.steps
    model = carried if sp.costs == "carried" else canonical
    bound = (lambda: canonical.bound_table(goals)) if sp.costs == "table" else None
    task = plan_anytime(model, goals, sp, bound, times, progress, costs=sp.costs, seeds=seeds)
    return Planned(canonical.seen(), task)
