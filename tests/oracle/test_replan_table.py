"""A replan's cost table (tmpnav.oracle.table.Origin): the moves from the robots' new starts
costed from there, the canonical states at the other rooms reached from where the plan being
revised started, so its moves between rooms are the first table's, read from the cache."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from tests.oracle.support import make_two_rooms
from tmpnav.oracle.cache import DiskCache
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.requests import Request
from tmpnav.oracle.table import build_table, initial_state, origins
from tmpnav.roadmap import with_starts
from tmpnav.types import Pose


@pytest.fixture(scope="module")
def ctx() -> OracleContext:
    return make_two_rooms()


def test_a_replans_table_costs_only_the_moves_from_its_new_starts(ctx: OracleContext, tmp_path: Path) -> None:
    """r1 started in A and now stands in C: its moves from A and B are the first table's (every
    one a cache hit), its moves from C are costed from where it stands; r2 has not moved."""
    cache = DiskCache(tmp_path)
    first = build_table(Oracle(ctx, cache, SerialExecutor()), ctx.world, "all-rooms")
    robots = tuple(replace(r, pose=Pose(4.0, 2.0, 0.0)) if r.name == "r1" else r for r in ctx.scenario.robots)
    scenario = replace(ctx.scenario, robots=robots)
    grown = with_starts(ctx.roadmap, ctx.world, robots, scenario.roadmap)
    assert grown is not None
    oracle = Oracle(OracleContext(scenario, ctx.world, grown), cache, SerialExecutor())
    origin = origins(ctx.scenario.robots, ctx.world, ctx.roadmap)
    assert origin["r1"].location == "A" and origin["r1"].state.node == ctx.roadmap.starts["r1"]
    table = build_table(oracle, ctx.world, "all-rooms", origin=origin)
    assert table.start_location["r1"] == "C"
    between = [m for m in first.single if m[0] == "r1" and m[1] in ("A", "B")]
    assert between and all(table.single[m] == first.single[m] for m in between)
    assert all(table.single[m] == first.single[m] for m in first.single if m[0] == "r2")
    new = initial_state(scenario, grown.starts["r1"], "r1")
    for room in ("A", "B"):
        alone = Oracle(OracleContext(scenario, ctx.world, grown)).evaluate([Request(("r1",), (new,), (room,))])[0]
        assert alone is not None and table.single[("r1", "C", room)] == alone.cost
    assert oracle.stats.cache_misses == 2  # r1 from C to A and to B: everything else was the first table's
    cache.close()


def test_without_origins_the_table_is_the_papers_rule(ctx: OracleContext) -> None:
    """Origins at the robots' own starts change nothing: the table of the paper's rule."""
    plain = build_table(Oracle(ctx), ctx.world, "all-rooms")
    same = build_table(Oracle(ctx), ctx.world, "all-rooms", origin=origins(ctx.scenario.robots, ctx.world, ctx.roadmap))
    assert plain.single == same.single and plain.duration == same.duration


def test_a_replans_motion_library_takes_what_holds_from_the_plans(ctx: OracleContext) -> None:
    """The library of the grown roadmap takes the plan's trees and motions from the nodes both
    share (MotionLibrary.inherit): the same motions as computed anew; none from a node numbered
    as one of its sources."""
    import numpy as np

    from tmpnav.oracle.motions import MotionLibrary

    robots = tuple(replace(r, pose=Pose(4.0, 2.0, 0.0)) if r.name == "r1" else r for r in ctx.scenario.robots)
    scenario = replace(ctx.scenario, robots=robots)
    grown = with_starts(ctx.roadmap, ctx.world, robots, scenario.roadmap)
    assert grown is not None
    plans = MotionLibrary(ctx.scenario, ctx.world, ctx.roadmap)
    a, b = ctx.roadmap.instantiations["A"][0], ctx.roadmap.instantiations["B"][0]
    for start in (a, b, ctx.roadmap.starts["r2"]):
        for goal in (a, b):
            plans.motion("r1", start, 0.5, goal)
    inherited, fresh = MotionLibrary(scenario, ctx.world, grown), MotionLibrary(scenario, ctx.world, grown)
    inherited.inherit(plans)
    assert inherited._motions and inherited.graph._trees
    for (robot, start, heading, goal), motion in list(inherited._motions.items()):
        again = fresh.motion(robot, start, heading, goal)
        assert motion is not None and again is not None and motion.path == again.path
        assert np.array_equal(motion.poses, again.poses) and np.array_equal(motion.lm_visible, again.lm_visible)
    for s, (dist, pred) in inherited.graph._trees.items():
        d, p = fresh.graph.tree(s)
        assert np.array_equal(dist, d) and np.array_equal(pred, p)
    new = grown.starts["r1"]
    assert inherited.motion("r1", new, 0.0, a) is not None  # its own start: computed on the grown roadmap


def test_a_library_is_never_shared_by_scenarios_with_other_goals(ctx: OracleContext) -> None:
    """One process planning two goal sets on one map: each run's clock reads its own goals and
    cost weights (a library kept for the first gave the second its goals: other sidings for its
    sidesteps, other windows and service times)."""
    from tmpnav.oracle.executors import library
    from tmpnav.types import Goals

    other = OracleContext(replace(ctx.scenario, goals=Goals(("B",), ())), ctx.world, ctx.roadmap)
    first, second = library(ctx), library(other)
    assert second is not first and second.scenario.goals == Goals(("B",), ())
    assert library(other) is second  # the same context again: the same library
