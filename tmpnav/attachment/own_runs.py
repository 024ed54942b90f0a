"""A plan run one robot at a time, where no robot takes in another.

Where the team runs on its robots' own legs (:mod:`tmpnav.attachment.own_legs`: no robot
observes another and none starts correlated with another) and every step of the plan is one
robot's move, a robot's run depends on its own moves, waits and detours only: each of its moves
starts as soon as it is free and its wait is over, the oracle picks the move's goal instantiation
from the robot's own belief then, and its legs follow. :meth:`TeamClock.run`'s event loop steps
every robot at every event of any robot; here each robot's run is made once for its own steps,
waits and detours and kept (:class:`RobotRuns`), and a plan's run is put together from its
robots' runs: the same moves, costs, schedule, end state and record as the event loop's, bit for
bit (``tests/attachment/test_own_runs.py``). Keeping a fleet's robots apart runs one plan dozens
of times, each with one robot's wait changed: the other robots' runs are read, not made again.

Put together, a move is closed (its cost terms, and the order in which the clock's state lists
it) where the event loop closes it: at the first event of any robot at or after its end (or at
the run's end), a move of no steps at its own start.
"""

from __future__ import annotations

import itertools
from collections import OrderedDict
from collections.abc import Generator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Protocol

import numpy as np

from tmpnav.attachment.clock_state import ClockRun, ClockState, Leg, MoveRun, Unreachable
from tmpnav.attachment.record import Trace
from tmpnav.attachment.team import Team
from tmpnav.oracle.requests import Request, StartState
from tmpnav.task.plans import MoveKey, Plan
from tmpnav.types import CostTerms, MotionResult, cov3, vec3

if TYPE_CHECKING:
    from tmpnav.attachment.own_legs import LegBelief, OwnLegs
    from tmpnav.oracle.motions import MotionLibrary
    from tmpnav.oracle.oracle import Oracle
    from tmpnav.types import Scenario

#: robots' runs kept (the least recently used dropped first)
MAX_ROBOT_RUNS = 8192
#: a detour's roadmap nodes (TeamClock.run's ``detours``)
Path = tuple[int, ...]


class TeamClock(Protocol):
    """What a robot's run reads of :class:`tmpnav.attachment.clock.TeamClock`."""

    start: Team
    dt: float
    scenario: Scenario
    oracle: Oracle
    lib: MotionLibrary
    own: OwnLegs | None

    def initial(self) -> ClockState: ...
    def opens_steps(self, room: str, arrive: int) -> int: ...
    def service_steps(self, room: str) -> int: ...
    def _own_start(self, i: int) -> tuple[np.ndarray, np.ndarray]: ...
    def _result(self, state: ClockState, plan: Plan, trace: Trace | None) -> ClockRun: ...


@dataclass(frozen=True, eq=False)
class RobotRun:
    """One robot's run for its own steps: its legs (the standing one it starts with first), its
    moves with their cost terms (``MoveRun.step``: the move's place among the robot's steps),
    when it is free after its last step, and whether a move arrives after its job's window."""

    legs: tuple[Leg, ...]
    moves: tuple[MoveRun, ...]
    free: int
    late: bool


class RobotRuns:
    """The robots' runs of one :class:`~tmpnav.attachment.clock.TeamClock`, kept by each robot's
    own steps, waits and detours (the module docstring)."""

    def __init__(self, clock: TeamClock):
        self.clock = clock
        self._runs: OrderedDict[tuple[object, ...], RobotRun | _Stopped] = OrderedDict()
        self.made = 0  # robots' runs made (for the benchmarks)

    @staticmethod
    def applies(clock: TeamClock, plan: Plan) -> bool:
        """Whether ``plan`` runs one robot at a time on ``clock``: its team on its own legs, and
        every step one robot's move."""
        return clock.own is not None and all(len(step) == 1 for step in plan)

    def run(self, plan: Plan, held: Mapping[int, int], ways: Mapping[tuple[int, str], Path], record: bool) -> ClockRun:
        """``plan`` run with waits ``held`` (control steps by plan step) and detours ``ways``, as
        :meth:`TeamClock.run` runs it."""
        clock = self.clock
        names, dt = clock.start.names, clock.dt
        priced = clock.scenario.planner.max_risk is not None or record
        initial = clock.initial()
        order = [[k for k, step in enumerate(plan) if step[0][0] == r] for r in names]
        found = self._robots(plan, order, held, ways, priced, initial)
        failed = [(f.t, order[i][f.place], f.error) for i, f in enumerate(found) if isinstance(f, _Stopped)]
        if failed:  # the event loop stops at the first, in its order: the earliest start, then plan step
            raise min(failed, key=lambda f: (f[0], f[1]))[2]
        robot_runs = [f for f in found if isinstance(f, RobotRun)]
        starts = sorted({m.start for run in robot_runs for m in run.moves})
        end = max([0, *(run.free for run in robot_runs)])
        moves = [replace(m, step=order[i][m.step]) for i, run in enumerate(robot_runs) for m in run.moves]
        closed, cost = _closed(moves, starts, end, clock)
        legs = tuple(run.legs for run in robot_runs)
        mean, cov = np.empty(3 * len(names)), np.zeros((3 * len(names), 3 * len(names)))
        for i in range(len(names)):
            b = self._belief(i, legs[i], priced, end)
            row = b.row(end - legs[i][-1].start)
            mean[3 * i : 3 * i + 3], cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = b.means[row], b.covs[row]
        nodes = tuple(legs[i][-1].node for i in range(len(names)))
        headings = tuple(legs[i][-1].heading for i in range(len(names)))
        state = ClockState(
            end,
            Team(names, nodes, headings, mean, cov, end * dt),
            legs,
            tuple(run.free for run in robot_runs),
            initial.csig,
            initial.risk,
            closed=closed,
            closed_cost=cost,
            late=initial.late or any(run.late for run in robot_runs),
        )
        trace = self._trace(initial, legs, priced, end) if record else None
        return clock._result(state, plan, trace)

    # ------------------------------------------------------------------ one robot

    def _robots(
        self,
        plan: Plan,
        order: list[list[int]],
        held: Mapping[int, int],
        ways: Mapping[tuple[int, str], Path],
        priced: bool,
        initial: ClockState,
    ) -> list[RobotRun | _Stopped]:
        """Each robot's run for its steps (``order``: its plan steps), read where kept, the others
        made together: each round asks the oracle for every such robot's next move at once, as
        the event loop asks for the moves of an event (one batch to its cache, not one a move)."""
        names = self.clock.start.names
        keys, found, making = [], [], {}
        for i, steps in enumerate(order):
            moves = tuple(plan[k][0] for k in steps)
            waits, paths = tuple(held.get(k, 0) for k in steps), tuple(ways.get((k, names[i])) for k in steps)
            key = (i, priced, moves, waits, paths)
            keys.append(key)
            kept = self._runs.get(key)
            if kept is not None:
                self._runs.move_to_end(key)
            else:
                making[i] = self._make(i, list(moves), waits, paths, priced, initial)
            found.append(kept)
        asking: dict[int, Request] = {}
        for i, run in making.items():
            self._step(i, run, asking, found, first=True)
        while asking:
            answers = self.clock.oracle.evaluate(list(asking.values()))
            now, asking = asking, {}
            for i, answer in zip(now, answers, strict=True):
                self._step(i, making[i], asking, found, answer=answer)
        for i in making:
            self._runs[keys[i]] = found[i]  # type: ignore[assignment]
            if len(self._runs) > MAX_ROBOT_RUNS:
                self._runs.popitem(last=False)
        return found  # type: ignore[return-value]

    @staticmethod
    def _step(
        i: int,
        run: Generator[Request, MotionResult | None, RobotRun],
        asking: dict[int, Request],
        found: list[RobotRun | _Stopped | None],
        answer: MotionResult | None = None,
        first: bool = False,
    ) -> None:
        """Robot i's run started (``first``) or taken on by the oracle's ``answer`` (None: its
        robot cannot reach the room), to its next question (into ``asking``) or its end (into
        ``found``)."""
        try:
            asking[i] = next(run) if first else run.send(answer)
        except StopIteration as done:
            found[i] = done.value
        except _Stopped as stopped:
            found[i] = stopped

    def _make(
        self,
        i: int,
        moves: list[MoveKey],
        holds: tuple[int, ...],
        paths: tuple[Path | None, ...],
        priced: bool,
        initial: ClockState,
    ) -> Generator[Request, MotionResult | None, RobotRun]:
        """Robot i's moves in its order, each started when the event loop starts it: when the
        robot is free and its wait is over, from its belief then (:meth:`TeamClock.dispatch`).
        Yields the oracle's request for each move and is sent its answer."""
        clock, own = self.clock, self.clock.own
        assert own is not None
        self.made += 1
        robot, dt, goals = clock.start.names[i], clock.dt, clock.scenario.goals
        legs, free, after, late = list(initial.legs[i]), initial.free[i], 0, False
        runs: list[MoveRun] = []
        for p, (move, hold, path) in enumerate(zip(moves, holds, paths, strict=True)):
            t = max(free, after) + hold
            after = t
            b = self._belief(i, tuple(legs), priced, t)
            row = b.row(t - legs[-1].start)
            node, heading = legs[-1].node, float(legs[-1].heading)
            start = StartState(node, heading, vec3(b.means[row]), cov3(b.covs[row]))
            result = yield Request((robot,), (start,), (move[2],), None)
            if result is None:
                raise _Stopped(t, p, Unreachable(f"{robot} cannot reach {move[2]} from where they are"))
            goal = result.goal_nodes[0]
            if path is not None and path[0] == node and path[-1] == goal:
                motion = clock.lib.along(robot, path, heading)
            else:
                found = clock.lib.motion(robot, node, heading, goal)
                assert found is not None  # the oracle just planned it
                motion = found
            key = own.key(i, legs[-1].key, t, motion, motion.poses[-1], motion.noise_seed)
            legs.append(Leg(t, motion, goal, motion.final_heading, motion.poses[-1], motion.noise_seed, key))
            run = MoveRun(p, i, free, t, t + motion.n_steps, motion, initial.csig[i], initial.risk[i])
            if motion.n_steps == 0:  # closed as it starts, on the robot's belief then
                arrival, c_sigma, bound = b.means[row, :2], 0.0, 0.0
            else:  # closed on its own leg's row at its end
                mine = self._belief(i, tuple(legs), priced, run.end)
                k = run.end - run.start
                arrival, c_sigma, bound = mine.means[k, :2], float(mine.csig[k]), float(mine.risk[k])
            c_g = float(np.hypot(*(arrival - motion.poses[-1, :2])))
            runs.append(replace(run, terms=CostTerms(motion.c_u(dt), c_g, c_sigma), risk=min(1.0, bound)))
            free = t + motion.n_steps
            late = late or goals.too_late(move[2], free * dt)
            free += clock.opens_steps(move[2], free) + clock.service_steps(move[2])
        return RobotRun(tuple(legs), tuple(runs), free, late)

    def _belief(self, i: int, legs: tuple[Leg, ...], priced: bool, t: int) -> LegBelief:
        """Robot i's belief along the last of ``legs``, computed to step ``t`` of the clock."""
        own = self.clock.own
        assert own is not None
        return own.belief(i, legs, priced, t - legs[-1].start, self.clock._own_start(i))

    def _trace(self, initial: ClockState, legs: tuple[tuple[Leg, ...], ...], priced: bool, end: int) -> Trace:
        """The record of the run to step ``end``: each robot's steps along each of its legs, to
        where the next leg starts (the event loop records a step on the leg it was on before the
        move that starts there)."""
        own = self.clock.own
        assert own is not None
        trace = Trace.at_start(self.clock.dt, initial)
        for i, mine in enumerate(legs):
            for j, leg in enumerate(mine):
                until = mine[j + 1].start if j + 1 < len(mine) else end
                if until > leg.start:
                    b = self._belief(i, mine[: j + 1], priced, until)
                    hi = until - leg.start + 1
                    trace.add(i, own.records(b, 1, hi), b, 1, hi)
        return trace


class _Stopped(Exception):
    """A robot's run that cannot go on: at step ``t`` of the clock, its move at ``place`` among
    its steps cannot reach its room (``error``, what the event loop raises)."""

    def __init__(self, t: int, place: int, error: Unreachable):
        super().__init__(t, place, error)
        self.t, self.place, self.error = t, place, error


def _closed(
    moves: list[MoveRun], starts: Sequence[int], end: int, clock: TeamClock
) -> tuple[tuple[MoveRun, ...], float]:
    """The moves in the order the event loop closes them, and the sum of their costs as it adds
    them up (batch by batch): a move of steps at the first event (``starts``) at or after its
    end, else at ``end``, those of one event by (end, plan step, robot); a move of no steps at
    its start, after the others closed there."""
    events = np.asarray(starts, dtype=np.int64)

    def when(m: MoveRun) -> tuple[int, int]:
        if m.end == m.start:
            return m.start, 1
        at = int(np.searchsorted(events, m.end))
        return (int(events[at]) if at < events.size else end), 0

    ordered = sorted(moves, key=lambda m: (*when(m), m.end, m.step, m.robot))
    w, delta = clock.scenario.cost, clock.scenario.planner.max_risk
    total = 0.0
    for _, batch in itertools.groupby(ordered, key=when):
        total = total + sum(m.cost(w, delta) for m in batch)
    return tuple(ordered), total
