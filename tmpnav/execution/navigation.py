"""How ``tmpnav simulate`` steers each robot along its move, as a nav2 robot's navigation stack does.

Each control step, for every robot that drives:

1. the pose it steers on: its localiser's estimate, or with ``steers_local`` (AMCL's default)
   that estimate placed among the walls by the lidar's nearby returns
   (:meth:`~tmpnav.execution.local_view.LocalView.steering_pose`), as nav2's costmaps place what
   the robot sees;
2. the controller's command from that pose: the waypoint follower (:mod:`.control`) or nav2's
   Regulated Pure Pursuit (:mod:`.rpp`), which at a job's station turns to its goal pose's heading;
   RPP gives the step's commands at nav2's controller rate (:attr:`Navigator.profiles`), and the
   command is their mean;
3. with ``steers_local``, the command checked against what the robot sees
   (:meth:`~tmpnav.execution.local_view.LocalView.safe_command`), and nav2's recoveries when
   the controller cannot go on (:mod:`.recovery`): a recovery behaviour's command replaces the
   controller's, and a move whose navigation fails is given up. A command changed there is
   held for the whole step.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tmpnav.errors import TmpnavError
from tmpnav.execution.control import ALIGN, ALIGN_START, control
from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import QueuedMove, RobotQueue
from tmpnav.execution.recovery import Recovery
from tmpnav.types import Scenario
from tmpnav.world import World

if TYPE_CHECKING:
    from tmpnav.execution.local_view import LocalView


#: m: other robots nearer than this are in a robot's costmap (nav2's obstacle_max_range)
OBSTACLE_RANGE = 2.5
#: m: a path that ends this near a station's pose ends on it (its roadmap node is the pose's position)
STATION_MATCH = 1e-6


class Navigator:
    """The navigation stacks of a session's robots (see the module docstring)."""

    def __init__(self, scenario: Scenario, localisation: Localisation, dt: float):
        self.scenario, self.localisation, self.dt = scenario, localisation, dt
        self.view: LocalView | None = None
        self.radii = np.array([r.radius for r in scenario.robots])
        #: the goal poses (x, y, heading) of the jobs' stations, by room (goals.jobs)
        self.stations = {j.room: j.pose for j in scenario.goals.jobs if j.pose is not None}
        self._steered: dict[int, np.ndarray] = {}  # the steering poses of step _steered_at, by robot
        self._steered_at = -1
        #: the commands (N, 2) at nav2's controller rate of the robots RPP drives this step, by
        #: robot (tmpnav.execution.rpp.RppFollower.step): :meth:`command` returns their mean
        self.profiles: dict[int, np.ndarray] = {}

    def see(self, world: World, site: object, session: int) -> None:
        """With ``steers_local``: what the robots' lidars show their controllers of the walls
        (:mod:`.local_view`), on ``site``, the site the localiser scans (None: the map)."""
        self._steered_at = -1
        if not self.localisation.steers_local:
            return
        from tmpnav.execution.local_view import LocalView
        from tmpnav.execution.site import Site, SiteNoise

        if self.scenario.models.range_sensor is None:
            raise TmpnavError(
                "--steer local: the scenario's robots carry no range sensor (models.range_sensor); "
                "expected a scenario with a lidar (the robots steer on the walls it sees)"
            )
        if not isinstance(site, Site):
            site = Site(world, SiteNoise.none(), session)
        self.view = LocalView(site, self.scenario.models.range_sensor)

    def recovery(self, truth: np.ndarray, step: int) -> Recovery | None:
        """A new move's navigation with nav2's recoveries: with ``steers_local`` (a robot that
        steers on its estimate alone never sees a command refused)."""
        if self.view is None or not self.localisation.recoveries:
            return None
        return Recovery(self.localisation.recovery, truth[:2], step, self.dt)

    def steering(self, i: int, est: np.ndarray, truth: np.ndarray, step: int) -> np.ndarray:
        """The pose robot i's controller steers on at ``step``: its estimate ``est``, placed among
        the walls by its lidar's nearby returns from its true pose ``truth`` when the robots steer
        on what they see (once per robot and step: poses change only between steps)."""
        if self.view is None:
            return est
        if self._steered_at != step:
            self._steered, self._steered_at = {}, step
        if i not in self._steered:
            self._steered[i] = self.view.steering_pose(est, truth, step * self.dt)
        return self._steered[i]

    def command(self, i: int, r: RobotQueue, est: np.ndarray, team: np.ndarray, step: int, world: World) -> np.ndarray:
        """Robot i's command (v, omega) at ``step``, driving its move ``r``, the team's true poses
        ``team`` (n, 3): a recovery behaviour's, or the controller's kept clear of what it sees
        (the walls, the clutter and the other robots within :data:`OBSTACLE_RANGE`). A failure of
        the controller is recorded in ``r.recovery`` (which may give the move up)."""
        self.profiles.pop(i, None)
        spec = self.scenario.robots[i]
        truth = team[i]
        if self.view is not None:
            self.view.robots = self._others(i, team)
        rec = r.recovery
        if rec is not None:
            rec.ended(truth[:2], step)
            clear = not rec.backing_up or self._clear_behind(truth, rec.params.backup_speed, spec.radius)
            behaviour = rec.behaviour(spec.turn_rate, clear)
            if behaviour is not None:
                return behaviour
        pose = self.steering(i, est, truth, step)
        assert r.waypoints
        if r.rpp is not None:  # the local costmap holds the walls where they truly are
            if r.rpp.goal_heading is None and r.move is not None:
                r.rpp.goal_heading = self.goal_heading(r.move)
            cell = world.grid.cells(truth[:2][None])
            commands = r.rpp.step(pose, float(world.clearance[cell[0], cell[1]][0]))
            command = commands.mean(axis=0)
            self.profiles[i] = commands
        else:
            align = ALIGN if r.aligned else ALIGN_START
            command = control(pose, r.waypoints[0], spec.speed, spec.turn_rate, self.dt, align)
            r.aligned = r.aligned or bool(command[0] > 0.0)  # it drives: the turn at the node is done
        if self.view is None:
            return command
        ahead = float(np.hypot(*(r.waypoints[0][:2] - pose[:2])))  # where it stops
        safe = self.view.safe_command(truth, command, spec.radius, (spec.speed, spec.turn_rate), ahead, r.waypoints[0])
        if rec is not None:
            rec.followed(safe is None, truth[:2], step)
        if safe is None or not np.array_equal(safe, command):  # a command of its own, held for the step
            self.profiles.pop(i, None)
        return np.array([0.0, command[1]]) if safe is None else safe

    def goal_heading(self, move: QueuedMove) -> float | None:
        """The heading (rad) of the goal pose ``move`` ends at: its target's station when its path
        ends on it (as the plan's motions turn there, tmpnav.oracle.motions), else None. nav2 is
        given a goal pose and turns to its heading once within the goal checker's distance."""
        pose = self.stations.get(move.target)
        if pose is None or not len(move.points) or np.hypot(*(move.points[-1] - np.asarray(pose[:2]))) > STATION_MATCH:
            return None
        return float(pose[2])

    def _others(self, i: int, team: np.ndarray) -> np.ndarray:
        """(k, 3): the centre and radius of every other robot within :data:`OBSTACLE_RANGE` of robot i."""
        near = np.hypot(*(team[:, :2] - team[i, :2]).T) <= OBSTACLE_RANGE
        near[i] = False
        return np.column_stack([team[near, :2], self.radii[near]])

    def _clear_behind(self, truth: np.ndarray, speed: float, radius: float) -> bool:
        """Whether a back-up at ``speed`` keeps clear of what the robot sees over nav2's
        ``simulate_ahead_time`` (no nearer than it is now)."""
        assert self.view is not None
        return self.view.clear_path(truth, -speed, radius, self.localisation.recovery.simulate_ahead)
