"""The pipeline: the only module that knows the order of the stages, and times each one.

    scenario -> world -> roadmap -> belief -> oracle -> task -> report
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from tmpnav import scenario as scenario_stage
from tmpnav import world as world_stage
from tmpnav.errors import ScenarioError
from tmpnav.types import Scenario, StageTimes
from tmpnav.world import MapImageError, World


@contextmanager
def timed(times: StageTimes, stage: str) -> Iterator[None]:
    start = time.perf_counter()
    try:
        yield
    finally:
        times.add(stage, time.perf_counter() - start)


def load_world(path: str | Path) -> tuple[Scenario, World]:
    """Stages 1-2 with every input problem reported at once (ScenarioError)."""
    scenario, problems = scenario_stage.load_partial(path)
    if scenario is None:
        raise ScenarioError(problems)
    try:
        world = world_stage.build(scenario)
    except MapImageError as err:
        raise ScenarioError([*problems, err.problem]) from None
    problems += world_stage.check(scenario, world)
    if problems:
        raise ScenarioError(problems)
    return scenario, world
