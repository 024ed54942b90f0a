"""A replan's roadmap: the plan's roadmap with the robots' new starts added as sources
(tmpnav.roadmap.with_starts), whose edges lead out only."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tests.oracle.support import make_two_rooms
from tmpnav.oracle.evaluate import Request
from tmpnav.oracle.executors import OracleContext, SerialExecutor
from tmpnav.oracle.keys import context_digest, request_key, source_bytes
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.table import initial_state
from tmpnav.roadmap import RoadmapGraph, with_starts
from tmpnav.roadmap.graph import safe_weights
from tmpnav.types import Pose


@pytest.fixture(scope="module")
def ctx() -> OracleContext:
    return make_two_rooms()


def moved(ctx: OracleContext, **poses: tuple[float, float, float]):  # type: ignore[no-untyped-def]
    """The scenario with robots at new poses, and its roadmap with them added."""
    robots = tuple(replace(r, pose=Pose(*poses[r.name])) if r.name in poses else r for r in ctx.scenario.robots)
    scenario = replace(ctx.scenario, robots=robots)
    return scenario, with_starts(ctx.roadmap, ctx.world, robots, scenario.roadmap)


def a_free_pose(ctx: OracleContext, room: str) -> tuple[float, float, float]:
    """A point between two of the room's instantiations (not a node of the roadmap)."""
    a, b = ctx.roadmap.instantiations[room][:2]
    x, y = (ctx.roadmap.nodes[a] + ctx.roadmap.nodes[b]) / 2
    return float(x), float(y), 0.3


def test_every_path_between_the_grown_nodes_is_the_same(ctx: OracleContext) -> None:
    room = ctx.scenario.rooms[0].name
    _, added = moved(ctx, r1=a_free_pose(ctx, room))
    assert added is not None and added.sources and added.base == ctx.roadmap.fingerprint
    assert added.grown == ctx.roadmap.fingerprint != added.fingerprint
    new = added.starts["r1"]
    assert new == ctx.roadmap.n_nodes and added.starts["r2"] == ctx.roadmap.starts["r2"]  # r2 has not moved
    assert (added.edges[ctx.roadmap.edges.shape[0] :, 0] == new).all()  # the new edges: out of the start
    before, after = RoadmapGraph(ctx.roadmap), RoadmapGraph(added)
    for source in (*ctx.roadmap.instantiations[room], ctx.roadmap.starts["r2"]):
        d0, _ = before.tree(source)
        d1, _ = after.tree(source)
        assert np.array_equal(d0, d1[: ctx.roadmap.n_nodes]) and np.isinf(d1[new])  # nothing drives into it
        for target in range(0, ctx.roadmap.n_nodes, 7):
            assert before.path(source, target) == after.path(source, target)
    assert after.path(new, ctx.roadmap.instantiations[room][0]) is not None


def test_the_safe_weights_of_the_grown_edges_are_those_of_the_plans_roadmap(ctx: OracleContext) -> None:
    _, added = moved(ctx, r1=a_free_pose(ctx, ctx.scenario.rooms[0].name))
    assert added is not None
    w0, w1 = safe_weights(ctx.roadmap, ctx.world, 0.3), safe_weights(added, ctx.world, 0.3)
    assert np.array_equal(w0, w1[: len(w0)]) and (w1[len(w0) :] >= added.weights[len(w0) :]).all()


def test_moves_from_the_grown_nodes_keep_their_keys_and_results(ctx: OracleContext) -> None:
    """A move from a room of the plan's roadmap is the same question in the replan: its key and
    its answer; a move from the new start has a key of its own."""
    room, other = ctx.scenario.rooms[0].name, ctx.scenario.rooms[1].name
    scenario, added = moved(ctx, r1=a_free_pose(ctx, room))
    assert added is not None
    node = ctx.roadmap.instantiations[room][0]
    start = replace(initial_state(ctx.scenario, node, "r1"), heading=0.0)
    from_room = Request(("r1",), (start,), (other,))
    old, new = OracleContext(ctx.scenario, ctx.world, ctx.roadmap), OracleContext(scenario, ctx.world, added)
    k0 = request_key(context_digest(ctx.scenario, ctx.world, ctx.roadmap), ctx.scenario, from_room)
    k1 = request_key(context_digest(scenario, ctx.world, added), scenario, from_room, source_bytes(added))
    assert k0 == k1
    a = Oracle(old, executor=SerialExecutor()).evaluate([from_room])[0]
    b = Oracle(new, executor=SerialExecutor()).evaluate([from_room])[0]
    assert a is not None and b is not None and (a.cost, a.paths) == (b.cost, b.paths)
    from_start = Request(("r1",), (initial_state(scenario, added.starts["r1"], "r1"),), (other,))
    moved_on = replace(ctx.scenario.robots[0], pose=Pose(*a_free_pose(ctx, other)))
    _, elsewhere = moved(ctx, r1=(moved_on.pose.x, moved_on.pose.y, moved_on.pose.theta))
    assert elsewhere is not None and elsewhere.starts["r1"] == added.starts["r1"]  # the same node number
    key = request_key(context_digest(scenario, ctx.world, added), scenario, from_start, source_bytes(added))
    there = request_key(context_digest(scenario, ctx.world, elsewhere), scenario, from_start, source_bytes(elsewhere))
    assert key != there  # the same node number elsewhere is another question
    result = Oracle(new, executor=SerialExecutor()).evaluate([from_start])[0]
    assert result is not None and result.paths[0][0] == added.starts["r1"]


def test_a_start_on_a_node_is_that_node_and_one_in_a_wall_joins_nothing(ctx: OracleContext) -> None:
    node = ctx.roadmap.instantiations[ctx.scenario.rooms[0].name][0]
    x, y = (float(v) for v in ctx.roadmap.nodes[node])
    _, on_node = moved(ctx, r1=(x, y, 0.0))
    assert on_node is not None and on_node.starts["r1"] == node and not on_node.sources
    xmin, ymin, _, _ = ctx.world.grid.extent
    _, walled = moved(ctx, r1=(xmin + 0.01, ymin + 0.01, 0.0))  # the map's corner: no free space
    assert walled is None


def test_graphs_of_one_grown_roadmap_share_its_trees(ctx: OracleContext, monkeypatch: pytest.MonkeyPatch) -> None:
    """A planning service's revisions each make a graph of the site's roadmap with other starts:
    the trees from the grown roadmap's nodes, and what is derived from them, are computed once
    in the process; a graph of other weights computes its own."""
    from tmpnav.roadmap import graph as graph_module

    monkeypatch.setattr(graph_module, "_SHARED", graph_module._Shared(graph_module.SHARED_BYTES))
    calls: list[list[int]] = []
    real = graph_module.dijkstra

    def counted(matrix, **kw):  # type: ignore[no-untyped-def]
        calls.append(list(kw["indices"]))
        return real(matrix, **kw)

    monkeypatch.setattr(graph_module, "dijkstra", counted)
    room = ctx.scenario.rooms[0].name
    sources = list(ctx.roadmap.instantiations[room])
    first = RoadmapGraph(ctx.roadmap)
    first.prepare(sources)
    made = first.derived(sources[0], ("test",), lambda: np.arange(3.0))
    _, added = moved(ctx, r1=a_free_pose(ctx, room))
    second = RoadmapGraph(added)
    second.prepare(sources)
    assert calls == [sorted(sources)]  # the second graph found every tree
    for s in sources:
        assert np.array_equal(first.tree(s)[0], second.tree(s)[0][: ctx.roadmap.n_nodes])
        assert np.isinf(second.tree(s)[0][ctx.roadmap.n_nodes :]).all()  # its start: unreached from there
    # derived arrays are shared between graphs with as many nodes only
    assert RoadmapGraph(ctx.roadmap).derived(sources[0], ("test",), lambda: np.zeros(3)) is made
    assert second.derived(sources[0], ("test",), lambda: np.zeros(3)).sum() == 0.0
    heavier = RoadmapGraph(ctx.roadmap, ctx.roadmap.weights * 2.0)
    heavier.prepare(sources[:1])
    assert calls[-1] == sources[:1]


def test_the_shared_trees_keep_to_their_bytes() -> None:
    from tmpnav.roadmap.graph import _Shared

    shared = _Shared(limit=100)
    shared.put(("a",), (np.zeros(5),))  # 40 bytes
    shared.put(("b",), (np.zeros(5),))
    assert shared.get(("a",)) is not None  # a used last: b goes first
    shared.put(("c",), (np.zeros(5),))
    assert shared.get(("b",)) is None and shared.get(("a",)) is not None and shared.size == 80
