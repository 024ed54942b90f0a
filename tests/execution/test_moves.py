"""A plan's queues read from its plan.json are the queues of the plan itself: a plan made by
``tmpnav serve`` is executed as one made in the process (``tmpnav simulate --server``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.test_replan import WORLD
from tmpnav import pipeline
from tmpnav.execution.moves import QueuedMove, queues, queues_of_document
from tmpnav.report.plan_json import plan_document


def _same(a: QueuedMove, b: QueuedMove) -> None:
    for name in ("step", "robot", "origin", "target", "partner", "nodes", "start", "steps", "arrivals"):
        assert getattr(a, name) == getattr(b, name), name
    np.testing.assert_allclose(a.points, b.points, rtol=0, atol=1e-9)
    assert len(a.planned_covs) == len(b.planned_covs)
    for x, y in zip(a.planned_covs, b.planned_covs, strict=True):
        assert (x is None) == (y is None)
        if x is not None:
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-15)
    for x, y in ((a.planned_track, b.planned_track), (a.planned_means, b.planned_means)):
        assert x is not None and y is not None
        np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-12)


def test_the_queues_of_a_plan_json_are_the_plans_own(tmp_path: Path) -> None:
    scenario = tmp_path / "world.yaml"
    scenario.write_text(WORLD)
    report = pipeline.plan(scenario, pipeline.PlanOptions.of(cache_dir=tmp_path / "cache"))
    doc = json.loads(json.dumps(plan_document(report)))  # as the service sends it
    mine, read = queues(report), queues_of_document(doc)
    assert list(mine) == list(read) and sum(len(q) for q in mine.values()) >= 2
    for robot in mine:
        assert len(mine[robot]) == len(read[robot])
        for a, b in zip(mine[robot], read[robot], strict=True):
            _same(a, b)


def test_a_schedule_move_missing_from_its_step_is_named() -> None:
    doc = {
        "dt": 0.5,
        "actions": [{"moves": [{"robot": "r2", "path_nodes": [0, 1], "path_points": [[0, 0], [1, 0]]}]}],
        "schedule": {"robots": {"r1": {"moves": [
            {"step": 1, "from": "A", "to": "B", "partner": None, "ready": 0, "start": 0, "end": 1}
        ]}}},
        "trajectories": {},
    }  # fmt: skip
    with pytest.raises(ValueError, match="move of r1 in step 1"):
        queues_of_document(doc)
