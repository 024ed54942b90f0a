"""Regulated Pure Pursuit: a path driven as nav2's RPP controller drives it.

The law is that of nav2's ``nav2_regulated_pure_pursuit_controller`` (Macenski et al.,
"Regulated Pure Pursuit for Robot Path Tracking", Autonomous Robots 2023). At every control
step, from the robot's pose:

1. the path, densified to ``pursuit_path.RESOLUTION`` (a costmap's cells, as nav2's global
   plans are), is pruned up to the point nearest the robot, searched within
   ``max_robot_pose_search_dist`` ahead of the last one;
2. the carrot is the path's point at the lookahead distance L from the robot (interpolated
   between the path's points), or the path's end when that is nearer;
3. when the carrot lies more than ``rotate_to_heading_min_angle`` to the side, the robot turns on
   the spot towards it at ``rotate_to_heading_angular_vel``, within ``max_angular_accel``,
   slowing so as to stop at its heading (at the start of a move and after a sharp bend);
4. otherwise it drives on the arc through the carrot, kappa = 2 y / (x² + y²) in its frame, with
   omega = v kappa, v the robot's ``speed`` regulated down:
   * on arcs of radius r below ``regulated_linear_scaling_min_radius``: times r / that radius;
   * with its centre d from the nearest obstacle within the inflation radius: times
     ``cost_scaling_gain`` d / ``cost_scaling_dist``;
   * never below ``regulated_linear_scaling_min_speed`` by those two;
   * within ``approach_velocity_scaling_dist`` of the path's end: times the distance left over
     that distance, never below ``min_approach_linear_velocity``.
   The robot's own limits clip the command: v at most its ``speed`` (RPP's
   ``desired_linear_vel``), |omega| at most its ``turn_rate``, by slowing down on the arc.

A move ends when the robot is within ``xy_goal_tolerance`` of the path's end (nav2's goal
checker). A move to a goal pose (a job's station) ends as nav2 ends one: once within that
distance the robot turns on the spot towards the pose's heading, as in 3, until it points within
``yaw_goal_tolerance`` of it; it does not close in on the pose's position.

:func:`command` is the law, compiled; ``tmpnav simulate --follower rpp`` steers with it on the
robot's estimate (tmpnav.execution.rpp), and :func:`pursuit_controls` rolls it out on the
nominal poses, :data:`PLAN_SUBSTEPS` times a control step: the motions the planner prices with
``models.controller: rpp``.

The path it drives is a roadmap path shortened first, its corners rounded to arcs RPP drives at
full speed where the map leaves room (tmpnav.roadmap.shortcut).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields

import numba as nb
import numpy as np

from tmpnav.belief.controls import PathControls
from tmpnav.belief.pursuit_path import Rounding, densified, rounded_path
from tmpnav.world.geometry import wrap_angle_scalar

#: the law's evaluations per control step in the planner's rollout (:func:`pursuit_controls`)
PLAN_SUBSTEPS = 2


@dataclass(frozen=True)
class RppParams:
    """RPP's parameters, with nav2's defaults (docs.nav2.org, "Regulated Pure Pursuit" in the
    configuration guide; ``nav2_regulated_pure_pursuit_controller/src/parameter_handler.cpp``),
    and the two of other nav2 components it works with: the goal checker's ``xy_goal_tolerance``
    (``SimpleGoalChecker``, 0.25 m) and ``yaw_goal_tolerance`` (0.25 rad), and the costmap's
    ``inflation_radius`` (0.55 m in nav2's default params). The order of the fields is that of the
    compiled law's parameter vector."""

    lookahead_dist: float = 0.6
    min_lookahead_dist: float = 0.3
    max_lookahead_dist: float = 0.9
    lookahead_time: float = 1.5
    use_velocity_scaled_lookahead_dist: bool = False
    rotate_to_heading_angular_vel: float = 1.8
    use_rotate_to_heading: bool = True
    rotate_to_heading_min_angle: float = 0.785
    max_angular_accel: float = 3.2
    use_regulated_linear_velocity_scaling: bool = True
    regulated_linear_scaling_min_radius: float = 0.9
    regulated_linear_scaling_min_speed: float = 0.25
    use_cost_regulated_linear_velocity_scaling: bool = True
    cost_scaling_dist: float = 0.6
    cost_scaling_gain: float = 1.0
    approach_velocity_scaling_dist: float = 0.6
    min_approach_linear_velocity: float = 0.05
    max_robot_pose_search_dist: float = 1.5
    xy_goal_tolerance: float = 0.25
    inflation_radius: float = 0.55
    yaw_goal_tolerance: float = 0.25

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def vector(self) -> np.ndarray:
        """The parameters as the compiled law takes them (booleans as 0 or 1); do not write to it."""
        return self._vector

    @functools.cached_property
    def _vector(self) -> np.ndarray:
        """:meth:`vector`, built once and kept with the parameters (the oracle drives thousands of
        paths with one set)."""
        found = np.array([float(getattr(self, f.name)) for f in fields(self)])
        found.setflags(write=False)
        return found

    @property
    def reach(self) -> float:
        """The longest lookahead the law can use (m)."""
        return max(self.lookahead_dist, self.max_lookahead_dist if self.use_velocity_scaled_lookahead_dist else 0.0)


# the parameter vector's entries (RppParams' order)
(
    _LOOKAHEAD,
    _MIN_LOOKAHEAD,
    _MAX_LOOKAHEAD,
    _LOOKAHEAD_TIME,
    _SCALED_LOOKAHEAD,
    _ROTATE_VEL,
    _USE_ROTATE,
    _ROTATE_MIN_ANGLE,
    _MAX_ANGULAR_ACCEL,
    _USE_CURVATURE,
    _MIN_RADIUS,
    _MIN_SPEED,
    _USE_COST,
    _COST_DIST,
    _COST_GAIN,
    _APPROACH_DIST,
    _MIN_APPROACH_V,
    _SEARCH_DIST,
    _GOAL_TOLERANCE,
    _INFLATION,
    _YAW_TOLERANCE,
) = range(21)


@nb.njit(cache=True, inline="always")
def _beyond(dx, dy, r):  # pragma: no cover
    """The sign of ``math.hypot(dx, dy) - r`` (-1, 0 or 1), to the bit: the hypotenuse is taken
    only where the sum of the squares, a few rounding errors off it, lies within a billionth of
    r² (the carrot's search asks of a dozen path points a command, and the hypotenuse cost more
    than the rest of it)."""
    q = dx * dx + dy * dy
    rr = r * r
    if q < rr * (1.0 - 1e-9):
        return -1
    if q > rr * (1.0 + 1e-9):
        return 1
    h = math.hypot(dx, dy)
    return 1 if h > r else (0 if h == r else -1)


@nb.njit(cache=True, inline="always")
def reaches(dx, dy, r):  # pragma: no cover
    """``math.hypot(dx, dy) >= r``, to the bit (:func:`_beyond`)."""
    return _beyond(dx, dy, r) >= 0


@nb.njit(cache=True, inline="always")
def is_near(dx, dy, r):  # pragma: no cover
    """``math.hypot(dx, dy) <= r``, to the bit (:func:`_beyond`)."""
    return _beyond(dx, dy, r) <= 0


@nb.njit(cache=True)
def rotate(angle, last_w, turn_rate, dt, p):  # pragma: no cover
    """omega (rad/s) of RPP's turn on the spot towards a heading ``angle`` rad away (positive: to
    the left), from ``last_w``: ``rotate_to_heading_angular_vel`` (at most ``turn_rate``) within
    ``max_angular_accel``, slowed so as to stop at the heading (nav2's ``rotateToHeading``)."""
    sign = 1.0 if angle > 0 else -1.0
    w = sign * min(p[_ROTATE_VEL], turn_rate)
    w = min(max(w, last_w - p[_MAX_ANGULAR_ACCEL] * dt), last_w + p[_MAX_ANGULAR_ACCEL] * dt)
    stop = math.sqrt(2.0 * p[_MAX_ANGULAR_ACCEL] * abs(angle))  # slow down so as not to overshoot
    if abs(w) > stop:
        w = sign * stop
    return w


@nb.njit(cache=True)
def heading_reached(th, goal_heading, p):  # pragma: no cover
    """nav2's goal checker on the heading: ``th`` within ``yaw_goal_tolerance`` of ``goal_heading``
    (rad; NaN: a goal without a heading, always reached)."""
    return math.isnan(goal_heading) or abs(wrap_angle_scalar(goal_heading - th)) <= p[_YAW_TOLERANCE]


@nb.njit(cache=True)
def command(path, left, index, x, y, th, last_v, last_w, obstacle, speed, turn_rate, dt, p, goal):  # pragma: no cover
    """The command (v, omega) RPP gives at the pose (x, y, th) on the densified ``path`` (n, 2)
    with ``left`` (n,) its length to the end, the robot having come as far as its point ``index``
    (returned moved on, the third value); ``last_v``, ``last_w`` the last command, ``obstacle`` the
    distance (m) from the robot's centre to the nearest obstacle, ``p`` :meth:`RppParams.vector`,
    ``goal`` the heading (rad) of the goal pose at the path's end (NaN: none).
    The module docstring states the law."""
    n = path.shape[0]
    # 1. prune: the nearest point within the search distance ahead of the last one
    best, best_d2 = index, np.inf
    j = index
    while j < n and left[index] - left[j] <= p[_SEARCH_DIST]:
        d2 = (path[j, 0] - x) ** 2 + (path[j, 1] - y) ** 2
        if d2 < best_d2:
            best, best_d2 = j, d2
        j += 1
    index = best
    # 2. the carrot, in the robot's frame
    lookahead = p[_LOOKAHEAD]
    if p[_SCALED_LOOKAHEAD] > 0.5:
        lookahead = min(max(abs(last_v) * p[_LOOKAHEAD_TIME], p[_MIN_LOOKAHEAD]), p[_MAX_LOOKAHEAD])
    c, s = math.cos(th), math.sin(th)
    cx, cy = 0.0, 0.0
    ax, ay = 0.0, 0.0
    found = False
    for j in range(index, n):
        rx, ry = path[j, 0] - x, path[j, 1] - y
        bx, by = c * rx + s * ry, -s * rx + c * ry
        if reaches(bx, by, lookahead):
            if j == index:
                cx, cy = bx, by
            else:  # the circle of radius lookahead crosses a -> b
                dx, dy = bx - ax, by - ay
                qa = dx * dx + dy * dy
                qb = 2.0 * (ax * dx + ay * dy)
                qc = ax * ax + ay * ay - lookahead * lookahead
                t = (-qb + math.sqrt(max(qb * qb - 4.0 * qa * qc, 0.0))) / (2.0 * qa) if qa > 0.0 else 1.0
                t = min(max(t, 0.0), 1.0)
                cx, cy = ax + t * dx, ay + t * dy
            found = True
            break
        ax, ay = bx, by
    if not found:  # the end is nearer than the lookahead
        rx, ry = path[n - 1, 0] - x, path[n - 1, 1] - y
        cx, cy = c * rx + s * ry, -s * rx + c * ry
    angle = math.atan2(cy, cx)
    # at a goal pose, within the goal checker's distance: turn on the spot to its heading
    goal_x, goal_y = path[n - 1, 0] - x, path[n - 1, 1] - y
    if p[_USE_ROTATE] > 0.5 and not math.isnan(goal) and math.hypot(goal_x, goal_y) < p[_GOAL_TOLERANCE]:
        return 0.0, rotate(wrap_angle_scalar(goal - th), last_w, turn_rate, dt, p), index
    # 3. turn on the spot towards a carrot far to the side
    if p[_USE_ROTATE] > 0.5 and abs(angle) > p[_ROTATE_MIN_ANGLE]:
        return 0.0, rotate(angle, last_w, turn_rate, dt, p), index
    # 4. the arc through the carrot, at the regulated speed
    d2 = cx * cx + cy * cy
    kappa = 2.0 * cy / d2 if d2 > 0.001 else 0.0
    v = curvature_v = cost_v = speed
    if p[_USE_CURVATURE] > 0.5 and kappa != 0.0:
        radius = 1.0 / abs(kappa)
        if radius < p[_MIN_RADIUS]:
            curvature_v = v * radius / p[_MIN_RADIUS]
    if p[_USE_COST] > 0.5 and obstacle < min(p[_INFLATION], p[_COST_DIST]):
        cost_v = v * p[_COST_GAIN] * obstacle / p[_COST_DIST]
    v = max(min(curvature_v, cost_v), p[_MIN_SPEED])
    rest = left[index]
    if rest < p[_APPROACH_DIST]:
        v = min(v, max(v * rest / p[_APPROACH_DIST], p[_MIN_APPROACH_V]))
    v = min(max(v, 0.0), speed)
    w = v * kappa
    if abs(w) > turn_rate:  # the robot's own limit: slow down to keep the arc
        v, w = v * turn_rate / abs(w), math.copysign(turn_rate, w)
    return v, w, index


@nb.njit(cache=True)
def step_commands(
    path, left, index, x, y, th, v, w, obstacle, speed, turn_rate, h, p, goal, within, out
):  # pragma: no cover
    """One control step's commands into ``out`` (N, 2), each held ``h`` s: the law (:func:`command`)
    N times, each on the pose the commands before it reached on their arcs (the motion model's
    midpoint step), the obstacle distance the step's start's; zero from the one at which nav2's
    goal checker is satisfied (``within``: its stateful position check, :func:`heading_reached`).
    Returns the path index, the goal checker's state and the last command. ``tmpnav simulate``'s
    follower runs it at nav2's 20 Hz, the planner's rollout :data:`PLAN_SUBSTEPS` times a step."""
    n = path.shape[0]
    for k in range(out.shape[0]):
        within = within or is_near(path[n - 1, 0] - x, path[n - 1, 1] - y, p[_GOAL_TOLERANCE])
        if within and heading_reached(th, goal, p):
            return index, within, 0.0, 0.0
        v, w, index = command(path, left, index, x, y, th, v, w, obstacle, speed, turn_rate, h, p, goal)
        out[k, 0], out[k, 1] = v, w
        mid = th + 0.5 * w * h
        x, y, th = x + v * h * math.cos(mid), y + v * h * math.sin(mid), th + w * h  # the law wraps differences
    return index, within, v, w


def pursuit_controls(
    points: np.ndarray,
    start_theta: float,
    speed: float,
    turn_rate: float,
    dt: float,
    params: RppParams,
    clearance: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    goal_heading: float | None = None,
    required: float | None = None,
    substeps: int = PLAN_SUBSTEPS,
) -> PathControls | None:
    """The controls and nominal poses of a robot driving the polyline ``points`` (P, 2) from its
    first point with heading ``start_theta`` under RPP (the module docstring), the obstacle
    distance read off ``clearance`` (a grid of ``resolution`` m cells from ``origin``: the
    distance from each cell's centre to the nearest occupied one, tmpnav.world.grid.clearance).
    Within each control step of ``dt`` the law runs ``substeps`` times (each command held
    dt / substeps on its arc, from the pose the ones before it reached, the obstacle distance
    the step's start's, as ``tmpnav simulate``'s follower runs it 20 times a second), and the step
    holds their mean: the kernel's beliefs take one command a step. The poses follow the motion
    model, paper eq. (4), step by step in its midpoint form (tmpnav.belief.models.motion: each step
    translates along the heading at its middle), so they stay on the arcs nav2's 20 Hz commands
    drive, and a turn on the spot ramps up within ``max_angular_accel`` as nav2's does. The
    motion ends within ``xy_goal_tolerance`` of the last point, with a ``goal_heading`` (rad: a
    goal pose's) turned on the spot to within ``yaw_goal_tolerance`` of it there, and
    ``node_steps[k]`` is the step at which the robot has come abreast of point k (its nearest path
    point at or beyond it). With ``required`` (m) the polyline's corners are rounded first,
    keeping that clearance (:func:`driven_path`). None when the law has not arrived within a
    generous number of steps (a path it cannot drive)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if pts.shape[0] == 0:
        raise ValueError("pursuit_controls needs at least one point")
    if speed <= 0 or turn_rate <= 0 or dt <= 0 or substeps < 1:
        raise ValueError("speed, turn_rate, dt and substeps must be positive")
    rounding = None if required is None else Rounding(required, clearance, origin, resolution)
    rounded, at = rounded_path(pts, rounding)
    return pursuit_along(
        rounded, at, pts.shape[0], start_theta, speed, turn_rate, dt, params, clearance, origin, resolution,
        goal_heading, substeps,
    )  # fmt: skip


def pursuit_along(
    rounded: np.ndarray,
    at: np.ndarray,
    points: int,
    start_theta: float,
    speed: float,
    turn_rate: float,
    dt: float,
    params: RppParams,
    clearance: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    goal_heading: float | None = None,
    substeps: int = PLAN_SUBSTEPS,
) -> PathControls | None:
    """:func:`pursuit_controls` along a polyline whose corners are rounded already: ``rounded``
    (m, 2) and ``at`` (P,), tmpnav.belief.pursuit_path.rounded_path of the ``points`` (P of
    them) given to it. The densified path, its lengths left and the rollout in one compiled
    call: the oracle drives each path from every heading a robot arrives at its start with."""
    x0, y0 = origin
    goal = math.nan if goal_heading is None else float(goal_heading)
    controls, poses, node_steps, arrived = _pursue_rounded(
        rounded, at, int(points), float(start_theta), float(speed), float(turn_rate), float(dt), params.vector(),
        clearance, float(x0), float(y0), float(resolution), goal, int(substeps),
    )  # fmt: skip
    if not arrived:
        return None
    return PathControls(controls=controls, poses=poses, node_steps=node_steps.astype(int), pursued=True)


@nb.njit(cache=True)
def _pursue_rounded(
    rounded, at, points, theta0, speed, turn_rate, dt, p, clear, x0, y0, res, goal, substeps
):  # pragma: no cover
    """:func:`pursuit_along`, compiled: the polyline densified (tmpnav.belief.pursuit_path.densify),
    its lengths left, the rollout's budget (every metre at the slowest speed, a full turn at every
    one of the ``points``, and a margin) and the rollout (:func:`_pursue`)."""
    path, vertices, left = densified(rounded, at)
    slowest = min(p[_MIN_APPROACH_V], p[_MIN_SPEED], speed)
    budget = int((left[0] + 1.0) / (slowest * dt) + points * 2.0 * math.pi / (min(turn_rate, 0.5) * dt)) + 100
    return _pursue(path, left, vertices, theta0, speed, turn_rate, dt, p, clear, x0, y0, res, budget, goal, substeps)


@nb.njit(cache=True)
def _pursue(
    path, left, vertices, theta0, speed, turn_rate, dt, p, clear, x0, y0, res, budget, goal, substeps
):  # pragma: no cover
    """The rollout of :func:`pursuit_controls` (which documents it): controls (T, 2), poses
    (T+1, 3), the step each vertex is passed (P,), and whether the goal was reached."""
    n = path.shape[0]
    rows, cols = clear.shape
    controls = np.empty((budget, 2))
    poses = np.empty((budget + 1, 3))
    P = vertices.shape[0]
    node_steps = np.full(P, -1, dtype=np.int64)
    node_steps[0] = 0
    poses[0, 0], poses[0, 1], poses[0, 2] = path[0, 0], path[0, 1], wrap_angle_scalar(theta0)
    index, v, w, t = 0, 0.0, 0.0, 0
    arrived = within = False
    h = dt / substeps
    out = np.zeros((substeps, 2))
    while t < budget:
        x, y, th = poses[t, 0], poses[t, 1], poses[t, 2]
        # nav2's goal checker: the position once within its tolerance stays reached (stateful)
        within = within or is_near(path[n - 1, 0] - x, path[n - 1, 1] - y, p[_GOAL_TOLERANCE])
        if within and heading_reached(th, goal, p):
            arrived = True
            break
        i = math.floor((y - y0) / res)
        j = math.floor((x - x0) / res)
        obstacle = clear[i, j] if 0 <= i < rows and 0 <= j < cols else 0.0
        # the law at substeps / dt Hz (the follower's step); the step holds their mean
        out[:] = 0.0
        index, within, v, w = step_commands(
            path, left, index, x, y, th, v, w, obstacle, speed, turn_rate, h, p, goal, within, out
        )
        dist, turned = 0.0, 0.0
        for k in range(substeps):
            dist += out[k, 0] * h
            turned += out[k, 1] * h
        for k in range(1, P):
            if node_steps[k] < 0 and index >= vertices[k]:
                node_steps[k] = t
        vm, wm = dist / dt, turned / dt
        controls[t, 0], controls[t, 1] = vm, wm
        poses[t + 1, 0] = x + vm * dt * math.cos(th + 0.5 * wm * dt)  # the midpoint step (models.motion)
        poses[t + 1, 1] = y + vm * dt * math.sin(th + 0.5 * wm * dt)
        poses[t + 1, 2] = wrap_angle_scalar(th + wm * dt)
        t += 1
    for k in range(P):
        if node_steps[k] < 0:
            node_steps[k] = t
    return controls[:t].copy(), poses[: t + 1].copy(), node_steps, arrived
