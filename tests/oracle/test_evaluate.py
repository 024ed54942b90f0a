"""What the oracle computes: minimum over instantiations, exact factorisation, Fig. 2."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tests.oracle.support import actions
from tmpnav.oracle.cache import NullCache
from tmpnav.oracle.evaluate import Request
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import initial_state
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap

ROOT = Path(__file__).resolve().parents[2]


def evaluate(ctx: OracleContext, reqs: list[Request]):  # type: ignore[no-untyped-def]
    return Oracle(ctx, NullCache(), SerialExecutor()).evaluate(reqs)


def test_same_inputs_same_beliefs(two_rooms: OracleContext) -> None:
    assert evaluate(two_rooms, actions(two_rooms)) == evaluate(two_rooms, actions(two_rooms))


def test_result_is_the_minimum_over_instantiations(two_rooms: OracleContext) -> None:
    sc, rm = two_rooms.scenario, two_rooms.roadmap
    s1 = initial_state(sc, rm.starts["r1"], "r1")
    best = evaluate(two_rooms, [Request(("r1",), (s1,), ("B",))])[0]
    assert best.goal_nodes[0] in rm.instantiations["B"]
    assert best.paths[0][0] == rm.starts["r1"] and best.paths[0][-1] == best.goal_nodes[0]
    assert best.cost == pytest.approx(sum(t.total(sc.cost) for t in best.terms))


def test_factorised_pair_equals_its_joint_simulation(two_rooms: OracleContext) -> None:
    """r1 stays in A and r2 in B, a wall between them: they never see each other."""
    sc, rm = two_rooms.scenario, two_rooms.roadmap
    s1, s2 = initial_state(sc, rm.starts["r1"], "r1"), initial_state(sc, rm.starts["r2"], "r2")
    factorised = Request(("r1", "r2"), (s1, s2), ("A", "B"))
    block = factorised.cov0()  # the same block-diagonal covariance, given explicitly:
    forced = replace(factorised, joint_cov=tuple(tuple(row) for row in block))  # forces the joint EKF
    singles = [Request(("r1",), (s1,), ("A",)), Request(("r2",), (s2,), ("B",))]
    f, j, a, b = evaluate(two_rooms, [factorised, forced, *singles])
    assert f.mutual_steps == 0 and j.mutual_steps == 0
    assert f.cost == pytest.approx(j.cost, abs=1e-9)
    assert f.cost == pytest.approx(a.cost + b.cost, abs=1e-12)
    assert f.goal_nodes == j.goal_nodes
    joint = np.array(j.final_cov)
    assert np.array_equal(joint[:3, 3:], np.zeros((3, 3)))  # no observation ever coupled them
    # a factorised result reports each robot's belief at its own arrival (the joint run
    # lets the robot that arrives first keep observing while it waits)
    np.testing.assert_allclose(np.array(f.final_cov)[:3, :3], np.array(a.final_cov), atol=0)


def test_factorisation_saves_joint_evaluations(two_rooms: OracleContext) -> None:
    oracle = Oracle(two_rooms, NullCache(), SerialExecutor())
    oracle.evaluate(actions(two_rooms))
    sims = oracle.stats.sims
    assert sims.joint_factorized > 0 and sims.joint_sims > 0
    assert sims.steps_computed < sims.steps_total  # shared prefixes ran once


@pytest.mark.slow
def test_fig2_mutual_observations_help_the_landmark_starved_robot() -> None:
    """The paper's Fig. 2 case on the corridor: r1 L1 -> L10, r2 L10 -> L1.

    L10 and the west end of the corridor have no landmarks: r1 ends its path there. With
    mutual observations its final position uncertainty is clearly lower than without.
    """
    sc, world = load_world(ROOT / "configs" / "corridor.yaml")
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    traces = {}
    for mutual in (True, False):
        scenario = replace(sc, models=replace(sc.models, mutual_observations=mutual))
        ctx = OracleContext(scenario, world, rm)
        starts = tuple(initial_state(scenario, rm.starts[r], r) for r in ("r1", "r2"))
        res = evaluate(ctx, [Request(("r1", "r2"), starts, ("L10", "L1"))])[0]
        cov = np.array(res.final_cov)
        traces[mutual] = float(np.trace(cov[:2, :2]))  # r1's position block
    assert traces[True] < 0.5 * traces[False], traces


def test_a_world_without_landmarks(two_rooms: OracleContext) -> None:
    """Landmarks are optional in a scenario: the robots then only predict (and see each other)."""
    world = two_rooms.world
    bare = replace(
        two_rooms,
        world=replace(world, landmarks=(), landmark_xy=np.zeros((0, 2)), fingerprint=world.fingerprint + "/bare"),
    )
    with_landmarks, without = evaluate(two_rooms, actions(two_rooms)), evaluate(bare, actions(bare))
    assert all(r is not None for r in without)
    singles = [(a, b) for a, b in zip(with_landmarks, without, strict=True) if len(a.robots) == 1 and a.paths[0][1:]]
    assert all(b.terms[0].c_Sigma >= a.terms[0].c_Sigma for a, b in singles)
    assert any(b.terms[0].c_Sigma > a.terms[0].c_Sigma for a, b in singles)
