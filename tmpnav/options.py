"""What a run is asked for: the command line's overrides of the scenario, where its costs are kept
and computed, who is told how it goes; and the scenario those overrides put in force
(:func:`apply_options`), its plan's size checked against the caps."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import cast

from tmpnav import scenario as scenario_stage
from tmpnav.choices import Costs, Objective, Search, choose, paper_conflict
from tmpnav.errors import InputError, Problem, ScenarioError
from tmpnav.results import SearchProgress
from tmpnav.types import DEFAULT_RISK_SOURCE, FLEET_DEFAULT, SAFE_MARGIN, Goals, Roadmap, RobotSpec, Scenario


@dataclass(frozen=True)
class Overrides:
    """Command-line choices that override the scenario's (None: the scenario's own)."""

    encoding: str | None = None
    planner: str | None = None
    timeout: float | None = None
    pair_min_gain: float | None = None
    mutual_observations: bool | None = None
    range_sensor: bool | None = None  # False: plan without the scenario's range sensor (the paper's model)
    goals: Goals | None = None
    search: Search | None = None
    time_budget: float | None = None
    work_budget: int | None = None
    routing_time: float | None = None
    time_limit: float | None = None
    costs: Costs | None = None
    objective: Objective | None = None
    min_rooms: int | None = None
    max_risk: float | None = None
    keep_apart: bool | None = None
    clearance: float | None = None  # m: roadmap.clearance
    accept_risk: bool = False  # hand out a plan that breaks the chance constraint or leaves robots in the way
    #: a plan to start the anytime search from, as steps of (robot, target room): the rest of the
    #: plan being executed, when ``tmpnav replan`` revises it (tmpnav.replan)
    incumbent: tuple[tuple[tuple[str, str], ...], ...] = ()
    #: the roadmap of the plan being revised, when the world is unchanged: the revision's starts
    #: are added to it (tmpnav.roadmap.with_starts) instead of growing a roadmap of its own
    roadmap_base: Roadmap | None = None
    #: the robots as the plan being revised started, with ``roadmap_base``: the revision's cost
    #: table reaches the rooms' canonical states from there, as that plan's table did, and reads
    #: its moves between rooms from the cache (tmpnav.oracle.table.Origin)
    origins: tuple[RobotSpec, ...] = ()


#: ``Overrides.max_risk`` that lifts the chance constraint (``--max-risk none``)
NO_THRESHOLD = -1.0


@dataclass(frozen=True)
class Execution:
    """Where a run keeps and computes its costs: the cache directory, the oracle's executor."""

    cache_dir: Path | None = None  # None: the default cache directory (tmpnav.cachedir)
    use_cache: bool = True
    replan: bool = False  # run the task planner even when the cache remembers its plan
    executor: str = "processes"
    workers: int | None = None
    ray_address: str | None = None


@dataclass(frozen=True)
class Reporters:
    """Who is told how a run goes."""

    oracle: Callable[[int, int], None] | None = None  # (requests done, requests in all)
    search: SearchProgress | None = None  # the anytime search's progress


@dataclass(frozen=True)
class PlanOptions:
    """How to plan: the scenario's overrides, where costs are kept and computed, who is told."""

    overrides: Overrides = Overrides()
    execution: Execution = Execution()
    reporters: Reporters = Reporters()

    @classmethod
    def of(cls, **keywords: object) -> PlanOptions:
        """The options from flat keywords, each the name of a field of :class:`Overrides`,
        :class:`Execution` or :class:`Reporters` (``progress`` and ``search_progress`` name the
        reporters): ``PlanOptions.of(costs="table", use_cache=False)``."""
        return cls().but(**keywords)

    def but(self, **keywords: object) -> PlanOptions:
        """These options with the fields that ``keywords`` name (as in :meth:`of`) changed."""
        # the reporters by their own names first: "search" also names an override
        reporters = self.reporters
        if "progress" in keywords:
            reporters = replace(reporters, oracle=cast("Callable[[int, int], None] | None", keywords.pop("progress")))
        if "search_progress" in keywords:
            reporters = replace(reporters, search=cast("SearchProgress | None", keywords.pop("search_progress")))
        parts = {}
        for name in ("overrides", "execution"):
            part = getattr(self, name)
            names = {f.name for f in fields(part)}
            parts[name] = replace(part, **{k: keywords.pop(k) for k in list(keywords) if k in names})
        parts["reporters"] = reporters
        if keywords:
            raise TypeError(f"unknown plan options: {', '.join(sorted(keywords))}")
        return PlanOptions(**parts)


def apply_options(scenario: Scenario, overrides: Overrides) -> Scenario:
    """The scenario with the command line's overrides (InputError for choices that conflict)."""
    o, planner = overrides, scenario.planner
    planner = replace(
        planner,
        encoding=o.encoding or planner.encoding,
        name=o.planner or planner.name,
        timeout=o.timeout if o.timeout is not None else planner.timeout,
        pair_min_gain=o.pair_min_gain if o.pair_min_gain is not None else planner.pair_min_gain,
        search=o.search or planner.search,
        time_budget=o.time_budget if o.time_budget is not None else planner.time_budget,
        work_budget=o.work_budget if o.work_budget is not None else planner.work_budget,
        routing_time=o.routing_time if o.routing_time is not None else planner.routing_time,
        time_limit=o.time_limit if o.time_limit is not None else planner.time_limit,
        costs=o.costs or planner.costs,
        objective=o.objective or planner.objective,
        min_rooms=o.min_rooms if o.min_rooms is not None else planner.min_rooms,
        min_rooms_from=planner.min_rooms_from if o.min_rooms is None else "--min-rooms" if o.min_rooms else "",
        max_risk=planner.max_risk if o.max_risk is None else None if o.max_risk == NO_THRESHOLD else o.max_risk,
        max_risk_from=planner.max_risk_from
        if o.max_risk is None
        else ""
        if o.max_risk == NO_THRESHOLD
        else "--max-risk",
        keep_apart=o.keep_apart if o.keep_apart is not None else planner.keep_apart,
    )
    if (why := paper_conflict(planner.encoding, o.search, o.costs, o.objective)) is not None:
        raise InputError(why)
    if (
        planner.min_rooms
        and planner.min_rooms_from == FLEET_DEFAULT
        and (planner.encoding == "paper" or planner.search == "exact")
    ):  # a fleet's default minimum gives way to a search asked for that does not keep one
        planner = replace(planner, min_rooms=0, min_rooms_from="")
    if planner.min_rooms and (planner.encoding == "paper" or planner.search == "exact"):
        raise InputError(
            f"planner.min_rooms {planner.min_rooms} needs the anytime search, which keeps it; the "
            + ("paper's encoding" if planner.encoding == "paper" else "exact search")
            + " does not: use --search anytime (or auto) with the mixed or single encoding, or --min-rooms 0"
        )
    if planner.encoding == "paper":  # the paper's model, as tmpnav.choices.choose plans it
        choice = choose(planner.encoding, planner.search, planner.costs, 0, 0)
        planner = replace(
            planner,
            costs=choice.costs,
            search=choice.mode,
            objective="cost",
            max_risk=None,
            max_risk_from="",
            keep_apart=False,
        )
    models = scenario.models
    if planner.encoding == "paper" and models.controller == "auto":  # the paper's robots turn, then drive
        models = replace(models, controller="turn-then-drive")
    if o.mutual_observations is not None:
        models = replace(models, mutual_observations=o.mutual_observations)
    if o.range_sensor is False:
        models = replace(models, range_sensor=None)
        if planner.max_risk_from == DEFAULT_RISK_SOURCE:  # the paper's model: no threshold by default
            planner = replace(planner, max_risk=None, max_risk_from="")
    if o.goals is not None and (unknown := [g for g in o.goals.all_rooms if g not in {r.name for r in scenario.rooms}]):
        raise InputError(f"goal rooms {', '.join(unknown)} are not rooms of scenario {scenario.name!r}")
    clearance = o.clearance if o.clearance is not None else scenario.roadmap.clearance
    if planner.encoding == "paper":
        clearance = 0.0
    elif clearance is None:  # robots that see the walls, or plan within a threshold, keep clear of walls
        clearance = SAFE_MARGIN if models.range_sensor is not None or planner.max_risk is not None else 0.0
    roadmap = replace(scenario.roadmap, clearance=clearance)
    return replace(scenario, planner=planner, models=models, goals=o.goals or scenario.goals, roadmap=roadmap)


def in_force(scenario: Scenario, overrides: Overrides) -> Scenario:
    """A scenario loaded earlier, with ``overrides`` applied and its plan sizes checked."""
    scenario = apply_options(scenario, overrides)
    if problems := size_problems(scenario):
        raise ScenarioError(problems)
    return scenario


def size_problems(scenario: Scenario) -> list[Problem]:
    """Goal rooms x robots and the cost table's estimated entries against their caps
    (tmpnav.scenario.limits)."""
    from tmpnav.scenario.extent import plan_sizes

    file = scenario_stage.display_path(scenario.source)
    return [Problem(file, p, message, scenario.line_of(p)) for p, message in plan_sizes(scenario)]
