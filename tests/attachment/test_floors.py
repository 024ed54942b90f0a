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
from tmpnav.attachment.floors import bearing_information, heading_floor, motion_floors, sigma_rate
from tmpnav.belief.rollout import Rollout, propagate_rollout
from tmpnav.task.bound import lower_bound
from tmpnav.types import Belief


@pytest.mark.slow
@pytest.mark.parametrize(
    ("config", "rooms"),
    [("corridor-2robots.yaml", ("L2", "L5", "L9")), ("sparse-warehouse.yaml", ("P1", "P3", "P8", "P5"))],
)
def test_every_move_of_every_schedule_costs_at_least_its_floor(config: str, rooms: tuple[str, ...]) -> None:
    scenario, _, carried = carried_problem(config, rooms, 2)
    floors = motion_floors(scenario, carried.lib.roadmap, carried.start_location, scenario.goals)
    plans = every_plan(carried, scenario.goals)
    assert any(len(s) == 2 for p in plans for s in p)
    best = float("inf")
    for plan in plans:  # every step of every plan, in the context the team's clock gives it
        cost = carried.plan_cost(plan)
        for step, c in zip(plan, cost.steps, strict=True):
            assert sum(floors.single[m] for m in step) <= c * (1 + 1e-9), step
        best = min(best, cost.total)
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
