"""The one value a task planner works with: :class:`TaskRun`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from tmpnav.attachment.canonical import CanonicalCosts
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.choices import TaskChoice, choose, time_budget, work_budget
from tmpnav.results import StageTimes, TaskResult
from tmpnav.task.memo import EntryStore
from tmpnav.task.objectives import OBJECTIVES
from tmpnav.task.search_run import SearchRun
from tmpnav.types import CostTable, Goals, PlannerOptions, Scenario
from tmpnav.world import World

if TYPE_CHECKING:
    from tmpnav.oracle.oracle import Oracle
    from tmpnav.oracle.table import Origin


@dataclass(frozen=True)
class TaskRun:
    """A run's task stage: the scenario in force, the search and costs chosen for it, the cost
    models on its oracle, where plans are remembered, and the run's clock and progress."""

    scenario: Scenario
    world: World
    choice: TaskChoice
    canonical: CanonicalCosts  # costs from canonical start states, computed as asked
    carried: CarriedCosts  # costs from the beliefs the robots carry (the re-simulation's too)
    store: EntryStore | None  # the cost database, which remembers task plans; None: --no-cache
    replan: bool  # search again even when the store remembers the plan
    search: SearchRun  # the run's clock (its stage times) and who is told of the search's progress
    #: a plan the anytime search starts from besides its own first plans, as steps of (robot,
    #: target): the rest of the plan being executed, for a replan (tmpnav.replan)
    incumbent: tuple[tuple[tuple[str, str], ...], ...] = ()

    @classmethod
    def of(
        cls,
        scenario: Scenario,
        world: World,
        oracle: Oracle,
        store: EntryStore | None,
        replan: bool,
        search: SearchRun,
        origin: Mapping[str, Origin] | None = None,
    ) -> TaskRun:
        """The task stage of a run whose oracle is open: its cost models on that oracle
        (``origin``: a replan's, tmpnav.oracle.table.origins)."""
        canonical = CanonicalCosts(oracle, world, scenario.planner.pair_min_gain, origin)
        choice = choice_for(scenario)
        return cls(scenario, world, choice, canonical, CarriedCosts(oracle, canonical), store, replan, search)

    @property
    def goals(self) -> Goals:
        return self.scenario.goals

    @property
    def planner(self) -> PlannerOptions:
        return self.scenario.planner

    @property
    def times(self) -> StageTimes:
        return self.search.times

    @property
    def span_weight(self) -> float:
        """The objective's price of a second of makespan (tmpnav.task.objectives)."""
        return span_weight_of(self.scenario)

    @property
    def budget(self) -> float:
        """The run's time cap for the anytime search (the whole run counts against it; inf: none)."""
        return time_budget(self.planner.time_budget)

    @property
    def work(self) -> int:
        """The anytime search's budget in work: the ENHSP sub-problems it may solve."""
        return work_budget(len(self.goals.all_rooms), len(self.scenario.robots), self.planner.work_budget)

    def left(self) -> float:
        """Seconds of the time cap not yet spent by the run's stages, and of the run's time limit
        less what the stages after the search keep of it (Deadline.after_search)."""
        deadline = self.search.deadline
        kept = deadline.after_search(len(self.goals.all_rooms))
        return min(self.budget - self.times.spent(), deadline.left() - kept)


@dataclass(frozen=True)
class Planned:
    """The task stage's result and the costs behind it."""

    table: CostTable  # the table costs the planner saw (the lazily computed ones for anytime)
    task: TaskResult


def choice_for(scenario: Scenario) -> TaskChoice:
    """The search and costs :func:`tmpnav.choices.choose` picks for the scenario."""
    sp = scenario.planner
    return choose(sp.encoding, sp.search, sp.costs, len(scenario.goals.all_rooms), len(scenario.robots), sp.min_rooms)


def span_weight_of(scenario: Scenario) -> float:
    """The scenario's objective's price of a second of makespan (tmpnav.task.objectives)."""
    return OBJECTIVES[scenario.planner.objective].span_weight(scenario.cost)
