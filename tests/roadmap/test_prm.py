"""The OMPL roadmap: deterministic, with connected pose instantiations in every room."""

from __future__ import annotations

import re
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tmpnav.errors import RoadmapError
from tmpnav.pipeline import load_world
from tmpnav.roadmap import RoadmapGraph, build_roadmap, prm
from tmpnav.world.geometry import points_in_polygon

ROOT = Path(__file__).resolve().parents[2]
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


@pytest.fixture(scope="module")
def loaded():  # type: ignore[no-untyped-def]
    return load_world(TWO_ROOMS)


def test_same_seed_same_roadmap_in_this_process(loaded) -> None:  # type: ignore[no-untyped-def]
    sc, world = loaded
    a = build_roadmap(world, sc.robots, sc.roadmap)
    b = build_roadmap(world, sc.robots, sc.roadmap)
    assert a.fingerprint == b.fingerprint
    assert np.array_equal(a.nodes, b.nodes) and np.array_equal(a.edges, b.edges)
    c = build_roadmap(world, sc.robots, replace(sc.roadmap, seed=sc.roadmap.seed + 1))
    assert c.fingerprint != a.fingerprint


def test_same_seed_same_roadmap_across_processes(loaded) -> None:  # type: ignore[no-untyped-def]
    sc, world = loaded
    here = build_roadmap(world, sc.robots, sc.roadmap).fingerprint
    code = (
        "from tmpnav.pipeline import load_world; from tmpnav.roadmap import build_roadmap;"
        f"sc, w = load_world({str(TWO_ROOMS)!r}); print(build_roadmap(w, sc.robots, sc.roadmap).fingerprint)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.stdout.strip() == here
    assert "nanobind" not in out.stderr


def test_instantiations_lie_in_their_rooms_free_and_connected(loaded) -> None:  # type: ignore[no-untyped-def]
    sc, world = loaded
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    graph = RoadmapGraph(rm)
    radius = max(r.radius for r in sc.robots)
    for room in sc.rooms:
        ids = rm.instantiations[room.name]
        assert len(ids) == sc.roadmap.instantiations
        pts = rm.nodes[list(ids)]
        assert points_in_polygon(pts, np.array(room.polygon)).all()
        assert world.is_free(pts, radius).all()
        for robot in sc.robots:
            assert all(graph.path(rm.starts[robot.name], i) is not None for i in ids)


def test_edges_are_collision_free(loaded) -> None:
    """Along every edge, densely sampled, the robot's disc never touches an occupied cell.

    Nodes and OMPL's checks (every half cell) keep a cell of margin beyond the radius; a
    sample between two checks may eat into that margin, never into the disc.
    """  # type: ignore[no-untyped-def]
    sc, world = loaded
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    radius = max(r.radius for r in sc.robots)
    t = np.linspace(0, 1, 60)[:, None, None]
    a, b = rm.nodes[rm.edges[:, 0]], rm.nodes[rm.edges[:, 1]]
    samples = (a[None] + t * (b - a)[None]).reshape(-1, 2)
    i, j, inside = world.grid.cells(samples)
    assert inside.all() and (world.clearance[i, j] >= radius).all()


def test_shortest_path_is_shortest(loaded) -> None:  # type: ignore[no-untyped-def]
    sc, world = loaded
    rm = build_roadmap(world, sc.robots, sc.roadmap)
    graph = RoadmapGraph(rm)
    s, g = rm.starts["r1"], rm.instantiations["B"][0]
    path = graph.path(s, g)
    assert path is not None and path[0] == s and path[-1] == g
    length = float(np.linalg.norm(np.diff(rm.nodes[list(path)], axis=0), axis=1).sum())
    assert length == pytest.approx(graph.distance(s, g))


def test_room_that_cannot_connect_is_named(loaded, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    sc, world = loaded
    monkeypatch.setattr(prm, "GROWTH", 1)  # no growth: 10 milestones of one neighbour each
    with pytest.raises(RoadmapError, match=r"room '[ABC]': none of its 3 pose instantiations connects .* grown to 10"):
        build_roadmap(world, sc.robots, replace(sc.roadmap, samples=10, neighbors=1))


def test_bounce_walks_find_the_doors_that_uniform_samples_miss(loaded) -> None:  # type: ignore[no-untyped-def]
    """One neighbour per milestone: uniform sampling alone did not get through the doors even at
    32 times 10 milestones; from the second growth round on, half of each round on PRM's bounce
    walks from the milestones that failed to connect does, within a few rounds."""
    sc, world = loaded
    small = build_roadmap(world, sc.robots, replace(sc.roadmap, samples=10, neighbors=1))
    assert set(small.instantiations) == {"A", "B", "C"} and all(small.instantiations.values())
    assert small.n_nodes < 320  # where uniform samples alone still had not connected it


def test_a_roadmap_too_small_grows_until_every_room_connects(loaded) -> None:  # type: ignore[no-untyped-def]
    """10 milestones of two neighbours each do not find the doors: the roadmap doubles until every
    room reaches a start, the same on every run; a roadmap that connects at its size is not grown."""
    sc, world = loaded
    small = build_roadmap(world, sc.robots, replace(sc.roadmap, samples=10, neighbors=2))
    assert set(small.instantiations) == {"A", "B", "C"} and all(small.instantiations.values())
    assert small.n_nodes > 40
    again = build_roadmap(world, sc.robots, replace(sc.roadmap, samples=10, neighbors=2))
    assert np.array_equal(small.nodes, again.nodes) and np.array_equal(small.edges, again.edges)
    enough = build_roadmap(world, sc.robots, sc.roadmap)
    assert enough.n_nodes <= sc.roadmap.samples + 3 * sc.roadmap.instantiations + len(sc.robots)


def test_only_the_roadmap_stage_imports_ompl() -> None:
    offenders = [
        str(p.relative_to(ROOT))
        for p in (ROOT / "tmpnav").rglob("*.py")
        if re.search(r"^\s*(from|import)\s+ompl\b", p.read_text(), re.M) and p.name != "prm.py"
    ]
    assert offenders == []


def test_instantiations_avoid_pockets_of_a_room_no_robot_reaches(tmp_path: Path) -> None:
    """A sealed box inside room A (as noise in a map can seal off a corner): its free cells lie in
    the room, but OMPL refuses them as milestones, so no instantiation may be drawn there."""
    from tests.scenario.helpers import base_scenario, build_world

    doc = base_scenario()
    doc["map"]["walls"].append([[0.5, 3.5], [2.0, 3.5], [2.0, 5.5], [0.5, 5.5], [0.5, 3.5]])
    doc["robots"][0]["pose"] = [3.5, 4.5, 0.0]
    box = np.array([[0.5, 3.5], [2.0, 3.5], [2.0, 5.5], [0.5, 5.5]])
    sc, world = build_world(tmp_path, doc)
    for seed in range(1, 9):
        rm = build_roadmap(world, sc.robots, replace(sc.roadmap, seed=seed, instantiations=4))
        assert not points_in_polygon(rm.nodes[list(rm.instantiations["A"])], box).any()


def test_compiled_edge_checks_agree_with_ompls_discrete_motion_validator(loaded) -> None:  # type: ignore[no-untyped-def]
    """The roadmap's motion validator (one compiled check per edge) answers as OMPL's own
    DiscreteMotionValidator with the same validity checker, on random segments of the map:
    short and long, through doors and walls, ending inside and outside the free space."""
    from ompl import base as ob

    from tmpnav.roadmap import prm

    sc, world = loaded
    radius = max(r.radius for r in sc.robots)
    free = prm.reachable_free_space(world, radius, np.array([[r.pose.x, r.pose.y] for r in sc.robots]))
    xmin, ymin, xmax, ymax = world.grid.extent
    space = prm.plane(ob, world)
    ours, theirs = ob.SpaceInformation(space), ob.SpaceInformation(space)
    for si in (ours, theirs):
        si.setStateValidityChecker(prm._validity_checker(world, free))
        si.setStateValidityCheckingResolution(0.5 * world.grid.resolution / space.getMaximumExtent())
    validator = prm._motion_validator(ob, ours, space, world, free)
    ours.setMotionValidator(validator)
    ours.setup()
    theirs.setup()
    rng = np.random.default_rng(3)
    a, b = ours.allocState(), ours.allocState()
    answers = {True: 0, False: 0}
    for k in range(3000):
        p = rng.uniform((xmin, ymin), (xmax, ymax))
        q = p + rng.normal(scale=0.3 if k % 2 else 3.0, size=2)
        a[0], a[1], b[0], b[1] = float(p[0]), float(p[1]), float(q[0]), float(q[1])
        expected = theirs.checkMotion(a, b)
        assert ours.checkMotion(a, b) == expected, (p, q)
        answers[expected] += 1
    assert min(answers.values()) > 300  # both answers were tested
    del validator, ours, theirs


def test_a_start_too_close_to_a_wall_for_a_milestone_is_named(loaded) -> None:  # type: ignore[no-untyped-def]
    """A robot that fits where it stands, but nearer a wall than the radius and a grid cell that
    the roadmap's milestones keep: one error naming the robot and the clearance, not a crash."""
    sc, world = loaded
    radius = max(r.radius for r in sc.robots)
    res = world.grid.resolution
    i, j = np.argwhere((world.clearance > radius + 0.3 * res) & (world.clearance < radius + 0.7 * res))[0]
    x, y = world.grid.origin[0] + (j + 0.5) * res, world.grid.origin[1] + (i + 0.5) * res
    robots = (replace(sc.robots[0], pose=replace(sc.robots[0].pose, x=float(x), y=float(y))), *sc.robots[1:])
    with pytest.raises(RoadmapError, match=rf"robot '{sc.robots[0].name}' starts at .* closer to a wall"):
        build_roadmap(world, robots, sc.roadmap)


def test_a_door_gets_milestones_along_its_middle_and_paths_through_it_keep_off_its_frames(loaded) -> None:  # type: ignore[no-untyped-def]
    """With a clearance, each 1.2 m door of the two-rooms world gets a milestone in its middle and
    one on either side along its axis (the wall's normal); the roadmap holds them, and the path
    from room A to room B crosses each door near its middle. Without a
    clearance (the paper's roadmap), none."""
    import itertools

    import numpy as np

    from tmpnav.roadmap.prm import passage_milestones, reachable_free_space

    sc, world = loaded
    radius = max(r.radius for r in sc.robots)
    starts = np.array([[r.pose.x, r.pose.y] for r in sc.robots])
    free = reachable_free_space(world, radius, starts)
    points = passage_milestones(world, radius, 0.5, free)
    res = world.grid.resolution
    for middle in (3.0, 9.0):  # door-A and door-B, in the wall y = 4
        mine = points[np.abs(points[:, 0] - middle) < 2 * res]
        assert len(mine) == 3, points
        assert sorted(np.round(mine[:, 1] - 4.0, 1).tolist()) == pytest.approx([-0.8, 0.0, 0.8], abs=0.1)
    assert len(passage_milestones(world, radius, 0.0, free)) == 0
    roadmap = build_roadmap(world, sc.robots, replace(sc.roadmap, clearance=0.5))
    for p in points:
        assert np.min(np.linalg.norm(roadmap.nodes - p, axis=1)) < 1e-9
    from tmpnav.roadmap.graph import safe_weights

    graph = RoadmapGraph(roadmap, safe_weights(roadmap, world, radius, 0.5))  # as the motions use it
    path = graph.path(roadmap.instantiations["A"][0], roadmap.instantiations["B"][0])
    assert path is not None
    xy = roadmap.nodes[list(path)]
    pairs = itertools.pairwise(xy)
    crossings = [a + (b - a) * (4.0 - a[1]) / (b[1] - a[1]) for a, b in pairs if (a[1] - 4.0) * (b[1] - 4.0) < 0]
    # within 0.1 m of a door's middle: its footprint 0.25 m and more from the frames (0.6 m away)
    assert len(crossings) == 2 and all(min(abs(c[0] - 3.0), abs(c[0] - 9.0)) <= 0.1 for c in crossings)
