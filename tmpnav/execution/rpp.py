"""nav2's Regulated Pure Pursuit controller (RPP), as ``tmpnav simulate --follower rpp`` drives a
move: the controller nav2 robots run, to check the plan's clock and paths against.

The algorithm is that of nav2's ``nav2_regulated_pure_pursuit_controller`` (Macenski et al.,
"Regulated Pure Pursuit for Robot Path Tracking", Autonomous Robots 2023), at every control
step, on the robot's estimate:

1. the move's path, densified to :data:`RESOLUTION` (a costmap's cells, as nav2's global plans
   are), is pruned up to the point nearest the robot (searched within
   ``max_robot_pose_search_dist`` ahead of the last one) and put in the robot's frame;
2. the carrot is the point of the path at the lookahead distance from the robot (interpolated
   between the path's points), or the path's end when it is nearer;
3. if the carrot lies more than ``rotate_to_heading_min_angle`` to the side, the robot turns on
   the spot towards it at ``rotate_to_heading_angular_vel``, within ``max_angular_accel`` and
   slowing to stop at its heading: this happens at the start of a move and after a sharp bend;
4. otherwise it drives on the arc through the carrot, curvature kappa = 2 y / (x² + y²), at
   ``desired_linear_vel`` regulated down
   * by curvature: times r / ``regulated_linear_scaling_min_radius`` on arcs of radius r below it;
   * by proximity to obstacles: times ``cost_scaling_gain`` d / ``cost_scaling_dist`` where the
     robot's centre is d from the nearest obstacle of the local costmap, within the inflation
     radius (nav2 decodes d from the inflation cost; here it is read off the true clearance: the
     local costmap is built from the robot's own scans, so the distance it holds is the true one);
   * never below ``regulated_linear_scaling_min_speed`` by those two;
   * then on approach to the path's end: times the distance left / ``approach_velocity_scaling_dist``,
     never below ``min_approach_linear_velocity``;
   and omega = v kappa.

A move ends when the robot is within ``xy_goal_tolerance`` of its end (nav2's goal checker). A
tmpnav goal is a position, not a pose: there is no final turn to a goal heading; the next move's
first turn, step 3, is that turn. Two limits are the robot's own, not RPP's: the speed never
exceeds the robot's ``speed`` and omega never exceeds its ``turn_rate`` (nav2's velocity
smoother would clip them the same way). ``desired_linear_vel`` (0.5 m/s in nav2) is the robot's
``speed``: the one the plan drives at.

Not modelled: the collision check that stops the robot (``use_collision_detection``), nav2's
recovery behaviours, and reversing.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, fields

import numpy as np

#: m: the spacing of the densified path (nav2's global plans come one per costmap cell)
RESOLUTION = 0.05


@dataclass(frozen=True)
class RppParams:
    """RPP's parameters, with nav2's defaults (docs.nav2.org, "Regulated Pure Pursuit" in the
    configuration guide; ``nav2_regulated_pure_pursuit_controller/src/parameter_handler.cpp``),
    and the two of other nav2 components it works with: the goal checker's ``xy_goal_tolerance``
    (``SimpleGoalChecker``, 0.25 m) and the costmap's ``inflation_radius`` (0.55 m in nav2's
    default params)."""

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

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


def densify(points: np.ndarray, spacing: float = RESOLUTION) -> tuple[np.ndarray, np.ndarray]:
    """The polyline ``points`` (k, 2) resampled every ``spacing`` m or closer, every vertex kept;
    and the index of each vertex in the result (k,)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    out, at = [points[:1]], [0]
    for a, b in itertools.pairwise(points):
        n = max(1, math.ceil(float(np.hypot(*(b - a))) / spacing))
        out.append(a + (b - a) * (np.arange(1, n + 1)[:, None] / n))
        at.append(at[-1] + n)
    return np.concatenate(out), np.array(at)


class RppFollower:
    """One robot's RPP along one move's path (:mod:`module docstring <tmpnav.execution.rpp>`)."""

    def __init__(self, points: np.ndarray, params: RppParams, speed: float, turn_rate: float, dt: float):
        self.path, self.vertices = densify(points)
        #: m: the path's length from each point to its end
        seg = np.hypot(*np.diff(self.path, axis=0).T)
        self.left = np.concatenate([np.cumsum(seg[::-1])[::-1], [0.0]])
        self.p, self.dt = params, dt
        self.speed = speed  # desired_linear_vel: the robot's own speed, the one the plan drives at
        self.turn_rate = turn_rate
        self.index = 0  # the path point nearest the robot, as far as it has come
        self.v, self.w = 0.0, 0.0  # the last command

    def passed(self, k: int) -> bool:
        """Whether the robot has come abreast of the path's vertex ``k`` (its nearest point is at
        or beyond it): RPP cuts corners, so a bend's vertex is passed, not reached."""
        return self.index >= self.vertices[k]

    def at_goal(self, est: np.ndarray) -> bool:
        """nav2's goal checker: within ``xy_goal_tolerance`` of the path's end."""
        return bool(np.hypot(*(self.path[-1] - est[:2])) <= self.p.xy_goal_tolerance)

    def _prune(self, xy: np.ndarray) -> None:
        ahead = self.left[self.index] - self.left[self.index :] <= self.p.max_robot_pose_search_dist
        window = self.path[self.index : self.index + int(np.count_nonzero(ahead))]
        self.index += int(np.argmin(np.sum((window - xy) ** 2, axis=1)))

    def _carrot(self, local: np.ndarray, lookahead: float) -> np.ndarray:
        dist = np.hypot(local[:, 0], local[:, 1])
        beyond = np.nonzero(dist >= lookahead)[0]
        if beyond.size == 0:
            return local[-1]
        j = int(beyond[0])
        if j == 0:
            return local[0]
        a, b = local[j - 1], local[j]  # the circle of radius lookahead crosses a -> b
        d = b - a
        qa, qb, qc = d @ d, 2 * a @ d, a @ a - lookahead**2
        t = (-qb + math.sqrt(max(qb * qb - 4 * qa * qc, 0.0))) / (2 * qa) if qa > 0 else 1.0
        return a + min(max(t, 0.0), 1.0) * d

    def command(self, est: np.ndarray, obstacle_distance: float) -> np.ndarray:
        """The command (v, omega) at the estimate ``est`` (3,), the robot's centre
        ``obstacle_distance`` m from the nearest obstacle of its local costmap."""
        p = self.p
        self._prune(est[:2])
        c, s = math.cos(est[2]), math.sin(est[2])
        rel = self.path[self.index :] - est[:2]
        local = np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]])
        lookahead = p.lookahead_dist
        if p.use_velocity_scaled_lookahead_dist:
            lookahead = min(max(abs(self.v) * p.lookahead_time, p.min_lookahead_dist), p.max_lookahead_dist)
        x, y = self._carrot(local, lookahead)
        angle = math.atan2(y, x)
        if p.use_rotate_to_heading and abs(angle) > p.rotate_to_heading_min_angle:
            v, w = 0.0, self._rotate(angle)
        else:
            d2 = x * x + y * y
            kappa = 2.0 * y / d2 if d2 > 0.001 else 0.0
            v = self._regulated(kappa, obstacle_distance)
            w = v * kappa
            if abs(w) > self.turn_rate:  # the robot's own limit: slow down to keep the arc
                v, w = v * self.turn_rate / abs(w), math.copysign(self.turn_rate, w)
        self.v, self.w = v, w
        return np.array([v, w])

    def _rotate(self, angle: float) -> float:
        p, sign = self.p, (1.0 if angle > 0 else -1.0)
        w = sign * min(p.rotate_to_heading_angular_vel, self.turn_rate)
        w = min(max(w, self.w - p.max_angular_accel * self.dt), self.w + p.max_angular_accel * self.dt)
        stop = math.sqrt(2.0 * p.max_angular_accel * abs(angle))  # slow down so as not to overshoot
        return sign * stop if abs(w) > stop else w

    def _regulated(self, kappa: float, obstacle: float) -> float:
        p = self.p
        v = curvature_v = cost_v = self.speed
        if p.use_regulated_linear_velocity_scaling and kappa != 0.0:
            radius = 1.0 / abs(kappa)
            if radius < p.regulated_linear_scaling_min_radius:
                curvature_v = v * radius / p.regulated_linear_scaling_min_radius
        near = obstacle < min(p.inflation_radius, p.cost_scaling_dist)
        if p.use_cost_regulated_linear_velocity_scaling and near:
            cost_v = v * p.cost_scaling_gain * obstacle / p.cost_scaling_dist
        v = max(min(curvature_v, cost_v), p.regulated_linear_scaling_min_speed)
        left = float(self.left[self.index])
        if left < p.approach_velocity_scaling_dist:
            v = min(v, max(v * left / p.approach_velocity_scaling_dist, p.min_approach_linear_velocity))
        return min(max(v, 0.0), self.speed)
