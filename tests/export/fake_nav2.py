"""A fake nav2 for the executor's tests: a simulated team clock and action servers that end each
goal after a simulated duration, on that clock, and check what they are sent."""

from __future__ import annotations

import heapq
import itertools
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass

from tmpnav.export.executor import Execution, Executor, GoalOutcome, MoveStatus
from tmpnav.export.moves import NavigateThroughPoses, Team


class SimClock:
    """A team clock that jumps from event to event: ``wait`` runs the next events it reaches."""

    def __init__(self) -> None:
        self.t = 0.0
        self._events: list[tuple[float, int, Callable[[], None]]] = []
        self._order = itertools.count()

    def now(self) -> float:
        return self.t

    def at(self, t: float, action: Callable[[], None]) -> None:
        heapq.heappush(self._events, (t, next(self._order), action))

    def wait(self, until: float | None, woken: threading.Event) -> None:
        if woken.is_set():
            return
        if not self._events or (until is not None and until < self._events[0][0]):
            assert until is not None, "the executor waits for a goal, but none is under way"
            assert until >= self.t, f"the executor waits for {until}, in the past of {self.t}"
            self.t = until
            return
        self.t = self._events[0][0]
        while self._events and self._events[0][0] == self.t:
            heapq.heappop(self._events)[2]()


@dataclass(frozen=True)
class Sent:
    """A goal as the fake server received it."""

    robot: str
    t: float
    goal: NavigateThroughPoses


class FakeNav2:
    """Every robot's navigate_through_poses server: a goal ends after ``duration(robot, goal)``
    seconds of the clock, successfully unless ``fails(robot, goal)`` gives a reason."""

    def __init__(
        self,
        clock: SimClock,
        duration: Callable[[str, NavigateThroughPoses], float],
        fails: Callable[[str, NavigateThroughPoses], str | None] = lambda robot, goal: None,
    ) -> None:
        self.clock, self.duration, self.fails = clock, duration, fails
        self.sent: list[Sent] = []
        self._driving: set[str] = set()

    def send_goal(self, robot: str, goal: NavigateThroughPoses, done: Callable[[GoalOutcome], None]) -> None:
        assert robot not in self._driving, f"{robot} got a goal at {self.clock.now()} while driving another"
        assert goal.poses and all(math.isfinite(v) for p in goal.poses for v in (p.x, p.y, p.yaw))
        self.sent.append(Sent(robot, self.clock.now(), goal))
        self._driving.add(robot)
        reason = self.fails(robot, goal)

        def end() -> None:
            self._driving.discard(robot)
            done(GoalOutcome(reason is None, reason or ""))

        self.clock.at(self.clock.now() + self.duration(robot, goal), end)


Duration = Callable[[str, NavigateThroughPoses], float]


def planned_durations(team: Team, slower: dict[str, float] | None = None) -> Duration:
    """Each goal takes its move's planned time (``arrive - depart``), times ``slower[robot]``."""
    moves = {id(m.goal): m for m in team.all_moves()}

    def duration(robot: str, goal: NavigateThroughPoses) -> float:
        m = moves[id(goal)]
        assert m.robot == robot and m.arrive is not None and m.depart is not None
        return (m.arrive - m.depart) * (slower or {}).get(robot, 1.0)

    return duration


def replay(team: Team, slower: dict[str, float] | None = None) -> tuple[Execution, FakeNav2]:
    """Run ``team`` against the fake on a simulated clock."""
    clock = SimClock()
    server = FakeNav2(clock, planned_durations(team, slower))
    return Executor(team, server, clock).run(), server


def check_order_kept(team: Team, run: Execution) -> None:
    """No move started before its planned departure, before its robot's previous move ended, or
    before its partner reached the sync point; both moves of a pair started together; and each
    started as soon as all three allowed (the executor holds no move longer than that)."""
    by_move = {(r.robot, r.index): r for r in run.moves}
    for move in team.all_moves():
        rec = by_move[(move.robot, move.index)]
        assert rec.status is MoveStatus.ARRIVED and rec.sent is not None and rec.ended is not None
        allowed = [move.depart or 0.0]
        allowed += [by_move[(a.robot, a.index)].ended or math.nan for a in team.after(move)]
        assert rec.sent >= max(allowed) - 1e-9, f"{move.name} sent at {rec.sent}, allowed from {max(allowed)}"
        assert rec.sent == max(allowed), f"{move.name} sent at {rec.sent}, held beyond {max(allowed)}"
        other = team.partner_move(move)
        if other is not None:
            assert by_move[(other.robot, other.index)].sent == rec.sent, f"{move.name} left without its partner"
