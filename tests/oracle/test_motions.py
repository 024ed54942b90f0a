"""The motion library's layouts of many motions for the kernel: each pose's sector reach and
scan found once per motion, and read through rows that stay valid as the tables grow."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tests.oracle.support import make_two_rooms
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.types import RangeSensor

LIDAR = RangeSensor(12.0, 2 * np.pi, 60, 0.05, 0.1, 1.3)


def test_the_reach_and_scan_rows_of_motions_are_their_poses_own() -> None:
    ctx = make_two_rooms()
    scenario = replace(ctx.scenario, models=replace(ctx.scenario.models, range_sensor=LIDAR))
    lib = MotionLibrary(scenario, ctx.world, ctx.roadmap)
    assert lib.scans is not None
    nodes = sorted(g for goals in ctx.roadmap.instantiations.values() for g in goals)
    start = ctx.roadmap.starts["r1"]
    motions = [m for g in nodes if (m := lib.motion("r1", start, 0.0, g)) is not None]
    first, later = motions[: len(motions) // 2], motions[len(motions) // 2 :]
    assert first and later

    def check(batch: list) -> None:
        codes, values, rows = lib.reach_layout(batch)
        assert np.array_equal(values[codes[rows]], np.concatenate([lib.reach(m) for m in batch]))
        scans = lib.scan_rows_all(batch)
        assert np.array_equal(scans, np.concatenate([m.scan_rows(lib.scans) for m in batch]))

    check(first)
    check(later)  # new cells and scans: both tables grow
    check([*later, *first, first[0]])  # remembered rows, in any order, repeated


def test_a_motion_set_built_before_is_taken_with_the_new_start() -> None:
    """The same node, heading and goals from another belief: the set built before, with the new
    start; what the kernel reads of it is what building it anew gives."""
    from tmpnav.oracle.motionsets import MotionSet, motion_sets
    from tmpnav.oracle.requests import StartState

    ctx = make_two_rooms()
    lib = MotionLibrary(ctx.scenario, ctx.world, ctx.roadmap)
    node = ctx.roadmap.starts["r1"]
    goals = {g for goals in ctx.roadmap.instantiations.values() for g in goals}
    cov = ((0.01, 0.0, 0.0), (0.0, 0.01, 0.0), (0.0, 0.0, 0.001))
    a = StartState(node, 0.0, (1.0, 2.0, 0.0), cov)
    b = StartState(node, 0.0, (1.1, 2.0, 0.0), cov)
    first = motion_sets(lib, {("r1", a): goals})[("r1", a)]
    again = motion_sets(lib, {("r1", b): goals})[("r1", b)]
    valid = {g: m for g in goals if (m := lib.motion("r1", node, 0.0, g)) is not None}
    fresh = MotionSet.build("r1", b, valid, ctx.scenario.models.dt)
    assert again.start == b and again.motions == first.motions == fresh.motions
    assert again.by_goal == fresh.by_goal and np.array_equal(again.prefix, fresh.prefix)
    assert np.array_equal(again.steps, fresh.steps) and np.array_equal(again.c_u, fresh.c_u)


def test_motions_are_ordered_by_their_controls_as_tuples_of_floats_order_them() -> None:
    """order_key sorts control sequences (T, 2) as tuples of their floats do: negative and
    positive values, zeros of both signs, infinities, equal sequences, and sequences that are
    each other's prefixes (the shorter first)."""
    from tmpnav.oracle.motionsets import order_key

    rng = np.random.default_rng(7)
    values = np.array([0.0, -0.0, 0.5, -0.5, 1e-300, -1e-300, 3.0, -3.0, np.inf, -np.inf, np.nextafter(0.5, 0.0)])
    for _ in range(500):
        seqs: list[np.ndarray] = []
        for _ in range(int(rng.integers(1, 20))):
            if seqs and rng.random() < 0.5:  # a prefix of another, perhaps changed at its end, perhaps longer
                base = seqs[int(rng.integers(len(seqs)))]
                c = base[: int(rng.integers(0, base.shape[0] + 1))].copy()
                if c.size and rng.random() < 0.5:
                    c[-1, int(rng.integers(2))] = rng.choice(values)
                if rng.random() < 0.5:
                    c = np.vstack([c, rng.choice(values, size=(int(rng.integers(1, 3)), 2))])
            else:
                c = rng.choice(values, size=(int(rng.integers(0, 5)), 2))
            seqs.append(c)
        by_tuples = sorted(range(len(seqs)), key=lambda i: tuple(seqs[i].ravel().tolist()))
        assert sorted(range(len(seqs)), key=lambda i: order_key(seqs[i])) == by_tuples


def test_rpp_motions_drive_the_shortened_path_and_keep_half_the_roadmap_margin() -> None:
    """models.controller: rpp on a map with narrow doors (the depot): a motion between two rooms'
    instantiations is RPP's (turning while it drives) along the roadmap path or its shortcut, or
    turn-then-drive where RPP would cut a corner into a door's frame, and says which; an RPP
    motion comes no nearer to a wall than half the margin the roadmap path keeps at its tightest."""
    from tmpnav.pipeline import load_world
    from tmpnav.roadmap import build_roadmap
    from tmpnav.roadmap.shortcut import least_clearance
    from tmpnav.shipped import configs_dir

    scenario, world = load_world(configs_dir() / "depot-jobs.yaml")
    assert scenario.models.driving == "rpp"  # auto: the robots carry a lidar
    roadmap = build_roadmap(world, scenario.robots, replace(scenario.roadmap, clearance=0.5))
    scenario = replace(scenario, roadmap=replace(scenario.roadmap, clearance=0.5))
    lib = MotionLibrary(scenario, world, roadmap)
    grid = world.grid
    origin, res = (float(grid.origin[0]), float(grid.origin[1])), float(grid.resolution)
    nodes = sorted(g for goals in roadmap.instantiations.values() for g in goals[:1])
    pursued = shortened = 0
    robot = scenario.robots[0]
    own = robot.radius + np.sqrt(2.0) * res
    for a in nodes[:8]:
        for b in nodes:
            path = lib.graph.path(a, b)
            m = lib.motion(robot.name, a, 0.0, b)
            if path is None or m is None or a == b:
                continue
            turned = lib.controls(robot.name, lib.graph.points(m.path), 0.0, pursue=False)
            same = np.array_equal(turned.controls, m.controls[: turned.n_steps])  # a job's final turn after it
            assert (m.controller == "turn-then-drive") == same
            pursued += m.controller == "rpp"
            shortened += len(m.path) < len(path)
            tightest = least_clearance(lib.graph.points(path), world.clearance, origin, res)
            keep = min(own + 0.5 * max(min(lib.required(robot.name), tightest) - own, 0.0), tightest)
            keep = max(keep - res, min(own, tightest))
            if m.controller == "rpp":
                assert least_clearance(m.poses, world.clearance, origin, res, polyline=False) >= keep - 1e-9
            assert set(m.path) <= set(path) and m.path[0] == a and m.path[-1] == b
    total = 8 * (len(nodes) - 1)
    # the depot's doors are about as wide as its robots: RPP drives half of these moves
    assert pursued >= 0.4 * total and shortened >= 0.3 * total, (pursued, shortened, total)


def test_the_library_keeps_the_motions_its_byte_budget_holds(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Least recently used motions go past MAX_MOTION_BYTES of arrays (footprint): asked again,
    one is computed again, the same; a motion of unseen landmarks counts no row of them."""
    from tmpnav.oracle import motions as motions_module

    ctx = make_two_rooms()
    scenario = replace(ctx.scenario, models=replace(ctx.scenario.models, range_sensor=LIDAR))
    lib = MotionLibrary(scenario, ctx.world, ctx.roadmap)
    nodes = sorted(g for goals in ctx.roadmap.instantiations.values() for g in goals)
    start = ctx.roadmap.starts["r1"]
    every = [m for g in nodes if (m := lib.motion("r1", start, 0.0, g)) is not None]
    assert lib._motion_bytes == sum(motions_module.footprint(m) for m in every)
    unseen = every[0]
    if not scenario.models.others_fused:
        assert unseen.lm_visible.strides[0] == 0
    budget = sum(motions_module.footprint(m) for m in every[-2:])
    monkeypatch.setattr(motions_module, "MAX_MOTION_BYTES", budget)
    small = MotionLibrary(scenario, ctx.world, ctx.roadmap)
    kept = [small.motion("r1", start, 0.0, g) for g in nodes]
    assert 1 <= len(small._motions) < len(every) and small._motion_bytes <= budget
    again = small.motion("r1", start, 0.0, nodes[0])  # dropped: computed again
    assert again is not None and again is not kept[0] and np.array_equal(again.poses, kept[0].poses)
