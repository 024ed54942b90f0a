"""PlanOptions from flat keywords: every keyword lands where it belongs."""

from __future__ import annotations

import pytest

from tmpnav.pipeline import PlanOptions


def test_the_search_reporter_and_the_search_override_are_told_apart() -> None:
    def told(*_: object) -> None:
        return None

    options = PlanOptions.of(search_progress=told, search="anytime", progress=told, max_risk=0.1, use_cache=False)
    assert options.reporters.search is told and options.reporters.oracle is told
    assert options.overrides.search == "anytime" and options.overrides.max_risk == 0.1
    assert options.execution.use_cache is False
    assert options.but(search="exact").reporters.search is told


def test_an_unknown_keyword_is_refused() -> None:
    with pytest.raises(TypeError, match="unknown plan options: colour"):
        PlanOptions.of(colour="red")


def test_the_routing_time_reaches_the_searchs_first_routes() -> None:
    """--routing-time (planner.routing_time) overrides the scenario's and is OR-Tools' limit."""
    from dataclasses import replace

    from tmpnav.options import apply_options
    from tmpnav.scenario import load
    from tmpnav.task.model import TableModel
    from tmpnav.task.stage import AnytimeTask
    from tmpnav.types import CostTable, Goals

    scenario = load("configs/corridor.yaml")
    scenario = replace(scenario, planner=replace(scenario.planner, routing_time=5.0))
    options = PlanOptions.of(routing_time=120.0)
    assert apply_options(scenario, options.overrides).planner.routing_time == 120.0
    assert apply_options(scenario, PlanOptions.of().overrides).planner.routing_time == 5.0
    task = AnytimeTask(TableModel(CostTable((), (), (), {}, {}, {})), Goals(visit=(), per_robot=()), scenario.planner)
    assert task.options(60.0).routing_time == 5.0
