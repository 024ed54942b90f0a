"""A run's record as arrays (tmpnav.attachment.record.Trace.tracks): the positions and position
stds of its steps, bit for bit, so that keeping robots apart finds the same conflicts from them."""

from __future__ import annotations

import numpy as np
import pytest

from tests.attachment.support import carried_problem
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockRun
from tmpnav.attachment.conflicts import radii_of
from tmpnav.attachment.own_legs import TAIL
from tmpnav.belief.conflicts import find_conflicts, position_sigma
from tmpnav.task.plans import Plan

ROOMS = ("A12", "A15", "B10", "C8", "A1", "C3")


@pytest.fixture(scope="module")
def team() -> tuple[CarriedCosts, Plan]:
    """building-4robots' first three robots (nav2's AMCL: each runs on its own legs), two rooms each."""
    _, _, carried = carried_problem("building-4robots.yaml", ROOMS, 3)
    at, plan = dict(carried.start_location), []
    for room, k in zip(ROOMS, (0, 1, 2, 0, 1, 2), strict=True):
        r = carried.robots[k]
        plan.append(((r, at[r], room),))
        at[r] = room
    return carried, tuple(plan)


def _same_as_steps(run: ClockRun) -> None:
    assert run.trajectories is not None and run.tracks is not None
    assert set(run.tracks) == set(run.trajectories)
    for robot, steps in run.trajectories.items():
        xy, sigma = run.tracks[robot]
        assert xy.shape == (len(steps), 2) and sigma.shape == (len(steps),)
        assert np.array_equal(xy, np.array([s.mean[:2] for s in steps]))
        assert np.array_equal(sigma, position_sigma(np.array([s.cov for s in steps])))


@pytest.mark.parametrize("joint", [False, True])
@pytest.mark.parametrize("delays", [{}, {0: 3.0}, {2: 1.5, 4: 2.0 * TAIL * 0.5}])
def test_a_runs_tracks_are_its_steps_positions_and_stds(team: tuple[CarriedCosts, Plan], joint: bool, delays) -> None:  # type: ignore[no-untyped-def]
    """On the robots' own legs (standing past a leg's computed tail included) and in the joint EKF."""
    carried, plan = team
    clock = TeamClock(carried.oracle, carried.lib, carried.start)
    if joint:
        clock.own = None
    run = clock.run(plan, delays, record=True)
    _same_as_steps(run)
    found = 0
    for radius in (None, 2.0):  # the robots' own radii, and discs that meet (conflicts to find)
        radii = {r: radius or own for r, own in radii_of(clock).items()}
        for delta in (0.05, 0.5, 1.0):
            conflicts = find_conflicts(run.trajectories, radii, delta)
            assert find_conflicts(run.trajectories, radii, delta, tracks=run.tracks) == conflicts
            found += len(conflicts)
    assert found > 0


def test_a_resumed_runs_tracks_are_a_fresh_runs(team: tuple[CarriedCosts, Plan]) -> None:
    carried, plan = team
    clock = TeamClock(carried.oracle, carried.lib, carried.start)
    clock.run(plan, record=True)
    for delays in ({3: 2.0}, {4: 5.0}, {1: 1.0, 5: 0.5}):
        resumed = clock.run(plan, delays, record=True)
        fresh = TeamClock(carried.oracle, carried.lib, carried.start).run(plan, delays, record=True)
        _same_as_steps(resumed)
        assert resumed.tracks is not None and fresh.tracks is not None
        for robot, (xy, sigma) in fresh.tracks.items():
            assert np.array_equal(resumed.tracks[robot][0], xy) and np.array_equal(resumed.tracks[robot][1], sigma)
