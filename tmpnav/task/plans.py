"""Task plans as values: the entry rules they obey, and the edits the anytime search makes.

A plan is a sequence of steps; a step is the moves (robot, origin, target) of the one or two
robots it moves. The rules are those of the ``single`` and ``mixed`` encodings
(pddl/mixed.pddl): a robot moves from where it is; it enters a room only if nobody has
visited it, or if the room is one of its own target rooms that it has not visited itself
(for a pair, both moves are checked against the state before the step), and never a room
whose job (``goals.jobs``) names other robots; a robot's end (``goals.ends``) counts as one
of its targets for entry, but a robot that starts there must still come back to it; a plan is
done when every room of ``goals.visit`` is visited (but the optional ones, which a plan may
leave undone at their penalty), every robot has visited its targets, and every robot with an
end is there (so its end is its last move).
The search edits plans only through :func:`splice`, and keeps only plans that
:meth:`Rules.check` accepts.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from tmpnav.task.timing import schedule, table_durations
from tmpnav.types import CostTable, Goals, MoveKey

Step = tuple[MoveKey, ...]
Plan = tuple[Step, ...]


class PlanError(ValueError):
    """A plan that breaks the entry rules or leaves a goal undone."""


@dataclass(frozen=True)
class State:
    """Where the robots are, which locations are visited, which targets are visited by their robot."""

    at: dict[str, str]
    visited: frozenset[str]
    visited_by: frozenset[tuple[str, str]]


class Rules:
    """The entry rules and goals of a task problem."""

    def __init__(self, start_location: dict[str, str], goals: Goals):
        self.start_location = dict(start_location)
        self.goals = goals
        self.targets = goals.targets
        self.entries = goals.entries  # the targets and the ends

    def start(self) -> State:
        at = dict(self.start_location)
        return State(at, frozenset(at.values()), self.goals.marked_at_start(at))

    def may_enter(self, state: State, robot: str, room: str) -> bool:
        if not self.goals.may_visit(robot, room):  # the room's job is for other robots
            return False
        return room not in state.visited or ((robot, room) in self.entries and (robot, room) not in state.visited_by)

    def apply(self, state: State, step: Step) -> State:
        """The state after ``step``; PlanError if the rules forbid it."""
        robots = [m[0] for m in step]
        if len(set(robots)) != len(robots) or not 1 <= len(step) <= 2:
            raise PlanError(f"a step moves one or two different robots, not {robots}")
        for r, origin, target in step:
            if state.at.get(r) != origin:
                raise PlanError(f"{r} is not at {origin} (it is at {state.at.get(r)})")
            if not self.may_enter(state, r, target):
                why = "visited before" if self.goals.may_visit(r, target) else "its job is for other robots"
                raise PlanError(f"{r} may not enter {target}: {why}")
        if len(step) == 2 and step[0][2] == step[1][2] and not any((r, t) in self.entries for r, _, t in step):
            raise PlanError(f"two robots enter {step[0][2]} at once")
        at, visited, by = dict(state.at), set(state.visited), set(state.visited_by)
        for r, _, target in step:
            at[r] = target
            visited.add(target)
            if (r, target) in self.entries:
                by.add((r, target))
        return State(at, frozenset(visited), frozenset(by))

    def run(self, plan: Iterable[Step], state: State | None = None) -> State:
        """The state after the plan's steps; PlanError at the first step the rules forbid."""
        state = state or self.start()
        for k, step in enumerate(plan):
            try:
                state = self.apply(state, step)
            except PlanError as err:
                raise PlanError(f"step {k + 1}: {err}") from None
        return state

    def done(self, state: State) -> bool:
        visited = set(self.goals.required) <= state.visited and self.targets <= state.visited_by
        return visited and self.goals.ended(state.at)

    def check(self, plan: Iterable[Step]) -> None:
        """Raise PlanError unless ``plan`` obeys the rules and reaches the goals."""
        state = self.run(plan)
        if not self.done(state):
            missing = sorted(set(self.goals.required) - state.visited)
            missing += sorted(f"{x} by {r}" for r, x in self.targets - state.visited_by)
            missing += sorted(f"{r} ends at {x}" for r, x in self.goals.ends if state.at.get(r) != x)
            raise PlanError(f"the plan leaves goals undone: {', '.join(missing)}")

    def valid(self, plan: Iterable[Step]) -> bool:
        try:
            self.check(plan)
        except PlanError:
            return False
        return True


Pairs = tuple[tuple[str, str], ...]


def without_revisits(steps: Iterable[Sequence[tuple[str, str]]], rules: Rules) -> tuple[Pairs, ...]:
    """Steps given as (robot, target) pairs without the moves into rooms the rules count as
    visited already when they come: what is left of a plan under way for a team that stands
    where a replan starts it (a robot that has driven into a goal room has visited it, and its
    move there is no move any more). From a step the rules refuse for another reason, the
    steps as they are."""
    state, out = rules.start(), list[Pairs]()
    given: list[Pairs] = [tuple(step) for step in steps]
    for k, step in enumerate(given):
        kept = tuple((r, t) for r, t in step if rules.may_enter(state, r, t))
        if not kept:
            continue
        try:
            state = rules.apply(state, tuple((r, state.at[r], t) for r, t in kept))
        except (PlanError, KeyError):
            return (*out, *given[k:])
        out.append(kept)
    return tuple(out)


def with_origins(steps: Iterable[Sequence[tuple[str, str]]], start_location: dict[str, str]) -> Plan:
    """Steps given as (robot, target) pairs, with each move's origin filled in: where its
    robot was after the steps before."""
    at = dict(start_location)
    out = []
    for step in steps:
        moves = tuple((r, at[r], t) for r, t in step)
        for r, _, t in moves:
            at[r] = t
        out.append(moves)
    return tuple(out)


def with_missing(plan: Plan, rules: Rules, singles: CostTable) -> Plan:
    """The plan with each goal room it leaves undone inserted where the single moves' costs
    rise least (cheapest insertion, as dynamic vehicle routing takes a new order into routes
    under way): as a move of a robot that may visit it, before one of that robot's moves or
    after its last, at the cheapest place where every robot still arrives within its jobs'
    windows (the single moves' durations, the robots' holds: ``goals.held``), else at the
    cheapest place. The plan as it is when nothing is missing, when the plan breaks the rules,
    or for a room no single move reaches."""
    try:
        state = rules.run(plan)
    except PlanError:
        return plan
    missing: list[tuple[str | None, str]] = [(None, x) for x in rules.goals.required if x not in state.visited]
    missing += sorted((r, x) for r, x in rules.targets - state.visited_by)
    if not missing:
        return plan
    steps = targets_only(plan)
    for robot, room in missing:
        places = _insertions(steps, robot, room, rules, singles)
        on_time = (p for p in places if not _late(_inserted(steps, p), rules, singles))
        best = next(on_time, places[0] if places else None)
        if best is not None:
            steps = _inserted(steps, best)
    return with_origins(steps, rules.start_location)


#: where a room goes into a plan's steps: (the rise of the single moves' costs, the step index
#: it goes before, the robot, the room)
_Place = tuple[float, int, str, str]


def _insertions(
    steps: list[tuple[tuple[str, str], ...]], robot: str | None, room: str, rules: Rules, singles: CostTable
) -> list[_Place]:
    """Every place ``room`` can go into a route of ``robot`` (any robot that may visit it when
    None), cheapest first."""
    robots = [robot] if robot is not None else sorted(singles.robots)
    out: list[_Place] = []
    for r in robots:
        if not rules.goals.may_visit(r, room):
            continue
        route = [(k, t) for k, step in enumerate(steps) for who, t in step if who == r]
        for p in range(len(route) + 1):
            before = rules.start_location[r] if p == 0 else route[p - 1][1]
            rise = singles.single.get((r, before, room), math.inf)
            if p < len(route):
                after = route[p][1]
                rise += singles.single.get((r, room, after), math.inf) - singles.single.get((r, before, after), 0.0)
            if math.isfinite(rise):
                out.append((rise, route[p][0] if p < len(route) else len(steps), r, room))
    return sorted(out, key=lambda p: p[0])


def _inserted(steps: list[tuple[tuple[str, str], ...]], place: _Place) -> list[tuple[tuple[str, str], ...]]:
    _, at, robot, room = place
    return [*steps[:at], ((robot, room),), *steps[at:]]


def _late(steps: list[tuple[tuple[str, str], ...]], rules: Rules, singles: CostTable) -> bool:
    """Whether a robot of ``steps`` arrives after a job's window closes (on the single moves'
    durations); False when nothing has a window or a move has no duration."""
    goals = rules.goals
    if not goals.windows:
        return False
    timed = schedule(with_origins(steps, rules.start_location), singles.robots, table_durations(singles), goals=goals)
    return timed is not None and bool(timed.late(goals.windows))


def targets_only(plan: Iterable[Step]) -> list[tuple[tuple[str, str], ...]]:
    """The steps as (robot, target) pairs, origins dropped."""
    return [tuple((r, t) for r, _, t in step) for step in plan]


@dataclass(frozen=True)
class Cut:
    """A plan opened for a sub-problem: the steps before the insertion point and after it.

    ``head`` ends where the sub-problem starts (its robots' states after ``head`` are the
    sub-problem's start); ``tail`` holds what is kept after it.
    """

    head: Plan
    tail: tuple[tuple[tuple[str, str], ...], ...]  # (robot, target) pairs: origins change with the insert


def cut(plan: Plan, removed: set[int], robots: set[str]) -> Cut:
    """Open ``plan`` for new moves of ``robots`` in place of their moves at ``removed``.

    The insertion point is the first removed step. A removed step may be a pair whose
    other robot is not one of ``robots``: that robot's move stays, as a single move, where
    the pair was. A step after the insertion point that moves one of ``robots`` joins the
    head when none of its robots has a move waiting behind the insertion point (so every
    robot still makes its moves in its order); a robot of ``robots`` with no removed step
    thus keeps all its moves in the head.
    """
    first = min(removed) if removed else len(plan)
    head, after = list(plan[:first]), []
    waiting: set[str] = set()  # robots with a move in ``after`` (or the insert): their later steps follow it
    for k in range(first, len(plan)):
        step = plan[k]
        moving = {m[0] for m in step}
        if k in removed:
            kept = tuple(m for m in step if m[0] not in robots)
            if kept:
                after.append(kept)
            waiting |= moving
            continue
        if moving & robots and not moving & waiting:
            head.append(step)
        else:
            after.append(step)
            waiting |= moving
    return Cut(tuple(head), tuple(targets_only(after)))


def splice(opened: Cut, insert: Sequence[Step], start_location: dict[str, str]) -> Plan:
    """The plan ``head + insert + tail``, origins recomputed (the caller checks the rules)."""
    steps = [*targets_only(opened.head), *targets_only(insert), *opened.tail]
    return with_origins(steps, start_location)
