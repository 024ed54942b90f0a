"""Carried-belief costs: the sub-team shortcut, the memo and the re-simulation agree exactly.

:class:`CarriedCosts` runs a step only on the robots that move and those correlated with
them, and remembers step outcomes. Neither may change a number: the reference here is the
re-simulation as it was written before, every robot in one joint EKF for every step.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.attachment.support import carried_problem
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.team import Team, mutual_sensing, stationary
from tmpnav.oracle.motionsets import trajectory
from tmpnav.task.plans import Plan

#: three robots on the corridor: r1 and r3 see each other in their paired move, then r1
#: moves alone while correlated with r3 (so r3's belief changes without r3 moving)
PLAN: Plan = (
    (("r1", "r1-start", "L2"), ("r2", "r2-start", "L9")),
    (("r3", "r3-start", "L4"),),
    (("r1", "L2", "L3"), ("r3", "L4", "L8")),
    (("r1", "L3", "L7"),),
    (("r2", "L9", "L10"),),
)


def full_team_step(carried: CarriedCosts, team: Team, step: tuple) -> tuple[float, Team]:
    """One step with every robot of the team in the joint EKF (the reference)."""
    lib = carried.lib
    robots = tuple(m[0] for m in step)
    request = team.request(robots, [m[2] for m in step])
    result = carried.oracle.evaluate([request])[0]
    assert result is not None
    motions = []
    for j, r in enumerate(team.names):
        if r in robots:
            motions.append(lib.motion(r, team.node[j], team.heading[j], result.goal_nodes[robots.index(r)]))
        else:
            motions.append(stationary(lib, r, team.node[j], team.heading[j]))
    h = max(m.n_steps for m in motions)
    idx = [team.names.index(r) for r in robots]
    mvis, noise = mutual_sensing(lib, motions, idx, robots, request.starts, h)
    run = trajectory(lib, motions, team.mean, team.cov, mvis, noise)
    cost = sum(run.terms[i].total(carried.scenario.cost) for i in idx)
    node = tuple(m.path[-1] for m in motions)
    heading = tuple(m.final_heading for m in motions)
    return cost, Team(team.names, node, heading, run.means[-1], run.covs[-1], team.t + h * carried.scenario.models.dt)


@pytest.fixture(scope="module")
def three() -> CarriedCosts:
    _, _, carried = carried_problem("corridor-3robots.yaml", ("L3", "L4", "L6", "L7", "L8", "L2"), 3)
    return carried


def test_the_sub_team_step_equals_the_whole_team_step(three: CarriedCosts) -> None:
    ours, ref = three.start, three.start
    r3_before = None
    for k, step in enumerate(PLAN):
        if k == 3:
            r3_before = ours.cov[6:9, 6:9].copy()
        outcome = three.advance(ours, step)
        cost, ref = full_team_step(three, ref, step)
        assert outcome.cost == pytest.approx(cost, rel=1e-12, abs=1e-12)
        ours = outcome.team
        diff = ours.mean - ref.mean
        diff[2::3] = (diff[2::3] + np.pi) % (2 * np.pi) - np.pi  # a robot that waits may have its heading wrapped
        np.testing.assert_allclose(diff, 0.0, rtol=0, atol=1e-12)
        np.testing.assert_allclose(ours.cov, ref.cov, rtol=0, atol=1e-12)
        assert ours.node == ref.node
    assert np.any(ours.cov[0:3, 6:9] != 0)  # r1 and r3 are correlated
    assert r3_before is not None and np.any(ours.cov[6:9, 6:9] != r3_before)  # and r1's move changed r3's belief


def test_a_plan_costed_again_simulates_nothing(three: CarriedCosts) -> None:
    first = three.plan_cost(PLAN)
    before = three.steps_simulated
    again = three.plan_cost(PLAN)
    assert again == first and three.steps_simulated == before
    shorter = three.plan_cost(PLAN[:2])
    assert shorter.steps == first.steps[:2] and three.steps_simulated == before


def test_the_replay_is_the_planners_cost(three: CarriedCosts) -> None:
    """The re-simulation replays the plan (tmpnav.resimulate): the same costs, with every control step."""
    cost = three.plan_cost(PLAN)
    replayed = three.replay(PLAN)
    assert [o.cost for o in replayed] == list(cost.steps)
    assert all(o.trajectories is not None and all(len(t) > 1 for t in o.trajectories.values()) for o in replayed)
    assert {r for o in replayed for r in o.trajectories or {}} == {"r1", "r2", "r3"}
