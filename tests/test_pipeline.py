"""The pipeline's start: what it tells the caller before the roadmap stage."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tmpnav.pipeline import PlanOptions, load_world, prepare, warm_site
from tmpnav.results import StageTimes
from tmpnav.types import Scenario

ROOT = Path(__file__).resolve().parents[1]


def test_the_caller_learns_before_the_roadmap_whether_it_is_stored(tmp_path: Path) -> None:
    """The plan command readies ENHSP's JVM beside the roadmap's growth only when the roadmap
    is to be grown: a warm command, whose plan is then often remembered, starts no JVM."""
    told: list[bool] = []

    def loaded(_: Scenario, stored: bool) -> None:
        told.append(stored)

    options = PlanOptions.of(cache_dir=tmp_path)
    for _ in range(2):
        prepare(ROOT / "configs" / "corridor.yaml", options, StageTimes(), on_loaded=loaded).oracle.close()
    assert told == [False, True]


def test_a_served_site_warms_its_paths_from_a_stored_roadmap_only(tmp_path: Path, monkeypatch: Any) -> None:
    """``tmpnav serve`` computes a site's shortest-path trees and motion floors ahead of its first
    request (tmpnav.pipeline.warm_site): from the roadmap in the cache, never growing one."""
    from tmpnav.roadmap import graph

    monkeypatch.setattr(graph, "_SHARED", graph._Shared(graph.SHARED_BYTES))
    options = PlanOptions.of(cache_dir=tmp_path)
    scenario, world = load_world(ROOT / "configs" / "corridor.yaml", options.overrides)
    assert not warm_site(scenario, world, options)  # nothing stored: nothing grown
    assert not graph._SHARED.items
    prepare(ROOT / "configs" / "corridor.yaml", options, StageTimes()).oracle.close()  # grows and stores it
    assert warm_site(scenario, world, options)
    kinds = {key[0] for key in graph._SHARED.items}
    assert kinds == {"tree", "derived", "memo"}
