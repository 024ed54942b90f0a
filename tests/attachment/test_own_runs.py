"""A plan run one robot at a time (tmpnav.attachment.own_runs) is the event loop's run, bit for
bit: its moves and costs, schedule, end state and record, with waits, jobs' service times and
windows, and robots' runs read back from other plans' runs."""

from __future__ import annotations

import numpy as np
import pytest

from tests.attachment.support import carried_problem
from tmpnav.attachment.canonical import CanonicalCosts
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockRun, Unreachable
from tmpnav.oracle.executors import OracleContext
from tmpnav.oracle.oracle import Oracle
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap
from tmpnav.shipped import configs_dir
from tmpnav.task.plans import Plan

ROOMS = ("A12", "A15", "B10", "C8", "A1", "C3")


def _dealt(start: dict[str, str], robots: tuple[str, ...], rooms: tuple[str, ...], who: tuple[int, ...]) -> Plan:
    at, plan = dict(start), []
    for room, k in zip(rooms, who, strict=True):
        r = robots[k]
        plan.append(((r, at[r], room),))
        at[r] = room
    return tuple(plan)


@pytest.fixture(scope="module")
def building() -> CarriedCosts:
    """building-4robots' first three robots (nav2's AMCL: each on its own legs)."""
    return carried_problem("building-4robots.yaml", ROOMS, 3)[2]


@pytest.fixture(scope="module")
def depot() -> CarriedCosts:
    """depot-jobs as shipped: four robots, stations with service times, a window, a job r4 may
    not do."""
    scenario, world = load_world(configs_dir() / "depot-jobs.yaml")
    roadmap = build_roadmap(world, scenario.robots, scenario.roadmap)
    oracle = Oracle(OracleContext(scenario, world, roadmap))
    return CarriedCosts(oracle, CanonicalCosts(oracle, world, scenario.planner.pair_min_gain))


def _both(clock: TeamClock, plan: Plan, delays: dict[int, float], record: bool) -> tuple[ClockRun, ClockRun]:
    """The event loop's run and the robots' runs put together, on one clock (the same legs)."""
    clock.one_at_a_time = False
    try:
        loop = clock.run(plan, delays, record=record)
    finally:
        clock.one_at_a_time = True
    return loop, clock.run(plan, delays, record=record)


def _same(a: ClockRun, b: ClockRun) -> None:
    assert [(m.step, m.robot, m.ready, m.start, m.end, m.motion, m.terms, m.risk) for m in a.moves] == [
        (m.step, m.robot, m.ready, m.start, m.end, m.motion, m.terms, m.risk) for m in b.moves
    ]
    assert a.schedule == b.schedule
    ea, eb = a.end, b.end
    assert (ea.t, ea.free, ea.late, ea.csig, ea.risk, ea.pairings, ea.open) == (
        eb.t,
        eb.free,
        eb.late,
        eb.csig,
        eb.risk,
        eb.pairings,
        eb.open,
    )
    assert [[leg.key for leg in legs] for legs in ea.legs] == [[leg.key for leg in legs] for legs in eb.legs]
    assert [(m.step, m.robot, m.terms) for m in ea.closed] == [(m.step, m.robot, m.terms) for m in eb.closed]
    assert ea.closed_cost == eb.closed_cost
    ta, tb = ea.team, eb.team
    assert (ta.names, ta.node, ta.heading, ta.t) == (tb.names, tb.node, tb.heading, tb.t)
    assert np.array_equal(ta.mean, tb.mean) and np.array_equal(ta.cov, tb.cov)
    assert a.trajectories == b.trajectories
    if a.tracks is not None:
        assert b.tracks is not None and a.tracks.keys() == b.tracks.keys()
        for robot, (xy, sigma) in a.tracks.items():
            assert np.array_equal(b.tracks[robot][0], xy) and np.array_equal(b.tracks[robot][1], sigma)


@pytest.mark.parametrize("record", [False, True])
@pytest.mark.parametrize(
    "who, delays",
    [
        ((0, 1, 2, 0, 1, 2), {}),
        ((0, 1, 2, 0, 1, 2), {0: 3.0, 4: 40.0}),
        ((0, 0, 2, 1, 1, 2), {2: 1.5, 5: 70.0}),
        ((2, 2, 2, 2, 0, 0), {1: 0.5}),  # r2 stands all the run
    ],
)
def test_the_robots_runs_put_together_are_the_event_loops(building: CarriedCosts, who, delays, record: bool) -> None:  # type: ignore[no-untyped-def]
    clock = building.clock
    assert clock.own is not None
    plan = _dealt(dict(building.start_location), building.robots, ROOMS, who)
    _same(*_both(clock, plan, delays, record))


def test_jobs_service_times_and_windows_run_as_the_event_loop_runs_them(depot: CarriedCosts) -> None:
    clock = depot.clock
    assert clock.own is not None
    jobs = ("P2", "P5", "P6", "P7", "P8")
    refused = 0
    for who, delays in (((0, 1, 2, 0, 1), {}), ((1, 1, 0, 2, 2), {2: 12.0}), ((3, 2, 1, 3, 3), {0: 5.0, 3: 1.0})):
        plan = _dealt(dict(depot.start_location), depot.robots, jobs, who)
        try:
            _same(*_both(clock, plan, delays, True))
        except Unreachable as err:  # a job its robot may not do (P7 is not for r4): both refuse it alike
            refused += 1
            clock.one_at_a_time = False
            with pytest.raises(Unreachable) as loop:
                clock.run(plan, delays)
            clock.one_at_a_time = True
            assert str(loop.value) == str(err)
    assert refused == 1


def test_a_robots_run_is_read_back_in_another_plans_run(building: CarriedCosts) -> None:
    """Runs that change one robot's wait make only that robot's run again, and still give the
    event loop's run; a fresh clock's run is the same too."""
    clock = building.clock
    plan = _dealt(dict(building.start_location), building.robots, ROOMS, (0, 1, 2, 0, 1, 2))
    clock.run(plan, {}, record=True)
    made = clock.robot_runs.made
    run = clock.run(plan, {4: 6.0}, record=True)  # r2's second move held back
    assert clock.robot_runs.made == made + 1
    fresh = TeamClock(clock.oracle, clock.lib, clock.start)
    fresh.one_at_a_time = False
    _same_values(fresh.run(plan, {4: 6.0}, record=True), run)


def _same_values(a: ClockRun, b: ClockRun) -> None:
    """Two runs on different clocks (their legs numbered apart): the same values."""
    assert [(m.step, m.robot, m.start, m.end, m.terms, m.risk) for m in a.moves] == [
        (m.step, m.robot, m.start, m.end, m.terms, m.risk) for m in b.moves
    ]
    assert a.schedule == b.schedule and a.trajectories == b.trajectories
    assert np.array_equal(a.end.team.mean, b.end.team.mean) and np.array_equal(a.end.team.cov, b.end.team.cov)


def test_a_plan_whose_robot_cannot_reach_its_room_fails_as_the_event_loop_fails(building: CarriedCosts) -> None:
    clock = building.clock
    plan = _dealt(dict(building.start_location), building.robots, ROOMS, (0, 1, 2, 0, 1, 2))
    broken = (*plan[:3], ((plan[3][0][0], plan[3][0][1], "no-such-room"),), *plan[4:])
    errors = []
    for one in (False, True):
        clock.one_at_a_time = one
        with pytest.raises(Exception) as err:
            clock.run(broken, {})
        errors.append((type(err.value), str(err.value)))
    assert errors[0] == errors[1]
