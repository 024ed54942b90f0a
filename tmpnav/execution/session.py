"""One session of ``tmpnav simulate``: the plan's schedule executed by the whole team at once.

Every robot follows its own queue of moves (:mod:`tmpnav.execution.moves`) at the same time,
on one clock of the models' ``dt``. A robot starts its next move when

* it has reached the end of its previous move (its estimate at the path's last node),
* for a paired move, its partner has reached the end of its own previous move (the one that
  is there first waits), and
* the plan's start time of the move has come (never earlier: the planner may hold a move back
  to keep clear of another robot).

Each control step, for the whole team together:

1. driving robots drop the waypoints they have reached (the position error recorded at each);
   a robot that reached its last one ends its move, and moves that may start now start;
2. every driving robot gets its navigation's command (:mod:`tmpnav.execution.navigation`: the
   waypoint controller or nav2's RPP; with ``steers_local``, AMCL's default, on its estimate
   placed among the walls it sees, each command checked against them, and nav2's recovery
   behaviours when the controller cannot go on, a move nav2 gives up cut where the robot stands),
   every other robot (waiting, idle, done) none: zero control, so its uncertainty does not grow;
3. the true robots move with the commands plus noise drawn from W(u) (paper eq. (4)); the
   team's localiser (:class:`~tmpnav.execution.localisers.TeamLocaliser`: the joint EKF of
   :mod:`.joint_ekf`, or every robot's AMCL) predicts with the commands;
4. every robot observes from its true pose, moving or standing, what its localiser takes: the
   landmarks it sees (range, field of view, line of sight) with sensor noise; with a range
   sensor, a scan of the walls the filter compares with one ray cast from its estimate
   (:mod:`tmpnav.execution.scans`); with mutual observations (config 1) any two robots in
   range and line of sight of each other at that instant;
5. the true poses are checked (:meth:`Session._collide`): a robot whose true position hits a
   wall (:func:`tmpnav.belief.risk.hits_wall`: its cell's clearance at most its radius, or off
   the map), and two robots whose true positions are closer than their radii added, are counted
   (compiled: :mod:`.contact`).

Both configurations of a session use the same random draws (initial poses, control noise and
observation noise are indexed by robot and control step), so their comparison is paired.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import replace

import numpy as np

from tmpnav.belief.models import motion, motion_noise_cov
from tmpnav.errors import TmpnavError
from tmpnav.execution.contact import walls_and_touches
from tmpnav.execution.control import reached
from tmpnav.execution.joint_ekf import JointEkf
from tmpnav.execution.localisers import Localisation, TeamLocaliser
from tmpnav.execution.moves import QueuedMove, RobotQueue
from tmpnav.execution.navigation import Navigator
from tmpnav.execution.recovery import BEHAVIOURS
from tmpnav.execution.rpp import RppFollower
from tmpnav.execution.trace import Draws, SessionTrace, nees
from tmpnav.results import TimedMove
from tmpnav.types import Belief, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility

#: a move may take this many times its planned steps (or 40 steps per waypoint) before it is cut
STEP_BUDGET = 6


class Session:
    """The state of one session in one configuration (see the module docstring)."""

    def __init__(
        self,
        scenario: Scenario,
        world: World,
        queues: Mapping[str, tuple[QueuedMove, ...]],
        draws: Draws,
        vis: LandmarkVisibility,
        mutual: bool,
        localisation: Localisation | None = None,
        session: int = 0,
    ):
        self.scenario, self.world, self.draws, self.vis, self.mutual = scenario, world, draws, vis, mutual
        self.localisation = (localisation or Localisation()).following(scenario.models.driving)
        self.base = world  # the world the session started in (a closed loop may close doors)
        self.barriers: np.ndarray | None = None  # (k, 2) m: the centres of the cells closed since
        self.names = tuple(r.name for r in scenario.robots)
        self.robots = [RobotQueue(queues.get(r, ())) for r in self.names]
        self.dt = scenario.models.dt
        self.step = 0  # control steps taken (indexes the draws)
        self.truth, belief, self.trace = self._initial()
        self.radii = np.array([r.radius for r in scenario.robots], dtype=float)
        self.trace.wall_hits = dict.fromkeys(self.names, 0)
        self.trace.contacts = dict.fromkeys(self.names, 0)
        self.trace.planned_nees = {r: [math.nan] for r in self.names}
        self.trace.own_nees = {r: [] for r in self.names}
        self.trace.beams = {r: [0, 0] for r in self.names}
        for terms in (self.trace.c_u, self.trace.c_sigma, self.trace.c_goal):
            terms.update(dict.fromkeys(self.names, 0.0))
        #: the robots' speed now, as a share of their commands (0: stopped; set by a closed loop's events)
        self.speed = np.ones(len(self.names))
        #: robots that are down: they stand where they are for the rest of the session
        self.down: set[int] = set()
        self.localiser = self._localiser(belief, queues, session)
        self.session = session
        self.trace.recoveries = dict.fromkeys(BEHAVIOURS, 0)
        self.navigator = Navigator(scenario, self.localisation, self.dt)
        self.navigator.see(world, getattr(self.localiser, "site", None), session)

    def _localiser(self, belief: Belief, queues: Mapping[str, tuple[QueuedMove, ...]], session: int) -> TeamLocaliser:
        """Who localises the team, as ``localisation`` says (tmpnav.execution.localisers)."""
        if self.localisation.particle_filter:
            from tmpnav.execution.amcl_team import AmclTeam

            return AmclTeam(self.scenario, self.world, self.draws, belief, self.localisation, queues, session)
        if self.localisation.compiled:
            from tmpnav.execution.fast_ekf import CompiledJointEkf

            return CompiledJointEkf(self.scenario, self.world, self.vis, self.draws, belief, self.mutual)
        return JointEkf(self.scenario, self.world, self.vis, self.draws, belief, self.mutual)

    def steering(self, i: int) -> np.ndarray:
        """The pose robot i's controller steers on (tmpnav.execution.navigation)."""
        return self.navigator.steering(i, self.estimate(i), self.truth[i], self.step)

    def _initial(self) -> tuple[np.ndarray, Belief, SessionTrace]:
        """True initial poses drawn from the initial beliefs, free of the map (:func:`free_start`);
        the filter starts at the beliefs."""
        robots = self.scenario.robots
        n = len(robots)
        mean = np.concatenate([r.pose.as_array() for r in robots])
        cov = np.zeros((3 * n, 3 * n))
        truth = np.empty((n, 3))
        for i, r in enumerate(robots):
            cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = r.cov
            truth[i] = free_start(r.pose.as_array(), r.cov, self.draws.initial[i], self.world, r.radius)
        errors = {r.name: [float(np.hypot(*(truth[i, :2] - mean[3 * i : 3 * i + 2])))] for i, r in enumerate(robots)}
        return truth, Belief(mean, cov), SessionTrace(errors, {r.name: [0.0] for r in robots})

    def estimate(self, i: int) -> np.ndarray:
        """Robot i's estimated pose: its localiser's."""
        return self.localiser.estimate(i)

    def estimate_cov(self, i: int) -> np.ndarray:
        """Robot i's covariance (3, 3) as its localiser reports it."""
        return self.localiser.estimate_cov(i)

    # ------------------------------------------------------------------ the run

    def run(self, pause: Callable[[], bool] | None = None) -> SessionTrace:
        """Execute the schedule until every robot has made all its moves (or the draws run out).

        ``pause``, when given, is asked at each control step once the robots have reached their
        waypoints and before any move starts: True returns at once, and a later ``run`` goes on
        from there (a closed loop changes the team's speed, moves or world in between)."""
        while True:
            if pause is not None:
                self._arrive()
                if pause():
                    return self.trace
            self._arrive_and_start()
            if all(r.move is None and r.next is None for r in self.robots):
                break
            if self.step >= self.draws.steps:
                self._cut_all()
                break
            if not any(r.move is not None for r in self.robots):
                self._check_waiting()
                if all(r.move is None and r.next is None for r in self.robots):
                    break
            u = np.zeros((len(self.names), 2))
            for i, r in enumerate(self.robots):
                if not r.waypoints:
                    continue
                command = self.navigator.command(i, r, self.estimate(i), self.truth, self.step, self.world)
                if r.recovery is not None and r.recovery.given_up:  # nav2 failed the navigation
                    self._give_up(i, r)
                    continue
                u[i] = self.speed[i] * command
                if self.speed[i] == 0.0:
                    r.since += 1  # a stopped robot's move does not use up its budget
                    if r.recovery is not None:
                        r.recovery.hold(self.step)  # nor its progress check
            self._move(u)
            self._observe()
            self._collide()
            self._add_costs(u)
            self.step += 1
        return self.trace

    @property
    def finished(self) -> bool:
        """Every robot has made all its moves (or was cut)."""
        return all(r.move is None and r.next is None for r in self.robots)

    def adopt(self, moves: Mapping[str, tuple[QueuedMove, ...]]) -> None:
        """Go on with new queues (a revised plan, its clock starting now): a move under way is
        dropped where the robot is (the new plan starts there), a robot at a station ends its
        service first, a robot down gets none."""
        for i, (name, r) in enumerate(zip(self.names, self.robots, strict=True)):
            queue = () if i in self.down else moves.get(name, ())
            shifted = tuple(replace(m, start=m.start + self.step) for m in queue)
            self.robots[i] = RobotQueue(shifted, ready=max(r.ready, self.step))

    def set_down(self, robot: str) -> None:
        """The robot is down from now: its move under way and its queue are dropped."""
        i = self.names.index(robot)
        self.down.add(i)
        r = self.robots[i]
        if r.move is not None:
            self._cut(robot, len(r.waypoints))
        self.robots[i] = RobotQueue((), started=0, ready=self.step)
        self.speed[i] = 0.0

    def set_world(self, world: World, vis: LandmarkVisibility) -> None:
        """The world changed (a door closed): the true robots, their scans and sightings see the new
        one, and a closed door stops a robot that drives into it (:meth:`_move`)."""
        self.world, self.vis = world, vis
        added = world.grid.occupied & ~self.base.grid.occupied  # the closed doors' cells
        xs, ys = world.grid.cell_centers()
        rows, cols = np.nonzero(added)
        self.barriers = np.column_stack([xs[cols], ys[rows]]) if added.shape == self.base.grid.occupied.shape else None
        self.localiser.set_world(world, vis)
        self.navigator.see(world, getattr(self.localiser, "site", None), self.session)

    def _add_costs(self, u: np.ndarray) -> None:
        """The executed cost terms of this step (SessionTrace.c_u, c_sigma)."""
        for i, (name, r) in enumerate(zip(self.names, self.robots, strict=True)):
            if r.waypoints:
                cov = self.estimate_cov(i)
                self.trace.c_u[name] += float(u[i, 0] * u[i, 0] + u[i, 1] * u[i, 1]) * self.dt
                self.trace.c_sigma[name] += float(cov[0, 0] + cov[1, 1] + cov[2, 2]) * self.dt

    def _arrive(self) -> None:
        """The waypoints reached now, and the moves ended by them."""
        for i, r in enumerate(self.robots):
            if r.move is not None:
                self._advance(i, r)

    def _arrive_and_start(self) -> None:
        """Waypoints reached, moves ended, then moves started (a move that starts where it ends
        ends at once, and the robot's next move may start too)."""
        while True:
            for i, r in enumerate(self.robots):
                if r.move is not None:
                    self._advance(i, r)
            if not self._start_moves():
                return

    def _advance(self, i: int, r: RobotQueue) -> None:
        """Drop the waypoints robot i has reached, recording the error at each; end its move when
        none is left, or cut it when it has run out of its budget."""
        name = self.names[i]
        assert r.previous is not None and r.move is not None
        while r.waypoints and self._reached(i, r):
            k = len(r.move.waypoints) - len(r.waypoints)  # the path point reached, after its start
            r.previous = r.waypoints.pop(0)
            r.aligned = False  # a new segment: turn towards its end first
            error = self.truth[i, :2] - self.estimate(i)[:2]
            self.trace.errors[name].append(float(np.hypot(*error)))
            self.trace.times[name].append(self.step * self.dt)
            planned = r.move.planned_covs[k] if k < len(r.move.planned_covs) else None
            self.trace.planned_nees[name].append(nees(error, planned))
        if r.waypoints and self.step - r.since >= STEP_BUDGET * max(r.move.steps, 40 * (len(r.move.nodes) - 1)):
            self._cut_move(i, r)
        if not r.waypoints and r.move is not None:
            self._end(r)

    def _reached(self, i: int, r: RobotQueue) -> bool:
        """Whether robot i has reached its next waypoint. With RPP, which cuts corners, a bend is
        reached once the robot is abreast of it, and the move's end within nav2's goal tolerance."""
        assert r.previous is not None
        est = self.steering(i)
        if r.rpp is None:
            return reached(est, r.previous, r.waypoints[0])
        if len(r.waypoints) == 1:
            return r.rpp.at_goal(est)
        k = len(r.rpp.vertices) - len(r.waypoints)  # the path vertex of the next waypoint
        return r.rpp.passed(k) or reached(est, r.previous, r.waypoints[0])

    def _cut_move(self, i: int, r: RobotQueue, given_up: bool = False) -> None:
        """Robot i's move under way ends where it is, short of its room (``given_up``: by nav2,
        else for want of steps)."""
        self._cut(self.names[i], len(r.waypoints), given_up)
        r.waypoints = []
        self._end(r, cut=True)

    def _give_up(self, i: int, r: RobotQueue) -> None:
        """nav2 failed robot i's navigation after its last recovery: the move is given up where it stands."""
        self._cut_move(i, r, given_up=True)
        self.trace.given_up.append(self.trace.moves[-1])

    def _end(self, r: RobotQueue, cut: bool = False) -> None:
        """Robot r ends its move now: record it as executed (``cut``: short of its room); the robot
        is ready for its next."""
        m = r.move
        assert m is not None
        dt = self.dt
        goals = self.scenario.goals
        # it waits at the station for the job's window to open, then stands there for the service
        opens = goals.opens_steps(m.target, self.step, dt)
        stand = goals.service_steps(m.target, dt)
        executed = TimedMove(
            m.step,
            m.robot,
            m.origin,
            m.target,
            m.partner,
            r.ready * dt,
            r.since * dt,
            self.step * dt,
            stand * dt,
            opens * dt,
        )
        self.trace.moves.append(executed)
        if cut:
            self.trace.cut.append(executed)
        r.move, r.ready = None, self.step + opens + stand
        if r.recovery is not None:
            for name, count in r.recovery.run.items():
                self.trace.recoveries[name] += count
            r.recovery = None
        if len(m.points):
            i = self.names.index(m.robot)
            self.trace.c_goal[m.robot] += float(np.hypot(*(self.estimate(i)[:2] - m.points[-1])))

    def _start_moves(self) -> bool:
        """Start every move whose robots are free and whose planned start has come; whether any did."""
        started = False
        for r in self.robots:
            m = r.next
            if m is None or m.start > self.step or r.ready > self.step:
                continue  # not yet planned to start, or still at a station
            if m.partner is not None:
                other = self.robots[self.names.index(m.partner)]
                n = other.next
                if n is None or n.step != m.step or n.start > self.step or other.ready > self.step:
                    continue  # the partner is not there yet: wait for it
                self._start(other, n)
            self._start(r, m)
            started = True
        return started

    def _start(self, r: RobotQueue, m: QueuedMove) -> None:
        r.move, r.started, r.since, r.aligned, r.track = m, r.started + 1, self.step, False, 0
        r.waypoints, r.previous = m.waypoints, np.asarray(m.points[0], dtype=float)
        r.recovery = self.navigator.recovery(self.truth[self.names.index(m.robot)], self.step)
        if self.localisation.steers_rpp(m.controller) and len(m.points) > 1:
            spec = self.scenario.robots[self.names.index(m.robot)]
            r.rpp = RppFollower(m.points, self.localisation.rpp, spec.speed, spec.turn_rate, self.dt)
        else:
            r.rpp = None

    def _cut(self, name: str, points: int, given_up: bool = False) -> None:
        """Points of a path never reached: no error, no time. The session is truncated (out of its
        step budget or draws) unless nav2 gave the move up."""
        self.trace.truncated = self.trace.truncated or not given_up
        self.trace.errors[name].extend([math.nan] * points)
        self.trace.times[name].extend([math.nan] * points)
        self.trace.planned_nees[name].extend([math.nan] * points)

    def _cut_all(self) -> None:
        """The draws have run out: every move under way or not started is cut."""
        for i, r in enumerate(self.robots):
            name = self.names[i]
            if r.move is not None:
                self._cut_move(i, r)
            for m in r.queue[r.started :]:
                self._cut(name, len(m.waypoints))
            r.started = len(r.queue)

    def _check_waiting(self) -> None:
        """Nobody drives: some robot must be waiting for a planned start still to come, or still at
        a station (waiting for a window, in service), else the schedule cannot go on (a paired
        move whose partner waits for another one)."""
        if any(r.next is not None and max(r.next.start, r.ready) > self.step for r in self.robots):
            return
        if self.down:  # robots waiting for a partner that is down wait for ever: their moves are cut
            for i, r in enumerate(self.robots):
                if r.next is not None:
                    for left in r.queue[r.started :]:
                        self._cut(self.names[i], len(left.waypoints))
                    r.started = len(r.queue)
            return
        stuck = ", ".join(
            f"{m.robot} at step {m.step + 1} waits for {m.partner}" for r in self.robots if (m := r.next) is not None
        )
        raise TmpnavError(f"the plan's schedule cannot be executed: {stuck}")

    # ------------------------------------------------------------------ the team's motion and sensing

    def _move(self, u: np.ndarray) -> None:
        """The true robots move with noisy controls (none for a robot standing: W(0) = 0); the
        filter predicts with the commands."""
        models = self.scenario.models
        W = motion_noise_cov(u, models.motion_noise)  # (n, 2, 2), diagonal
        noisy = u + np.sqrt(np.stack([W[:, 0, 0], W[:, 1, 1]], axis=-1)) * self.draws.motion[:, self.step]
        moved = motion(self.truth, noisy, models.dt)
        if self.world is self.base:
            self.truth = moved
        else:
            for i in range(len(self.names)):
                if not self._closed_in_way(moved[i, :2], self.radii[i]):
                    self.truth[i] = moved[i]
        self.localiser.predict(u)

    def _closed_in_way(self, xy: np.ndarray, radius: float) -> bool:
        """Whether a robot at ``xy`` would touch a cell the world has now and had not at the start (a
        closed door): such a robot stands where it is, blocked. Every other wall a true pose reaches
        is counted as a hit (:meth:`_collide`) and passed, as the collision bound assumes."""
        if self.barriers is None or not len(self.barriers):
            return False
        return bool(np.min(np.hypot(*(self.barriers - xy).T)) < radius)

    def _observe(self) -> None:
        """The robots' observations from their true poses, to their localiser."""
        for name, (used, rejected) in zip(self.names, self.localiser.observe(self.truth, self.step), strict=True):
            self.trace.beams[name][0] += used
            self.trace.beams[name][1] += rejected

    def _record_consistency(self, i: int, error: np.ndarray, own: np.ndarray) -> None:
        """Robot i's actual position error (2,), its localiser's covariance (2, 2) and the plan's at this
        step of its move, when it drives."""
        r = self.robots[i]
        if r.move is None or not r.waypoints:
            return
        r.track = r.move.planned_from(r.track, self.truth[i, :2])
        self.trace.consistency.record(self.names[i], r.move.step, error, own, r.move.planned_at(r.track))

    def _collide(self) -> None:
        """Count the true poses, after this control step, that hit a wall, and the robots that touch
        (closer than their radii added): what the collision bound (docs/models.md) bounds. Each
        robot's error against its localiser's covariance is recorded too (consistency, NEES)."""
        for i, name in enumerate(self.names):
            error = self.truth[i, :2] - self.estimate(i)[:2]
            own = self.estimate_cov(i)[:2, :2]
            self._record_consistency(i, error, own)
            value = nees(error, own)
            if not math.isnan(value):
                self.trace.own_nees[name].append(value)
        walls, touch = walls_and_touches(self.world, self.truth, self.radii)
        for i, name in enumerate(self.names):
            if walls[i] or touch[i]:
                self.trace.wall_hits[name] += int(walls[i])
                self.trace.contacts[name] += int(touch[i])
                key = (name, self._move_step(self.robots[i]))
                self.trace.move_hits[key] = self.trace.move_hits.get(key, 0) + int(walls[i])
                self.trace.move_contacts[key] = self.trace.move_contacts.get(key, 0) + int(touch[i])

    @staticmethod
    def _move_step(r: RobotQueue) -> int:
        """The plan step of robot r's move under way, or of its last one when it stands (-1 before its first)."""
        if r.move is not None:
            return r.move.step
        return r.queue[r.started - 1].step if r.started else -1


#: redraws of a true start that a robot's disc would find in collision with the map
START_REDRAWS = 64


def free_start(mean: np.ndarray, cov: np.ndarray, z: np.ndarray, world: World, radius: float) -> np.ndarray:
    """A true start pose (3,) drawn from the belief N(mean, cov) with the standard normal draw
    ``z`` (3,), conditioned on the robot's disc being free of the map: a robot cannot stand in a
    wall, however wide its initial belief. Where mean + L z (L L^T = cov) is free, that pose;
    else the first free one of up to :data:`START_REDRAWS` redraws from a stream seeded by the
    bits of ``z`` (the same in every process), or the last of them."""
    root = np.linalg.cholesky(cov)
    pose = mean + root @ z
    if world.is_free(pose[None, :2], radius)[0]:
        return pose
    rng = np.random.default_rng(np.frombuffer(np.ascontiguousarray(z, dtype=float).tobytes(), dtype=np.uint32))
    for _ in range(START_REDRAWS):
        pose = mean + root @ rng.standard_normal(3)
        if world.is_free(pose[None, :2], radius)[0]:
            break
    return pose
