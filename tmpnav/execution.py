"""Plan execution (``tmpnav simulate``): a plan run many times with simulated noise (paper, Fig. 3(a)).

Each session draws the robots' true initial poses from their initial beliefs, then runs the
plan's actions in order. A moving robot follows its roadmap path with a waypoint
controller that steers on its own estimate (turn towards the next waypoint when it points
more than ``ALIGN`` away, otherwise drive with a heading correction; a waypoint counts as
reached when the estimate is within ``ARRIVED`` of it or has passed it along its segment,
so that a robot that lands a few centimetres off never turns around for it); the true robot
receives the commanded control plus noise drawn from W(u) (paper eq. (4)). Observations
are generated from the true poses (landmarks in range, field of view and line of sight;
the other moving robot when mutually visible) with sensor noise, and the joint EKF of
:mod:`tmpnav.belief.ekf` (the filterpy reference) estimates the poses.

Config 1 uses mutual observations, config 2 ignores them. Both configurations of a session
use the same random draws (initial poses, control noise and observation noise are indexed
by robot and step), so the comparison is paired. The error recorded is the distance
between the true and the estimated position when a robot reaches each node of its path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tmpnav.belief import ekf
from tmpnav.belief.models import landmark_obs, motion, motion_noise_cov, mutual_obs, noisy_observation, wrap_angle
from tmpnav.results import PlanReport
from tmpnav.types import Belief, Roadmap, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility, MutualSensing

ALIGN = 0.3  # rad: beyond this heading error the robot turns on the spot
ARRIVED = 0.05  # m: a waypoint is reached when the estimate is this close (or this close to abreast)
STEP_BUDGET = 6  # an action may take this many times its planned steps before it is cut


@dataclass
class SessionTrace:
    """Errors of one session and configuration: robot -> error (m) at each path node."""

    errors: dict[str, list[float]] = field(default_factory=dict)
    truncated: bool = False


@dataclass
class ExecutionResult:
    """Position errors of every session: with (config 1) and without (config 2) mutual observations."""

    robots: list[str]
    nodes: dict[str, list[int]]  # robot -> roadmap node at each recorded point (start first)
    errors: dict[tuple[int, str], np.ndarray]  # (config, robot) -> (sessions, nodes)
    truncated_sessions: int

    def mean_errors(self, config: int, robot: str) -> np.ndarray:
        return np.nanmean(self.errors[(config, robot)], axis=0)

    def worst(self, config: int, robot: str) -> float:
        """The worst-case position error: the largest average error over the path nodes."""
        return float(np.nanmax(self.mean_errors(config, robot)))

    def reduction(self, robot: str) -> float:
        """How much lower (%) the worst-case error is with mutual observations."""
        w1, w2 = self.worst(1, robot), self.worst(2, robot)
        return 100.0 * (w2 - w1) / w2 if w2 > 0 else 0.0

    @property
    def starved(self) -> str:
        """The robot that suffers most without mutual observations (the paper's r')."""
        return max(self.robots, key=lambda r: self.worst(2, r))


@dataclass(frozen=True)
class Draws:
    """A session's random numbers, indexed so that both configurations share them."""

    initial: np.ndarray  # (N, 3)
    motion: np.ndarray  # (N, S, 2)
    landmark: np.ndarray  # (N, S, L, 2)
    mutual: np.ndarray  # (N, N, S, 2)

    @staticmethod
    def draw(seed: int, session: int, n: int, steps: int, landmarks: int) -> Draws:
        rng = np.random.default_rng([seed, session])
        return Draws(
            initial=rng.standard_normal((n, 3)),
            motion=rng.standard_normal((n, steps, 2)),
            landmark=rng.standard_normal((n, steps, landmarks, 2)),
            mutual=rng.standard_normal((n, n, steps, 2)),
        )


def reached(est: np.ndarray, previous: np.ndarray, waypoint: np.ndarray) -> bool:
    """Whether the robot (its estimate) is at ``waypoint`` or abreast of it: no more than
    ``ARRIVED`` short of the line through the waypoint perpendicular to the segment from
    ``previous``. Without the second test a robot a few centimetres to the side of a
    waypoint turns on the spot to reach it, and every such turn adds heading noise."""
    dx, dy = waypoint[0] - est[0], waypoint[1] - est[1]
    if math.hypot(dx, dy) < ARRIVED:
        return True
    sx, sy = waypoint[0] - previous[0], waypoint[1] - previous[1]
    length = math.hypot(sx, sy)
    return length > ARRIVED and (dx * sx + dy * sy) / length <= ARRIVED


def advance(
    queue: list[np.ndarray], previous: np.ndarray, est: np.ndarray, errors: list[float], truth: np.ndarray
) -> np.ndarray:
    """Drop the waypoints the robot has reached from ``queue``, recording the position error
    at each; returns the last waypoint reached (``previous`` if none)."""
    while queue and reached(est, previous, queue[0]):
        previous = queue.pop(0)
        errors.append(float(np.hypot(*(truth[:2] - est[:2]))))
    return previous


def control(est: np.ndarray, waypoint: np.ndarray, speed: float, turn_rate: float, dt: float) -> np.ndarray:
    """The waypoint controller: turn on the spot, or drive with a heading correction."""
    dx, dy = waypoint[0] - est[0], waypoint[1] - est[1]
    err = float(wrap_angle(math.atan2(dy, dx) - est[2]))
    omega = max(-turn_rate, min(turn_rate, err / dt))
    if abs(err) > ALIGN:
        return np.array([0.0, omega])
    return np.array([min(speed, math.hypot(dx, dy) / dt), omega])


Waypoints = list[np.ndarray]  # a robot's path as (x, y) points, its start first


@dataclass
class _Team:
    """The state of one session: the true poses, the filter's joint belief, the errors so far."""

    scenario: Scenario
    world: World
    draws: Draws
    vis: LandmarkVisibility
    mutual: bool
    truth: np.ndarray  # (N, 3) true poses
    belief: Belief  # the joint EKF belief over all robots
    trace: SessionTrace
    step: int = 0  # control steps taken (indexes the draws)

    @classmethod
    def start(cls, scenario: Scenario, world: World, draws: Draws, vis: LandmarkVisibility, mutual: bool) -> _Team:
        """True initial poses drawn from the initial beliefs; the filter starts at the beliefs."""
        n = len(scenario.robots)
        mean = np.concatenate([r.pose.as_array() for r in scenario.robots])
        cov = np.zeros((3 * n, 3 * n))
        truth = np.empty((n, 3))
        for i, r in enumerate(scenario.robots):
            cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = r.cov
            truth[i] = r.pose.as_array() + np.linalg.cholesky(r.cov) @ draws.initial[i]
        errors = {
            r.name: [float(np.hypot(*(truth[i, :2] - mean[3 * i : 3 * i + 2])))] for i, r in enumerate(scenario.robots)
        }
        return cls(scenario, world, draws, vis, mutual, truth, Belief(mean, cov), SessionTrace(errors))

    def estimate(self, i: int) -> np.ndarray:
        return self.belief.mean[3 * i : 3 * i + 3]

    def run_action(self, paths: dict[str, Waypoints]) -> None:
        """Drive the robots of one plan step along their paths until all arrive (or the budget ends)."""
        robots = [r.name for r in self.scenario.robots]
        moving = [robots.index(r) for r in paths]
        queue = {i: [np.asarray(p, dtype=float) for p in paths[robots[i]][1:]] for i in moving}
        previous = {i: np.asarray(paths[robots[i]][0], dtype=float) for i in moving}
        budget = STEP_BUDGET * max(1, sum(len(q) for q in queue.values())) * 40
        for _ in range(budget):
            if not any(queue.values()) or self.step >= self.draws.motion.shape[1]:
                break
            u = np.zeros((len(robots), 2))
            for i in moving:
                errors = self.trace.errors[robots[i]]
                previous[i] = advance(queue[i], previous[i], self.estimate(i), errors, self.truth[i])
                if queue[i]:
                    spec = self.scenario.robots[i]
                    u[i] = control(self.estimate(i), queue[i][0], spec.speed, spec.turn_rate, self.scenario.models.dt)
            self._move(moving, u)
            self._observe(moving)
            self.step += 1
        for i in moving:  # arrival at the last waypoint is checked after the final step
            errors = self.trace.errors[robots[i]]
            previous[i] = advance(queue[i], previous[i], self.estimate(i), errors, self.truth[i])
            if queue[i]:
                self.trace.truncated = True
                errors.extend([math.nan] * len(queue[i]))

    def _move(self, moving: list[int], u: np.ndarray) -> None:
        """The true robots move with noisy controls; the filter predicts with the commands."""
        models = self.scenario.models
        for i in moving:
            W = motion_noise_cov(u[i], models.motion_noise)
            noisy = u[i] + np.sqrt(np.diag(W)) * self.draws.motion[i, self.step]
            self.truth[i] = motion(self.truth[i], noisy, models.dt)
        self.belief = ekf.predict(self.belief, u, models.dt, models.motion_noise)

    def _observe(self, moving: list[int]) -> None:
        """Landmark observations of the moving robots, then (config 1) their mutual observations."""
        models, truth, step = self.scenario.models, self.truth, self.step
        q_lm = models.landmark_sensor.Q
        chol_lm = np.linalg.cholesky(q_lm)
        landmarks = self.world.landmark_xy
        seen = self.vis.visible(truth[moving], models.landmark_sensor.fov)
        for k, i in enumerate(moving):
            for lm in np.flatnonzero(seen[k]):
                z = noisy_observation(landmark_obs(truth[i], landmarks[lm]), chol_lm, self.draws.landmark[i, step, lm])
                self.belief = ekf.update_landmark(self.belief, i, landmarks[lm], z, q_lm)
        if not self.mutual or len(moving) < 2:
            return
        q_mu = models.mutual_sensor.Q
        chol_mu = np.linalg.cholesky(q_mu)
        robots = self.scenario.robots
        for i in moving:
            for j in (j for j in moving if j != i):
                # config 1 senses whatever the scenario's switch says
                sensing = MutualSensing.of_sensor(self.scenario, robots[i].name, robots[j].name)
                if sensing.visible(self.world, truth[i : i + 1], truth[j : j + 1])[0]:
                    z = noisy_observation(mutual_obs(truth[i], truth[j]), chol_mu, self.draws.mutual[i, j, step])
                    self.belief = ekf.update_mutual(self.belief, i, j, z, q_mu)


def run_session(
    scenario: Scenario,
    world: World,
    plan_paths: list[dict[str, Waypoints]],
    draws: Draws,
    mutual: bool,
    vis: LandmarkVisibility,
) -> SessionTrace:
    """One execution of the plan: ``plan_paths`` lists, per plan step, {robot: its path's points,
    start first}."""
    team = _Team.start(scenario, world, draws, vis, mutual)
    for paths in plan_paths:
        team.run_action(paths)
    return team.trace


def execute(report: PlanReport, sessions: int = 25, seed: int = 0) -> ExecutionResult:
    """Execute ``report``'s plan ``sessions`` times in both configurations."""
    scenario, world, roadmap = report.scenario, report.world, report.roadmap
    robots = [r.name for r in scenario.robots]
    plan_paths: list[dict[str, Waypoints]] = []
    nodes: dict[str, list[int]] = {r: [roadmap.starts[r]] for r in robots}
    for action in report.actions:
        step = {}
        for (robot, _, _), path in zip(action.moves, action.paths, strict=True):
            step[robot] = [roadmap.nodes[n] for n in path]
            nodes[robot].extend(path[1:])
        plan_paths.append(step)
    planned = sum(len(t) for t in report.trajectories.values())
    vis = LandmarkVisibility(world, scenario.models.landmark_sensor.range)
    errors: dict[tuple[int, str], list[list[float]]] = {(c, r): [] for c in (1, 2) for r in robots}
    truncated = 0
    for s in range(sessions):
        draws = Draws.draw(seed, s, len(robots), STEP_BUDGET * planned + 100, world.landmark_xy.shape[0])
        cut = False
        for config, mutual in ((1, True), (2, False)):
            trace = run_session(scenario, world, plan_paths, draws, mutual, vis)
            cut |= trace.truncated
            for r in robots:
                errors[(config, r)].append(trace.errors[r])
        truncated += int(cut)
    return ExecutionResult(robots, nodes, {k: np.array(v, dtype=float) for k, v in errors.items()}, truncated)


def error_summary(result: ExecutionResult, sessions: int) -> list[str]:
    """The worst-case position error per robot in both configurations (what ``tmpnav simulate`` prints)."""
    lines = [f"{sessions} sessions; worst-case position error (largest average error over the path's nodes):"]
    for robot in result.robots:
        lines.append(
            f"  {robot}: with mutual observations {result.worst(1, robot):.3f} m, "
            f"without {result.worst(2, robot):.3f} m, {result.reduction(robot):.1f}% lower"
        )
    starved = result.starved
    lines.append(
        f"landmark-starved robot (largest error without mutual observations): {starved}, "
        f"{result.reduction(starved):.1f}% lower with mutual observations"
    )
    if result.truncated_sessions:
        lines.append(f"note: {result.truncated_sessions} session(s) did not reach every node within the step budget")
    return lines


def errors_csv(result: ExecutionResult, roadmap: Roadmap) -> str:
    """Average (and spread of) the position error at each node, per robot and configuration."""
    rows = [
        "config,mutual_observations,robot,node_index,roadmap_node,x,y,mean_error_m,std_error_m,max_error_m,sessions"
    ]
    for config in (1, 2):
        for robot in result.robots:
            errors = result.errors[(config, robot)]
            for k, node in enumerate(result.nodes[robot]):
                col = errors[:, k]
                x, y = roadmap.nodes[node]
                rows.append(
                    f"{config},{'yes' if config == 1 else 'no'},{robot},{k},{node},{x:.4f},{y:.4f},"
                    f"{np.nanmean(col):.6f},{np.nanstd(col):.6f},{np.nanmax(col):.6f},{int(np.sum(~np.isnan(col)))}"
                )
    return "\n".join(rows) + "\n"
