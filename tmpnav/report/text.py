"""The terminal summary of a plan: what ``tmpnav plan`` prints (plain text, no colours).

Under the header, a ``warning:`` line for each reason to doubt the plan (tmpnav.report.quality):
a lower bound far below its cost (or objective), a robot more uncertain than a door it passes
allows. All robots move at once, on one clock: a step's ``t [s]`` is its window on that clock
(steps of different robots overlap); under the totals, the makespan and the objective; then one
row per robot: its rooms, its time driving (``busy``, in control steps), waiting before its
moves (``waits``) and neither (``idle``, after its last move: busy + waits + idle = makespan),
the distance its belief mean drives, its position std along the widest axis of its covariance
(sqrt of the largest eigenvalue; largest / at the end), its heading std at the end and the collision
bound of its riskiest move; then the plan's collision bound and robots in each other's way.
Figures read as tmpnav.numbers prints them: a std below 0.1 m in cm, a bound below 1e-6 as
``< 1e-6``, a heading std below 0.1 deg as ``< 0.1 deg``.

Example (the paper's Fig. 2 task, ``tmpnav plan configs/corridor.yaml --costs table``, a
second time)::

    corridor (configs/corridor.yaml): encoding mixed, planner enhsp-blind, solved-optimally
    2 robots, mutual observations on; goals: r1 visits L10; r2 visits L1
    localisation: landmarks and partners only (the paper's model); chance constraint: none
    search: exact, costs table
    lower bound on the objective: 31.198 (exact (A* over every schedule)); proved optimal

    step  moves                            planner cost  re-sim cost     diff  t [s]
       1  r1: L1 -> L10  &  r2: L10 -> L1        10.698       10.698   +0.000  0.0-20.5
    total (1 step)                               10.698       10.698   +0.000  0.0-20.5
    makespan 20.5 s; objective weighted (cost + 1 per s of makespan): 31.198

    robot  rooms    busy   waits  idle [s]  travelled  pos. std max / end  heading std  collision bound
    r1         1    18.5     0.0       2.0      7.1 m     0.21 m / 0.21 m      6.4 deg            0.045
    r2         1    20.5     0.0       0.0      7.6 m     0.16 m / 0.12 m      2.3 deg            0.005
    (busy: driving, in control steps of 0.5 s; idle: after the last move; busy + waits + idle: makespan)
    (pos. std: along the widest axis of the position covariance, the sqrt of its largest eigenvalue)
    collision bound: plan 0.05 (no --max-risk); robots in each other's way: 1, the first:
     r1 and r2 at 8.0 s, 4.0 cm apart, 0.94 m needed; --max-risk keeps robots apart: docs/planning.md

    time [s]  roadmap  oracle  planner  resimulate   other   total  (load)
                 0.00    0.00     0.00        0.20    0.01    0.21    0.05
    cache (/home/me/.cache/tmpnav): roadmap from cache; move costs: cost table from cache, then 1 more
    from cache and 0 computed
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from tmpnav.attachment.drift import clock_drift
from tmpnav.belief.risk import position_std
from tmpnav.choices import STOP_MEANINGS
from tmpnav.numbers import angle, length, probability
from tmpnav.report.quality import least_rooms, plan_conflicts, warning_lines
from tmpnav.report.schedule import (
    T_TOL,
    bound_values,
    bound_verdict,
    driving_steps,
    dropped_goals,
    objective_values,
    step_windows,
)
from tmpnav.results import OTHER, STAGES, PlanReport
from tmpnav.shipped import PREFIX, configs_dir
from tmpnav.types import PlanStatus, ScanModelKind


def _display_path(path: Path) -> str:
    """The scenario file relative to the working directory when it lies below it, as
    ``shipped configs/NAME.yaml`` when it is a scenario shipped with tmpnav."""
    resolved = Path(path).resolve()
    try:
        return str(resolved.relative_to(Path(os.getcwd()).resolve()))
    except ValueError:
        pass
    try:
        return f"shipped {PREFIX}/{resolved.relative_to(configs_dir().resolve())}"
    except ValueError:
        return str(path)


def _goals(report: PlanReport) -> str:
    goals = report.scenario.goals
    parts = []
    if goals.visit:
        parts.append("visit " + ", ".join(goals.visit))
    parts += [f"{robot} visits {', '.join(rooms)}" for robot, rooms in goals.per_robot]
    parts += [f"{robot} ends at {room}" for robot, room in goals.ends]
    if goals.optional:
        dropped = dropped_goals(report)
        parts.append(
            f"optional {', '.join(goals.optional)}: "
            + (
                f"left undone {', '.join(dropped)} (penalty {sum(goals.optional[x] for x in dropped):g})"
                if dropped
                else "all done"
            )
        )
    return "; ".join(parts) or "none"


def _header(report: PlanReport) -> list[str]:
    sc = report.scenario
    status = report.status.value
    if report.task.bound is None and report.status is PlanStatus.SOLVED_SATISFICING:
        status += " (not proven optimal)"  # with a bound, its line below says how far from it
    mutual = "on" if sc.models.mutual_observations else "off"
    if sc.models.range_sensor is not None and not sc.models.range_sensor.localiser.fuses_others:
        mutual = "off (the lidar alone)"
    return [
        f"{sc.name} ({_display_path(sc.source)}): encoding {report.encoding}, planner {report.planner}, {status}",
        f"{len(sc.robots)} robots, mutual observations {mutual}; goals: {_goals(report)}",
        _sensing_line(report),
        *_search(report),
        *warning_lines(report),
    ]


def _sensing_line(report: PlanReport) -> str:
    """What the robots localise with, and the chance constraint in force with where it comes from."""
    sc = report.scenario
    lidar = sc.models.range_sensor
    sensing = (
        "landmarks and partners only (the paper's model)"
        if lidar is None
        else f"a {lidar.range:g} m lidar of {lidar.beams} beams against the walls, landmarks and partners"
        if lidar.localiser.fuses_others
        else f"a {lidar.range:g} m lidar of {lidar.beams} beams against the walls, as nav2's AMCL takes it "
        f"(information share {lidar.localiser.information:g}), alone"
    )
    amcl = lidar.localiser if lidar is not None and lidar.localiser.kind is ScanModelKind.AMCL else None
    if amcl is not None and amcl.prediction_noise is not None:
        alphas = ", ".join(f"{a:g}" for a in amcl.prediction_noise)
        sensing += f", its drift predicted with nav2's alpha1-4 {alphas} (prediction_noise)"
    if amcl is not None and amcl.floor_beams > 0:
        sensing += f", each direction less {amcl.floor_beams:g} beams' information (floor_beams)"
    if amcl is not None and amcl.heading_blur > 0:
        sensing += f", far returns blurred by a {amcl.heading_blur:g} rad heading spread (heading_blur)"
    if lidar is not None and lidar.localiser.hazard > 0:
        sensing += f"; the localiser failing {lidar.localiser.hazard:.3g} times per m driven (failure_rate)"
    delta, source = sc.planner.max_risk, sc.planner.max_risk_from
    constraint = "none" if delta is None else f"max_risk {delta:g} ({source})" if source else f"max_risk {delta:g}"
    return f"localisation: {sensing}; chance constraint: {constraint}"


def _search(report: PlanReport) -> list[str]:
    """How the plan was searched, and the lower bound with the gap."""
    search, bound = report.task.search, report.task.bound
    lines = []
    if search is not None:
        line = f"search: {search.mode}, costs {search.costs}"
        if search.mode == "exact" and search.start:
            line += f"; {search.start}"
        if search.mode == "anytime":
            line += (
                f"; first plan by {search.start}; {_plural(search.subproblems, 'sub-problem')} solved by ENHSP, "
                f"{_plural(search.improvements, 'improvement')}; stopped: {STOP_MEANINGS[search.stopped]}"
            )
        lines.append(line)
        if search.capped:  # tmpnav.task.budget
            lines.append(
                f"time cap: {', '.join(search.capped)} cut the search short: another machine, or this one less "
                "busy, may give another plan"
            )
    own, verdict = bound_values(report), bound_verdict(report)
    if bound is not None and own is not None:
        if own.units == "s":
            lines.append(f"lower bound on the makespan: {own.value:.1f} s ({own.relaxation}); {verdict}")
        else:
            what = "lower bound on the objective" if objective_values(report).span_weight else "lower bound"
            lines.append(f"{what}: {_cost(own.value)} ({own.relaxation}); {verdict}")
    return lines


def _cost(x: float) -> str:
    return f"{x:.3f}" if math.isfinite(x) else str(x)


def _steps(report: PlanReport) -> list[str]:
    """One row per plan step and the totals; ``diff`` is re-simulated minus planner cost; ``t [s]``
    is the step's window on the shared clock (steps of different robots overlap)."""
    windows = step_windows(report.schedule, len(report.actions))
    moves = ["  &  ".join(f"{r}: {o} -> {t}" for r, o, t in a.moves) for a in report.actions]
    n = len(report.actions)
    total = f"total ({n} step{'s' if n != 1 else ''})"
    width = max([len("moves"), len(total) - 6, *map(len, moves)])
    rows = [f"step  {'moves':<{width}}  planner cost  re-sim cost     diff  t [s]"]
    for action, text, window in zip(report.actions, moves, windows, strict=True):
        rows.append(
            f"{action.index:>4}  {text:<{width}}  {_cost(action.planner_cost):>12}  "
            f"{_cost(action.resimulated_cost):>11}  {action.resimulated_cost - action.planner_cost:>+7.3f}  "
            f"{_window(window)}"
        )
    if not report.actions:
        rows.append("   -  (no moves: the goals hold in the initial state)")
    rows.append(
        f"{total:<{width + 6}}  {_cost(report.planner_cost):>12}  {_cost(report.resimulated_cost):>11}  "
        f"{report.resimulated_cost - report.planner_cost:>+7.3f}  {_window((0.0, report.schedule.makespan))}"
    )
    return [*rows, *_objective(report)]


def _window(window: tuple[float, float] | None) -> str:
    """A time window on the shared clock as ``start-end`` (s), empty when unknown."""
    return "" if window is None else f"{window[0]:.1f}-{window[1]:.1f}"


def _objective(report: PlanReport) -> list[str]:
    """The makespan (the planner's too, when it saw another) and the objective with its value."""
    o = objective_values(report)
    makespan = f"makespan {o.makespan:.1f} s"
    if o.planner_makespan is not None and abs(o.planner_makespan - o.makespan) > T_TOL:
        makespan += f" (planner's schedule: {o.planner_makespan:.1f} s)"
    if o.units == "s":  # the makespan first, then the sum of costs: each in its own units
        value = f"{o.own:.1f} s, then cost {_cost(report.resimulated_cost)}"
        first = "the makespan, then the sum of action costs"
        return [f"{makespan}; objective {o.name} ({first}): {value}", *_minimum(report)]
    formula = f"cost + {o.span_weight:g} per s of makespan" if o.span_weight else "the sum of action costs"
    if report.scenario.goals.optional:
        formula += " + the penalties of optional goals left undone"
    value = _cost(o.value)
    if o.planner_value is not None and abs(o.planner_value - o.value) > 5e-4:
        value = f"planner {_cost(o.planner_value)}, re-simulated {value}"
    return [f"{makespan}; objective {o.name} ({formula}): {value}", *_minimum(report)]


def _minimum(report: PlanReport) -> list[str]:
    """The minimum of goal rooms per robot the plan keeps (planner.min_rooms), with what lowered it."""
    asked = report.scenario.planner.min_rooms
    if asked <= 0:
        return []
    least = least_rooms(report)
    lowered = ", lowered to the goal rooms' share per robot" if least < asked else ""
    source = report.scenario.planner.min_rooms_from or "planner.min_rooms"
    source = f"{source} {asked}" if source in ("planner.min_rooms", "--min-rooms") else f"{asked}: {source}"
    return [f"every robot to visit at least {least} goal rooms ({source}{lowered})"]


def _robots(report: PlanReport) -> list[str]:
    """One row per robot: on the shared clock, the rooms it reaches, its seconds driving (busy),
    waiting for a partner or held back before its moves (waits), and neither (idle: after its last
    move); in belief space, the distance its belief mean drives, its position std along the
    widest axis (largest along the plan / at its end), its heading std at the end, and the
    collision bound of its riskiest move. Then the plan's collision bound and its conflicts."""
    schedule, dt = report.schedule, report.scenario.models.dt
    served = any(m.service > 0 for m in schedule.moves)  # a service column only for plans with jobs' times
    head = "robot  rooms    busy   waits  " + ("service  " if served else "")
    rows = [head + "idle [s]  travelled  pos. std max / end  heading std  collision bound"]
    for robot in schedule.robots:
        steps = report.trajectories.get(robot, [])
        service = f"{schedule.service(robot):>7.1f}  " if served else ""
        timing = (
            f"{robot:<5}  {len(schedule.timeline(robot)):>5}  {schedule.busy(robot):>6.1f}  "
            f"{schedule.waits(robot):>6.1f}  {service}{schedule.idle(robot):>8.1f}"
        )
        if not steps:
            rows.append(timing)
            continue
        means = np.array([s.mean for s in steps], dtype=float)
        covs = np.array([s.cov for s in steps], dtype=float)
        driving = np.array([a is not None for a in driving_steps(schedule, robot, [s.t for s in steps])])
        legs = np.linalg.norm(np.diff(means[:, :2], axis=0), axis=1)
        travelled = float(np.sum(legs[driving[1:]]))  # standing, the mean only shifts with observations
        pos_std = position_std(covs)  # sqrt(lambda_max) of the (x, y) block: along its widest axis
        heading_std = angle(math.sqrt(max(covs[-1, 2, 2], 0.0)))
        risks = [p for a in report.actions for (r, _, _), p in zip(a.moves, a.risk, strict=False) if r == robot]
        stds = f"{length(float(pos_std.max()))} / {length(float(pos_std[-1]))}"
        riskiest = probability(max(risks)) if risks else "-"  # no move, no bound
        rows.append(f"{timing}  {travelled:>7.1f} m  {stds:>18}  {heading_std:>11}  {riskiest:>15}")
    if served:
        rows += [
            f"(busy: driving, in control steps of {dt:g} s; service: standing at stations for their jobs;",
            " idle: after the last move; busy + waits + service + idle: makespan)",
        ]
    else:
        rows.append(
            f"(busy: driving, in control steps of {dt:g} s; idle: after the last move; busy + waits + idle: makespan)"
        )
    rows.append("(pos. std: along the widest axis of the position covariance, the sqrt of its largest eigenvalue)")
    rows.extend(_risk_lines(report))
    return rows


def _risk_lines(report: PlanReport) -> list[str]:
    """The plan's collision bound against the chance constraint (each robot's riskiest move is in
    the table above), what kept robots apart, and robots still in each other's way."""
    delta = report.scenario.planner.max_risk
    risks = [float(r) for action in report.actions for r in action.risk]
    over = sum(r > delta for r in risks) if delta is not None else 0
    if delta is None:
        within = "no --max-risk"
    elif over:  # a plan taken as it is (--accept-risk)
        within = f"{over} of {len(risks)} moves over max_risk {delta:g}"
    else:
        within = f"every move within max_risk {delta:g}"
    drift = clock_drift(report.scenario)
    late = f" (their clocks drifting up to {drift:g} s per s driven)" if drift > 0 else ""
    bound = f"collision bound: plan {probability(report.risk)} ({within}); robots in each other's way{late}: "
    conflicts = plan_conflicts(report)
    if not conflicts:
        return [bound + "none", *_apart_lines(report)]
    first = conflicts[0]
    if not report.scenario.planner.keep_apart:
        hint = "--keep-apart keeps robots apart"
    else:
        hint = "no wait or detour clears them" if delta is None else "no wait, detour or sidestep clears them"
    return [
        f"{bound}{len(conflicts)}, the first:",
        f" {' and '.join(first.robots)} at {first.t_from:.1f} s"
        + (f" (their clocks {first.window:.1f} s apart)" if first.window > 0 else "")
        + f", {length(first.closest_distance)} apart, {length(first.required_separation)} needed; "
        f"{hint}: docs/planning.md",
        *_apart_lines(report),
    ]


def _apart_lines(report: PlanReport) -> list[str]:
    """What kept the robots apart, and what it cost against the plan as planned (run on the clock)."""
    apart = report.apart
    if apart is None:
        return []
    waits = [f"step {k} +{s:.1f} s" for k, s in apart.waits[:2]]
    if len(apart.waits) > 2:
        waits.append(f"{len(apart.waits) - 2} more")
    done = [_plural(len(apart.waits), "wait") + (f" ({', '.join(waits)})" if waits else "")] if waits else []
    done += [f"a detour: {r} in step {k} (+{m:.1f} m)" for k, r, m in apart.detours[:2]]
    if len(apart.detours) > 2:
        done.append(f"{len(apart.detours) - 2} more detours")
    done += [
        f"a sidestep: {r} {o} -> {via} -> {t}" if t != via else f"a sidestep: {r} {o} -> {via}, out of the way"
        for r, o, via, t in apart.sidesteps[:2]
    ]
    if len(apart.sidesteps) > 2:
        done.append(f"{len(apart.sidesteps) - 2} more sidesteps")
    what = f"kept apart: {apart.conflicts_before} -> {apart.conflicts_left} conflicts by {'; '.join(done)}"
    cost = (
        f"cost {report.resimulated_cost - apart.cost_before:+.3f}, "
        f"makespan {report.schedule.makespan - apart.makespan_before:+.1f} s"
    )
    if len(what) + len(cost) + 2 <= 100:
        return [f"{what}; {cost}"]
    return [f"{what};", f" {cost}"]


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}{'es' if word.endswith('s') else 's'}"


def _times(report: PlanReport) -> list[str]:
    """Seconds per stage as a small table, then the oracle cache. ``total`` is the run's wall-clock
    time but ``load``: the stages before it (``other``: the time in none) add up to it."""
    seconds = report.times.seconds
    cache = report.cache
    stages = [s for s in (*STAGES, OTHER, "total") if s != "load" and s in seconds]
    stages += ["load"] if "load" in seconds else []
    names = [f"({s})" if s == "load" else s for s in stages]
    widths = [max(len(n), 6) for n in names]
    head = "time [s]  " + "  ".join(f"{n:>{w}}" for n, w in zip(names, widths, strict=True))
    row = " " * 10 + "  ".join(f"{seconds[s]:>{w}.2f}" for s, w in zip(stages, widths, strict=True))
    return [head, row, _cache_line(report)] + [f"cache warning: {w}" for w in cache.warnings]


def _cache_line(report: PlanReport) -> str:
    """What the cache gave and what was computed, in one statement: the roadmap, the move costs
    (the whole cost table at once, or one by one: a search with carried beliefs asks for costs the
    table does not hold), the task plan."""
    cache = report.cache
    roadmap = "roadmap from cache" if cache.roadmap_hit else "roadmap grown"
    if report.roadmap.base:  # tmpnav.roadmap.with_starts: a replan's roadmap
        roadmap = "the revised plan's roadmap, the robots' starts added"
    hits, misses = cache.hits, cache.misses
    if not cache.enabled:
        return f"cache: off ({_plural(misses, 'move cost')} computed); {roadmap}"
    costs = f"{hits} from cache, {misses} computed"
    if cache.table_hit:
        more = f", then {hits} more from cache and {misses} computed" if hits + misses else ""
        costs = "cost table from cache" + more
    # tmpnav replan has no --replan: a revision is planned again from another state, or without the cache
    again = "--no-cache plans it again" if report.revision is not None else "--replan runs the planner"
    plan = f"; task plan from cache ({again})" if cache.plan_hit else ""
    where = f" ({cache.directory})" if cache.directory is not None else ""
    return f"cache{where}: {roadmap}; move costs: {costs}{plan}"


def plan_summary(report: PlanReport) -> str:
    """The plan at a glance: header, one line per plan step, totals with the makespan and the
    objective, the robots on the shared clock, their beliefs, time per stage."""
    blocks = [_header(report), _steps(report), _robots(report), _times(report)]
    return "\n\n".join("\n".join(block) for block in blocks)
