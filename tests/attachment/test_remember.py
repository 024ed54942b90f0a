"""Remembered search plans: a warm run reads them; a damaged entry is a miss, never a wrong plan."""

from __future__ import annotations

from pathlib import Path

import pytest

from tmpnav.attachment.remember import search_key
from tmpnav.oracle.cache import DiskCache
from tmpnav.oracle.keys import context_digest
from tmpnav.pipeline import PlanOptions, plan

ROOT = Path(__file__).resolve().parents[2]
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


def moves(report) -> list:
    return [(a.moves, a.goal_nodes, a.planner_cost) for a in report.actions]


@pytest.mark.slow
@pytest.mark.parametrize("search", ["exact", "anytime"])
def test_a_warm_run_reads_the_plan_and_a_damaged_entry_is_a_miss(search: str, tmp_path: Path) -> None:
    options = PlanOptions(cache_dir=tmp_path, executor="serial", search=search)
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
