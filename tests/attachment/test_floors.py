"""Motion floors: no move costs less, whatever beliefs it starts from, alone, paired or among
robots that move at once."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.attachment.support import carried_problem, every_plan
from tests.belief.support import models, random_case
from tmpnav.attachment.floors import _Walks, bearing_information, heading_floor, motion_floors, sigma_rate
from tmpnav.belief.controls import path_controls
from tmpnav.belief.rollout import Rollout, propagate_rollout
from tmpnav.task.bound import lower_bound
from tmpnav.types import Belief


@pytest.mark.slow
@pytest.mark.parametrize(
    ("config", "rooms", "controller"),
    [
        ("corridor-2robots.yaml", ("L2", "L5", "L9"), None),
        ("sparse-warehouse.yaml", ("P1", "P3", "P8", "P5"), None),
        ("sparse-warehouse.yaml", ("P1", "P3", "P8", "P5"), "rpp"),
    ],
)
def test_every_move_of_every_schedule_costs_at_least_its_floor(
    config: str, rooms: tuple[str, ...], controller: str | None
) -> None:
    """Every step of every plan costs at least its floors, and takes at least its time floor;
    under RPP (models.controller: rpp) too, whose floors are the straight line's."""
    scenario, _, carried = carried_problem(config, rooms, 2, controller)
    floors = motion_floors(scenario, carried.lib.graph, carried.start_location, scenario.goals, arrived=True)
    plans = every_plan(carried, scenario.goals)
    assert any(len(s) == 2 for p in plans for s in p)
    best, tight = float("inf"), 0
    for plan in plans:  # every step of every plan, in the context the team's clock gives it
        cost = carried.plan_cost(plan)
        for step, c in zip(plan, cost.steps, strict=True):
            assert sum(floors.single[m] for m in step) <= c * (1 + 1e-9), step
        assert cost.schedule is not None
        for move in cost.schedule.moves:  # each robot drives at least its move's time floor
            floor = floors.duration[(move.robot, move.origin, move.target)]
            assert floor <= move.end - move.start + 1e-9, move
            tight += floor > move.end - move.start - 1e-9
        best = min(best, cost.total)
    assert tight or controller == "rpp"  # a single move from a robot's start takes exactly its time floor
    assert lower_bound(floors, scenario.goals, 0.0).value <= best


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]), st.floats(1e-12, 1.0), st.booleans())
def test_no_move_accumulates_less_uncertainty_than_its_floor(seed: int, n: int, prior: float, driving: bool) -> None:
    """Random moves (controls, landmarks and partners in view at random), from random priors
    down to almost no uncertainty, through the oracle's EKF: each robot's c_Sigma is at least
    the sum of its steps' heading floors, and, for moves that only drive, kappa c_u."""
    rng = np.random.default_rng(seed)
    T, L = int(rng.integers(1, 15)), int(rng.integers(0, 5))
    belief, rollout, landmarks, noise = random_case(rng, n, T, L, p_see=0.7)
    belief = Belief(belief.mean, prior * belief.cov)
    controls = rollout.controls.copy()
    if driving:
        controls[:, :, 1] = 0.0
    rollout = replace(rollout, controls=controls)
    m = models()
    run = propagate_rollout(belief, rollout, landmarks, m, noise)
    information = bearing_information(m, L, n - 1)
    for i, terms in enumerate(run.terms):
        own = controls[i, : rollout.active_steps[i]]
        floor = m.dt * float(heading_floor(m, own[:, 0], own[:, 1], information).sum())
        assert floor <= terms.c_Sigma * (1 + 1e-9)
        if driving and own.size:
            speed = float(own[:, 0].max())
            assert sigma_rate(m, speed, n, L) * terms.c_u <= terms.c_Sigma * (1 + 1e-9) + 1e-15


@pytest.mark.parametrize("config", ["corridor-2robots.yaml", "building-20.yaml"])
def test_the_walk_drives_as_path_controls_does(config: str) -> None:
    """The floors' walk along the roadmap's shortest paths (tmpnav.attachment.floors._walk)
    counts the steps and the control usage that turn-then-drive (path_controls) gives the
    same path from the same heading: exactly, but for the slack of SLACK (1e-6)."""
    scenario, _, carried = carried_problem(config, (), 1)
    spec, dt, paths = scenario.robots[0], scenario.models.dt, carried.lib.graph
    rng = np.random.default_rng(1)
    nodes = rng.choice(paths.roadmap.n_nodes, size=(12, 2), replace=False)
    walks = _Walks(paths, spec, dt)
    for source, target in nodes:
        heading = float(rng.uniform(-np.pi, np.pi))
        path = paths.path(int(source), int(target))
        assert path is not None
        driven = path_controls(paths.points(path), heading, spec.speed, spec.turn_rate, dt)
        c_u = float((np.square(driven.controls).sum(axis=1) * dt).sum())
        cost, seconds = walks.floors(int(source), (heading,), np.array([target]), 1.0, 1.0)
        assert float(cost[0]) == pytest.approx(c_u, rel=1e-4, abs=1e-5)
        assert float(cost[0]) <= c_u * (1 + 1e-12)
        assert float(seconds[0]) == pytest.approx(driven.controls.shape[0] * dt)


def test_the_floor_is_reached_when_the_robot_knows_all_but_its_last_step() -> None:
    """The heading floor is tight: one step from a certain belief, no measurement, gives
    exactly the step's heading noise (the floor cannot be raised without assumptions)."""
    m = models()
    belief = Belief(np.zeros(3), np.zeros((3, 3)))
    v, omega = 0.8, 0.3
    rollout = Rollout(
        np.array([[[v, omega]]]),
        np.array([[[0.0, 0.0, 0.0], [v * m.dt, 0.0, omega * m.dt]]]),
        np.array([1]),
        np.zeros((1, 2, 0), dtype=bool),
        np.zeros((1, 1, 2), dtype=bool),
    )
    run = propagate_rollout(belief, rollout, np.zeros((0, 2)), m)
    theta = float(run.covs[1][2, 2])
    assert theta == pytest.approx(float(heading_floor(m, np.array([v]), np.array([omega]), 0.0)[0]), rel=1e-12)


def test_a_stop_ends_the_floors_and_the_bound_gives_way() -> None:
    """Under a time limit the bound has a share of it (tmpnav.planning.bound): the floors stop
    between their rows when it has passed, and the bound is then 0, said so, and cut short."""
    from tmpnav.attachment.floors import FloorsStopped
    from tmpnav.planning.bound import NO_FLOORS, stop_at_share

    scenario, _, carried = carried_problem("corridor-2robots.yaml", ("L2", "L5", "L9"), 2, None)
    with pytest.raises(FloorsStopped):
        motion_floors(scenario, carried.lib.graph, carried.start_location, scenario.goals, True, lambda: True)
    assert stop_at_share(float("inf")) is None  # without a limit the bound does all its work
    assert stop_at_share(0.0)() and not stop_at_share(3600.0)()
    assert NO_FLOORS.startswith("none")


def test_the_floors_among_some_rooms_are_those_among_all() -> None:
    """A move's floor does not depend on which other rooms are among the floors' rooms (each row
    is a least over the origin's and the target's own pose instantiations), so the carried costs
    compute them among the goal rooms and the robots' start rooms only, not every room of the
    site: the same floors for those moves, and none for a move outside them (a floor of 0)."""
    from tmpnav.attachment.carried import _START, room_floors

    scenario, _, carried = carried_problem("building-20.yaml", ("S2", "N5", "S9"), 2)
    robots = [r.name for r in scenario.robots]
    every = room_floors(scenario, carried.lib, robots)
    some = room_floors(scenario, carried.lib, robots, ("S2", "N5", "S9"))
    assert some and set(some) < set(every)
    assert all(every[m] == f for m, f in some.items())
    assert {t for _, o, t in some} == {"S2", "N5", "S9"}
    assert {o for _, o, _ in some} <= {"S2", "N5", "S9", *(_START.format(r) for r in robots)}
    assert carried._floor((robots[0], "S2", "N5")) == some[(robots[0], "S2", "N5")] > 0.0
    outside = next(x for x in carried.lib.roadmap.instantiations if x not in ("S2", "N5", "S9"))
    assert carried._floor((robots[0], outside, "N5")) == 0.0
