"""Runs of a plan resumed from an earlier run's checkpoint give the run from the start, to the bit."""

from __future__ import annotations

import numpy as np
import pytest

from tests.attachment.support import carried_problem
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockRun
from tmpnav.attachment.resume import Made, parting
from tmpnav.task.plans import Plan

ROOMS = ("L1", "L2", "L3", "L4", "L6", "L7", "L8", "L9")


@pytest.fixture(scope="module")
def team() -> tuple[CarriedCosts, Plan]:
    """corridor-4robots' first two robots, each visiting four rooms: 8 single moves."""
    _, _, carried = carried_problem("corridor-4robots.yaml", ROOMS, 2)
    at = dict(carried.start_location)
    plan = []
    for k, room in enumerate(ROOMS):
        r = carried.robots[k % 2]
        plan.append(((r, at[r], room),))
        at[r] = room
    return carried, tuple(plan)


def _same(a: ClockRun, b: ClockRun) -> None:
    assert [(m.step, m.robot, m.ready, m.start, m.end, m.terms, m.risk) for m in a.moves] == [
        (m.step, m.robot, m.ready, m.start, m.end, m.terms, m.risk) for m in b.moves
    ]
    assert a.schedule == b.schedule
    assert a.trajectories == b.trajectories
    assert np.array_equal(a.end.team.mean, b.end.team.mean) and np.array_equal(a.end.team.cov, b.end.team.cov)
    assert a.end.csig == b.end.csig and a.end.risk == b.end.risk and a.end.closed_cost == b.end.closed_cost


#: waits as keeping robots apart tries them: depth first, each run the one before with one more
#: wait; then others from scratch (a first step's wait: no event to resume from)
WAITS: tuple[dict[int, float], ...] = (
    {5: 2.0},
    {5: 2.0, 7: 1.0},
    {5: 2.0, 7: 1.0, 6: 6.5},
    {3: 1.0},
    {3: 1.0, 4: 0.5},
    {3: 1.0, 4: 0.5, 7: 2.0},
    {0: 2.0},
    {2: 6.5, 7: 0.5},
    {},
)


def test_runs_with_other_waits_resume_and_match_runs_from_the_start(team: tuple[CarriedCosts, Plan]) -> None:
    carried, plan = team
    clock = carried.clock
    clock.run(plan, record=True)
    resumed = []
    for delays in WAITS:
        found = clock.resumes.find(plan, {k: round(v / clock.dt) for k, v in delays.items()}, {})
        resumed.append(None if found is None else found.at)
        ours = clock.run(plan, delays, record=True)
        theirs = TeamClock(clock.oracle, clock.lib, clock.start).run(plan, delays, record=True)  # from the start
        _same(ours, theirs)
    # the event each run resumed from (None: from the start)
    assert resumed == [1, 3, 4, 0, 2, 3, None, 0, 0]
    # the same waits again: the run already made
    again = clock.resumes.find(plan, {0: round(2.0 / clock.dt)}, {})
    assert again is not None and again.at is None


def test_a_run_parts_from_another_where_a_changed_step_is_scheduled_or_started() -> None:
    made: Made[None, None] = Made(
        {2: 4}, {(3, "r1"): (1, 2)}, (), {1: -1, 2: 0, 3: 1, 4: 3}, {1: 0, 2: 2, 3: 3, 4: 5}, {}, {}, None
    )
    assert parting(made, {2: 4}, {(3, "r1"): (1, 2)}) is None  # the same run
    assert parting(made, {2: 4, 4: 1}, {(3, "r1"): (1, 2)}) == 3  # a wait on step 4: where it was scheduled
    assert parting(made, {}, {(3, "r1"): (1, 2)}) == 0  # step 2's wait taken away
    assert parting(made, {2: 4}, {}) == 3  # step 3's detour: where it started
    assert parting(made, {2: 4, 1: 2}, {(3, "r1"): (1, 2)}) == -1  # a first step: before the first event
