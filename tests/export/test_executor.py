"""The executor against a fake nav2 on a simulated clock: moves leave at their planned departure,
after their robot's previous move and after their partner reaches the sync point; a late robot
holds its partner, an early one waits; a failed goal stops the run with a clear result."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import pytest

from tests.export.fake_nav2 import FakeNav2, SimClock, check_order_kept, planned_durations, replay
from tmpnav.errors import InputError
from tmpnav.export.executor import ExecutionStatus, Executor, GoalOutcome, MoveStatus, WallClock
from tmpnav.export.moves import MoveRequest, NavigateThroughPoses, Pose, Team


def move(
    robot: str, index: int, step: int, depart: float, arrive: float, ready: float, partner: str | None = None
) -> MoveRequest:
    goal = NavigateThroughPoses((Pose(float(step), float(index), 0.0),))
    return MoveRequest(robot, index, step, "a", "b", partner, ready, depart, arrive, goal, 2)


def paired_team() -> Team:
    """r1 and r2 each make a move alone (r1 ends at 10 s, r2 at 8 s), then step 3 together,
    held back to 12 s by the plan; r2's part of it takes longer."""
    r1 = (move("r1", 1, 1, 0.0, 10.0, 0.0), move("r1", 2, 3, 12.0, 20.0, 10.0, "r2"))
    r2 = (move("r2", 1, 2, 0.0, 8.0, 0.0), move("r2", 2, 3, 12.0, 22.0, 8.0, "r1"))
    return Team(("r1", "r2"), {"r1": r1, "r2": r2}, 22.0, "test")


def sent(run_moves: tuple, name: str) -> tuple[float | None, float | None, str]:
    rec = next(m for m in run_moves if m.name == name)
    return rec.sent, rec.ended, rec.held_by


def test_on_time_every_move_leaves_at_its_planned_departure() -> None:
    team = paired_team()
    run, server = replay(team)
    assert run.status is ExecutionStatus.COMPLETED and run.failed is None
    check_order_kept(team, run)
    assert [(m.name, m.sent, m.ended, m.lateness) for m in run.moves] == [
        ("r1/1", 0.0, 10.0, 0.0),
        ("r1/2", 12.0, 20.0, 0.0),
        ("r2/1", 0.0, 8.0, 0.0),
        ("r2/2", 12.0, 22.0, 0.0),
    ]
    assert sent(run.moves, "r2/2")[2] == "depart"  # held back by the plan, not by r1
    assert [(s.robot, s.t) for s in server.sent] == [("r1", 0.0), ("r2", 0.0), ("r1", 12.0), ("r2", 12.0)]
    assert run.makespan == 22.0


def test_a_late_robot_holds_its_partner_at_the_sync_point() -> None:
    team = paired_team()
    run, _ = replay(team, slower={"r1": 2.0})  # r1 reaches its sync point at 20 s, not 10 s
    check_order_kept(team, run)
    assert sent(run.moves, "r1/2") == (20.0, 36.0, "previous move")
    assert sent(run.moves, "r2/2") == (20.0, 30.0, "partner r1")  # r2 waited 12 s at the sync point, not 4 s
    assert run.record("r2", 2).lateness == pytest.approx(8.0)


def test_an_early_robot_waits_for_the_planned_departure() -> None:
    team = paired_team()
    run, _ = replay(team, slower={"r1": 0.5, "r2": 0.5})
    check_order_kept(team, run)
    assert sent(run.moves, "r1/2") == (12.0, 16.0, "depart")  # ready at 5 s: never before 12 s
    assert sent(run.moves, "r2/2") == (12.0, 17.0, "depart")
    assert run.record("r1", 1).lateness == -5.0


def test_a_late_robot_still_serves_its_station_before_its_next_move() -> None:
    """r1's first move ends at a station with 5 s of service (goals.jobs): late by 10 s, it
    leaves for its next move 5 s after it arrives, not at once."""
    first = move("r1", 1, 1, 0.0, 10.0, 0.0)
    first = MoveRequest(**{**first.__dict__, "service": 5.0})
    team = Team(("r1",), {"r1": (first, move("r1", 2, 2, 15.0, 25.0, 15.0))}, 25.0, "test")
    run, _ = replay(team, slower={"r1": 2.0})  # arrives at 20 s
    assert sent(run.moves, "r1/2") == (25.0, 45.0, "previous move")
    on_time, _ = replay(team)
    assert sent(on_time.moves, "r1/2") == (15.0, 25.0, "depart")


def test_an_early_robot_waits_at_its_station_for_the_window_to_open() -> None:
    """r1's first move ends at a station whose window opens at 30 s (goals.jobs), with 5 s of
    service: early or on time, it stands there until 30 s, serves, and leaves at 35 s; late
    past the opening (arriving at 40 s), it serves at once."""
    first = move("r1", 1, 1, 0.0, 10.0, 0.0)
    first = MoveRequest(**{**first.__dict__, "service": 5.0, "opens_at": 30.0})
    team = Team(("r1",), {"r1": (first, move("r1", 2, 2, 35.0, 45.0, 35.0))}, 45.0, "test")
    on_time, _ = replay(team)
    assert sent(on_time.moves, "r1/2") == (35.0, 45.0, "depart")
    early, _ = replay(team, slower={"r1": 0.5})  # arrives at 5 s
    assert sent(early.moves, "r1/2") == (35.0, 40.0, "depart")
    late, _ = replay(team, slower={"r1": 4.0})  # arrives at 40 s
    assert sent(late.moves, "r1/2") == (45.0, 85.0, "previous move")


def test_a_failed_goal_stops_the_run_and_says_which_move() -> None:
    team = paired_team()
    clock = SimClock()

    def fails(robot: str, goal: NavigateThroughPoses) -> str | None:
        return "aborted: no valid path" if robot == "r2" else None

    server = FakeNav2(clock, planned_durations(team), fails)
    run = Executor(team, server, clock).run()
    assert run.status is ExecutionStatus.FAILED
    assert run.failed is not None and (run.failed.name, run.failed.ended) == ("r2/1", 8.0)
    assert run.failed.status is MoveStatus.FAILED and run.failed.reason == "aborted: no valid path"
    # r1's goal under way when r2's failed is let end; nothing is sent after the failure
    assert [(m.name, m.status) for m in run.moves] == [
        ("r1/1", MoveStatus.ARRIVED),
        ("r1/2", MoveStatus.NOT_SENT),
        ("r2/1", MoveStatus.FAILED),
        ("r2/2", MoveStatus.NOT_SENT),
    ]
    assert max(s.t for s in server.sent) < 8.0 and run.record("r1", 2).sent is None


def test_a_second_report_of_one_goal_is_ignored() -> None:
    team = paired_team()
    clock = SimClock()
    server = FakeNav2(clock, planned_durations(team))

    class Twice:
        def send_goal(self, robot: str, goal: NavigateThroughPoses, done: Callable[[GoalOutcome], None]) -> None:
            def twice(outcome: GoalOutcome) -> None:
                done(outcome)
                done(GoalOutcome(False, "a stale report"))

            server.send_goal(robot, goal, twice)

    run = Executor(team, Twice(), clock).run()
    assert run.status is ExecutionStatus.COMPLETED
    check_order_kept(team, run)


def test_moves_that_cannot_be_made_are_refused() -> None:
    server = FakeNav2(SimClock(), lambda robot, goal: 1.0)
    r1 = (move("r1", 1, 1, 0.0, 10.0, 0.0, "r2"),)
    with pytest.raises(InputError, match=r"move r1/1 \(step 1\) is paired with r2, which has no move of that step"):
        Executor(Team(("r1", "r2"), {"r1": r1, "r2": ()}, 10.0, "t"), server, SimClock())
    r1 = (move("r1", 1, 1, 0.0, 1.0, 0.0, "r2"), move("r1", 2, 2, 1.0, 2.0, 1.0, "r2"))
    r2 = (move("r2", 1, 2, 0.0, 1.0, 0.0, "r1"), move("r2", 2, 1, 1.0, 2.0, 1.0, "r1"))
    circle = Team(("r1", "r2"), {"r1": r1, "r2": r2}, 2.0, "t")
    with pytest.raises(InputError, match="the moves r1/1, r2/1 wait for each other's partners in a circle"):
        Executor(circle, server, SimClock())


def test_the_wall_clock_waits_until_its_time_or_a_goal_ends() -> None:
    clock = WallClock()
    woken = threading.Event()
    began = time.monotonic()
    clock.wait(clock.now() + 0.05, woken)
    assert time.monotonic() - began >= 0.045
    threading.Timer(0.02, woken.set).start()
    began = time.monotonic()
    clock.wait(None, woken)
    assert woken.is_set() and time.monotonic() - began < 5.0
    assert WallClock(start=time.time() - 100.0).now() == pytest.approx(100.0, abs=1.0)


def test_the_executor_runs_on_the_wall_clock_with_a_threaded_server() -> None:
    """Goals that end on another thread, as a ROS client's callbacks do."""
    team = paired_team()
    scale = 0.002  # s of wall clock per s of plan
    fast = Team(
        team.robots,
        {r: tuple(_scaled(m, scale) for m in ms) for r, ms in team.moves.items()},
        None,
        "t",
    )
    durations = planned_durations(fast)
    timers: list[threading.Timer] = []

    class Threaded:
        def send_goal(self, robot: str, goal: NavigateThroughPoses, done: Callable[[GoalOutcome], None]) -> None:
            timers.append(threading.Timer(durations(robot, goal), done, (GoalOutcome(True),)))
            timers[-1].start()

    run = Executor(fast, Threaded(), WallClock()).run()
    assert run.status is ExecutionStatus.COMPLETED
    for m in fast.all_moves():
        rec = run.record(m.robot, m.index)
        assert rec.sent is not None and m.depart is not None and rec.sent >= m.depart
    assert run.record("r2", 2).sent == pytest.approx(run.record("r1", 2).sent)


def _scaled(m: MoveRequest, k: float) -> MoveRequest:
    from dataclasses import replace

    return replace(m, ready=(m.ready or 0.0) * k, depart=(m.depart or 0.0) * k, arrive=(m.arrive or 0.0) * k)
