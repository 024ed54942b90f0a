"""nav2's recoveries in the simulator (tmpnav/execution/recovery.py): when the controller fails,
the round robin of behaviours, and the goal given up after the last retry."""

from __future__ import annotations

import math

import numpy as np

from tests.execution.test_local_view import RADIUS, view
from tests.execution.test_site import WALL
from tmpnav.belief.models import motion
from tmpnav.execution.control import control
from tmpnav.execution.recovery import BEHAVIOURS, Recovery, RecoveryParams

DT = 0.5


def _refuse_until_given_up(rec: Recovery, limit: int = 1000) -> list[str]:
    """Drive ``rec`` with a controller refused at every step and a robot that never moves; the
    behaviours started, in order."""
    xy, started = np.zeros(2), []
    for step in range(limit):
        rec.ended(xy, step)
        if rec.behaviour(1.0, True) is None:
            running = rec.running
            rec.followed(True, xy, step)
            if rec.running is not None and rec.running != running:
                started.append(rec.running)
        if rec.given_up:
            return started
    raise AssertionError("never given up")


def test_a_controller_that_keeps_failing_runs_the_round_robin_then_gives_up() -> None:
    """nav2's tree: each failure of the pipeline (two of the controller's, the local costmap
    cleared between) runs the next behaviour of clear, spin, wait, back up; the 7th gives up."""
    params = RecoveryParams()
    rec = Recovery(params, np.zeros(2), 0, DT)
    started = _refuse_until_given_up(rec)
    assert started == [BEHAVIOURS[k % 4] for k in range(params.retries)]
    assert rec.failures == params.retries + 1
    assert sum(rec.run.values()) == params.retries


def test_a_refusal_shorter_than_the_failure_tolerance_is_no_failure() -> None:
    rec = Recovery(RecoveryParams(failure_tolerance=1.0), np.zeros(2), 0, DT)
    for step in range(20):  # refused every other step: never 1 s in a row
        rec.followed(step % 2 == 0, np.array([0.1 * step, 0.0]), step)
    assert rec.running is None and not rec.retried and rec.failures == 0


def test_the_progress_checker_fails_a_robot_that_moves_less_than_half_a_metre_in_ten_seconds() -> None:
    p = RecoveryParams()
    rec = Recovery(p, np.zeros(2), 0, DT)
    creeping = [np.array([0.02 * s, 0.0]) for s in range(60)]  # 4 cm/s: 0.4 m in 10 s
    steps = next(s for s, xy in enumerate(creeping) if (rec.followed(False, xy, s), rec.retried)[1])
    assert steps * DT == p.progress_time
    moving = Recovery(p, np.zeros(2), 0, DT)
    for s in range(100):  # 10 cm/s: half a metre in 5 s
        moving.followed(False, np.array([0.05 * s, 0.0]), s)
    assert not moving.retried and moving.failures == 0


def test_a_robot_held_still_by_an_event_is_not_failed_by_the_progress_checker() -> None:
    rec = Recovery(RecoveryParams(), np.zeros(2), 0, DT)
    for s in range(100):
        rec.hold(s)
        rec.followed(False, np.zeros(2), s)
    assert not rec.retried


def test_the_behaviours_move_as_nav2s_do() -> None:
    """A spin turns 1.57 rad at no more than 1 rad/s, a wait stands 5 s, a back-up reverses
    0.30 m at 0.05 m/s; a back-up that would come nearer to what the robot sees fails at once."""
    p = RecoveryParams()
    rec = Recovery(p, np.zeros(2), 0, DT)
    motions: dict[str, list[np.ndarray]] = {name: [] for name in BEHAVIOURS}
    for name in BEHAVIOURS:
        rec._start_next()
        assert rec.running == name
        step = 0
        while rec.running is not None:
            command = rec.behaviour(2.0, True)
            assert command is not None
            motions[name].append(command)
            step += 1
            rec.ended(np.zeros(2), step)
    assert math.isclose(sum(c[1] for c in motions["spin"]) * DT, p.spin) and max(c[1] for c in motions["spin"]) <= 1.0
    assert len(motions["wait"]) * DT == p.wait and not np.any(motions["wait"])
    assert math.isclose(-sum(c[0] for c in motions["backup"]) * DT, p.backup_distance)
    blocked = Recovery(p, np.zeros(2), 0, DT)
    blocked.next = BEHAVIOURS.index("backup")
    blocked._start_next()
    assert blocked.behaviour(1.0, False) is not None and blocked.running == "clear"


def test_a_robot_driven_at_a_wall_backs_away_and_gives_its_goal_up_without_touching_it() -> None:
    """A robot 0.4 m from a corridor's wall, heading for it, its waypoint beyond the wall (its
    estimate is off): every command towards it is refused; the recoveries spin, wait and back it
    away from the wall, and after the last retry the goal is given up, the footprint clear of
    the wall throughout."""
    v = view(width=2.0)
    truth = np.array([10.0, WALL + 1.6, math.pi / 2])  # the upper wall 0.15 m past its radius
    waypoint = truth[:2] + np.array([0.0, 1.5])  # beyond the wall
    p = RecoveryParams()
    rec = Recovery(p, truth[:2], 0, DT)
    closest = math.inf
    for step in range(1000):
        rec.ended(truth[:2], step)
        clear = not rec.backing_up or v.clear_path(truth, -p.backup_speed, RADIUS, p.simulate_ahead)
        command = rec.behaviour(1.0, clear)
        if command is None:
            wanted = control(truth, waypoint, 0.5, 1.0, DT)
            safe = v.safe_command(truth, wanted, RADIUS, (0.5, 1.0), 5.0)
            rec.followed(safe is None, truth[:2], step)
            command = np.zeros(2) if safe is None else safe
        truth = motion(truth[None], command[None], DT)[0]
        closest = min(closest, float(v.clearance(truth[None, :2])[0]) - RADIUS)
        if rec.given_up:
            break
    assert rec.given_up and step * DT < 60.0
    assert rec.run == {"clear": 2, "spin": 2, "wait": 1, "backup": 1}
    assert closest > 0.0 and truth[1] < WALL + 1.6  # it backed away from the wall ahead
