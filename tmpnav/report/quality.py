"""Plain warnings about a plan's quality, from what a :class:`~tmpnav.results.PlanReport` holds.

A plan can be poor in two ways the status line does not show:

- **Far from its bound.** The gap (plan cost - lower bound) / plan cost is above
  :data:`GAP_WARN`: no plan can cost less than the bound, so the plan may be up to that much too
  expensive. With carried costs the bound counts driving and turning but not uncertainty
  (motion floors), so part of a large gap is the bound's; a search stopped by its time budget says more time may help.
  With an objective that prices time, the bound and the gap are on the objective (cost plus a
  price per second of makespan), and the warning says so.
- **A fleet the chance constraint splits.** Where the goal rooms fall into groups that different
  robots reach without a move over the chance constraint, and robots outside the group of the
  robot that ends the plan stand idle for more than :data:`tmpnav.report.reach.IDLE_SHARE` of the
  makespan: no plan can give them its work (:mod:`tmpnav.report.reach`).
- **A fleet the objective leaves idle.** Where the objective prices time (``weighted``) and at
  least :data:`IDLE_ROBOTS` robots, and at least :data:`IDLE_TEAM` of the team, make fewer than
  half the moves a robot makes on average and stand idle for more than
  :data:`tmpnav.report.reach.IDLE_SHARE` of the makespan, and no split by the chance
  constraint explains it: the objective's price of a second did not pay for the motion of
  giving them rooms. ``--objective makespan`` plans for the earliest end instead.
- **Robots short of the minimum.** Where ``planner.min_rooms`` asks every robot to visit so many
  goal rooms (:mod:`tmpnav.task.minimum`) and the plan leaves robots short of it.
- **More uncertain than a door allows.** Where a robot's belief mean passes an open door, the
  2-sigma spread of its position across the door (along the door's segment) is compared with
  the room it has there: half the door's width less the robot's radius. Past that, the robot
  as executed may hit the door frame: the plan relies on a localization it does not have. The
  time is on the plan's shared clock (all robots at once), with the move the robot is making.

Thresholds are module constants, documented in docs/plan-json.md (``warnings``).
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tmpnav.belief.conflicts import Conflict
from tmpnav.choices import time_budget, work_budget
from tmpnav.numbers import length
from tmpnav.planning.safety import conflicts_left, riskiest_point, what_would_help
from tmpnav.report.reach import IDLE_SHARE, reach_groups, reached_by, split_message
from tmpnav.report.schedule import bound_values, move_at, objective_values, searched_gap
from tmpnav.results import PlanReport
from tmpnav.task.minimum import counts, need, work_rooms
from tmpnav.types import Door, TrajectoryStep

#: warn when the lower bound is more than this fraction of the plan's cost below it
GAP_WARN = 0.20
#: the spread compared with a door's room: this many standard deviations across the door
N_SIGMA = 2.0
#: an ``idle`` warning needs at least this many robots idle for most of the plan ...
IDLE_ROBOTS = 2
#: ... and at least this share of the team
IDLE_TEAM = 0.25
#: robots named in an ``idle`` warning at most (the rest counted)
IDLE_NAMED = 4


@dataclass(frozen=True)
class PlanWarning:
    """One warning: what it is about, its numbers, and the message with what to try."""

    kind: str  # "risk" | "conflict" | "gap" | "split" | "idle" | "short" | "door"
    robot: str | None  # the robot a "door" warning is about; split, idle: the robot that ends the plan
    value: float  # gap: the gap (fraction); split: the groups; idle: the idle robots; door: the 2-sigma spread (m)
    limit: float  # gap: GAP_WARN; split, idle: IDLE_SHARE; door: half the door's width less the robot's radius (m)
    message: str


def plan_warnings(report: PlanReport) -> list[PlanWarning]:
    """The warnings of a plan: a move over the chance constraint and robots still in each other's
    way (a plan taken with --accept-risk), its gap, then each robot's worst door (at most one per
    robot)."""
    found = [w for w in (_over_threshold(report), _in_the_way(report), _gap(report)) if w is not None]
    split = _split(report)
    found += [w for w in (split if split is not None else _idle(report),) if w is not None]
    if (short := _short(report)) is not None:
        found.append(short)
    for robot in report.scenario.robots:
        door = _worst_door(report, robot.name, robot.radius)
        if door is not None:
            found.append(door)
    return found


def _over_threshold(report: PlanReport) -> PlanWarning | None:
    delta = report.scenario.planner.max_risk
    if delta is None or report.worst_risk <= delta:
        return None
    point = riskiest_point(report)
    where = f": {what_would_help(report, point)}" if point is not None else ""
    text = f"a move's collision bound is over the chance constraint max_risk {delta:g}{where}."
    return PlanWarning("risk", point.robot if point else None, report.worst_risk, delta, text)


def _in_the_way(report: PlanReport) -> PlanWarning | None:
    planner = report.scenario.planner
    if planner.max_risk is None or not planner.keep_apart or not (left := plan_conflicts(report)):
        return None
    first = left[0]
    late = f" if their clocks drift {first.window:.1f} s apart (planner.clock_drift)" if first.window > 0 else ""
    text = (
        f"robots stay in each other's way{late}: {' and '.join(first.robots)} at {first.t_from:.1f} s, "
        f"{length(first.closest_distance)} apart where {length(first.required_separation)} are needed"
        + (f" (and {len(left) - 1} more)." if len(left) > 1 else ".")
    )
    return PlanWarning("conflict", first.robots[0], first.closest_distance, first.required_separation, text)


def _split(report: PlanReport) -> PlanWarning | None:
    """Robots idle for most of the plan because the chance constraint keeps them out of the group
    of rooms of the robot that ends it (:mod:`tmpnav.report.reach`)."""
    delta, schedule = report.scenario.planner.max_risk, report.schedule
    if delta is None or not schedule.moves or len(schedule.robots) < 2:
        return None
    groups = reach_groups(report.table, report.scenario.goals.all_rooms)
    if len([g for g in groups if g.robots]) < 2:
        return None
    makespan = schedule.makespan
    last = max(schedule.moves, key=lambda m: m.done).robot
    busiest = next((g for g in groups if last in g.robots), None)
    idle = {r: t for r in schedule.robots if (t := schedule.idle(r)) > IDLE_SHARE * makespan}
    if busiest is None or not any(r not in busiest.robots for r in idle):
        return None
    anyway = reached_by(report.table)  # without the constraint: do the idle robots reach those rooms?
    if not any(r in anyway.get(x, ()) for x in busiest.rooms for r in idle if r not in busiest.robots):
        return None  # their jobs or the roadmap keep them out, not the chance constraint
    text = split_message(groups, idle, last, makespan, delta)
    return PlanWarning("split", last, float(len(groups)), IDLE_SHARE, text)


def _idle(report: PlanReport) -> PlanWarning | None:
    """Robots idle for most of the plan, with fewer than half the moves a robot makes on average,
    where the objective (``weighted``) did not pay for giving them rooms: the price of a second
    of makespan against the motion it would take."""
    planner, schedule = report.scenario.planner, report.schedule
    if planner.objective != "weighted" or not schedule.moves or len(schedule.robots) < 3:
        return None
    makespan, team = schedule.makespan, len(schedule.robots)
    fair = len(schedule.moves) / team  # the moves a robot makes on average
    idle = [
        r for r in schedule.robots if len(schedule.timeline(r)) < fair / 2 and schedule.idle(r) > IDLE_SHARE * makespan
    ]
    if len(idle) < max(IDLE_ROBOTS, IDLE_TEAM * team):
        return None
    last = max(schedule.moves, key=lambda m: m.done).robot
    named = ", ".join(idle[:IDLE_NAMED]) + (f" and {len(idle) - IDLE_NAMED} more" if len(idle) > IDLE_NAMED else "")
    text = (
        f"{len(idle)} of {len(schedule.robots)} robots ({named}) stand idle for more than half of the "
        f"{makespan:.1f} s makespan, which {last} ends: the weighted objective prices a second of makespan at "
        f"cost.M_T = {report.scenario.cost.M_T:g}, and giving them rooms was not found to save more than the "
        'motion it adds. --objective makespan plans for the earliest end instead (docs/planning.md, "Objective"); '
        "--min-rooms N gives every robot N rooms at least."
    )
    return PlanWarning("idle", last, float(len(idle)), IDLE_SHARE, text)


def least_rooms(report: PlanReport) -> int:
    """The goal rooms each robot of the plan is to visit: planner.min_rooms, lowered to the goals'
    share per robot (tmpnav.task.minimum.need, from the robots' starts the planner saw)."""
    table = report.table
    starts = {r: table.start_location.get(r, "") for r in table.robots}
    return need(report.scenario.goals, starts, report.scenario.planner.min_rooms)


def _short(report: PlanReport) -> PlanWarning | None:
    """Robots that visit fewer work rooms than planner.min_rooms asks (lowered to the goals' share
    per robot, tmpnav.task.minimum): the search found no plan that keeps to it."""
    sc, least = report.scenario, least_rooms(report)
    entered = counts(report.task.steps, work_rooms(sc.goals))
    short = {r.name: entered.get(r.name, 0) for r in sc.robots if entered.get(r.name, 0) < least}
    if not short:
        return None
    named = ", ".join(f"{r} ({n})" for r, n in list(short.items())[:IDLE_NAMED])
    more = f" and {len(short) - IDLE_NAMED} more" if len(short) > IDLE_NAMED else ""
    text = (
        f"{len(short)} of {len(sc.robots)} robots visit fewer than the {least} goal rooms planner.min_rooms asks "
        f"each: {named}{more}. The search found no plan that keeps to it: their jobs, the roadmap or the chance "
        "constraint may keep them out of the rooms, or a larger --anytime-work may find one."
    )
    return PlanWarning("short", next(iter(short)), float(len(short)), float(least), text)


def warning_lines(report: PlanReport, width: int = 100) -> list[str]:
    """The warnings as text lines of at most ``width`` characters, each starting ``warning:``."""
    lines: list[str] = []
    for w in plan_warnings(report):
        lines += textwrap.wrap(f"warning: {w.message}", width, subsequent_indent="  ", break_on_hyphens=False)
    return lines


def _gap(report: PlanReport) -> PlanWarning | None:
    """The search's gap (of the plan it found, before robots were kept apart: what keeping them
    apart costs is reported on its own line) when it is above GAP_WARN."""
    bound, search = bound_values(report), report.task.search
    if bound is None or bound.proved_optimal or not math.isfinite(bound.gap) or bound.gap <= GAP_WARN:
        return None
    searched = searched_gap(report) if bound.units == "cost" else None
    if searched is not None and searched <= GAP_WARN:
        return None
    value = f"{bound.value:.1f} s" if bound.units == "s" else f"{bound.value:.3f}"
    text = (
        f"the plan may be far from the best: its lower bound, {value}, is {100 * bound.gap:.0f}% below "
        f"{_planned(report)} (warned above {100 * GAP_WARN:.0f}%)."
    )
    if search is not None and search.stopped == "time budget":
        sc = report.scenario
        budget = time_budget(sc.planner.time_budget)
        if math.isfinite(budget):
            text += f" The search stopped at its time cap of {budget:g} s: try --anytime-budget {2 * budget:g}."
        else:
            text += " The search stopped at the run's time limit: try a larger --time-limit."
    elif search is not None and search.stopped == "work budget":
        sc = report.scenario
        work = work_budget(len(sc.goals.all_rooms), len(sc.robots), sc.planner.work_budget)
        text += f" The search stopped at its work budget of {work} sub-problems: try --anytime-work {2 * work}."
    elif search is not None and search.mode == "anytime":
        text += " The search stopped improving: try --anytime-budget with more time, or --search exact if small."
    if "floors" in bound.relaxation:
        text += (
            " The bound counts driving and turning, not uncertainty (motion floors): part of the gap is the bound's."
        )
    if (
        objective_values(report).span_weight
        and not bound.relaxation.startswith("exact")
        and "makespan" not in bound.relaxation
    ):
        text += " The bound puts no price on the makespan, so the time's share of the objective is in the gap."
    return PlanWarning("gap", None, bound.gap, GAP_WARN, text)


def _planned(report: PlanReport) -> str:
    """What the bound is compared with: the plan's objective as the planner saw it (its cost
    when the objective puts no price on time)."""
    o = objective_values(report)
    if o.units == "s":
        makespan = o.planner_makespan if o.planner_makespan is not None else o.makespan
        return f"its makespan, {makespan:.1f} s"
    if not o.span_weight:
        return f"its cost, {report.planner_cost:.3f}"
    value = o.planner_value if o.planner_value is not None else o.value
    return f"its objective ({o.name}: cost + {o.span_weight:g} per s of makespan), {value:.3f}"


def _worst_door(report: PlanReport, robot: str, radius: float) -> PlanWarning | None:
    """The door ``robot`` passes with the least room for its uncertainty, if it has too little."""
    steps = report.trajectories.get(robot, [])
    if len(steps) < 2:
        return None
    means = np.array([s.mean[:2] for s in steps], dtype=float)
    worst: tuple[float, Door, float, float, TrajectoryStep] | None = None  # (excess, door, spread, room, step)
    for door in report.scenario.doors:
        if not door.open:
            continue
        (ax, ay), (bx, by) = door.segment
        width = math.hypot(bx - ax, by - ay)
        room = width / 2 - radius
        if room <= 0:  # the roadmap does not pass a door the robot does not fit through
            continue
        along = np.array([bx - ax, by - ay]) / width
        for i in _crossings(means, np.array([ax, ay]), np.array([bx, by])):
            cov = np.asarray(steps[i].cov, dtype=float)[:2, :2]
            spread = N_SIGMA * math.sqrt(max(float(along @ cov @ along), 0.0))
            if spread > room and (worst is None or spread - room > worst[0]):
                worst = (spread - room, door, spread, room, steps[i])
    if worst is None:
        return None
    _, door, spread, room, step = worst
    width = 2 * (room + radius)
    move = move_at(report.schedule, robot, step.t)
    way = "" if move is None else f" on its way to {move.target} (step {move.step + 1}),"
    text = (
        f"{robot} passes door {door.name} ({width:.2f} m wide, {length(room)} to spare each side) "
        f"at t {step.t:.1f} s,{way} with a {N_SIGMA:g}-sigma position spread of {length(spread)} across it: "
    )
    sensor = report.scenario.models.range_sensor
    if sensor is not None and sensor.localiser.local_walls:
        # the robot keeps clear of the frame its lidar sees; its estimate decides where the map's frame lies
        text += (
            "where its estimate is that far off, the frame its lidar sees and the frame of the map leave nav2's "
            "planner too narrow a gap, and the robot may stop there to clear its costmaps and plan again (time "
            "lost, not a wall hit: the collision bound counts the walls the lidar sees). A wider door, or features "
            "near it that the lidar can localise on, would help."
        )
    else:
        text += (
            "as executed it may hit the frame. "
            "Try landmarks near that door, a partner robot that sees it there, or less models.motion_noise."
        )
    return PlanWarning("door", robot, spread, room, text)


def _crossings(means: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]) -> list[int]:
    """Indices of the trajectory steps that end a move across the segment a-b (the belief mean
    goes from one side of it to the other between step i-1 and step i, within the segment)."""
    p, q = means[:-1], means[1:]
    d = b - a
    side_p = d[0] * (p[:, 1] - a[1]) - d[1] * (p[:, 0] - a[0])
    side_q = d[0] * (q[:, 1] - a[1]) - d[1] * (q[:, 0] - a[0])
    move = q - p
    side_a = move[:, 0] * (a[1] - p[:, 1]) - move[:, 1] * (a[0] - p[:, 0])
    side_b = move[:, 0] * (b[1] - p[:, 1]) - move[:, 1] * (b[0] - p[:, 0])
    crossing = (side_p * side_q < 0) & (side_a * side_b <= 0)
    return [int(i) + 1 for i in np.nonzero(crossing)[0]]


def plan_conflicts(report: PlanReport) -> list[Conflict]:
    """Robots closer than their radii plus the margin of their uncertainty, within the time
    windows of planner.clock_drift (tmpnav.planning.safety.conflicts_left: the independent
    checker over the re-simulated trajectories). Robots asked to be kept apart were kept apart first where that helps
    (tmpnav.attachment.apart.keep_apart): what is left."""
    return conflicts_left(report)
