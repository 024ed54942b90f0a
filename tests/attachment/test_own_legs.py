"""A team whose robots take in nothing of each other runs one robot at a time
(tmpnav.attachment.own_legs): the joint EKF's beliefs and costs, to rounding, whatever ran before."""

from __future__ import annotations

import numpy as np
import pytest

from tests.attachment.support import carried_problem
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockRun
from tmpnav.attachment.own_legs import TAIL
from tmpnav.task.plans import Plan

ROOMS = ("A12", "A15", "B10", "C8", "A1", "C3")


@pytest.fixture(scope="module")
def team() -> tuple[CarriedCosts, Plan, Plan]:
    """building-4robots' first three robots with its shipped localiser (nav2's AMCL, its lidar
    alone: no robot takes in another), two rooms each; and the same rooms dealt otherwise."""
    _, _, carried = carried_problem("building-4robots.yaml", ROOMS, 3)
    return carried, _dealt(carried, (0, 1, 2, 0, 1, 2)), _dealt(carried, (0, 0, 2, 1, 1, 2))


def _dealt(carried: CarriedCosts, who: tuple[int, ...]) -> Plan:
    at, plan = dict(carried.start_location), []
    for room, k in zip(ROOMS, who, strict=True):
        r = carried.robots[k]
        plan.append(((r, at[r], room),))
        at[r] = room
    return tuple(plan)


def _joint(clock: TeamClock, plan: Plan, delays: dict[int, float], record: bool) -> ClockRun:
    own, clock.own = clock.own, None
    try:
        return clock.run(plan, delays, record=record)
    finally:
        clock.own = own


def _fresh(carried: CarriedCosts) -> TeamClock:
    return TeamClock(carried.oracle, carried.lib, carried.start)


def test_the_shipped_lidar_team_runs_on_its_own_legs(team: tuple[CarriedCosts, Plan, Plan]) -> None:
    carried, _, _ = team
    assert carried.clock.own is not None and carried.clock.own.static
    assert not carried.clock.sensing


@pytest.mark.parametrize("delays", [{}, {0: 3.0}, {2: 1.5, 4: 40.0}])
def test_own_legs_give_the_joint_runs_beliefs_and_costs(team: tuple[CarriedCosts, Plan, Plan], delays) -> None:  # type: ignore[no-untyped-def]
    """The joint EKF's run on a clock of its own (on the same clock it would resume from the
    run on own legs, and be it)."""
    carried, plan, _ = team
    own, joint = _fresh(carried).run(plan, delays, record=True), _joint(_fresh(carried), plan, delays, True)
    assert own.schedule == joint.schedule
    w, delta = carried.scenario.cost, carried.scenario.planner.max_risk
    np.testing.assert_allclose(own.step_costs(len(plan), w, delta), joint.step_costs(len(plan), w, delta), rtol=1e-12)
    for a, b in zip(own.moves, joint.moves, strict=True):
        assert a.terms is not None and b.terms is not None
        assert a.terms.c_u == b.terms.c_u
        np.testing.assert_allclose(
            [a.terms.c_G, a.terms.c_Sigma], [b.terms.c_G, b.terms.c_Sigma], rtol=1e-10, atol=1e-15
        )
        assert a.risk == pytest.approx(b.risk, rel=1e-9, abs=1e-15)
    np.testing.assert_allclose(own.end.team.mean, joint.end.team.mean, rtol=1e-13)
    np.testing.assert_allclose(own.end.team.cov, joint.end.team.cov, rtol=1e-10, atol=1e-18)
    assert own.trajectories is not None and joint.trajectories is not None
    for robot, steps in joint.trajectories.items():
        mine = own.trajectories[robot]
        assert [(s.t, s.node) for s in mine] == [(s.t, s.node) for s in steps]
        np.testing.assert_allclose([s.mean[:2] for s in mine], [s.mean[:2] for s in steps], rtol=1e-13)
        # the heading: the same angle (a robot standing on its own legs keeps its start's 3.1416,
        # where the joint EKF's prediction wraps it to -3.14159 at its first step)
        turn = np.array([s.mean[2] for s in mine]) - np.array([s.mean[2] for s in steps])
        np.testing.assert_allclose(np.angle(np.exp(1j * turn)), 0.0, atol=1e-12)
        np.testing.assert_allclose([s.cov for s in mine], [s.cov for s in steps], rtol=1e-10, atol=1e-18)


def test_a_run_reads_the_same_legs_whatever_ran_before(team: tuple[CarriedCosts, Plan, Plan]) -> None:
    """Legs are kept by each robot's history and computed in pieces at fixed rows: a plan run
    after others (its legs partly read from theirs) gives the bits of a run on a fresh clock."""
    carried, plan, other = team
    clock = _fresh(carried)
    for before in (other, plan):
        clock.run(before, {1: 2.0}, record=True)
    clock.resumes = type(clock.resumes)()  # nothing to resume from: the legs alone are shared
    later = clock.run(plan, {0: 1.0, 3: 2.0 * TAIL * clock.dt}, record=True)
    computed = clock.own.computed if clock.own is not None else 0
    first = _fresh(carried).run(plan, {0: 1.0, 3: 2.0 * TAIL * clock.dt}, record=True)
    assert [(m.terms, m.risk, m.start, m.end) for m in later.moves] == [
        (m.terms, m.risk, m.start, m.end) for m in first.moves
    ]
    assert later.trajectories == first.trajectories
    assert np.array_equal(later.end.team.cov, first.end.team.cov)
    again = clock.run(plan, {0: 1.0, 3: 2.0 * TAIL * clock.dt})  # every leg read, none computed
    assert clock.own is not None and clock.own.computed == computed
    assert [m.terms for m in again.moves] == [m.terms for m in first.moves]


def test_robots_that_see_each_other_stay_in_one_joint_ekf() -> None:
    """The paper's corridor: landmarks and mutual observations couple the robots."""
    _, _, carried = carried_problem("corridor-4robots.yaml", ("L1", "L2"), 2)
    assert carried.clock.own is None and carried.clock.sensing
