"""Remembered search plans: a warm run reads them; a damaged entry is a miss, never a wrong plan."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from tmpnav.oracle.cache import DiskCache
from tmpnav.oracle.keys import context_digest
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.planning.remember import search_key
from tmpnav.scenario.load import load

ROOT = Path(__file__).resolve().parents[2]
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


def moves(report) -> list:
    return [(a.moves, a.goal_nodes, a.planner_cost) for a in report.actions]


@pytest.mark.slow
@pytest.mark.parametrize("search", ["exact", "anytime"])
def test_a_warm_run_reads_the_plan_and_a_damaged_entry_is_a_miss(search: str, tmp_path: Path) -> None:
    options = PlanOptions.of(cache_dir=tmp_path, executor="serial", search=search)
    cold = plan(TWO_ROOMS, options)
    warm = plan(TWO_ROOMS, options)
    assert not cold.task.plan_hit and warm.task.plan_hit
    assert moves(warm) == moves(cold) and warm.task.search == cold.task.search
    key = search_key(cold.scenario, context_digest(cold.scenario, cold.world, cold.roadmap))
    cache = DiskCache(tmp_path)
    try:
        assert key in cache.get_many([key])
        cache.put_many({key: {"steps": "not a plan"}})
    finally:
        cache.close()
    again = plan(TWO_ROOMS, options)
    assert not again.task.plan_hit and moves(again) == moves(cold)


@pytest.mark.slow
def test_a_plan_cut_short_by_its_work_budget_is_read_again_only_with_the_same_budget(tmp_path: Path) -> None:
    options = PlanOptions.of(cache_dir=tmp_path, executor="serial", search="anytime", work_budget=5)
    cold = plan(TWO_ROOMS, options)
    key = search_key(cold.scenario, context_digest(cold.scenario, cold.world, cold.roadmap))
    cache = DiskCache(tmp_path)
    try:
        entry = cache.get_many([key])[key]
        assert entry["work"] == 5
        # as if the search had been cut short: a plan that depends on the budget
        cache.put_many({key: {**entry, "search": {**entry["search"], "stopped": "work budget"}}})
    finally:
        cache.close()
    assert plan(TWO_ROOMS, options).task.plan_hit
    again = plan(TWO_ROOMS, options.but(work_budget=4))
    assert not again.task.plan_hit and moves(again) == moves(cold)
    # that search converged after fewer sub-problems than a larger budget allows: the same plan
    assert again.task.search.stopped == "converged"
    assert plan(TWO_ROOMS, options.but(work_budget=50)).task.plan_hit


@pytest.mark.slow
def test_a_plan_a_time_cap_cut_short_is_not_remembered(tmp_path: Path) -> None:
    options = PlanOptions.of(cache_dir=tmp_path, executor="serial", search="anytime", time_budget=1e-3)
    cold = plan(TWO_ROOMS, options)
    assert "the search's time cap" in cold.task.search.capped
    assert not plan(TWO_ROOMS, options).task.plan_hit


def test_the_key_names_the_clock_drift_the_search_prices_plans_with() -> None:
    scenario = load(TWO_ROOMS)
    drifting = replace(scenario, planner=replace(scenario.planner, clock_drift=0.1))
    assert search_key(scenario, "context") != search_key(drifting, "context")
    on_time = replace(scenario, planner=replace(scenario.planner, clock_drift=0.0))
    assert search_key(scenario, "context") == search_key(on_time, "context")  # no AMCL: 0 by default
