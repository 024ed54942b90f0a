"""The belief space of a small task, unfolded on the team's clock: every schedule, as ENHSP's graph.

With ``--costs carried`` a move's cost depends on the beliefs its robots bring into it, and
with the team moving at once on what the other robots do meanwhile. For a small task tmpnav
enumerates every schedule as a sequence of decisions taken in the order of time, on the
team's clock (:mod:`tmpnav.attachment.clock`): at each decision point the robot that is free
first (ties: in the scenario's order) either starts a move into a room the entry rules let
it enter, starts a paired move with another free robot (which waits for it when it is still
driving), or stops for good. A *context* is the clock at that point (every robot's belief,
legs and moves under way), the task state, the paired moves decided but not started, and
who has stopped. Every schedule is one path of decisions: the robot that decides is always
the one free first, so no schedule is reached twice.

An edge costs what the team runs up between its two decision points: the costs of the moves
that end in between (c = M_u c_u + M_G c_G + M_Sigma c_Sigma each, tmpnav.attachment.clock)
and the objective's price of the time that passes (``span_weight`` per second). When every
robot has stopped and the goals are reached, a last edge runs the team until its last move
ends, into the one goal context. The sum of a path's edges is the objective of its plan, so
ENHSP's optimal path through the graph (:func:`tmpnav.task.stage.plan_unfolded`) is the
schedule of least objective among all schedules of single moves and paired moves that save
``pair_min_gain`` over the same two moves made alone from the same beliefs. It grows quickly
with rooms and robots; :func:`unfold` gives up (returns None) past ``max_contexts``.
"""

from __future__ import annotations

from dataclasses import dataclass

from tmpnav.attachment.canonical import _offered
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockState, Unreachable
from tmpnav.attachment.team import paired_moves
from tmpnav.oracle.requests import Request
from tmpnav.task.plans import Rules, State, Step
from tmpnav.task.unfolded import BeliefGraph, Edge
from tmpnav.types import Goals

#: contexts beyond which unfolding gives up (the anytime search takes over)
MAX_CONTEXTS = 6000

Pending = tuple[tuple[int, Step], ...]  # paired moves decided but not started: (their start step, the step)


@dataclass(frozen=True)
class Context:
    """A decision point (see the module docstring)."""

    clock: ClockState
    task: State
    pending: Pending
    stopped: frozenset[int]  # robots that make no more moves


class _Unfolding:
    def __init__(self, carried: CarriedCosts, goals: Goals, min_gain: float, span_weight: float, limit: int):
        self.clock: TeamClock = carried.clock
        self.names = carried.start.names
        self.rules = Rules(carried.start_location, goals)
        self.keep = paired_moves(carried.scenario, goals, carried.start_location)
        self.rooms = tuple(dict.fromkeys(goals.all_rooms))
        self.min_gain, self.span_weight, self.limit = min_gain, span_weight, limit
        self.edges: list[Edge] = []
        self.contexts = 1  # the start is context 0; the goal context is numbered last

    def accounted(self, state: ClockState) -> float:
        """What the team has run up by the clock's time: the ended moves and the time's price."""
        return state.closed_cost + self.span_weight * state.t * self.clock.dt

    def run(self) -> BeliefGraph | None:
        start = Context(self.clock.initial(), self.rules.start(), (), frozenset())
        frontier: list[tuple[int, Context]] = [(0, start)]
        ends: list[tuple[int, float]] = []  # (context, cost of its last edge)
        while frontier:
            here, ctx = frontier.pop()
            for step, child, cost in self.expand(ctx):
                if child is None:
                    ends.append((here, cost))
                    continue
                if self.contexts >= self.limit:
                    return None
                self.edges.append(Edge(here, self.contexts, step, cost))
                frontier.append((self.contexts, child))
                self.contexts += 1
        goal = self.contexts
        self.edges += [Edge(c, goal, (), cost) for c, cost in ends]
        return BeliefGraph(goal + 1, tuple(self.edges), (goal,) if ends else (), 0)

    # ------------------------------------------------------------------ one decision point

    def expand(self, ctx: Context) -> list[tuple[Step, Context | None, float]]:
        """The decisions at ``ctx``: (step (empty: a robot stops, or the run ends), the next
        context (None: the goal context), the edge's cost)."""
        before = self.accounted(ctx.clock)
        caught = self._catch_up(ctx)
        if caught is None:
            return []
        ctx, deciding = caught, self._undecided(caught)
        if ctx.clock.late:
            return []  # a move arrives after its job's window closes: a dead end
        if self.rules.done(ctx.task) and not ctx.pending:
            end = self.clock.advance(ctx.clock, max(ctx.clock.free, default=0))
            return [((), None, self.accounted(end) - before)]
        if not deciding:
            return []  # every robot has stopped, the goals undone: a dead end
        r = min(deciding, key=lambda i: (ctx.clock.free[i], i))
        clock = self.clock.advance(ctx.clock, max(ctx.clock.free[r], ctx.clock.t))
        ctx = Context(clock, ctx.task, ctx.pending, ctx.stopped)
        children: list[tuple[Step, Context]] = [((), Context(clock, ctx.task, ctx.pending, ctx.stopped | {r}))]
        now, later = self._choices(ctx, r, deciding)
        children += self._start_now(ctx, now)
        for step, at in later:
            pending = ((at, step), *ctx.pending)
            children.append((step, Context(clock, self.rules.apply(ctx.task, step), pending, ctx.stopped)))
        return [(step, child, self.accounted(child.clock) - before) for step, child in children]

    def _undecided(self, ctx: Context) -> list[int]:
        committed = {self.names.index(m[0]) for _, step in ctx.pending for m in step}
        return [i for i in range(len(self.names)) if i not in ctx.stopped and i not in committed]

    def _catch_up(self, ctx: Context) -> Context | None:
        """Start the pending paired moves due before the next decision (None: one of them is
        not worth its pair, or cannot be made)."""
        while ctx.pending:
            deciding = self._undecided(ctx)
            due = min(at for at, _ in ctx.pending)
            if deciding and due > max(min(ctx.clock.free[i] for i in deciding), ctx.clock.t):
                return ctx
            clock = self.clock.advance(ctx.clock, due)
            starting = [step for at, step in ctx.pending if at == due]
            if not all(self._worth_it(clock, step) for step in starting):
                return None
            try:
                clock = self.clock.dispatch(clock, [(0, step) for step in starting])
            except Unreachable:
                return None
            ctx = Context(clock, ctx.task, tuple(p for p in ctx.pending if p[0] != due), ctx.stopped)
        return ctx

    def _choices(self, ctx: Context, r: int, deciding: list[int]) -> tuple[list[Step], list[tuple[Step, int]]]:
        """Robot r's moves that start now (single moves; paired moves with a free partner) and
        the paired moves whose partner is still driving (with the step at which they start)."""
        robot, task, clock = self.names[r], ctx.task, ctx.clock
        singles = [((robot, task.at[robot], x),) for x in self.rooms if self._wanted(task, robot, x)]
        now: list[Step] = list(singles)
        later: list[tuple[Step, int]] = []
        for s in deciding:
            if s == r:
                continue
            partner = self.names[s]
            for x in self.rooms:
                if not self._wanted(task, partner, x):
                    continue
                for (m1,) in singles:
                    m2 = (partner, task.at[partner], x)
                    pair = (m1, m2) if r < s else (m2, m1)
                    if x == m1[2] or not self.keep(*pair) or not self._allowed(task, pair):
                        continue
                    at = max(clock.free[s], clock.t)
                    if at == clock.t:
                        now.append(pair)
                    else:
                        later.append((pair, at))
        return now, later

    def _start_now(self, ctx: Context, steps: list[Step]) -> list[tuple[Step, Context]]:
        """The moves that start at the decision point, the oracle asked once for all of them;
        a paired move only when it saves ``min_gain`` over its two moves made alone now."""
        clock, gain = ctx.clock, self.min_gain if self.min_gain > 0 else None
        alone_steps = list(dict.fromkeys((m,) for step in steps for m in step))
        asked = [self._asked(clock, step, gain) for step in steps] + [self.clock.request(clock, a) for a in alone_steps]
        results = self.clock.oracle.evaluate(asked)
        alone = {a[0]: res.cost for a, res in zip(alone_steps, results[len(steps) :], strict=True) if res is not None}
        out = []
        for step, res in zip(steps, results[: len(steps)], strict=True):
            if res is None or res.pruned:
                continue
            if len(step) == 2:
                if not (step[0] in alone and step[1] in alone):
                    continue
                if not _offered(res.cost, alone[step[0]] + alone[step[1]], self.min_gain):
                    continue
            started = self.clock.dispatch(clock, [(0, step)], [res])
            out.append((step, Context(started, self.rules.apply(ctx.task, step), ctx.pending, ctx.stopped)))
        return out

    def _asked(self, clock: ClockState, step: Step, gain: float | None) -> Request:
        """The oracle's request for ``step`` now; a pair's with ``gain`` (pruned when it cannot save it)."""
        q = self.clock.request(clock, step)
        return Request(q.robots, q.starts, q.rooms, q.joint_cov, min_gain=gain if len(step) == 2 else None)

    def _worth_it(self, clock: ClockState, pair: Step) -> bool:
        """Does a paired move, started now, save ``min_gain`` over its two moves made alone now?"""
        asked = [self._asked(clock, pair, self.min_gain if self.min_gain > 0 else None)]
        asked += [self.clock.request(clock, (m,)) for m in pair]
        both, one, two = self.clock.oracle.evaluate(asked)
        if both is None or both.pruned or one is None or two is None:
            return False
        return _offered(both.cost, one.cost + two.cost, self.min_gain)

    def _wanted(self, task: State, robot: str, room: str) -> bool:
        """May ``robot`` enter ``room``, and is there a reason to (a goal not yet achieved)?"""
        if not self.rules.may_enter(task, robot, room):
            return False
        return room not in task.visited or (robot, room) in self.rules.entries

    def _allowed(self, task: State, pair: Step) -> bool:
        try:
            self.rules.apply(task, pair)
        except ValueError:
            return False
        return True


def unfold(
    carried: CarriedCosts, goals: Goals, min_gain: float, span_weight: float = 0.0, max_contexts: int = MAX_CONTEXTS
) -> BeliefGraph | None:
    """Every schedule of the task as a graph of decisions (see the module docstring); None when
    there are more than ``max_contexts`` decision points."""
    return _Unfolding(carried, goals, min_gain, span_weight, max_contexts).run()
