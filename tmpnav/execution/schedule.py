"""Where the team is in the plan's schedule while ``tmpnav simulate`` executes it.

Every robot follows its own queue of moves (:mod:`tmpnav.execution.moves`). A robot starts its
next move when

* it has reached the end of its previous move (its estimate at the path's last node),
* for a paired move, its partner has reached the end of its own previous move (the one that
  is there first waits), and
* the plan's start time of the move has come (never earlier: the planner may hold a move back
  to keep clear of another robot).

:class:`TeamSchedule` keeps this bookkeeping on the session's clock: it starts the moves, drops
the waypoints reached, ends a move at its last one (then the robot waits at the station for the
job's window and its service), cuts a move out of its step budget (:data:`STEP_BUDGET`) or
draws, and records every move as executed in the session's trace. What it needs to know of the
simulated robots it asks a :class:`Team` (:class:`~tmpnav.execution.session.Session` is one).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Protocol

import numpy as np

from tmpnav.errors import TmpnavError
from tmpnav.execution.moves import QueuedMove, RobotQueue
from tmpnav.execution.recovery import Recovery
from tmpnav.execution.rpp import RppFollower
from tmpnav.execution.trace import SessionTrace, nees
from tmpnav.results import TimedMove
from tmpnav.types import Goals

#: a move may take this many times its planned steps (or 40 steps per waypoint) before it is cut
STEP_BUDGET = 6


class Team(Protocol):
    """What the schedule asks of the simulated robots (robot ``i`` in the scenario's order)."""

    def at_waypoint(self, i: int, r: RobotQueue) -> bool:
        """Whether robot i has reached the next waypoint of its move under way."""
        ...

    def estimate(self, i: int) -> np.ndarray:
        """Robot i's estimated pose (3,)."""
        ...

    def position_error(self, i: int) -> np.ndarray:
        """Robot i's true position minus its estimated one (2,) m."""
        ...

    def navigation(self, i: int, m: QueuedMove) -> tuple[Recovery | None, RppFollower | None]:
        """How robot i drives the move ``m`` it starts now: nav2's recoveries and RPP, when it has them."""
        ...


class TeamSchedule:
    """The robots' queues on the session's clock (see the module docstring). Every method that
    changes them takes the control step ``now``."""

    def __init__(
        self,
        names: tuple[str, ...],
        queues: Mapping[str, tuple[QueuedMove, ...]],
        trace: SessionTrace,
        goals: Goals,
        dt: float,
        team: Team,
    ):
        self.names, self.trace, self.goals, self.dt, self.team = names, trace, goals, dt, team
        self.robots = [RobotQueue(queues.get(r, ())) for r in names]
        #: robots that are down: they stand where they are for the rest of the session
        self.down: set[int] = set()

    @property
    def finished(self) -> bool:
        """Every robot has made all its moves (or was cut)."""
        return all(r.move is None and r.next is None for r in self.robots)

    @property
    def driving(self) -> bool:
        """Some robot has a move under way."""
        return any(r.move is not None for r in self.robots)

    def move_step(self, i: int) -> int:
        """The plan step of robot i's move under way, or of its last one when it stands (-1 before its first)."""
        r = self.robots[i]
        if r.move is not None:
            return r.move.step
        return r.queue[r.started - 1].step if r.started else -1

    # ------------------------------------------------------------------ changes of the plan

    def adopt(self, moves: Mapping[str, tuple[QueuedMove, ...]], now: int) -> None:
        """Go on with new queues (a revised plan, its clock starting ``now``): a move under way is
        dropped where the robot is (the new plan starts there), a robot at a station ends its
        service first, a robot down gets none."""
        for i, (name, r) in enumerate(zip(self.names, self.robots, strict=True)):
            queue = () if i in self.down else moves.get(name, ())
            shifted = tuple(replace(m, start=m.start + now) for m in queue)
            self.robots[i] = RobotQueue(shifted, ready=max(r.ready, now))

    def set_down(self, i: int, now: int) -> None:
        """Robot i is down from ``now``: its move under way and its queue are dropped."""
        self.down.add(i)
        r = self.robots[i]
        if r.move is not None:
            self._cut(self.names[i], len(r.waypoints))
        self.robots[i] = RobotQueue((), started=0, ready=now)

    # ------------------------------------------------------------------ each control step

    def arrive(self, now: int) -> None:
        """The waypoints reached now, and the moves ended by them."""
        for i, r in enumerate(self.robots):
            if r.move is not None:
                self._advance(i, r, now)

    def arrive_and_start(self, now: int) -> None:
        """Waypoints reached, moves ended, then moves started (a move that starts where it ends
        ends at once, and the robot's next move may start too)."""
        while True:
            self.arrive(now)
            if not self._start_moves(now):
                return

    def hold(self, i: int, now: int) -> None:
        """Robot i stands still this step (stopped): its move does not use up its budget, nor
        nav2's progress check."""
        r = self.robots[i]
        r.since += 1
        if r.recovery is not None:
            r.recovery.hold(now)

    def give_up(self, i: int, now: int) -> None:
        """nav2 failed robot i's navigation after its last recovery: the move is given up where it stands."""
        self._cut_move(i, self.robots[i], now, given_up=True)
        self.trace.given_up.append(self.trace.moves[-1])

    def cut_all(self, now: int) -> None:
        """The draws have run out: every move under way or not started is cut."""
        for i, r in enumerate(self.robots):
            name = self.names[i]
            if r.move is not None:
                self._cut_move(i, r, now)
            for m in r.queue[r.started :]:
                self._cut(name, len(m.waypoints))
            r.started = len(r.queue)

    def check_waiting(self, now: int) -> None:
        """Nobody drives: some robot must be waiting for a planned start still to come, or still at
        a station (waiting for a window, in service), else the schedule cannot go on (a paired
        move whose partner waits for another one)."""
        if any(r.next is not None and max(r.next.start, r.ready) > now for r in self.robots):
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

    # ------------------------------------------------------------------ a move's life

    def _advance(self, i: int, r: RobotQueue, now: int) -> None:
        """Drop the waypoints robot i has reached, recording the error at each; end its move when
        none is left, or cut it when it has run out of its budget."""
        name = self.names[i]
        assert r.previous is not None and r.move is not None
        while r.waypoints and self.team.at_waypoint(i, r):
            k = len(r.move.waypoints) - len(r.waypoints)  # the path point reached, after its start
            r.previous = r.waypoints.pop(0)
            r.aligned = False  # a new segment: turn towards its end first
            error = self.team.position_error(i)
            self.trace.errors[name].append(float(np.hypot(*error)))
            self.trace.times[name].append(now * self.dt)
            planned = r.move.planned_covs[k] if k < len(r.move.planned_covs) else None
            self.trace.planned_nees[name].append(nees(error, planned))
        if r.waypoints and now - r.since >= STEP_BUDGET * max(r.move.steps, 40 * (len(r.move.nodes) - 1)):
            self._cut_move(i, r, now)
        if not r.waypoints and r.move is not None:
            self._end(r, now)

    def _start_moves(self, now: int) -> bool:
        """Start every move whose robots are free and whose planned start has come; whether any did."""
        started = False
        for r in self.robots:
            m = r.next
            if m is None or m.start > now or r.ready > now:
                continue  # not yet planned to start, or still at a station
            if m.partner is not None:
                other = self.robots[self.names.index(m.partner)]
                n = other.next
                if n is None or n.step != m.step or n.start > now or other.ready > now:
                    continue  # the partner is not there yet: wait for it
                self._start(other, n, now)
            self._start(r, m, now)
            started = True
        return started

    def _start(self, r: RobotQueue, m: QueuedMove, now: int) -> None:
        r.move, r.started, r.since, r.aligned, r.track = m, r.started + 1, now, False, 0
        r.waypoints, r.previous = m.waypoints, np.asarray(m.points[0], dtype=float)
        r.recovery, r.rpp = self.team.navigation(self.names.index(m.robot), m)

    def _end(self, r: RobotQueue, now: int, cut: bool = False) -> None:
        """Robot r ends its move now: record it as executed (``cut``: short of its room); the robot
        is ready for its next."""
        m = r.move
        assert m is not None
        dt = self.dt
        # it waits at the station for the job's window to open, then stands there for the service
        opens = self.goals.opens_steps(m.target, now, dt)
        stand = self.goals.service_steps(m.target, dt)
        executed = TimedMove(
            m.step,
            m.robot,
            m.origin,
            m.target,
            m.partner,
            r.ready * dt,
            r.since * dt,
            now * dt,
            stand * dt,
            opens * dt,
        )
        self.trace.moves.append(executed)
        if cut:
            self.trace.cut.append(executed)
        r.move, r.ready = None, now + opens + stand
        if r.recovery is not None:
            for name, count in r.recovery.run.items():
                self.trace.recoveries[name] += count
            r.recovery = None
        if len(m.points):
            i = self.names.index(m.robot)
            self.trace.c_goal[m.robot] += float(np.hypot(*(self.team.estimate(i)[:2] - m.points[-1])))

    def _cut_move(self, i: int, r: RobotQueue, now: int, given_up: bool = False) -> None:
        """Robot i's move under way ends where it is, short of its room (``given_up``: by nav2,
        else for want of steps)."""
        self._cut(self.names[i], len(r.waypoints), given_up)
        r.waypoints = []
        self._end(r, now, cut=True)

    def _cut(self, name: str, points: int, given_up: bool = False) -> None:
        """Points of a path never reached: no error, no time. The session is truncated (out of its
        step budget or draws) unless nav2 gave the move up."""
        self.trace.truncated = self.trace.truncated or not given_up
        self.trace.errors[name].extend([math.nan] * points)
        self.trace.times[name].extend([math.nan] * points)
        self.trace.planned_nees[name].extend([math.nan] * points)
