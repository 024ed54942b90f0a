"""The compiled joint EKF that sessions run (tmpnav.execution.fast_ekf) against its filterpy
reference (tmpnav.execution.joint_ekf): the same sessions, the same figures to rounding."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from tests.test_execution import R1_EAST, R1_OUT, R2_OUT, move
from tmpnav.execution import Draws, Session, SessionTrace
from tmpnav.execution.localisers import Localisation
from tmpnav.pipeline import load_world
from tmpnav.types import RangeSensor, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility

ROOT = Path(__file__).resolve().parents[2]
#: the shipped scenarios' lidar (docs/scenario.md's defaults)
LIDAR = RangeSensor(
    range=12.0, fov=2 * math.pi, beams=60, sigma_range=0.03, min_range=0.1, max_incidence=math.radians(75),
    divergence=0.01,
)  # fmt: skip
#: r1 leaves L1 and drives east with r2 (leaving L10), then r2 drives back: landmarks, partners in sight
QUEUES = {
    "r1": (move(0, "r1", R1_OUT), move(1, "r1", R1_EAST, partner="r2")),
    "r2": (move(1, "r2", R2_OUT, partner="r1"), move(2, "r2", [(5.0, 8.0), (5.0, 6.5)])),
}


def _corridor(lidar: bool) -> tuple[Scenario, World, LandmarkVisibility]:
    scenario, world = load_world(ROOT / "configs" / "corridor.yaml")
    if lidar:
        models = dataclasses.replace(scenario.models, range_sensor=LIDAR)
        scenario = dataclasses.replace(scenario, models=models)
    return scenario, world, LandmarkVisibility(world, scenario.models.landmark_sensor.range)


def _run(
    setup: tuple[Scenario, World, LandmarkVisibility], seed: int, mutual: bool, compiled: bool, rpp: bool = False
) -> SessionTrace:
    scenario, world, vis = setup
    sensor = scenario.models.range_sensor
    beams = sensor.beams if sensor is not None else 0
    draws = Draws.draw(seed, 0, 2, 2000, world.landmark_xy.shape[0], beams)
    queues = QUEUES
    if rpp:
        queues = {r: tuple(dataclasses.replace(m, controller="rpp") for m in q) for r, q in QUEUES.items()}
    return Session(scenario, world, queues, draws, vis, mutual, Localisation(compiled=compiled)).run()


@pytest.mark.parametrize("lidar", [False, True], ids=["landmarks and partners", "with a lidar"])
@pytest.mark.parametrize("mutual", [True, False], ids=["config 1", "config 2"])
def test_the_compiled_filter_is_the_reference(lidar: bool, mutual: bool) -> None:
    setup = _corridor(lidar)
    for seed in range(2):
        fast, ref = _run(setup, seed, mutual, True), _run(setup, seed, mutual, False)
        assert not fast.truncated and not ref.truncated
        assert [(m.step, m.robot, m.start, m.end) for m in fast.moves] == [
            (m.step, m.robot, m.start, m.end) for m in ref.moves
        ]
        for robot in ("r1", "r2"):
            np.testing.assert_allclose(fast.errors[robot], ref.errors[robot], rtol=1e-7, atol=1e-9)
            np.testing.assert_allclose(fast.planned_nees[robot], ref.planned_nees[robot], rtol=1e-6)
            np.testing.assert_allclose(fast.own_nees[robot], ref.own_nees[robot], rtol=1e-6, atol=1e-9)
            assert fast.c_sigma[robot] == pytest.approx(ref.c_sigma[robot], rel=1e-9)
            assert fast.c_goal[robot] == pytest.approx(ref.c_goal[robot], rel=1e-7, abs=1e-9)
        assert fast.beams == ref.beams and fast.wall_hits == ref.wall_hits and fast.contacts == ref.contacts
        if lidar:
            assert fast.beams["r1"][0] > 1000


def test_the_compiled_count_is_hits_wall_and_the_radii() -> None:
    """tmpnav.execution.contact against tmpnav.belief.risk.hits_wall and the radii added."""
    from tmpnav.belief.risk import hits_wall
    from tmpnav.execution.contact import walls_and_touches

    _, world, _ = _corridor(False)
    rng = np.random.default_rng(5)
    (x0, y0), (rows, cols) = world.grid.origin, world.grid.shape
    span = np.array([cols, rows]) * world.grid.resolution
    for _ in range(200):
        truth = np.column_stack([rng.uniform(-1.0, 1.1, (4, 2)) * span + (x0, y0), rng.uniform(-3, 3, 4)])
        truth[1, :2] = truth[0, :2] + rng.normal(0.0, 0.3, 2)  # now and then two robots closer than their radii
        radii = rng.uniform(0.1, 0.4, 4)
        walls, touch = walls_and_touches(world, truth, radii)
        gap = np.hypot(*(truth[:, None, :2] - truth[None, :, :2]).transpose(2, 0, 1))
        near = (gap < radii[:, None] + radii[None, :]) & ~np.eye(4, dtype=bool)
        np.testing.assert_array_equal(walls, hits_wall(world.grid, world.clearance, truth[:, :2], radii))
        np.testing.assert_array_equal(touch, near.any(axis=1))


def test_with_rpp_at_nav2s_rate_the_compiled_filter_is_the_reference_and_consistent() -> None:
    """Moves RPP drives: each control step's commands at nav2's rate, the truth and both filters
    following them one by one; the two filters agree, and the lidar's filter stays consistent
    (its own NEES about a consistent filter's 1.39)."""
    setup = _corridor(True)
    for seed in range(2):
        fast, ref = _run(setup, seed, True, True, rpp=True), _run(setup, seed, True, False, rpp=True)
        assert not fast.truncated and [m.end for m in fast.moves] == [m.end for m in ref.moves]
        for robot in ("r1", "r2"):
            np.testing.assert_allclose(fast.errors[robot], ref.errors[robot], rtol=1e-7, atol=1e-9)
            np.testing.assert_allclose(fast.own_nees[robot], ref.own_nees[robot], rtol=1e-6, atol=1e-9)
        own = np.concatenate([fast.own_nees[r] for r in ("r1", "r2")])
        assert 0.7 <= float(np.median(own)) <= 2.2 and float(np.mean(own > 9.0)) <= 0.05
