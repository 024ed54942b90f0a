"""Remembered search plans: a warm run reads them; a damaged entry is a miss, never a wrong plan."""

from __future__ import annotations

from pathlib import Path

import pytest

from tmpnav.oracle.cache import DiskCache
from tmpnav.oracle.keys import context_digest
from tmpnav.pipeline import PlanOptions, plan
from tmpnav.planning.remember import search_key

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
def test_a_plan_cut_short_by_its_budget_is_read_again_only_with_no_larger_budget(tmp_path: Path) -> None:
    options = PlanOptions.of(cache_dir=tmp_path, executor="serial", search="anytime", time_budget=5.0)
    cold = plan(TWO_ROOMS, options)
    key = search_key(cold.scenario, context_digest(cold.scenario, cold.world, cold.roadmap))
    cache = DiskCache(tmp_path)
    try:
        entry = cache.get_many([key])[key]
        assert entry["budget"] == 5.0
        # as if the search had been cut short: a plan that depends on the budget
        cache.put_many({key: {**entry, "search": {**entry["search"], "stopped": "time budget"}}})
    finally:
        cache.close()
    assert plan(TWO_ROOMS, options).task.plan_hit
    assert plan(TWO_ROOMS, options.but(time_budget=4.0)).task.plan_hit
    longer = plan(TWO_ROOMS, options.but(time_budget=50.0))
    assert not longer.task.plan_hit and moves(longer) == moves(cold)
