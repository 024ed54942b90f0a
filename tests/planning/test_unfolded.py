"""The exact search with carried costs when robots are kept apart (tmpnav.planning.unfolded)."""

from __future__ import annotations

from pathlib import Path

import pytest

import tmpnav


@pytest.mark.slow
def test_an_exact_plan_that_keeping_apart_makes_dearer_is_searched_on_as_executed(tmp_path: Path) -> None:
    """The paper's Fig. 2 swap: the unfolded search's optimum as planned is two single moves
    that pass through each other; kept apart, a detour makes it dearer than the paired move,
    which the anytime search, pricing every plan as executed, then takes."""
    plain = tmpnav.plan("configs/corridor.yaml", keep_apart=False, cache_dir=tmp_path)
    kept = tmpnav.plan("configs/corridor.yaml", cache_dir=tmp_path)
    assert [len(s.moves) for s in plain.steps] == [1, 1]
    assert plain.document()["search"]["mode"] == "exact"
    assert [len(s.moves) for s in kept.steps] == [2]
    search, bound = kept.document()["search"], kept.document()["bound"]
    assert search["mode"] == "anytime"
    # the exact optimum as planned bounds every plan as executed
    assert bound["value"] == pytest.approx(plain.objective[1], rel=1e-9)
    assert plain.objective[1] <= kept.objective[1] < 1.05 * plain.objective[1]
    assert kept.planner_cost == pytest.approx(kept.resimulated_cost, rel=1e-9)
    assert kept.conflicts == []
