"""Runs a plan's moves on a team of nav2 robots, on the team's clock: send move k to robot r at
its planned departure, after its previous move and its partner's sync point.

No ROS here: a fleet adapter gives the executor a :class:`NavigationClient` (sends a robot a
``NavigateThroughPoses`` goal and reports once when it ends) and a :class:`Clock` (the team's
clock, :class:`WallClock` for real robots), then calls :meth:`Executor.run`::

    team = move_files.read_team("out/nav2")   # the export of `tmpnav plan -o out --export nav2`
    result = Executor(team, client, WallClock()).run()

A move is sent at the latest of: its planned departure (``depart``), the end of its robot's
previous move, and for a paired move the end of the partner's previous move (the partner at
the sync point); both moves of a pair are sent together. Goals are never retried: when one fails
no further move is sent, the goals under way are let end, and the result says which move
failed (:class:`Execution`, ``status`` FAILED). docs/nav2.md shows an adapter.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from enum import Enum
from typing import Protocol

from tmpnav.errors import InputError
from tmpnav.export.moves import MoveRequest, NavigateThroughPoses, Team


@dataclass(frozen=True)
class GoalOutcome:
    """How a goal ended: reached (``succeeded``), or not, with the server's reason."""

    succeeded: bool
    reason: str = ""


class NavigationClient(Protocol):
    """The robots' nav2 action servers, as the executor uses them."""

    def send_goal(self, robot: str, goal: NavigateThroughPoses, done: Callable[[GoalOutcome], None]) -> None:
        """Send ``goal`` to ``robot``'s ``navigate_through_poses`` server and return at once;
        call ``done`` once when the goal ends (from any thread), also when the server rejects it."""
        ...


class Clock(Protocol):
    """The team's clock: seconds since the plan's start, one instant for every robot."""

    def now(self) -> float:
        """The time on the team's clock (s)."""
        ...

    def wait(self, until: float | None, woken: threading.Event) -> None:
        """Return when the clock reads ``until`` (``None``: no time set) or when ``woken`` is set,
        whichever comes first (at once if it is set already)."""
        ...


class WallClock:
    """The team's clock on this computer's: ``start`` (a Unix time, default now) is the plan's t = 0."""

    def __init__(self, start: float | None = None):
        self.start = time.time() if start is None else start

    def now(self) -> float:
        """Seconds since ``start``."""
        return time.time() - self.start

    def wait(self, until: float | None, woken: threading.Event) -> None:
        """Block until ``until`` on the team's clock or until ``woken`` is set."""
        woken.wait(None if until is None else max(0.0, until - self.now()))


class MoveStatus(Enum):
    """What became of one move."""

    ARRIVED = "arrived"  # its goal succeeded
    FAILED = "failed"  # its goal failed (aborted, canceled or rejected)
    NOT_SENT = "not sent"  # a goal failed before this move was due


class ExecutionStatus(Enum):
    """How a run ended."""

    COMPLETED = "completed"  # every move arrived
    FAILED = "failed"  # a goal failed: the moves after it were not sent


@dataclass(frozen=True)
class MoveRecord:
    """One move as it ran, beside its plan (times in s on the team's clock)."""

    robot: str
    index: int
    step: int
    partner: str | None
    planned_depart: float | None
    planned_arrive: float | None
    status: MoveStatus
    sent: float | None = None  # when the goal was sent: the move's start
    ended: float | None = None  # when the goal ended (arrived or failed)
    held_by: str = ""  # what it waited for last: "depart", "previous move" or "partner <name>"
    reason: str = ""  # the server's reason, for a failed goal

    @property
    def name(self) -> str:
        """``<robot>/<index>``, as in schedule.yaml."""
        return f"{self.robot}/{self.index}"

    @property
    def lateness(self) -> float | None:
        """Seconds the move arrived after its planned arrival (negative: early); None if it did not arrive."""
        if self.status is not MoveStatus.ARRIVED or self.ended is None or self.planned_arrive is None:
            return None
        return self.ended - self.planned_arrive


@dataclass(frozen=True)
class Execution:
    """The result of a run: every move's record (robot by robot, in order) and how it ended."""

    status: ExecutionStatus
    moves: tuple[MoveRecord, ...]
    failed: MoveRecord | None  # the first move whose goal failed

    @property
    def makespan(self) -> float | None:
        """When the last goal ended (s on the team's clock)."""
        return max((m.ended for m in self.moves if m.ended is not None), default=None)

    def record(self, robot: str, index: int) -> MoveRecord:
        """The record of ``robot``'s move ``index`` (1-based)."""
        return next(m for m in self.moves if (m.robot, m.index) == (robot, index))


class Executor:
    """Sends a team's moves to its robots in the plan's order and on its clock (see the module)."""

    def __init__(self, team: Team, client: NavigationClient, clock: Clock):
        check_syncs(team)
        self.team, self.client, self.clock = team, client, clock
        self._next = dict.fromkeys(team.robots, 0)  # per robot: its next move to send (0-based)
        self._free_at = dict.fromkeys(team.robots, 0.0)  # when its last move ended (0: at the start)
        self._under_way: dict[str, MoveRequest] = {}  # robot -> its move whose goal has not ended
        self._records: dict[tuple[str, int], MoveRecord] = {}
        self._results: queue.SimpleQueue[tuple[MoveRequest, GoalOutcome, float]] = queue.SimpleQueue()
        self._woken = threading.Event()
        self._failed: MoveRecord | None = None

    def run(self) -> Execution:
        """Send every move when it is due and wait for it; returns when all have ended, or when a
        goal failed and the goals under way have ended."""
        while True:
            self._collect()
            if self._failed is None:
                self._send_due()
            if not self._under_way and (self._failed is not None or self._all_sent()):
                return self._result()
            until = None if self._failed is not None else self._next_departure()
            if until is None and not self._under_way:  # check_syncs rules this out
                raise RuntimeError("no move can be sent and no goal is under way")
            self.clock.wait(until, self._woken)
            self._woken.clear()

    def _due(self, move: MoveRequest) -> tuple[float, str] | None:
        """When ``move`` may be sent and what holds it last (its planned departure, its robot's
        previous move, or its partner); None while its robot or its partner has a move under way."""
        other = self.team.partner_move(move)
        if move.robot in self._under_way:
            return None
        holds = [(move.depart or 0.0, "depart"), (self._free_at[move.robot], "previous move")]
        if other is not None:
            if other.robot in self._under_way or self._pending(other.robot) is not other:
                return None  # the partner has not reached the sync point yet
            holds.append((self._free_at[other.robot], f"partner {other.robot}"))
        return max(holds, key=lambda h: h[0])  # the first of equal times: "depart" when on time

    def _send_due(self) -> None:
        now = self.clock.now()
        for robot in self.team.robots:
            move = self._pending(robot)
            due = None if move is None else self._due(move)
            if move is None or due is None or due[0] > now:
                continue
            other = self.team.partner_move(move)
            other_due = None if other is None else self._due(other)  # a pair leaves together
            self._send(move, now, due[1])
            if other is not None:
                self._send(other, now, "" if other_due is None else other_due[1])

    def _send(self, move: MoveRequest, now: float, held_by: str) -> None:
        self._under_way[move.robot] = move
        self._next[move.robot] += 1
        self._records[(move.robot, move.index)] = replace(_record(move), sent=now, held_by=held_by)

        def done(outcome: GoalOutcome) -> None:  # from any thread: the run loop records it
            self._results.put((move, outcome, self.clock.now()))
            self._woken.set()

        self.client.send_goal(move.robot, move.goal, done)

    def _collect(self) -> None:
        """Record the goals that ended since the last look."""
        while not self._results.empty():
            move, outcome, t = self._results.get()
            if self._under_way.get(move.robot) is not move:
                continue  # a second report of one goal: the first counts
            key = (move.robot, move.index)
            if outcome.succeeded:
                self._records[key] = replace(self._records[key], status=MoveStatus.ARRIVED, ended=t)
            else:
                self._records[key] = replace(
                    self._records[key], status=MoveStatus.FAILED, ended=t, reason=outcome.reason
                )
                self._failed = self._failed or self._records[key]
            del self._under_way[move.robot]
            # it waits at the station for the job's window to open, then stands there for its service
            self._free_at[move.robot] = max(t, move.opens_at or t) + move.service

    def _pending(self, robot: str) -> MoveRequest | None:
        moves = self.team.moves[robot]
        k = self._next[robot]
        return moves[k] if k < len(moves) else None

    def _all_sent(self) -> bool:
        return all(self._pending(r) is None for r in self.team.robots)

    def _next_departure(self) -> float | None:
        """The earliest time a move not sent yet may be sent, among those not waiting for a goal."""
        dues = (self._due(m) for m in map(self._pending, self.team.robots) if m is not None)
        return min((due[0] for due in dues if due is not None), default=None)

    def _result(self) -> Execution:
        records = tuple(self._records.get((m.robot, m.index)) or _record(m) for m in self.team.all_moves())
        status = ExecutionStatus.COMPLETED if self._failed is None else ExecutionStatus.FAILED
        return Execution(status, records, self._failed)


def _record(move: MoveRequest) -> MoveRecord:
    """The record of a move not sent (yet)."""
    return MoveRecord(move.robot, move.index, move.step, move.partner, move.depart, move.arrive, MoveStatus.NOT_SENT)


def check_syncs(team: Team) -> None:
    """Raise :class:`InputError` unless every paired move has its partner's move of the same step,
    naming it back, and the moves can all be made: no robots waiting for each other in a circle."""
    for move in team.all_moves():
        other = team.partner_move(move)
        if move.partner is not None and (other is None or other.partner != move.robot):
            raise InputError(
                f"move {move.name} (step {move.step}) is paired with {move.partner}, which has no move of that "
                "step paired with it: the files are not of one plan"
            )
    nxt = dict.fromkeys(team.robots, 0)
    progress = True
    while progress:  # make every move whose robot (and partner) are at it, until none is left or none can go
        progress = False
        for robot in team.robots:
            moves = team.moves[robot]
            if nxt[robot] == len(moves):
                continue
            other = team.partner_move(moves[nxt[robot]])
            if other is None:
                nxt[robot] += 1
                progress = True
            elif nxt[other.robot] == other.index - 1:
                nxt[robot] += 1
                nxt[other.robot] += 1
                progress = True
    stuck = [team.moves[r][nxt[r]].name for r in team.robots if nxt[r] < len(team.moves[r])]
    if stuck:
        raise InputError(f"the moves {', '.join(stuck)} wait for each other's partners in a circle: not a plan's order")
