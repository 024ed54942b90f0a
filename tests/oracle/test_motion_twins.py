"""Robots of one model share their nominal motions (tmpnav.oracle.motions.MotionLibrary._alike):
a motion another robot of the same radius, speed and turn rate drove from the same node and
heading is the one the robot would drive, with its own name and noise stream."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.oracle.support import make_two_rooms
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import NominalMotion
from tmpnav.types import RangeSensor

LIDAR = RangeSensor(12.0, 2 * np.pi, 60, 0.05, 0.1, 1.3)


def same_motion(a: NominalMotion, b: NominalMotion) -> bool:
    arrays = ("controls", "poses", "node_steps", "lm_visible", "cells", "scan_keys")
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in arrays) and (
        (a.robot, a.path, a.noise_seed, a.controller) == (b.robot, b.path, b.noise_seed, b.controller)
    )


@pytest.mark.parametrize("sensor", [None, LIDAR], ids=["turn-then-drive", "rpp"])
def test_a_robot_takes_the_motion_of_its_twin_as_it_would_drive_it(sensor: RangeSensor | None) -> None:
    ctx = make_two_rooms()
    scenario = replace(ctx.scenario, models=replace(ctx.scenario.models, range_sensor=sensor))
    shared, fresh = MotionLibrary(scenario, ctx.world, ctx.roadmap), MotionLibrary(scenario, ctx.world, ctx.roadmap)
    start = ctx.roadmap.starts["r1"]
    goals = sorted(g for nodes in ctx.roadmap.instantiations.values() for g in nodes)
    taken = 0
    for g in goals:
        first = shared.motion("r1", start, 0.3, g)
        twin = shared.motion("r2", start, 0.3, g)
        own = fresh.motion("r2", start, 0.3, g)
        assert (twin is None) == (own is None) == (first is None)
        if twin is None or own is None or first is None:
            continue
        assert same_motion(twin, own) and twin.noise_seed != first.noise_seed
        assert twin.controls is first.controls and twin.rows is first.rows  # shared, not computed again
        taken += 1
    assert taken >= 3


def test_robots_of_another_radius_drive_their_own_motions() -> None:
    ctx = make_two_rooms()
    robots = tuple(replace(r, radius=r.radius + 0.05) if r.name == "r2" else r for r in ctx.scenario.robots)
    scenario = replace(ctx.scenario, robots=robots, models=replace(ctx.scenario.models, range_sensor=LIDAR))
    lib = MotionLibrary(scenario, ctx.world, ctx.roadmap)
    start = ctx.roadmap.starts["r1"]
    goal = max(g for nodes in ctx.roadmap.instantiations.values() for g in nodes)
    first, second = lib.motion("r1", start, 0.3, goal), lib.motion("r2", start, 0.3, goal)
    assert first is not None and second is not None and second.controls is not first.controls
