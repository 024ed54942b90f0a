"""nav2's recovery behaviours in ``tmpnav simulate``: what a nav2 robot does when its controller
cannot go on, and when it gives a goal up.

nav2 drives every goal through the behaviour tree of its default navigator
(``navigate_to_pose_w_replanning_and_recovery.xml``). Its controller server fails a path when

* the controller finds no command that keeps clear of what the robot sees for longer than
  ``failure_tolerance`` (0.3 s), or
* the progress checker sees the robot move less than ``required_movement_radius`` (0.5 m) in
  ``movement_time_allowance`` (10 s).

The tree then clears the local costmap and tries the path once more (the ``FollowPath``
recovery node's one retry). A second failure fails the navigation's pipeline. The tree runs one
recovery behaviour from a round robin and starts the pipeline again:

1. clear both costmaps;
2. spin 1.57 rad;
3. wait 5 s;
4. back up 0.30 m at 0.05 m/s.

After the 6th retry the navigation fails, and the robot gives its goal up. nav2 checks each
behaviour against the local costmap. A spin of a round footprint moves none of it. A back-up
whose path over the next 2 s (``simulate_ahead_time``) comes nearer to what the robot sees fails
at once, and the round robin goes on to the next behaviour.

In the simulator a costmap holds only what the lidar sees now (:mod:`.local_view`), so clearing it
changes nothing but a control step. A spin and a back-up move the robot and give its localiser
new scans, and AMCL updates after every 0.2 rad and 0.25 m. A robot whose estimate lies half a
metre off in a corner may then find itself again.

The values are nav2's defaults (:class:`RecoveryParams`): the tree of
``nav2_bt_navigator/behavior_trees/navigate_to_pose_w_replanning_and_recovery.xml``, and the
``controller_server`` and ``behavior_server`` sections of ``nav2_bringup/params/nav2_params.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the round robin's behaviours, in nav2's order
BEHAVIOURS = ("clear", "spin", "wait", "backup")


@dataclass(frozen=True)
class RecoveryParams:
    """nav2's defaults for the controller's failures and the recovery behaviours (module docstring)."""

    failure_tolerance: float = 0.3  # s: controller_server.failure_tolerance
    progress_radius: float = 0.5  # m: progress_checker.required_movement_radius
    progress_time: float = 10.0  # s: progress_checker.movement_time_allowance
    retries: int = 6  # the NavigateRecovery node's number_of_retries
    spin: float = 1.57  # rad: Spin spin_dist
    spin_rate: float = 1.0  # rad/s: behavior_server.max_rotational_vel
    wait: float = 5.0  # s: Wait wait_duration
    backup_distance: float = 0.30  # m: BackUp backup_dist
    backup_speed: float = 0.05  # m/s: BackUp backup_speed
    simulate_ahead: float = 2.0  # s: behavior_server.simulate_ahead_time


class Recovery:
    """nav2's navigation of one robot's move: the controller's failures, the recoveries, the
    give-up. The session calls :meth:`behaviour` each control step, and calls :meth:`followed`
    after each step the controller drove."""

    def __init__(self, params: RecoveryParams, xy: np.ndarray, step: int, dt: float):
        self.params, self.dt = params, dt
        self.failures = 0  # the pipeline's failures so far (each one a recovery, the 7th the end)
        self.retried = False  # the FollowPath node has used its one retry (the local costmap cleared)
        self.next = 0  # the round robin's next behaviour
        self.running: str | None = None  # the behaviour under way
        self.left = 0.0  # what is left of it: rad of a spin, s of a wait, m of a back-up
        self.given_up = False
        self.run: dict[str, int] = dict.fromkeys(BEHAVIOURS, 0)  # behaviours started, by name
        self._restart(xy, step)

    def _restart(self, xy: np.ndarray, step: int) -> None:
        """The controller starts on the path again: a new progress check, no refusal."""
        self.anchor, self.anchor_step = np.array(xy[:2], dtype=float), step
        self.refused_since: int | None = None

    def behaviour(self, turn_rate: float, backup_clear: bool) -> np.ndarray | None:
        """The command of the recovery behaviour under way (None: the controller drives). A spin
        turns at ``turn_rate`` (at most nav2's ``spin_rate``); a back-up goes on while
        ``backup_clear`` (its path over :attr:`RecoveryParams.simulate_ahead` keeps clear of what
        the robot sees)."""
        p = self.params
        if self.running == "spin":
            rate = min(turn_rate, p.spin_rate)
            turn = min(rate, self.left / self.dt)
            self.left -= turn * self.dt
            return np.array([0.0, turn])
        if self.running in ("clear", "wait"):  # clearing the costmaps takes a control step
            self.left -= self.dt
            return np.zeros(2)
        if self.running == "backup":
            if not backup_clear:  # a collision ahead: the back-up fails, the round robin goes on
                self._start_next()
                return self.behaviour(turn_rate, backup_clear)
            self.left -= p.backup_speed * self.dt
            return np.array([-p.backup_speed, 0.0])
        return None

    def hold(self, step: int) -> None:
        """The robot is held still (stopped by an event, not by its controller): the progress
        check starts again from ``step``."""
        self.anchor_step = step
        self.refused_since = None

    def ended(self, xy: np.ndarray, step: int) -> None:
        """After a control step: a behaviour whose motion is done ends, and the controller starts again."""
        if self.running is not None and (self.running == "clear" or self.left <= 1e-9):
            self.running = None
            self._restart(xy, step)

    def followed(self, refused: bool, xy: np.ndarray, step: int) -> None:
        """After a control step the controller drove: ``refused``, no command kept clear of what
        the robot sees; ``xy`` its position in the odometry's frame (its true motion). A failure
        of the controller clears the local costmap and tries again once, then fails the pipeline:
        the next recovery, or after the last retry the goal given up (:attr:`given_up`)."""
        p = self.params
        if refused:
            if self.refused_since is None:
                self.refused_since = step
        else:
            self.refused_since = None
        if float(np.hypot(*(xy[:2] - self.anchor))) >= p.progress_radius:
            self.anchor, self.anchor_step = np.array(xy[:2], dtype=float), step
        stuck = (step - self.anchor_step) * self.dt >= p.progress_time
        failed = self.refused_since is not None and (step - self.refused_since) * self.dt >= p.failure_tolerance
        if not (stuck or failed):
            return
        if not self.retried:  # FollowPath's own recovery: clear the local costmap, try again
            self.retried = True
            self._restart(xy, step)
            return
        self.retried = False
        self.failures += 1
        if self.failures > p.retries:
            self.given_up = True
            return
        self._start_next()
        self._restart(xy, step)

    def _start_next(self) -> None:
        """The round robin's next behaviour starts."""
        p = self.params
        name = BEHAVIOURS[self.next % len(BEHAVIOURS)]
        self.next += 1
        self.run[name] += 1
        self.running = name
        self.left = {"clear": 0.0, "spin": p.spin, "wait": p.wait, "backup": p.backup_distance}[name]

    @property
    def backing_up(self) -> bool:
        """Whether the behaviour under way is the back-up (the session checks its path)."""
        return self.running == "backup"
