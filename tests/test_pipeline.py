"""The pipeline's start: what it tells the caller before the roadmap stage."""

from __future__ import annotations

from pathlib import Path

from tmpnav.pipeline import PlanOptions, prepare
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
