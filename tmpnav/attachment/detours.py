"""Detours: one robot's move driven along another roadmap path, clear of the others on the clock.

Two robots that swap rooms across a corridor meet head-on, and no wait separates them: each
must pass where the other is, at some time. In a corridor wider than their margins they can
pass side by side if one of them leaves the shortest path for a parallel lane. That is a
detour: the same move (the same start, the same goal instantiation, chosen by the oracle),
driven along another path of the roadmap that keeps clear of the other robots' planned
centres at every control step.

The search is prioritised planning in space and time (Erdmann and Lozano-Perez 1987; Silver's
cooperative A*, AIIDE 2005): the other robots' schedules are fixed (their centres at each step
of the team's clock, a robot standing where its trajectory ends), and A* runs over states
(node, the node it came from, clock step) of the roadmap, with the robot's own timing: every
edge is driven as :func:`tmpnav.belief.controls.path_controls` drives it, a turn on the spot
then a straight drive, in whole control steps. A state is kept only when the robot's centre
stays at least the required separation from every other robot's centre at each step on the
way; the goal is accepted only when the robot can stand there while the others go on. The
cost is the arrival step, and the heuristic the straight-line drive to the goal in steps
(admissible: an edge takes at least its length over the speed), so the detour found is the
earliest-arriving one among the paths searched. The search stays near the original path
(roadmap nodes within ``reach`` metres of it), on the roadmap edges it is given (the resolver
gives those whose footprint clears the walls, tmpnav.attachment.passing), and gives up after
``max_expansions`` states.

There is no wait on the way: a move is one continuous motion, so that its controls, its
beliefs and its cost are computed as every other move's (by the team's clock). The detour's
beliefs differ from the planned ones (other landmarks in view, other distances to the
partner), so the clock runs the plan again with it, and the independent checker
(:mod:`tmpnav.belief.conflicts`) says whether it worked.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numba as nb
import numpy as np

from tmpnav.types import Roadmap
from tmpnav.world.geometry import wrap_angle_scalar

#: A* states a detour search may expand
MAX_EXPANSIONS = 20000
#: the detour may use roadmap nodes within this distance of the original path (m)
REACH = 4.0
#: the detour may take at most this many times the original move's steps, plus SLACK steps
STRETCH = 2.0
SLACK = 20
#: turns below this are skipped, as path_controls does (rad)
ANGLE_EPS = 1e-9


@dataclass(frozen=True)
class Obstacle:
    """Another robot as a detour must avoid it: its planned centre at each control step from
    ``t0`` on (``xy``: (H, 2) m; after the last row it stands at the last), the separation
    its centre requires from the detouring robot's at each of those steps (``separation``: (H,)
    m), and the pair's time window in control steps at each of them (``window``: (H,) int,
    tmpnav.attachment.drift; None: 0): the detouring robot at step t keeps the separation from
    every row within the window of t's row, as the independent checker asks."""

    t0: int
    xy: np.ndarray
    separation: np.ndarray
    window: np.ndarray | None = None

    def clear(self, steps: np.ndarray, points: np.ndarray) -> bool:
        """Whether ``points`` (n, 2) at clock ``steps`` (n,) keep the separation (steps before
        ``t0`` are not constrained)."""
        window = self.steps_window()
        for step, point in zip(steps, points, strict=True):
            r = int(step) - self.t0
            if r < 0:
                continue
            last = self.xy.shape[0] - 1
            w = int(window[min(r, last)])
            rows = np.arange(min(max(r - w, 0), last), min(r + w, last) + 1)
            gap = np.hypot(*(point[None] - self.xy[rows]).T)
            if np.any(gap < self.separation[rows]):
                return False
        return True

    def steps_window(self) -> np.ndarray:
        """The window at each row (control steps; zeros without one)."""
        if self.window is None:
            return np.zeros(self.xy.shape[0], dtype=np.int64)
        return np.asarray(self.window, dtype=np.int64)

    @property
    def last_step(self) -> int:
        return self.t0 + self.xy.shape[0] - 1


@dataclass(frozen=True)
class Drive:
    """How a robot drives: speed (m/s), turn rate (rad/s), control step (s)."""

    speed: float
    turn_rate: float
    dt: float


def detour(
    roadmap: Roadmap,
    path: Sequence[int],
    heading: float,
    t_start: int,
    drive: Drive,
    obstacles: Sequence[Obstacle],
    original_steps: int,
    edges: np.ndarray | None = None,
    reach: float = REACH,
    max_expansions: int = MAX_EXPANSIONS,
) -> tuple[int, ...] | None:
    """The earliest-arriving roadmap path from ``path[0]`` to ``path[-1]`` (starting at clock
    step ``t_start`` with ``heading``) that keeps clear of ``obstacles`` at every step and
    lets the robot stand at the goal while they go on; None when the search finds none (see
    the module docstring). ``path`` is the move's original path and ``original_steps`` its
    length in control steps; ``edges`` (E,) bool: the roadmap edges the detour may use (all
    when None)."""
    nodes = np.ascontiguousarray(roadmap.nodes, dtype=np.float64)
    start, goal = int(path[0]), int(path[-1])
    near = near_nodes(nodes, nodes[list(path)], reach)
    near[start] = near[goal] = True
    indptr, indices = _adjacency(roadmap, near, edges)
    horizon = t_start + int(STRETCH * original_steps) + SLACK
    end = max((o.last_step for o in obstacles), default=t_start)
    longest = max((o.xy.shape[0] for o in obstacles), default=1)
    count = len(obstacles)
    t0 = np.array([o.t0 for o in obstacles], dtype=np.int64)
    rows = np.array([o.xy.shape[0] for o in obstacles], dtype=np.int64)
    xy = np.zeros((count, longest, 2))
    sep = np.zeros((count, longest))
    win = np.zeros((count, longest), dtype=np.int64)
    for k, o in enumerate(obstacles):
        xy[k, : o.xy.shape[0]] = o.xy
        sep[k, : o.xy.shape[0]] = o.separation
        win[k, : o.xy.shape[0]] = o.steps_window()
    found = _search(
        nodes,
        indptr,
        indices,
        start,
        goal,
        float(heading),
        int(t_start),
        drive.speed,
        drive.turn_rate,
        drive.dt,
        t0,
        rows,
        xy,
        sep,
        win,
        _window_boxes(rows, xy, sep, win),
        horizon,
        max(end, t_start),
        max_expansions,
    )
    return None if found.shape[0] == 0 else tuple(int(n) for n in found)


@nb.njit(cache=True)
def _window(win, k, r, last):
    """The first and last of obstacle k's rows within the window of its row r (past its last
    row: the window of the last, reaching back from r)."""
    w = win[k, min(r, last)]
    return min(max(r - w, 0), last), min(r + w, last)


@nb.njit(cache=True)
def _window_boxes(rows, xy, sep, win):
    """For each obstacle k and row r (past its last row, as far as its window still reaches back,
    then the last), the box (x0, y0, x1, y1) of its rows within r's window, as :func:`_clear`
    reads them, and their largest separation: (K, R, 5). With the drift's windows at fleet size
    (tens of rows each, for every other robot) the rows of most obstacles lie far from the
    detour, and their boxes say so in one test (office of 100 rooms and 16 robots: a search
    that expands its 20,000 states took 3.4 s)."""
    count = rows.shape[0]
    reach = 1
    for k in range(count):
        reach = max(reach, rows[k] + win[k, rows[k] - 1] if rows[k] > 0 else 1)
    box = np.empty((count, reach, 5))
    for k in range(count):
        last = rows[k] - 1
        for r in range(reach):
            if last < 0:
                box[k, r, 0], box[k, r, 1], box[k, r, 2], box[k, r, 3], box[k, r, 4] = 0.0, 0.0, 0.0, 0.0, 0.0
                continue
            lo, hi = _window(win, k, r, last)
            x0, y0, x1, y1, s = math.inf, math.inf, -math.inf, -math.inf, 0.0
            for q in range(lo, hi + 1):
                x0, x1 = min(x0, xy[k, q, 0]), max(x1, xy[k, q, 0])
                y0, y1 = min(y0, xy[k, q, 1]), max(y1, xy[k, q, 1])
                s = max(s, sep[k, q])
            box[k, r, 0], box[k, r, 1], box[k, r, 2], box[k, r, 3], box[k, r, 4] = x0, y0, x1, y1, s
    return box


@nb.njit(cache=True)
def _clear(t0, rows, xy, sep, win, box, step, x, y):
    """Whether the point (x, y) at clock ``step`` keeps every obstacle's separation from each
    of its rows within the window of ``step``'s row. An obstacle whose rows of that window lie
    in a box (:func:`_window_boxes`) at least their largest separation from the point is clear
    without looking at its rows: each row is at least as far."""
    for k in range(t0.shape[0]):
        r = step - t0[k]
        if r < 0:
            continue
        last = rows[k] - 1
        b = min(r, box.shape[1] - 1)
        gx = max(box[k, b, 0] - x, 0.0, x - box[k, b, 2])
        gy = max(box[k, b, 1] - y, 0.0, y - box[k, b, 3])
        if gx * gx + gy * gy >= box[k, b, 4] * box[k, b, 4]:
            continue
        lo, hi = _window(win, k, r, last)
        for q in range(lo, hi + 1):
            dx, dy = x - xy[k, q, 0], y - xy[k, q, 1]
            if dx * dx + dy * dy < sep[k, q] * sep[k, q]:
                return False
    return True


@nb.njit(cache=True)
def _drives(t0, rows, xy, sep, win, box, t, n_turn, n_drive, ax, ay, bx, by):
    """Whether turning at (ax, ay) for ``n_turn`` steps from step ``t``, then driving to (bx, by)
    in ``n_drive`` steps, keeps every obstacle's separation."""
    for k in range(1, n_turn + n_drive + 1):
        frac = 0.0 if k <= n_turn else (k - n_turn) / n_drive
        if not _clear(t0, rows, xy, sep, win, box, t + k, ax + frac * (bx - ax), ay + frac * (by - ay)):
            return False
    return True


@nb.njit(cache=True)
def _stands(t0, rows, xy, sep, win, box, first, last, x, y):
    """Whether standing at (x, y) from step ``first`` to ``last`` keeps every separation."""
    for step in range(first, last + 1):  # noqa: SIM110 -- numba compiles no generator into all()
        if not _clear(t0, rows, xy, sep, win, box, step, x, y):
            return False
    return True


@nb.njit(cache=True)
def _unwind(st_node, st_parent, s):
    """The nodes from the search's first state to state ``s``."""
    out = []
    while s >= 0:
        out.append(st_node[s])
        s = st_parent[s]
    path = np.empty(len(out), dtype=np.int64)
    for k in range(len(out)):
        path[k] = out[len(out) - 1 - k]
    return path


@nb.njit(cache=True)
def _search(
    nodes, indptr, indices, start, goal, heading0, t_start, speed, turn_rate, dt, t0, rows, xy, sep, win, box, horizon,
    end, cap,
):  # fmt: skip
    """A* over (node, previous node, clock step) (the module docstring); the path's nodes, or
    an empty array."""
    per_step = speed * dt
    gx, gy = nodes[goal, 0], nodes[goal, 1]
    empty = np.empty(0, dtype=np.int64)
    if not _clear(t0, rows, xy, sep, win, box, t_start, nodes[start, 0], nodes[start, 1]):
        return empty
    n = nodes.shape[0]
    st_node = [start]
    st_parent = [-1]
    st_heading = [heading0]
    h0 = math.ceil(math.hypot(nodes[start, 0] - gx, nodes[start, 1] - gy) / per_step - 1e-9)
    frontier = [(t_start + h0, t_start, 0)]  # (f, t, state index)
    seen = {np.int64(0): True}
    seen.clear()
    expanded = 0
    while len(frontier) > 0 and expanded < cap:
        _, t, s = heapq.heappop(frontier)
        node, parent = st_node[s], st_parent[s]
        prev = st_node[parent] if parent >= 0 else -1
        key = (np.int64(node) * (n + 1) + (prev + 1)) * (horizon + 2) + t
        if key in seen:
            continue
        seen[key] = True
        expanded += 1
        if node == goal:
            if _stands(t0, rows, xy, sep, win, box, t, max(end, t), gx, gy):
                return _unwind(st_node, st_parent, s)
            continue
        ax, ay = nodes[node, 0], nodes[node, 1]
        heading = st_heading[s]
        for e in range(indptr[node], indptr[node + 1]):
            nxt = indices[e]
            if nxt == prev:
                continue
            bx, by = nodes[nxt, 0], nodes[nxt, 1]
            length = math.hypot(bx - ax, by - ay)
            if length <= 0.0:
                continue
            direction = math.atan2(by - ay, bx - ax)
            turn = abs(wrap_angle_scalar(direction - heading))
            n_turn = 0 if turn < ANGLE_EPS else max(1, math.ceil(turn / (turn_rate * dt)))
            n_drive = max(1, math.ceil(length / per_step))
            t_next = t + n_turn + n_drive
            h = math.ceil(math.hypot(bx - gx, by - gy) / per_step - 1e-9)
            if t_next + h > horizon:
                continue
            if _drives(t0, rows, xy, sep, win, box, t, n_turn, n_drive, ax, ay, bx, by):
                st_node.append(nxt)
                st_parent.append(s)
                st_heading.append(direction)
                heapq.heappush(frontier, (t_next + h, t_next, len(st_node) - 1))
    return empty


def near_nodes(nodes: np.ndarray, path_xy: np.ndarray, reach: float) -> np.ndarray:
    """Nodes within ``reach`` of the polyline ``path_xy``."""
    if path_xy.shape[0] == 1:
        return np.asarray(np.hypot(*(nodes - path_xy[0]).T) <= reach)
    best = np.full(nodes.shape[0], np.inf)
    for a, b in itertools.pairwise(path_xy):
        d = b - a
        length2 = float(d @ d)
        s = np.clip(((nodes - a) @ d) / length2, 0.0, 1.0) if length2 > 0 else np.zeros(nodes.shape[0])
        best = np.minimum(best, np.hypot(*(nodes - (a[None] + s[:, None] * d[None])).T))
    return best <= reach


def _adjacency(roadmap: Roadmap, keep: np.ndarray, edges: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The roadmap's ``edges`` (all when None) between ``keep`` nodes as a CSR adjacency
    (indptr, indices)."""
    e = roadmap.edges
    both = keep[e[:, 0]] & keep[e[:, 1]]
    if edges is not None:
        both &= edges
    src = np.concatenate([e[both, 0], e[both, 1]])
    dst = np.concatenate([e[both, 1], e[both, 0]])
    order = np.argsort(src, kind="stable")
    indptr = np.zeros(roadmap.nodes.shape[0] + 1, dtype=np.int64)
    np.add.at(indptr, src + 1, 1)
    return np.cumsum(indptr), np.ascontiguousarray(dst[order], dtype=np.int64)
