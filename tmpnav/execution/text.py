"""What ``tmpnav simulate`` prints and writes: the summary (terminal and summary.md), errors.csv,
sessions.csv, moves.csv and hits.csv."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tmpnav.execution.consistency import CONSISTENT_BEYOND, CONSISTENT_MEDIAN, Nees, summary_lines
from tmpnav.execution.result import ExecutionResult, Rate
from tmpnav.numbers import length, nees, percent, probability
from tmpnav.types import Roadmap


def error_summary(result: ExecutionResult, sessions: int) -> list[str]:
    """The worst-case position error per robot in both configurations, the makespan executed
    against the planned one, and the robots' waits (what ``tmpnav simulate`` prints). A robot
    without moves has no error to report: it is named as such, not given its start's error."""
    head = f"{sessions} sessions; worst-case position error (largest average error over the path's nodes)"
    moving = [r for r in result.robots if result.planned.timeline(r)]
    idle = [f"{r} no moves" for r in result.robots if r not in moving]
    if result.configs == (1,):  # one localiser per robot (AMCL): no mutual observations to compare
        cells = [f"{robot} {length(result.worst(1, robot))}" for robot in moving] + idle
        return _rest(result, [f"{head}:", "  " + ", ".join(cells)])
    differ = [r for r in moving if length(result.worst(1, r)) != length(result.worst(2, r))]
    if not differ:  # the same figure for every robot: one line, no "0% lower" per robot
        cells = [f"{robot} {length(result.worst(1, robot))}" for robot in moving] + idle
        return _rest(result, [f"{head}, the same with and without mutual observations:", "  " + ", ".join(cells)])
    lines = [f"{head}:"]
    for robot in moving:
        w1, w2 = length(result.worst(1, robot)), length(result.worst(2, robot))
        lines.append(
            f"  {robot}: with mutual observations {w1}, without {w2}, {_lower(result.reduction(robot))}"
            if robot in differ
            else f"  {robot}: {w1} with and without mutual observations"
        )
    lines += [f"  {cell}" for cell in idle]
    starved = max(moving, key=lambda r: result.worst(2, r))
    lines.append(
        f"landmark-starved robot (largest error without mutual observations): {starved}, "
        + (
            f"{_lower(result.reduction(starved))} with mutual observations"
            if starved in differ
            else "the same with them"
        )
    )
    return _rest(result, lines)


def _rest(result: ExecutionResult, lines: list[str]) -> list[str]:
    lines.append(makespan_line(result))
    lines += wait_lines(result)
    lines += consistency_lines(result)
    lines += summary_lines(result.consistency, result.localiser) if result.localiser else []
    lines += collision_lines(result)
    lines += move_lines(result)
    lines += hit_lines(result)
    lines += recovery_lines(result)
    if result.truncated_sessions:
        lines.append(f"note: {result.truncated_sessions} session(s) did not reach every node within the step budget")
    return lines


def recovery_lines(result: ExecutionResult) -> list[str]:
    """nav2's recovery behaviours and the moves given up, when the robots ran any."""
    runs = sum(result.recoveries.values())
    if not runs:
        return []
    sessions = result.given_up.size
    names = ", ".join(f"{name} {count}" for name, count in result.recoveries.items())
    given_up = int(result.given_up.sum())
    line = f"nav2's recovery behaviours: {runs} ({names})"
    if not given_up:
        line += "; no move given up"
    else:
        line += (
            f"; {given_up} move(s) given up after the last retry, in {np.count_nonzero(result.given_up)} "
            f"of {sessions} sessions (the robot stopped short of its room)"
        )
    return [line]


def labels(result: ExecutionResult) -> list[tuple[int, str]]:
    """The configurations run, each with its label: with and without mutual observations (the
    EKF), or one with each robot's AMCL."""
    if result.configs == (1,):
        return [(1, "with AMCL")]
    return [(1, "with mutual observations"), (2, "without")]


def makespan_line(result: ExecutionResult) -> str:
    """Planned makespan, and the executed one's mean and worst over the sessions, per configuration."""
    parts = []
    for config, label in labels(result):
        spans = result.makespans(config)
        worst = int(np.argmax(spans))
        parts.append(f"{label} {spans.mean():.1f} s mean, {spans[worst]:.1f} s worst (session {worst + 1})")
    return f"makespan (until the last robot is done): planned {result.planned.makespan:.1f} s; executed " + "; ".join(
        parts
    )


def wait_lines(result: ExecutionResult) -> list[str]:
    """Each robot's waits before its moves, planned and executed (none when nobody waits)."""
    planned = {r: result.planned.waits(r) for r in result.robots}
    executed = {r: float(result.waits(1, r).mean()) for r in result.robots}
    if not any(planned.values()) and not any(executed.values()):
        return []
    cells = ", ".join(f"{r} {executed[r]:.1f} s (planned {planned[r]:.1f} s)" for r in result.robots)
    return [f"waiting for partners and planned starts, mean per session {labels(result)[0][1]}: {cells}"]


def consistency_lines(result: ExecutionResult) -> list[str]:
    """How well the errors agree with the covariances: the position NEES's median and share
    beyond 3 sigma (:class:`~tmpnav.execution.consistency.Nees`), one line per configuration (one
    for both when they agree), and with a range sensor the share of beams the filters' innovation
    gate rejected."""
    texts = [(label, _nees_text(result, config)) for config, label in labels(result)]
    if len(texts) == 2 and texts[0][1] == texts[1][1]:
        texts = [("with and without mutual observations alike", texts[0][1])]
    lines = [
        f"position NEES {label}, median and share beyond 3 sigma ({nees(CONSISTENT_MEDIAN)} and "
        f"{percent(CONSISTENT_BEYOND)} when the errors agree with the covariance): {text}"
        for label, text in texts
    ]
    used = sum(result.beams[(1, r)][0] for r in result.robots)
    if used and result.configs != (1,):  # AMCL has no innovation gate
        rejected = sum(result.beams[(1, r)][1] for r in result.robots)
        lines.append(
            f"range beams with mutual observations: {used} returned in both the true and the predicted scan, "
            f"{percent(rejected / used)} rejected by the innovation gate"
        )
    return lines


def _nees_text(result: ExecutionResult, config: int) -> str:
    """The NEES of a configuration against the plan's covariance at the path's nodes (per robot:
    a robot without moves, or whose path has no planned covariance, says so) and against the
    filter's own at every step."""

    def figures(n: Nees) -> str:
        return f"{nees(n.median)}, {percent(n.beyond)}"

    cells = []
    for r in result.robots:
        n = result.nees(config, r)
        cells.append(
            f"{r} {nees(n.median)}"
            if n.steps
            else f"{r} none ({'no moves' if not result.planned.timeline(r) else 'no planned covariance'})"
        )
    planned, own = result.nees(config), result.own_nees(config)
    against_plan = (
        f"against the plan's covariance at the path's nodes {figures(planned)} ({', '.join(cells)})"
        if planned.steps
        else "no path node with a planned covariance"
    )
    return f"{against_plan}; against the filter's own at every step {figures(own) if own.steps else 'none'}"


def collision_lines(result: ExecutionResult) -> list[str]:
    """Executions in which a true pose hit a wall, and in which two robots touched, per
    configuration: the rate with its exact 95% interval (Clopper-Pearson), and per robot."""
    lines = []
    for what, rate in (
        (
            "wall hits (executions with a true pose whose cell's clearance is at most the robot's radius)",
            result.wall_rate,
        ),
        ("robot contacts (executions with two true positions closer than their radii added)", result.contact_rate),
    ):
        lines.append(f"{what}:")
        for config, label in labels(result):
            robots = ", ".join(f"{r} {rate(config, r).events}" for r in result.robots)
            lines.append(f"  {label}: {rate_text(rate(config))}; per robot {robots}")
    return lines


def rate_text(rate: Rate) -> str:
    """Executions with an event out of all, as a percentage with its exact 95% interval:
    ``1/200 = 0.5% (95% CI < 0.1% to 2.8%)``."""
    lo, hi = rate.interval
    return f"{rate.events}/{rate.sessions} = {percent(rate.value)} (95% CI {percent(lo)} to {percent(hi)})"


def _lower(reduction: float) -> str:
    """How much lower (%) the worst-case error is with mutual observations, or how much higher."""
    if reduction < 0:
        return f"{percent(-reduction / 100)} higher"
    return f"{percent(reduction / 100)} lower"


#: moves listed by name in the summary (moves.csv has them all)
MOVES_SHOWN = 5


def move_lines(result: ExecutionResult) -> list[str]:
    """The moves against their collision bounds, with mutual observations: the executions with a wall
    hit during each (95% interval), the moves whose interval lies wholly above their bound, and the
    few with the most."""
    moves = [m for m in result.move_rates(1) if m[0] in result.robots]
    if not moves:
        return []
    above = [m for m in moves if m[2].interval[0] > m[4]]
    worst = sorted(moves, key=lambda m: (-m[2].events, -m[4]))[:MOVES_SHOWN]
    shown = "; ".join(
        f"{r} step {k + 1}: {rate_text(hits)}, bound {probability(bound)}" for r, k, hits, _, bound in worst
    )
    return [
        f"moves against their bounds, {labels(result)[0][1]} ({len(moves)} moves; moves.csv has each): "
        f"{len(above)} with a wall-hit rate whose 95% interval lies above the move's bound; most hits: {shown}"
    ]


def moves_csv(result: ExecutionResult) -> str:
    """One row per configuration and move: executions with a wall hit and with a robot contact
    during the move (or while its robot stands after it), with 95% intervals, and its bound."""
    rows = [
        "config,mutual_observations,robot,step,sessions,wall_hit_executions,wall_hit_rate,wall_hit_ci_low,"
        "wall_hit_ci_high,contact_executions,contact_rate,contact_ci_low,contact_ci_high,bound"
    ]
    for config in result.configs:
        for robot, step, hits, touches, bound in result.move_rates(config):
            (hl, hh), (cl, ch) = hits.interval, touches.interval
            rows.append(
                f"{config},{'yes' if config == 1 else 'no'},{robot},{step + 1},{hits.sessions},{hits.events},"
                f"{hits.value:.6g},{hl:.6g},{hh:.6g},{touches.events},{touches.value:.6g},{cl:.6g},{ch:.6g},"
                f"{bound:.6g}"
            )
    return "\n".join(rows) + "\n"


def hits_csv(result: ExecutionResult) -> str:
    """One row per contact: where and when a robot's true pose hit a wall (``wall``) or touched
    another robot's (``robot``), in which session and plan step, the localiser's position error
    and its own std there, and for how many control steps in a row."""
    rows = ["config,mutual_observations,session,robot,step,kind,t_s,x,y,position_error_m,localiser_std_m,steps"]
    for config in result.configs:
        for s, e in result.hit_events.get(config, []):
            rows.append(
                f"{config},{'yes' if config == 1 else 'no'},{s + 1},{e.robot},{e.step + 1},{e.kind},{e.t:.6g},"
                f"{e.x:.4f},{e.y:.4f},{e.error:.4f},{e.own_std:.4f},{e.steps}"
            )
    return "\n".join(rows) + "\n"


#: wall hits placed by name in the summary (hits.csv has them all)
HITS_SHOWN = 4


def hit_lines(result: ExecutionResult) -> list[str]:
    """Where the first configuration's walls were hit: the first few contacts, each with its robot,
    plan step, true position and the localiser's error there."""
    walls = [(s, e) for s, e in result.hit_events.get(result.configs[0], []) if e.kind == "wall"]
    if not walls:
        return []
    shown = "; ".join(
        f"{e.robot} step {e.step + 1} at ({e.x:.1f}, {e.y:.1f}) m, session {s + 1}, {e.steps} control "
        f"{'step' if e.steps == 1 else 'steps'}, localiser {length(e.error)} off"
        for s, e in walls[:HITS_SHOWN]
    )
    more = f" and {len(walls) - HITS_SHOWN} more" if len(walls) > HITS_SHOWN else ""
    return [f"where walls were hit, {labels(result)[0][1]} (hits.csv has each): {shown}{more}"]


def errors_csv(result: ExecutionResult, roadmap: Roadmap) -> str:
    """Average (and spread of) the position error at each node, per robot and configuration,
    with the planned arrival time there and the executed one (mean and latest over the sessions)."""
    rows = [
        "config,mutual_observations,robot,node_index,roadmap_node,x,y,mean_error_m,std_error_m,max_error_m,sessions,"
        "planned_t_s,mean_t_s,max_t_s"
    ]
    for config in result.configs:
        for robot in result.robots:
            errors, times = result.errors[(config, robot)], result.times[(config, robot)]
            for k, node in enumerate(result.nodes[robot]):
                col, t = errors[:, k], times[:, k]
                x, y = roadmap.nodes[node]
                planned = result.planned_times[robot][k]
                rows.append(
                    f"{config},{'yes' if config == 1 else 'no'},{robot},{k},{node},{x:.4f},{y:.4f},"
                    f"{np.nanmean(col):.6f},{np.nanstd(col):.6f},{np.nanmax(col):.6f},{int(np.sum(~np.isnan(col)))},"
                    f"{'' if planned is None else f'{planned:.6g}'},{_seconds(t, np.nanmean)},{_seconds(t, np.nanmax)}"
                )
    return "\n".join(rows) + "\n"


def sessions_csv(result: ExecutionResult) -> str:
    """One row per session, configuration and robot: when the robot was done, how long it
    waited, the session's makespan next to the planned one, and the control steps after which
    the robot's true pose hit a wall (``wall_hits``) or touched another robot (``contacts``)."""
    rows = ["config,mutual_observations,session,robot,done_s,wait_s,makespan_s,planned_makespan_s,wall_hits,contacts"]
    for config in result.configs:
        for s, schedule in enumerate(result.schedules[config]):
            for robot in result.robots:
                done = max((m.done for m in schedule.timeline(robot)), default=0.0)
                rows.append(
                    f"{config},{'yes' if config == 1 else 'no'},{s + 1},{robot},{done:.6g},"
                    f"{schedule.waits(robot):.6g},{schedule.makespan:.6g},{result.planned.makespan:.6g},"
                    f"{result.wall_hits[(config, robot)][s]},{result.contacts[(config, robot)][s]}"
                )
    return "\n".join(rows) + "\n"


def _seconds(times: np.ndarray, statistic: Callable[[np.ndarray], float]) -> str:
    """A statistic of the sessions' times at a node ("" when no session got there)."""
    return "" if np.all(np.isnan(times)) else f"{statistic(times):.6g}"
