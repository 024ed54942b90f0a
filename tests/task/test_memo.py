"""The remembered task plan: a warm run reuses it, and it never changes what is planned."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from tmpnav.oracle.cache import DiskCache
from tmpnav.pipeline import PlanOptions, pddl_texts, plan
from tmpnav.task.memo import entry_to_memo, memo_key, memo_to_entry, table_digest
from tmpnav.task.stage import TaskProblem
from tmpnav.types import Goals

ROOT = Path(__file__).resolve().parents[2]
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"

pytestmark = pytest.mark.slow


def summary(report) -> tuple:
    return (
        [(a.name, a.moves, a.paths, a.goal_nodes) for a in report.actions],
        report.planner_cost,
        report.resimulated_cost,
        report.status,
    )


def stored(cache_dir: Path, report) -> tuple[str, object]:
    """The memo key of ``report``'s task problem and the entry the cache holds for it."""
    key = TaskProblem.of(report.scenario, report.table).memo_key()
    cache = DiskCache(cache_dir)
    try:
        return key, cache.get_many([key])[key]
    finally:
        cache.close()


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory):
    cache = tmp_path_factory.mktemp("cache")
    # ENHSP's plans are remembered by their PDDL problem: the paper's objective, the exact search on a table
    options = PlanOptions.of(cache_dir=cache, executor="serial", costs="table", search="exact", objective="cost")
    cold = plan(TWO_ROOMS, options)
    warm = plan(TWO_ROOMS, options)
    replanned = plan(TWO_ROOMS, options.but(replan=True))
    uncached = plan(TWO_ROOMS, options.but(use_cache=False))
    return cache, cold, warm, replanned, uncached


def test_the_second_run_reads_the_plan_and_plans_the_same(runs) -> None:
    _, cold, warm, replanned, uncached = runs
    assert not cold.cache.plan_hit and warm.cache.plan_hit
    assert not replanned.cache.plan_hit and not uncached.cache.plan_hit
    assert warm.task.plan_hit and warm.task.pddl is None and warm.times.seconds["encode"] == 0.0
    assert summary(warm) == summary(cold) == summary(replanned) == summary(uncached)
    assert warm.task.counts == cold.task.counts


def test_pddl_of_a_remembered_plan_is_the_one_planned(runs) -> None:
    _, cold, warm, _, _ = runs
    assert pddl_texts(warm) == pddl_texts(cold)


def test_the_key_covers_goals_encoding_gain_planner_and_costs(runs) -> None:
    _, cold, _, _, _ = runs
    table, goals = cold.table, cold.scenario.goals
    base = memo_key(table, goals, "mixed", 0.05, "enhsp-blind", "two")
    others = {
        memo_key(table, Goals(visit=goals.visit[:1], per_robot=()), "mixed", 0.05, "enhsp-blind", "two"),
        memo_key(table, goals, "single", 0.05, "enhsp-blind", "two"),
        memo_key(table, goals, "mixed", 0.0, "enhsp-blind", "two"),
        memo_key(table, goals, "mixed", 0.05, "enhsp-opt", "two"),
        memo_key(table, goals, "mixed", 0.05, "enhsp-blind", "other"),
    }
    changed = dataclasses.replace(table, single={k: v * (1 + 1e-12) for k, v in table.single.items()})
    assert table_digest(changed) != table_digest(table)
    others.add(memo_key(changed, goals, "mixed", 0.05, "enhsp-blind", "two"))
    assert base not in others and len(others) == 6
    assert memo_key(table, goals, "mixed", 0.05, "enhsp-blind", "two") == base


@pytest.mark.parametrize(
    "damage",
    [
        lambda d: {**d, "steps": [[["r9", "L1", "L2"]]]},  # a move the cost table does not have
        lambda d: {**d, "steps": d["steps"][:-1]},  # steps and actions disagree
        lambda d: {**d, "status": "maybe"},
        lambda d: {"nothing": 1},
        lambda d: [1, 2, 3],
    ],
)
def test_an_entry_that_does_not_fit_is_a_miss(runs, damage) -> None:
    cache_dir, cold, _, _, _ = runs
    _, good = stored(cache_dir, cold)
    assert entry_to_memo(good, cold.table) is not None
    assert entry_to_memo(damage(good), cold.table) is None


def test_a_damaged_entry_makes_the_planner_run_again(tmp_path: Path) -> None:
    options = PlanOptions.of(cache_dir=tmp_path, executor="serial", costs="table", search="exact", objective="cost")
    first = plan(TWO_ROOMS, options)
    key, entry = stored(tmp_path, first)
    cache = DiskCache(tmp_path)
    try:
        cache.put_many({key: {**entry, "steps": [[["nobody", "nowhere", "L1"]]]}})
    finally:
        cache.close()
    again = plan(TWO_ROOMS, options)
    assert not again.cache.plan_hit
    assert summary(again) == summary(first)
    third = plan(TWO_ROOMS, options)  # the good plan was stored again
    assert third.cache.plan_hit and summary(third) == summary(first)


def test_round_trip_of_an_entry(runs) -> None:
    cache_dir, cold, _, _, _ = runs
    _, entry = stored(cache_dir, cold)
    memo = entry_to_memo(entry, cold.table)
    assert memo is not None and memo_to_entry(memo) == entry
