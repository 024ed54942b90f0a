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

The law is compiled once, in :mod:`tmpnav.belief.pursuit`: the planner's motions under
``models.controller: rpp`` are its rollout on the nominal poses, and this follower steers with it
on the robot's estimate. A move ends when the robot is within ``xy_goal_tolerance`` of its end
(nav2's goal checker). A move to a goal pose (a job's station, ``goals.jobs``) ends as nav2 ends
one: within that distance the robot turns on the spot to the pose's heading (as in step 3) until
it points within ``yaw_goal_tolerance`` of it, without closing in on the pose's position. Other
goals are positions: there is no final turn, and the next move's first turn, step 3, is that
turn. Two limits are the robot's own, not RPP's: the speed never exceeds the robot's ``speed``
and omega never exceeds its ``turn_rate`` (nav2's velocity smoother would clip them the same
way). ``desired_linear_vel`` (0.5 m/s in nav2) is the robot's ``speed``: the one the plan drives
at.

**At nav2's rate.** nav2's controller server runs the law at ``controller_frequency``, 20 Hz by
default (:data:`CONTROLLER_FREQUENCY`); the plan and the localisers step every ``dt`` (0.5 s).
:meth:`RppFollower.step` gives a control step's commands as the controller server gives them:
the law :data:`CONTROLLER_FREQUENCY` times a second, each time on the estimate dead-reckoned with
the commands given since the step began (the robot's odometry between two localiser updates),
stopping once nav2's goal checker is satisfied. The true robot drives those commands
(:func:`drive`), and the localiser predicts with them one by one, as a robot's odometry follows
each (tmpnav.execution.localisers.TeamLocaliser.predict). The planner's motions
(tmpnav.belief.pursuit) evaluate the same law twice per ``dt`` and hold their mean: executing a
plan at nav2's rate is a check of that discretisation, not the planner's rollout run again.

Not modelled: the collision check that stops the robot (``use_collision_detection``), nav2's
recovery behaviours, and reversing.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from tmpnav.belief.pursuit import RppParams, command, heading_reached, step_commands
from tmpnav.belief.pursuit_path import RESOLUTION, Rounding, densify, driven_path, length_left
from tmpnav.world.geometry import wrap_angle_scalar

__all__ = ["CONTROLLER_FREQUENCY", "RESOLUTION", "Rounding", "RppFollower", "RppParams", "densify", "drive"]

#: Hz: how often nav2's controller server runs the law (``controller_server.controller_frequency``,
#: nav2_bringup/params/nav2_params.yaml and nav2's configuration guide: 20.0)
CONTROLLER_FREQUENCY = 20.0


class RppFollower:
    """One robot's RPP along one move's path (:mod:`module docstring <tmpnav.execution.rpp>`)."""

    def __init__(
        self,
        points: np.ndarray,
        params: RppParams,
        speed: float,
        turn_rate: float,
        dt: float,
        goal_heading: float | None = None,
        rounding: Rounding | None = None,
    ):
        #: the densified path (its corners rounded with ``rounding``, as the plan's motion rounds
        #: them: tmpnav.belief.pursuit_path.driven_path) and the index of each of ``points`` in it
        self.path, self.vertices = driven_path(points, rounding)
        #: m: the path's length from each point to its end
        self.left = length_left(self.path)
        self.p, self.dt = params, dt
        self._vector = params.vector()
        self.speed = speed  # desired_linear_vel: the robot's own speed, the one the plan drives at
        self.turn_rate = turn_rate
        self.index = 0  # the path point nearest the robot, as far as it has come
        self.v, self.w = 0.0, 0.0  # the last command
        #: rad: the heading of the goal pose the move ends at (a job's station); None: a position
        self.goal_heading = goal_heading
        self.within = False  # nav2's stateful goal checker: the goal's position, once reached, stays reached

    def passed(self, k: int) -> bool:
        """Whether the robot has come abreast of the path's vertex ``k`` (its nearest point is at
        or beyond it): RPP cuts corners, so a bend's vertex is passed, not reached."""
        return self.index >= self.vertices[k]

    def at_goal(self, est: np.ndarray) -> bool:
        """nav2's goal checker (``SimpleGoalChecker``, stateful): within ``xy_goal_tolerance`` of
        the path's end, or once was, and with a goal heading, within ``yaw_goal_tolerance`` of it."""
        self.within = self.within or bool(np.hypot(*(self.path[-1] - est[:2])) <= self.p.xy_goal_tolerance)
        return self.within and bool(heading_reached(float(est[2]), self._goal, self._vector))

    @property
    def _goal(self) -> float:
        """The goal heading as the compiled law takes it (NaN: none)."""
        return math.nan if self.goal_heading is None else float(self.goal_heading)

    def command(self, est: np.ndarray, obstacle_distance: float) -> np.ndarray:
        """The command (v, omega) at the estimate ``est`` (3,), the robot's centre
        ``obstacle_distance`` m from the nearest obstacle of its local costmap: the compiled law
        the planner's motions are driven with (tmpnav.belief.pursuit.command)."""
        v, w, self.index = command(
            self.path, self.left, self.index, float(est[0]), float(est[1]), float(est[2]), self.v, self.w,
            float(obstacle_distance), self.speed, self.turn_rate, self.dt, self._vector, self._goal,
        )  # fmt: skip
        self.v, self.w = float(v), float(w)
        return np.array([self.v, self.w])

    @property
    def substeps(self) -> int:
        """The law's commands in a control step of ``dt`` at :data:`CONTROLLER_FREQUENCY` (at least 1)."""
        return max(1, round(self.dt * CONTROLLER_FREQUENCY))

    def step(self, est: np.ndarray, obstacle_distance: float) -> np.ndarray:
        """The commands (N, 2) (v, omega) of one control step at nav2's rate (N = :attr:`substeps`,
        each held dt / N), from the estimate ``est`` (3,) at the step's start, dead-reckoned with
        them from one to the next; zero from the one at which nav2's goal checker is satisfied (the
        position once reached stays reached, :meth:`at_goal`). The obstacle distance is the step's
        start's (module docstring)."""
        out = np.zeros((self.substeps, 2))
        self.index, self.within, self.v, self.w = step_commands(
            self.path, self.left, self.index, float(est[0]), float(est[1]), float(est[2]), self.v, self.w,
            float(obstacle_distance), self.speed, self.turn_rate, self.dt / self.substeps, self._vector,
            self._goal, self.within, out,
        )  # fmt: skip
        return out


@nb.njit(cache=True)
def drive(pose, commands, z, alphas, dt):  # pragma: no cover
    """The pose (3,) after a control step of ``dt`` s from ``pose`` driving ``commands`` (N, 2), each
    held dt / N, with the step's control noise: command u plus sqrt(W(u)) ``z`` (``z`` (2,) the
    step's standard normal draw, W(u) = diag(a1 v² + a2 omega², a3 v² + a4 omega²) with ``alphas``
    (a1..a4), paper eq. (4)), each on its arc by the motion model's midpoint step
    (tmpnav.belief.models.motion). With one command it is that step of ``dt``."""
    h = dt / commands.shape[0]
    x, y, th = pose[0], pose[1], pose[2]
    for k in range(commands.shape[0]):
        v, w = commands[k, 0], commands[k, 1]
        v2, w2 = v * v, w * w
        v += math.sqrt(alphas[0] * v2 + alphas[1] * w2) * z[0]
        w += math.sqrt(alphas[2] * v2 + alphas[3] * w2) * z[1]
        mid = th + 0.5 * w * h
        x, y = x + v * h * math.cos(mid), y + v * h * math.sin(mid)
        th = wrap_angle_scalar(th + w * h)
    return np.array([x, y, th])
