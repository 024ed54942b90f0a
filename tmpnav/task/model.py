"""What the task-level search asks of action costs: the :class:`CostModel` protocol.

The search (:mod:`tmpnav.task.search`) never computes a cost itself. It asks a cost model
for the single moves it starts from, for the cost of a whole plan, and for the small cost
tables of its sub-problems, costed from where the robots are at that point of the plan.
Two models implement it:

* :class:`TableModel` (here): a fixed cost table, the planner's model of ``--costs table``
  and of the tests' random tables; every move costs the same wherever it is made;
* the oracle's models (:mod:`tmpnav.attachment.canonical`, :mod:`tmpnav.attachment.carried`),
  which call the semantic attachment on demand: with canonical start states, or with the
  beliefs the robots carry at that point of the plan.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

from tmpnav.choices import Costs
from tmpnav.results import Schedule
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.objectives import strict_price
from tmpnav.task.plans import Plan, Rules
from tmpnav.task.timing import schedule, table_durations
from tmpnav.types import CostTable, Goals, MoveKey


@dataclass(frozen=True)
class PlanCost:
    """A plan's cost under a model: the total and each step's share, and when the team ends it
    (its schedule: every robot at once, on one clock; None without durations)."""

    total: float
    steps: tuple[float, ...]
    schedule: Schedule | None = None
    dropped: float = 0.0  # the penalties of the optional goals it leaves undone (goals.jobs)
    #: the makespan when it is not the schedule's: a plan executed with a move split in two
    #: (a sidestep, tmpnav.attachment.apart.ExecutedCost) keeps the plan's own schedule
    span: float | None = None
    #: under a chance constraint, the robots still in each other's way when the plan is kept
    #: apart (tmpnav.attachment.apart.ExecutedCost): ``tmpnav plan`` refuses such a plan, so the
    #: search ranks it below every plan without (``ranked``)
    unsafe: int = 0
    #: the work rooms its robots lack of planner.min_rooms (tmpnav.task.minimum): the search ranks
    #: it below every plan that lacks fewer (``ranked``)
    short: int = 0

    @property
    def makespan(self) -> float:
        """When the last robot ends its last move (inf for an impossible plan; 0 without durations)."""
        if not math.isfinite(self.total):
            return math.inf
        if self.span is not None:
            return self.span
        return self.schedule.makespan if self.schedule is not None else 0.0

    def value(self, span_weight: float) -> float:
        """The objective: the total plus ``span_weight`` per second of makespan (tmpnav.task.objectives),
        plus the penalties of the optional goals left undone."""
        return self.total + self.dropped + (span_weight * self.makespan if span_weight else 0.0)

    def ranked(self, span_weight: float) -> float:
        """:meth:`value`, plus :func:`~tmpnav.task.objectives.strict_price` for each conflict left
        and each room short of the minimum: what the search compares. So a plan the command would
        refuse is taken only where no plan kept apart was found, under every objective."""
        return self.value(span_weight) + strict_price(span_weight) * (self.unsafe + self.short)

    @classmethod
    def impossible(cls, n: int) -> PlanCost:
        return cls(math.inf, (math.inf,) * n)


class CostModel(Protocol):
    """Action costs as the task-level search sees them."""

    robots: tuple[str, ...]
    start_location: dict[str, str]
    #: "table": a move costs the same wherever in the plan it is made (so one optimal search of
    #: the whole problem proves a plan optimal); "carried": it depends on the beliefs it starts from
    costs: Costs

    def singles(self, goals: Goals) -> CostTable:
        """Every single move between the robots' starts and the goal rooms (no pairs)."""
        ...

    def plan_cost(self, plan: Plan) -> PlanCost:
        """The plan's cost under this model (inf where a move is impossible)."""
        ...

    def subtable(self, head: Plan, robots: Sequence[str], rooms: Sequence[str], goals: Goals) -> CostTable:
        """The moves of ``robots`` into ``rooms`` from where they are after ``head``, and the
        paired moves among them, costed from the robots' states after ``head``, with their
        durations. The table's ``start_location`` is each robot's location after ``head``;
        ``goals`` are the sub-problem's (they decide which pairs can ever happen)."""
        ...

    def ends(self, head: Plan) -> dict[str, float]:
        """When each robot ends its moves of ``head`` (seconds), the team moving at once."""
        ...


def entered(plan: Plan, start_location: dict[str, str]) -> set[str]:
    """The locations a plan visits: the robots' starts and every room it enters."""
    return {*start_location.values(), *(m[2] for step in plan for m in step)}


def head_locations(head: Plan, start_location: dict[str, str], robots: Sequence[str]) -> dict[str, str]:
    """Where each of ``robots`` is after the steps of ``head``."""
    at = dict(start_location)
    for step in head:
        for r, _, t in step:
            at[r] = t
    return {r: at[r] for r in robots}


def sub_moves(at: dict[str, str], rooms: Sequence[str]) -> list[MoveKey]:
    """The single moves of a sub-problem: each robot from where it is, and between its rooms."""
    moves: list[MoveKey] = []
    for r, here in at.items():
        for origin in dict.fromkeys([here, *rooms]):
            moves.extend((r, origin, t) for t in rooms if t != origin and t != here)
    return moves


class TableModel:
    """A fixed cost table: a move costs the same wherever in the plan it is made. With ``goals``,
    a plan that arrives after a job's window closes costs infinity, and one that leaves optional
    goals undone pays their penalties."""

    costs: Costs = "table"

    def __init__(self, table: CostTable, min_gain: float = 0.0, goals: Goals | None = None):
        self.table = table
        self.robots = table.robots
        self.start_location = dict(table.start_location)
        self.min_gain = min_gain
        self.goals = goals

    def singles(self, goals: Goals) -> CostTable:
        t = self.table
        return CostTable(t.robots, t.rooms, t.locations, t.start_location, t.single, {}, t.duration)

    def plan_cost(self, plan: Plan) -> PlanCost:
        costs = []
        for step in plan:
            if len(step) == 1:
                costs.append(self.table.single.get(step[0], math.inf))
            else:
                m1, m2 = step
                costs.append(self.table.pair.get((m1, m2), self.table.pair.get((m2, m1), math.inf)))
        timed = table_schedule(self.table, plan, self.goals)
        if self.goals is None:
            return PlanCost(float(sum(costs)), tuple(costs), timed)
        if timed is not None and timed.late(self.goals.windows):
            return PlanCost.impossible(len(plan))
        dropped = self.goals.drop_penalty(entered(plan, self.start_location))
        return PlanCost(float(sum(costs)), tuple(costs), timed, dropped)

    def ends(self, head: Plan) -> dict[str, float]:
        """When each robot ends its moves of ``head`` (seconds; 0 without durations)."""
        return robot_ends(table_schedule(self.table, head, self.goals), self.robots)

    def subtable(self, head: Plan, robots: Sequence[str], rooms: Sequence[str], goals: Goals) -> CostTable:
        at = head_locations(head, self.start_location, robots)
        t = self.table
        single = {m: t.single[m] for m in sub_moves(at, rooms) if m in t.single}
        keep = ENCODINGS["mixed"].pair_filter(goals, at)
        assert keep is not None
        pair = {(m1, m2): c for (m1, m2), c in t.pair.items() if m1 in single and m2 in single and keep(m1, m2)}
        locations = tuple(dict.fromkeys([*rooms, *at.values()]))
        duration = {m: t.duration[m] for m in single if m in t.duration}
        pair_duration = {p: t.pair_duration[p] for p in pair if p in t.pair_duration}
        return CostTable(tuple(robots), tuple(rooms), locations, at, single, pair, duration, pair_duration)


def table_schedule(table: CostTable, plan: Plan, goals: Goals | None = None) -> Schedule | None:
    """The plan's schedule with the table's durations (None when the table has none); with
    ``goals``, the jobs' service and windows apart from the drive (tmpnav.task.timing.schedule)."""
    if not table.duration:
        return None
    return schedule(plan, table.robots, table_durations(table), goals=goals)


def robot_ends(found: Schedule | None, robots: Sequence[str]) -> dict[str, float]:
    """When each robot ends its last move of a schedule (0 for none, or without a schedule)."""
    ends = dict.fromkeys(robots, 0.0)
    for m in found.moves if found is not None else ():
        ends[m.robot] = max(ends[m.robot], m.done)
    return ends


def plan_rules(model: CostModel, goals: Goals) -> Rules:
    """The entry rules and goals of the whole task problem of ``model``."""
    return Rules(model.start_location, goals)
