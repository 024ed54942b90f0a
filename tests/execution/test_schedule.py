"""The team's schedule on the session's clock: a team in which nobody drives is not stuck
while a robot is still at a station; a paired move starts only with its partner."""

from __future__ import annotations

import numpy as np
import pytest

from tmpnav.errors import TmpnavError
from tmpnav.execution.moves import QueuedMove, RobotQueue
from tmpnav.execution.recovery import Recovery
from tmpnav.execution.rpp import RppFollower
from tmpnav.execution.schedule import TeamSchedule
from tmpnav.execution.trace import SessionTrace
from tmpnav.types import Goals


def _move(start: int, partner: str | None = None, robot: str = "r1") -> QueuedMove:
    return QueuedMove(1, robot, "P1", "P2", partner, (0, 1), np.zeros((2, 2)), start, 10, (None,))


class _Standing:
    """Robots that never reach a waypoint (the schedule's waiting rules read only the clock)."""

    def at_waypoint(self, i: int, r: RobotQueue) -> bool:
        return False

    def estimate(self, i: int) -> np.ndarray:
        return np.zeros(3)

    def position_error(self, i: int) -> np.ndarray:
        return np.zeros(2)

    def navigation(self, i: int, m: QueuedMove) -> tuple[Recovery | None, RppFollower | None]:
        return None, None


def _schedule(queues: dict[str, tuple[QueuedMove, ...]]) -> TeamSchedule:
    names = tuple(queues)
    trace = SessionTrace({r: [0.0] for r in names}, {r: [0.0] for r in names})
    trace.planned_nees = {r: [0.0] for r in names}
    trace.c_goal = dict.fromkeys(names, 0.0)
    return TeamSchedule(names, queues, trace, Goals(("P2",), ()), 0.1, _Standing())


def test_a_robot_in_service_past_its_next_moves_planned_start_is_not_stuck() -> None:
    """It arrived late and is serving its job: the next move's planned start has passed, and
    it starts when the service ends (a plan with jobs executed more slowly than planned)."""
    schedule = _schedule({"r1": ()})
    schedule.robots[0] = RobotQueue((_move(start=50),), ready=80)
    schedule.check_waiting(60)


def test_a_robot_waiting_for_a_partner_that_never_comes_is_stuck() -> None:
    schedule = _schedule({"r1": ()})
    schedule.robots[0] = RobotQueue((_move(start=50, partner="r2"),), ready=40)
    with pytest.raises(TmpnavError, match="r1 at step 2 waits for r2"):
        schedule.check_waiting(60)


def test_a_paired_move_starts_when_both_robots_are_free_and_not_before_its_planned_start() -> None:
    schedule = _schedule({"r1": (_move(5, "r2"),), "r2": (_move(5, "r1", robot="r2"),)})
    schedule.robots[1].ready = 8  # r2 is still at a station
    schedule.arrive_and_start(6)
    assert all(r.move is None for r in schedule.robots)  # r1 waits for its partner
    schedule.arrive_and_start(8)
    assert [r.started for r in schedule.robots] == [1, 1]
    assert schedule.driving and not schedule.finished


def test_the_draws_running_out_cut_every_move_left() -> None:
    schedule = _schedule({"r1": (_move(0), _move(20))})
    schedule.arrive_and_start(0)
    schedule.cut_all(7)
    assert schedule.finished and schedule.trace.truncated
    assert [(m.start, m.end) for m in schedule.trace.cut] == [(0.0, pytest.approx(0.7))]
    assert len(schedule.trace.errors["r1"]) == 3  # the start, then both moves' waypoint, never reached
