"""One session of ``tmpnav simulate``: the plan's schedule executed by the whole team at once.

Every robot follows its own queue of moves at the same time, on one clock of the models'
``dt``; where each robot is in its queue, when it starts its next move (at the plan's start
time, never earlier, and with its partner for a paired move) and when a move ends or is cut is
the schedule's bookkeeping (:mod:`tmpnav.execution.schedule`). :class:`Session` runs the
simulated world around it. Each control step, for the whole team together:

1. driving robots drop the waypoints they have reached (the position error recorded at each);
   a robot that reached its last one ends its move, and moves that may start now start;
2. every driving robot gets its navigation's command (:mod:`tmpnav.execution.navigation`: the
   waypoint controller or nav2's RPP; with ``steers_local``, AMCL's default, on its estimate
   placed among the walls it sees, each command checked against them, and nav2's recovery
   behaviours when the controller cannot go on, a move nav2 gives up cut where the robot stands),
   every other robot (waiting, idle, done) none: zero control, so its uncertainty does not grow;
3. the true robots move with the commands plus noise drawn from W(u) (paper eq. (4)); the
   team's localiser (:class:`~tmpnav.execution.localisers.TeamLocaliser`: the joint EKF of
   :mod:`.joint_ekf`, or every robot's AMCL) predicts with the commands. In a step where RPP
   drives a robot at nav2's controller rate (:meth:`RppFollower.step
   <tmpnav.execution.rpp.RppFollower.step>`), every robot moves, and is predicted, command by
   command, as odometry follows them;
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

import numpy as np

from tmpnav.belief.models import motion, motion_noise_cov
from tmpnav.execution.contact import walls_and_touches
from tmpnav.execution.control import reached
from tmpnav.execution.joint_ekf import JointEkf
from tmpnav.execution.localisers import Localisation, TeamLocaliser
from tmpnav.execution.moves import QueuedMove, RobotQueue
from tmpnav.execution.navigation import Navigator
from tmpnav.execution.recovery import BEHAVIOURS, Recovery
from tmpnav.execution.rpp import Rounding, RppFollower, drive
from tmpnav.execution.schedule import TeamSchedule
from tmpnav.execution.trace import Draws, HitEvent, SessionTrace, free_start, nees
from tmpnav.roadmap.shortcut import required_clearance
from tmpnav.types import Belief, Scenario
from tmpnav.world import World
from tmpnav.world.visibility import LandmarkVisibility


class Session:
    """The state of one session in one configuration (see the module docstring): the simulated
    world (true poses, commands, sensing, the localiser); where the robots are in their queues is
    :attr:`schedule`'s, which asks this session what it needs to know of the robots."""

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
        self.dt = scenario.models.dt
        self.step = 0  # control steps taken (indexes the draws)
        self.truth, belief, self.trace = self._initial()
        self.radii = np.array([r.radius for r in scenario.robots], dtype=float)
        self._contacts: dict[tuple[int, str], HitEvent] = {}  # (robot, kind) -> the contact going on
        self.trace.wall_hits = dict.fromkeys(self.names, 0)
        self.trace.contacts = dict.fromkeys(self.names, 0)
        self.trace.planned_nees = {r: [math.nan] for r in self.names}
        self.trace.own_nees = {r: [] for r in self.names}
        self.trace.beams = {r: [0, 0] for r in self.names}
        for terms in (self.trace.c_u, self.trace.c_sigma, self.trace.c_goal):
            terms.update(dict.fromkeys(self.names, 0.0))
        #: the robots' speed now, as a share of their commands (0: stopped; set by a closed loop's events)
        self.speed = np.ones(len(self.names))
        #: this step's commands (N, 2) at nav2's controller rate of the robots RPP drives, by robot
        #: (tmpnav.execution.rpp.RppFollower.step; their mean is the robot's command)
        self.profiles: dict[int, np.ndarray] = {}
        self.schedule = TeamSchedule(self.names, queues, self.trace, scenario.goals, self.dt, self)
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
        schedule = self.schedule
        while True:
            if pause is not None:
                schedule.arrive(self.step)
                if pause():
                    return self.trace
            schedule.arrive_and_start(self.step)
            if schedule.finished:
                break
            if self.step >= self.draws.steps:
                schedule.cut_all(self.step)
                break
            if not schedule.driving:
                schedule.check_waiting(self.step)
                if schedule.finished:
                    break
            u = self._commands()
            self._move(u)
            self._observe()
            self._collide()
            self._add_costs(u)
            self.step += 1
        return self.trace

    def _commands(self) -> np.ndarray:
        """The driving robots' commands (n, 2) this step, at their speed now; zero for the others.
        The robots RPP drives get the mean of the step's commands at nav2's controller rate, which
        they drive (:attr:`profiles`)."""
        u = np.zeros((len(self.names), 2))
        self.profiles = {}
        for i, r in enumerate(self.schedule.robots):
            if not r.waypoints:
                continue
            command = self.navigator.command(i, r, self.estimate(i), self.truth, self.step, self.world)
            if r.recovery is not None and r.recovery.given_up:  # nav2 failed the navigation
                self.schedule.give_up(i, self.step)
                continue
            u[i] = self.speed[i] * command
            if (profile := self.navigator.profiles.get(i)) is not None and self.speed[i] > 0.0:
                self.profiles[i] = self.speed[i] * profile
            if self.speed[i] == 0.0:
                self.schedule.hold(i, self.step)
        return u

    @property
    def robots(self) -> list[RobotQueue]:
        """Where each robot is in its queue (:class:`~tmpnav.execution.schedule.TeamSchedule`)."""
        return self.schedule.robots

    @property
    def down(self) -> set[int]:
        """The robots that are down: they stand where they are for the rest of the session."""
        return self.schedule.down

    @property
    def finished(self) -> bool:
        """Every robot has made all its moves (or was cut)."""
        return self.schedule.finished

    def adopt(self, moves: Mapping[str, tuple[QueuedMove, ...]]) -> None:
        """Go on with new queues (a revised plan, its clock starting now): a move under way is
        dropped where the robot is (the new plan starts there), a robot at a station ends its
        service first, a robot down gets none."""
        self.schedule.adopt(moves, self.step)

    def set_down(self, robot: str) -> None:
        """The robot is down from now: its move under way and its queue are dropped, and it stands."""
        i = self.names.index(robot)
        self.schedule.set_down(i, self.step)
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
        for i, (name, r) in enumerate(zip(self.names, self.schedule.robots, strict=True)):
            if r.waypoints:
                cov = self.estimate_cov(i)
                self.trace.c_u[name] += float(u[i, 0] * u[i, 0] + u[i, 1] * u[i, 1]) * self.dt
                self.trace.c_sigma[name] += float(cov[0, 0] + cov[1, 1] + cov[2, 2]) * self.dt

    # ------------------------------------------------------------------ what the schedule asks (schedule.Team)

    def at_waypoint(self, i: int, r: RobotQueue) -> bool:
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

    def position_error(self, i: int) -> np.ndarray:
        """Robot i's true position minus its estimated one (2,) m."""
        return self.truth[i, :2] - self.estimate(i)[:2]

    def navigation(self, i: int, m: QueuedMove) -> tuple[Recovery | None, RppFollower | None]:
        """How robot i drives the move ``m`` it starts now: nav2's recoveries (with ``steers_local``)
        and RPP (when the move's controller is RPP's)."""
        recovery = self.navigator.recovery(self.truth[i], self.step)
        if self.localisation.steers_rpp(m.controller) and len(m.points) > 1:
            spec = self.scenario.robots[i]
            rpp = self.localisation.rpp
            return recovery, RppFollower(m.points, rpp, spec.speed, spec.turn_rate, self.dt, rounding=self._rounding(i))
        return recovery, None

    def _rounding(self, i: int) -> Rounding:
        """How robot i's RPP rounds a path's corners: as the plan's motions round them, on the map
        the plan was made on (tmpnav.oracle.motions.MotionLibrary.required)."""
        grid = self.world.grid
        required = required_clearance(self.scenario.robots[i].radius, self.scenario.roadmap, float(grid.resolution))
        origin = (float(grid.origin[0]), float(grid.origin[1]))
        return Rounding(required, self.world.clearance, origin, float(grid.resolution))

    # ------------------------------------------------------------------ the team's motion and sensing

    def _move(self, u: np.ndarray) -> None:
        """The true robots move with noisy controls (none for a robot standing: W(0) = 0); the
        filter predicts with the commands. In a step where RPP drives some robot at nav2's
        controller rate (:attr:`profiles`), every robot moves command by command (the others
        holding theirs), each command with the robot's noise of the step, and the localiser
        predicts with them one by one, as odometry would: truth and prediction follow the same
        commands."""
        models = self.scenario.models
        z = self.draws.motion[:, self.step]
        steps = self._steps(u)
        if steps is None:
            W = motion_noise_cov(u, models.motion_noise)  # (n, 2, 2), diagonal
            moved = motion(self.truth, u + np.sqrt(np.stack([W[:, 0, 0], W[:, 1, 1]], axis=-1)) * z, models.dt)
        else:
            alphas = np.asarray(models.motion_noise, dtype=float)
            moved = np.stack([drive(self.truth[i], steps[i], z[i], alphas, models.dt) for i in range(len(u))])
        if self.world is self.base:
            self.truth = moved
        else:
            for i in range(len(self.names)):
                if not self._closed_in_way(moved[i, :2], self.radii[i]):
                    self.truth[i] = moved[i]
        self.localiser.predict(u, steps)

    def _steps(self, u: np.ndarray) -> np.ndarray | None:
        """The team's commands (n, N, 2) at the controller rate this step, where some robot has
        them (:attr:`profiles`), the others holding theirs (``u``) N times; None where none has."""
        if not self.profiles:
            return None
        n = next(iter(self.profiles.values())).shape[0]  # every follower steps at the same dt
        steps = np.repeat(u[:, None, :], n, axis=1)
        for i, commands in self.profiles.items():
            steps[i] = commands
        return steps

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
        r = self.schedule.robots[i]
        if r.move is None or not r.waypoints:
            return
        r.track = r.move.planned_from(r.track, self.truth[i, :2])
        self.trace.consistency.record(self.names[i], r.move.step, error, own, r.move.planned_at(r.track))

    def _collide(self) -> None:
        """Count the true poses, after this control step, that hit a wall, and the robots that touch
        (closer than their radii added): what the collision bound (docs/models.md) bounds. Each
        robot's error against its localiser's covariance is recorded too (consistency, NEES)."""
        for i, name in enumerate(self.names):
            error = self.position_error(i)
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
                key = (name, self.schedule.move_step(i))
                self.trace.move_hits[key] = self.trace.move_hits.get(key, 0) + int(walls[i])
                self.trace.move_contacts[key] = self.trace.move_contacts.get(key, 0) + int(touch[i])
            for kind, now in (("wall", bool(walls[i])), ("robot", bool(touch[i]))):
                self._mark(i, kind, now)

    def _mark(self, i: int, kind: str, now: bool) -> None:
        """Record a contact of robot i of ``kind`` where it begins (a :class:`HitEvent`), and count
        the steps it lasts."""
        going = self._contacts.get((i, kind))
        if not now:
            self._contacts.pop((i, kind), None)
        elif going is not None:
            going.steps += 1
        else:
            error = self.position_error(i)
            cov = self.estimate_cov(i)[:2, :2]
            event = HitEvent(
                self.names[i],
                self.schedule.move_step(i),
                kind,
                (self.step + 1) * self.dt,
                float(self.truth[i, 0]),
                float(self.truth[i, 1]),
                float(math.hypot(error[0], error[1])),
                float(math.sqrt(max(np.trace(cov), 0.0) / 2.0)),
            )
            self._contacts[(i, kind)] = event
            self.trace.hit_events.append(event)
