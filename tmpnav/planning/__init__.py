"""Stage 6 as the pipeline runs it: the registry of task planners, one per search and costs.

=================  ======================================================================
``--costs table``  ``exact``: every cost of the table first, one optimal ENHSP search
                   (:mod:`~tmpnav.planning.exact`); ``anytime``: the large-neighbourhood
                   search on lazily computed costs, with the certified lower bound of the
                   table (:mod:`~tmpnav.planning.anytime`).
``--costs carried`` ``exact``: the belief space unfolded and searched by ENHSP
                   (:mod:`~tmpnav.planning.unfolded`); ``anytime``: the same search as above,
                   every plan costed with carried-over beliefs
                   (:mod:`~tmpnav.planning.anytime`).
=================  ======================================================================

Which one runs is :func:`tmpnav.choices.choose`'s decision (the one rule); :data:`PLANNERS`
maps it to the function that plans it, every one with the same signature (a :class:`TaskRun`
in, a :class:`Planned` out), as pyperplan's ``SEARCHES`` table does. A new search is one
module with such a function and one line here. The algorithms themselves are in
:mod:`tmpnav.task` (searches over tables and cost models) and :mod:`tmpnav.attachment` (the
cost models on the oracle); this package only joins them for a run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from tmpnav.choices import Costs, SearchMode
from tmpnav.errors import InputError
from tmpnav.planning.anytime import anytime_carried, anytime_table
from tmpnav.planning.exact import exact_table
from tmpnav.planning.remember import recall, remember, search_key
from tmpnav.planning.run import Planned, TaskRun, choice_for, span_weight_of
from tmpnav.planning.unfolded import exact_carried
from tmpnav.planning.windows import check_arrivals, check_windows
from tmpnav.task.solve import engine_class, reads_pddl_text
from tmpnav.task.stage import warm_up_searches
from tmpnav.types import Scenario

#: a task planner: the run in, its plan and the costs it saw out
TaskPlanner = Callable[[TaskRun], Planned]


@dataclass(frozen=True)
class PlannerEntry:
    """A task planner and what the stage does around it."""

    plan: TaskPlanner
    #: its plan is remembered under the run's search key (tmpnav.planning.remember); the exact
    #: search with table costs remembers its own, by the PDDL problem (tmpnav.task.memo)
    remembered: bool
    #: it gives ENHSP tmpnav's own PDDL text, so the planner must be an ENHSP engine
    enhsp_only: bool


PLANNERS: dict[tuple[SearchMode, Costs], PlannerEntry] = {
    ("exact", "table"): PlannerEntry(exact_table, remembered=False, enhsp_only=False),
    ("exact", "carried"): PlannerEntry(exact_carried, remembered=True, enhsp_only=True),
    ("anytime", "table"): PlannerEntry(anytime_table, remembered=True, enhsp_only=True),
    ("anytime", "carried"): PlannerEntry(anytime_carried, remembered=True, enhsp_only=True),
}


def plan_stage(run: TaskRun) -> Planned:
    """The task plan of ``run``: remembered, or planned by the entry of :data:`PLANNERS` that
    the run's choice names (and then remembered)."""
    entry = PLANNERS[(run.choice.mode, run.choice.costs)]
    if entry.enhsp_only:
        _check_engine(run.planner.name)
    check_windows(run)
    planned = _planned(run, entry)
    check_arrivals(run, planned.task.schedule)
    return planned


def _planned(run: TaskRun, entry: PlannerEntry) -> Planned:
    if not entry.remembered:
        return entry.plan(run)
    key = search_key(run.scenario, run.canonical.oracle.context)
    model = run.carried if run.choice.costs == "carried" else run.canonical
    if run.store is not None and not run.replan:
        with run.times.timed("planner"):
            found = recall(run.store, key, model, run.goals, run.work, run.span_weight)
        if found is not None:
            return Planned(run.canonical.seen(), found)
    planned = entry.plan(run)
    if run.store is not None:
        remember(run.store, key, planned.task, run.work)
    return planned


def _check_engine(planner: str) -> None:
    """The searches that write tmpnav's own PDDL text need an ENHSP engine (an unknown name is
    the planner's error, exit code 4)."""
    if not reads_pddl_text(planner):
        engine_class(planner)  # raises PlannerUnavailableError for a name unified-planning does not know
        raise InputError(
            f"planner {planner!r} is not an ENHSP engine; the anytime search and carried costs run ENHSP "
            "(enhsp-blind, enhsp-opt, enhsp): use one of them, or --costs table --search exact for other engines"
        )


__all__ = ["PLANNERS", "Planned", "PlannerEntry", "TaskPlanner", "TaskRun", "plan_stage"]


def get_ready(scenario: Scenario) -> None:
    """Start ENHSP's searches for a run that will need them, as soon as its scenario is known:
    when :func:`tmpnav.choices.choose` picks the anytime search, ENHSP's server starts and
    makes its searches ready (:func:`tmpnav.task.stage.warm_up_searches`) while the run
    builds its world and roadmap, opens its oracle and computes its first costs, instead of
    from its first plan on (a fresh 10-room `tmpnav plan`: the JVM's start, two slots of
    ENHSP's classes and their first searches, about 0.8 s of the JVM's work, out of the way
    of the searches). A run that then finds its plan in the cache leaves the server idle."""
    sp = scenario.planner
    if choice_for(scenario).mode == "anytime":
        warm_up_searches(sp.name, sp.encoding, span_weight_of(scenario), sp.pair_min_gain)
