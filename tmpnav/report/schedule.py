"""The plan's schedule as the reports read it: the numbers plan.json, the summary and the figures share.

All robots move at once on one shared clock (:class:`~tmpnav.results.Schedule`, made by the
team's clock of :mod:`tmpnav.attachment.clock`). The reports need a few readings of it that
must agree everywhere: each plan step's time window, which plan step a robot is driving in at
a given control step (and so how many control steps it drives), and the plan's objective with
its price on time (:mod:`tmpnav.task.objectives`). They are here, once.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from tmpnav.numbers import percent
from tmpnav.results import PlanReport, Schedule, TimedMove
from tmpnav.task.bound import OPTIMAL_GAP
from tmpnav.task.objectives import OBJECTIVES

#: s: trajectory times are rounded to 1e-9 s, schedule times are multiples of the control step
T_TOL = 1e-6


def step_windows(schedule: Schedule, n_steps: int) -> list[tuple[float, float] | None]:
    """(start, end) in seconds of each of ``n_steps`` plan steps on the shared clock: from when
    its moves start (together, for a paired step) to when its last robot arrives; None for a
    step without a move in the schedule (never expected)."""
    windows: list[tuple[float, float] | None] = [None] * n_steps
    for move in schedule.moves:
        if not 0 <= move.step < n_steps:
            continue
        window = windows[move.step]
        windows[move.step] = (
            (move.start, move.end) if window is None else (min(window[0], move.start), max(window[1], move.end))
        )
    return windows


def driving_steps(schedule: Schedule, robot: str, times: Sequence[float]) -> list[int | None]:
    """For each time of ``robot``'s trajectory (increasing, s): the 1-based plan step whose move
    it drives during the control step that ends then (``start < t <= end``), None while it
    stands (its initial belief, waiting, held back, or done)."""
    moves = sorted(schedule.timeline(robot), key=lambda m: m.start)
    out: list[int | None] = []
    k = 0
    for t in times:
        while k < len(moves) and moves[k].end < t - T_TOL:
            k += 1
        driving = k < len(moves) and moves[k].start + T_TOL < t
        out.append(moves[k].step + 1 if driving else None)
    return out


def move_at(schedule: Schedule, robot: str, t: float) -> TimedMove | None:
    """The move ``robot`` drives at time ``t`` (s), None if it stands then."""
    return next((m for m in schedule.timeline(robot) if m.start + T_TOL < t <= m.end + T_TOL), None)


@dataclass(frozen=True)
class ObjectiveValues:
    """What the plan minimised and what it came to: as the planner saw it and as re-simulated.

    ``value = cost + span_weight * makespan`` (:mod:`tmpnav.task.objectives`), plus the penalties
    of the optional goals left undone; the planner's
    makespan is None when its costs had no durations (then so is its value)."""

    name: str  # weighted | cost | makespan (tmpnav.choices)
    doc: str
    span_weight: float  # cost units per second of makespan
    makespan: float  # s, the re-simulated schedule's
    planner_makespan: float | None  # s, the planner's schedule's
    value: float  # of the re-simulated plan
    planner_value: float | None  # of the plan as the planner saw it
    units: str = "cost"  # the objective's own: cost, or s (the makespan objective)
    own: float = 0.0  # ``value`` in those units
    planner_own: float | None = None  # ``planner_value`` in those units

    def differs(self, tol: float = 5e-4) -> bool:
        """Whether the planner's makespan or value is not the re-simulated one (or unknown)."""
        if self.planner_makespan is None or self.planner_value is None:
            return True
        return abs(self.planner_makespan - self.makespan) > T_TOL or abs(self.planner_value - self.value) > tol


def visited_rooms(report: PlanReport) -> set[str]:
    """The locations the plan visits: where its moves start (each robot's start among them) and end."""
    return {loc for step in report.task.steps for m in step for loc in m[1:]}


def dropped_goals(report: PlanReport) -> tuple[str, ...]:
    """The optional goals (``goals.jobs[].penalty``) the plan leaves undone."""
    return report.scenario.goals.dropped(visited_rooms(report))


def objective_values(report: PlanReport) -> ObjectiveValues:
    """The objective of ``report``'s plan, planner's and re-simulated."""
    name = report.scenario.planner.objective
    objective, weights = OBJECTIVES[name], report.scenario.cost
    makespan, planned = report.schedule.makespan, report.task.makespan
    dropped = report.scenario.goals.drop_penalty(visited_rooms(report))  # optional goals left undone
    value = objective.value(report.resimulated_cost, makespan, weights) + dropped
    planner_value = None if planned is None else objective.value(report.planner_cost, planned, weights) + dropped
    dt = report.scenario.models.dt
    return ObjectiveValues(
        name=name,
        doc=objective.doc,
        span_weight=objective.span_weight(weights),
        makespan=makespan,
        planner_makespan=planned,
        value=value,
        planner_value=planner_value,
        units=objective.units,
        own=objective.own(value, dt),
        planner_own=None if planner_value is None else objective.own(planner_value, dt),
    )


@dataclass(frozen=True)
class BoundValues:
    """The plan's lower bound in its objective's own units (:meth:`tmpnav.task.objectives.Objective.own`):
    on the makespan objective a bound on the makespan (s), and the gap (plan - bound) / plan
    between the two in those units."""

    value: float
    relaxation: str
    gap: float
    proved_optimal: bool
    units: str


def searched_gap(report: PlanReport) -> float | None:
    """The gap of the plan the search found, before robots were kept apart (its cost and
    makespan run on the clock, ``report.apart``), in objective units; None for a plan not kept
    apart, without a bound, or of no cost."""
    apart, b = report.apart, report.task.bound
    if apart is None or b is None:
        return None
    value = OBJECTIVES[report.scenario.planner.objective].value(
        apart.cost_before, apart.makespan_before, report.scenario.cost
    )
    return (value - b.value) / value if value > 0.0 else None


def bound_verdict(report: PlanReport) -> str | None:
    """The plan against its bound, in words: "proved optimal" or its gap, never both (None
    without a bound). A plan kept apart after a search whose plan met its bound has a gap, the
    whole of it from keeping the robots apart: the line says that, and proves nothing of it."""
    own = bound_values(report)
    if own is None:
        return None
    if own.proved_optimal:
        return "proved optimal"
    verdict = f"gap {percent(own.gap)}"
    searched = searched_gap(report)
    if searched is not None and searched <= OPTIMAL_GAP:
        verdict += ", all of it from keeping the robots apart (the plan as searched met the bound)"
    return verdict


def bound_values(report: PlanReport) -> BoundValues | None:
    """``report``'s lower bound and gap in its objective's own units; None without a bound."""
    b = report.task.bound
    if b is None:
        return None
    o = objective_values(report)
    if o.units == "cost":
        return BoundValues(b.value, b.relaxation, b.gap, b.proved_optimal, o.units)
    value = OBJECTIVES[report.scenario.planner.objective].own(b.value, report.scenario.models.dt)
    plan = o.planner_makespan if o.planner_makespan is not None else o.makespan
    gap = 0.0 if b.proved_optimal or plan <= 0.0 else max(0.0, (plan - value) / plan)
    return BoundValues(value, b.relaxation, gap, b.proved_optimal, o.units)
