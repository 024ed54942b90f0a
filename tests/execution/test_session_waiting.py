"""A team in which nobody drives is not stuck while a robot is still at a station."""

from __future__ import annotations

import numpy as np
import pytest

from tmpnav.errors import TmpnavError
from tmpnav.execution.moves import QueuedMove, RobotQueue
from tmpnav.execution.session import Session


def _move(start: int, partner: str | None = None) -> QueuedMove:
    return QueuedMove(1, "r1", "P1", "P2", partner, (0, 1), np.zeros((2, 2)), start, 10, (None,))


def _team(robot: RobotQueue, step: int) -> Session:
    team = object.__new__(Session)  # the waiting rule reads the robots, the clock and who is down
    team.robots, team.names, team.step, team.down = [robot], ("r1",), step, set()
    return team


def test_a_robot_in_service_past_its_next_moves_planned_start_is_not_stuck() -> None:
    """It arrived late and is serving its job: the next move's planned start has passed, and
    it starts when the service ends (a plan with jobs executed more slowly than planned)."""
    _team(RobotQueue((_move(start=50),), ready=80), step=60)._check_waiting()


def test_a_robot_waiting_for_a_partner_that_never_comes_is_stuck() -> None:
    with pytest.raises(TmpnavError, match="r1 at step 2 waits for r2"):
        _team(RobotQueue((_move(start=50, partner="r2"),), ready=40), step=60)._check_waiting()
