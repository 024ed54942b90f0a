"""The true start a simulated session draws: from the initial belief, free of the map."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tmpnav.execution.trace import free_start
from tmpnav.pipeline import load_world
from tmpnav.shipped import configs_dir
from tmpnav.types import Pose


def test_a_true_start_is_drawn_free_of_the_map_and_as_drawn_where_that_is_free() -> None:
    """A robot 0.29 m from an occupied pixel of office-ros' ROS map (where its r1 started before
    it was moved clear) with a 0.1 m std: a plain draw puts its disc in collision in about a
    third of sessions; the start drawn is free
    every time, and is the plain draw itself whenever that is free."""
    scenario, world = load_world(configs_dir() / "office-ros.yaml")
    robot = replace(scenario.robots[0], pose=Pose(3.0, 7.2, 0.0))
    mean, cov = robot.pose.as_array(), np.array(robot.covariance)
    rng = np.random.default_rng(7)
    plain_hits = 0
    for _ in range(300):
        z = rng.standard_normal(3)
        plain = mean + np.linalg.cholesky(cov) @ z
        free = world.is_free(plain[None, :2], robot.radius)[0]
        plain_hits += not free
        drawn = free_start(mean, cov, z, world, robot.radius)
        assert world.is_free(drawn[None, :2], robot.radius)[0]
        if free:
            assert np.array_equal(drawn, plain)
        assert np.array_equal(drawn, free_start(mean, cov, z, world, robot.radius))  # deterministic
    assert plain_hits > 30
