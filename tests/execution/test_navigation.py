"""How ``tmpnav simulate`` steers each robot: the goal pose nav2 is given for a move."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import QueuedMove
from tmpnav.execution.navigation import Navigator
from tmpnav.scenario.load import load

ROOT = Path(__file__).resolve().parents[2]


def move_to(target: str, end: tuple[float, float]) -> QueuedMove:
    points = np.array([[1.0, 1.0], end])
    return QueuedMove(0, "r2", "P4", target, None, (0, 1), points, 0, 10, (None,))


def test_a_move_that_ends_on_a_station_is_given_its_heading_and_any_other_none() -> None:
    scenario = load(ROOT / "configs" / "depot-jobs.yaml")
    nav = Navigator(scenario, Localisation(), scenario.models.dt)
    assert nav.goal_heading(move_to("P8", (25.2, 10.7))) == np.pi  # the station's pose, 180 deg
    assert nav.goal_heading(move_to("P8", (25.0, 10.0))) is None  # in the room, not on its station
    assert nav.goal_heading(move_to("P4", (25.2, 10.7))) is None  # a room without a job's pose
