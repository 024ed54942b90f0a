"""The detour search (tmpnav/attachment/detours.py) on a lattice roadmap of a 3 m corridor: a
robot that meets another head-on passes it on a parallel lane, driven as path_controls drives
it, clear of the other at every control step; no detour where none exists."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tmpnav.attachment.detours import Drive, Obstacle, detour
from tmpnav.belief.controls import path_controls
from tmpnav.types import Roadmap

DT, SPEED, TURN = 0.5, 0.5, 1.0


def lattice(length: float = 12.0, width: float = 3.0, spacing: float = 0.5) -> Roadmap:
    """Nodes every ``spacing`` m over a corridor, joined to their 8 neighbours."""
    xs, ys = np.arange(0.0, length + 1e-9, spacing), np.arange(0.0, width + 1e-9, spacing)
    nodes = np.array([(x, y) for x in xs for y in ys])
    index = {(round(x / spacing), round(y / spacing)): k for k, (x, y) in enumerate(nodes)}
    edges = []
    for (i, j), k in index.items():
        for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
            other = index.get((i + di, j + dj))
            if other is not None:
                edges.append((k, other))
    e = np.array(edges)
    weights = np.hypot(*(nodes[e[:, 0]] - nodes[e[:, 1]]).T)
    return Roadmap(nodes, e, weights, {}, {})


def node_at(roadmap: Roadmap, x: float, y: float) -> int:
    return int(np.argmin(np.hypot(*(roadmap.nodes - (x, y)).T)))


def centre_line(roadmap: Roadmap, x0: float, x1: float, y: float = 1.5) -> tuple[int, ...]:
    step = 0.5 if x1 > x0 else -0.5
    return tuple(node_at(roadmap, x, y) for x in np.arange(x0, x1 + step / 2, step))


def oncoming(roadmap: Roadmap, separation: float) -> Obstacle:
    """A robot driving the centre line from x = 12 to x = 0 from step 0, then standing."""
    points = roadmap.nodes[list(centre_line(roadmap, 12.0, 0.0))]
    poses = path_controls(points, np.pi, SPEED, TURN, DT).poses
    return Obstacle(0, poses[:, :2], np.full(poses.shape[0], separation))


def test_the_detour_keeps_the_separation_at_every_step() -> None:
    roadmap = lattice()
    mine = centre_line(roadmap, 0.0, 12.0)
    other = oncoming(roadmap, 1.0)  # it ends where this robot starts, long after it has left
    original = path_controls(roadmap.nodes[list(mine)], 0.0, SPEED, TURN, DT)
    assert not other.clear(np.arange(original.poses.shape[0]), original.poses[:, :2])  # they meet head-on
    path = detour(roadmap, mine, 0.0, 0, Drive(SPEED, TURN, DT), [other], original.controls.shape[0])
    assert path is not None and (path[0], path[-1]) == (mine[0], mine[-1]) and path != mine
    edges = {frozenset(e) for e in roadmap.edges.tolist()}
    assert all(frozenset((a, b)) in edges for a, b in itertools.pairwise(path))  # along the roadmap
    driven = path_controls(roadmap.nodes[list(path)], 0.0, SPEED, TURN, DT).poses
    # the motion as the clock drives it (to rounding: the search may graze the separation)
    assert Obstacle(0, other.xy, other.separation - 1e-9).clear(np.arange(driven.shape[0]), driven[:, :2])
    assert np.abs(driven[:, 1] - 1.5).max() >= 1.0 - 1e-9  # it left the centre line by a lane


def test_without_others_the_detour_is_no_slower_than_the_path() -> None:
    roadmap = lattice()
    mine = centre_line(roadmap, 0.0, 12.0)
    original = path_controls(roadmap.nodes[list(mine)], 0.0, SPEED, TURN, DT)
    path = detour(roadmap, mine, 0.0, 0, Drive(SPEED, TURN, DT), [], original.controls.shape[0])
    assert path is not None
    driven = path_controls(roadmap.nodes[list(path)], 0.0, SPEED, TURN, DT)
    assert driven.controls.shape[0] <= original.controls.shape[0]


@pytest.mark.parametrize("separation", [3.5, 10.0])
def test_no_detour_where_the_corridor_is_too_narrow(separation: float) -> None:
    roadmap = lattice()
    mine = centre_line(roadmap, 0.0, 12.0)
    original = path_controls(roadmap.nodes[list(mine)], 0.0, SPEED, TURN, DT)
    path = detour(roadmap, mine, 0.0, 0, Drive(SPEED, TURN, DT), [oncoming(roadmap, separation)], 100)
    assert path is None and original.controls.shape[0] > 0


def test_a_robot_standing_on_the_goal_blocks_every_detour() -> None:
    roadmap = lattice()
    mine = centre_line(roadmap, 0.0, 12.0)
    standing = Obstacle(0, roadmap.nodes[[mine[-1]]], np.array([1.0]))
    assert detour(roadmap, mine, 0.0, 0, Drive(SPEED, TURN, DT), [standing], 100) is None


def crossing(roadmap: Roadmap, before: float, window: int) -> Obstacle:
    """A robot crossing the corridor at x = 6 (from y = 3 to y = 0, then standing) ``before``
    seconds before a robot driving the centre line from x = 0 gets there, with a time window
    of ``window`` control steps (tmpnav.attachment.drift)."""
    points = roadmap.nodes[[node_at(roadmap, 6.0, y) for y in np.arange(3.0, -0.01, -0.5)]]
    poses = path_controls(points, -np.pi / 2, SPEED, TURN, DT).poses[:, :2]
    t0 = round((6.0 / SPEED - before - 1.5 / SPEED) / DT)
    return Obstacle(t0, poses, np.full(poses.shape[0], 0.8), np.full(poses.shape[0], window))


def test_a_time_window_makes_the_detour_keep_clear_of_an_earlier_crossing() -> None:
    roadmap = lattice()
    mine = centre_line(roadmap, 0.0, 12.0)
    original = path_controls(roadmap.nodes[list(mine)], 0.0, SPEED, TURN, DT)
    steps, drive = np.arange(original.poses.shape[0]), Drive(SPEED, TURN, DT)
    on_time, late = crossing(roadmap, 3.0, 0), crossing(roadmap, 3.0, 6)  # 3 s before; a 3 s window
    assert on_time.clear(steps, original.poses[:, :2]) and not late.clear(steps, original.poses[:, :2])
    assert detour(roadmap, mine, 0.0, 0, drive, [on_time], original.controls.shape[0]) == mine
    path = detour(roadmap, mine, 0.0, 0, drive, [late], original.controls.shape[0])
    assert path is not None and path != mine and (path[0], path[-1]) == (mine[0], mine[-1])
    driven = path_controls(roadmap.nodes[list(path)], 0.0, SPEED, TURN, DT).poses
    assert late.clear(np.arange(driven.shape[0]), driven[:, :2])  # what the checker asks, within the window


def test_the_window_boxes_clear_exactly_the_points_the_rows_clear() -> None:
    """The search tests each obstacle against the box of its rows within the step's window first
    (tmpnav.attachment.detours._window_boxes): on random obstacles with clock-drift windows,
    points near and far, before, during and long after their rows, the compiled test says what
    each obstacle's own rows say (Obstacle.clear)."""
    from tmpnav.attachment import detours

    rng = np.random.default_rng(5)
    for _ in range(40):
        obstacles = []
        for _ in range(int(rng.integers(1, 6))):
            n = int(rng.integers(1, 40))
            xy = np.cumsum(rng.normal(0.0, 0.3, (n, 2)), axis=0) + rng.uniform(0.0, 6.0, 2)
            window = np.minimum(np.arange(n) // int(rng.integers(2, 8)), 12)
            obstacles.append(Obstacle(int(rng.integers(0, 20)), xy, rng.uniform(0.3, 1.2, n), window))
        longest = max(o.xy.shape[0] for o in obstacles)
        t0 = np.array([o.t0 for o in obstacles], dtype=np.int64)
        rows = np.array([o.xy.shape[0] for o in obstacles], dtype=np.int64)
        xy, sep = np.zeros((len(obstacles), longest, 2)), np.zeros((len(obstacles), longest))
        win = np.zeros((len(obstacles), longest), dtype=np.int64)
        for k, o in enumerate(obstacles):
            xy[k, : o.xy.shape[0]], sep[k, : o.xy.shape[0]], win[k, : o.xy.shape[0]] = o.xy, o.separation, o.window
        box = detours._window_boxes(rows, xy, sep, win)
        for _ in range(200):
            step, point = int(rng.integers(0, 90)), rng.uniform(-2.0, 9.0, 2)
            expected = all(o.clear(np.array([step]), point[None]) for o in obstacles)
            assert detours._clear(t0, rows, xy, sep, win, box, step, point[0], point[1]) == expected
