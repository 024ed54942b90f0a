"""plan.json: a task-motion plan as plain JSON data (schema ``tmpnav-plan/2``, see docs/plan-json.md).

The document holds what a reader needs to check or redraw a plan without tmpnav: the plan steps
with their roadmap paths, the schedule (every robot's moves on the team's shared clock), every
robot's re-simulated belief at every control step of that clock, the objective, and the
counters and timings of the run. Means and covariances keep full float precision (Python's
shortest round-trip repr); times on the plan's clock are rounded to 1e-9 s, stage timings to
microseconds. Non-finite floats become
``null`` so the file is strict JSON.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict

import numpy as np

from tmpnav.report.quality import plan_conflicts, plan_warnings
from tmpnav.report.schedule import bound_values, driving_steps, dropped_goals, objective_values, step_windows
from tmpnav.results import JSON, OTHER, STAGES, CacheUse, PlanReport, Schedule, TimedMove
from tmpnav.types import PlannedAction, Roadmap, TrajectoryStep
from tmpnav.version import __version__

SCHEMA = "tmpnav-plan/2"


def number(value: float | int, digits: int | None = None) -> float | None:
    """A plain Python float (numpy scalars included), optionally rounded; None if not finite."""
    x = float(value)
    if not math.isfinite(x):
        return None
    return round(x, digits) if digits is not None else x


def _points(roadmap: Roadmap, nodes: Sequence[int]) -> list[JSON]:
    return [[number(v) for v in roadmap.nodes[int(n)]] for n in nodes]


def _action(action: PlannedAction, roadmap: Roadmap, span: tuple[float, float] | None) -> JSON:
    parts = action.moves
    moves: list[JSON] = [
        {
            "robot": robot,
            "from": origin,
            "to": target,
            "goal_node": int(goal),
            "goal_pose": [number(v) for v in pose],
            "path_nodes": [int(n) for n in path],
            "path_points": _points(roadmap, path),
            "controller": controller,
            "risk": None if risk is None else number(risk, 9),
        }
        for (robot, origin, target), goal, pose, path, risk, controller in zip(
            parts,
            action.goal_nodes,
            action.goal_poses,
            action.paths,
            _risks(action),
            action.controllers or ("turn-then-drive",) * len(parts),
            strict=True,
        )
    ]
    return {
        "index": int(action.index),
        "name": str(action.name),
        "robots": [p[0] for p in parts],
        "from": [p[1] for p in parts],
        "to": [p[2] for p in parts],
        "planner_cost": number(action.planner_cost),
        "resimulated_cost": number(action.resimulated_cost),
        "t_start": None if span is None else number(span[0], 9),
        "t_end": None if span is None else number(span[1], 9),
        "moves": moves,
    }


def _trajectory(report: PlanReport, robot: str, steps: list[TrajectoryStep]) -> list[JSON]:
    """A robot's belief at every control step of the shared clock, each with the plan step it drives in."""
    driving = driving_steps(report.schedule, robot, [s.t for s in steps])
    return [
        {
            "t": number(step.t, 9),
            "mean": [number(v) for v in step.mean],
            "cov": [[number(v) for v in row] for row in step.cov],
            "node": None if step.node is None else int(step.node),
            "action": action,
        }
        for step, action in zip(steps, driving, strict=True)
    ]


def _timed_move(move: TimedMove) -> JSON:
    """One move of a robot's timeline in plan.json's ``schedule`` (``step`` 1-based, as ``actions[].index``)."""
    return {
        "step": move.step + 1,
        "from": move.origin,
        "to": move.target,
        "partner": move.partner,
        "ready": number(move.ready, 9),
        "start": number(move.start, 9),
        "end": number(move.end, 9),
        "wait": number(move.wait, 9),
        "opens": number(move.opens, 9),
        "service": number(move.service, 9),
    }


def schedule_section(schedule: Schedule) -> JSON:
    """plan.json's ``schedule``: the makespan, and per robot its moves on the shared clock with
    the time it drives (``busy``), waits (``waits``: before its moves, for windows to open),
    stands at stations for their jobs (``service``) and none of these (``idle``, after its last
    move): busy + waits + service + idle = makespan."""
    return {
        "makespan": number(schedule.makespan, 9),
        "robots": {
            robot: {
                "rooms": len(schedule.timeline(robot)),
                "busy": number(schedule.busy(robot), 9),
                "idle": number(schedule.idle(robot), 9),
                "waits": number(schedule.waits(robot), 9),
                "service": number(schedule.service(robot), 9),
                "moves": [_timed_move(m) for m in schedule.timeline(robot)],
            }
            for robot in schedule.robots
        },
    }


def _objective(report: PlanReport) -> tuple[JSON, JSON]:
    """plan.json's ``makespan`` and ``objective``: each as the planner saw it and re-simulated."""
    o = objective_values(report)
    makespan: JSON = {
        "planner": None if o.planner_makespan is None else number(o.planner_makespan, 9),
        "resimulated": number(o.makespan, 9),
    }
    objective: JSON = {
        "name": o.name,
        "units": o.units,
        "span_weight": number(o.span_weight),
        "planner": None if o.planner_own is None else number(o.planner_own),
        "resimulated": number(o.own),
    }
    return makespan, objective


def _goals(report: PlanReport) -> JSON:
    goals = report.scenario.goals
    out: dict[str, JSON] = {
        "visit": list(goals.visit),
        "per_robot": {robot: list(rooms) for robot, rooms in goals.per_robot},
    }
    if goals.ends:
        out["ends"] = dict(goals.ends)
    if goals.jobs:
        out["jobs"] = {
            j.room: {
                "service": number(j.service, 9),
                "robots": list(j.robots),
                "pose": None if j.pose is None else [number(v, 9) for v in j.pose],
                "window": None if j.window is None else [number(v, 9) for v in j.window],
                "penalty": None if j.penalty is None else number(j.penalty, 9),
            }
            for j in goals.jobs
        }
    if goals.optional:
        out["dropped"] = list(dropped_goals(report))
    if report.scenario.stations:  # station -> the room or place it stands in
        out["stations"] = {r.name: r.place for r in report.scenario.stations}
    return out


def _roadmap(roadmap: Roadmap) -> JSON:
    return {
        "nodes": roadmap.n_nodes,
        "edges": len(roadmap.edges),
        "fingerprint": roadmap.fingerprint,
        "starts": {robot: int(n) for robot, n in roadmap.starts.items()},
        "pose_instantiations": {
            room: {"nodes": [int(n) for n in ids], "points": _points(roadmap, ids)}
            for room, ids in roadmap.instantiations.items()
        },
    }


def _risks(action: PlannedAction) -> tuple[float | None, ...]:
    return action.risk if action.risk else (None,) * len(action.moves)


def risk_section(report: PlanReport) -> JSON:
    """plan.json's ``risk``: the chance constraint, the plan's collision bound (its moves'
    summed), the largest move's, and each robot's largest position standard deviation."""
    return {
        "max_risk": None if report.scenario.planner.max_risk is None else number(report.scenario.planner.max_risk),
        "plan": number(report.risk, 9),
        "largest_move": number(report.worst_risk, 9),
        "largest_std": {robot: number(s) for robot, s in report.largest_std().items()},
        "conflicts": [
            {
                "robots": list(c.robots),
                "t_from": number(c.t_from, 9),
                "t_to": number(c.t_to, 9),
                "closest_distance": number(c.closest_distance),
                "required_separation": number(c.required_separation),
                "where": [number(v) for v in c.where],
            }
            for c in plan_conflicts(report)
        ],
        "kept_apart": _kept_apart(report),
    }


def _kept_apart(report: PlanReport) -> JSON:
    """The waits, detours and sidesteps that kept the robots apart (null: none)."""
    apart = report.apart
    if apart is None:
        return None
    return {
        "conflicts_before": apart.conflicts_before,
        "conflicts_left": apart.conflicts_left,
        "waits": [{"step": k, "seconds": number(v, 6)} for k, v in apart.waits],
        "sidesteps": [{"robot": r, "origin": o, "siding": via, "target": t} for r, o, via, t in apart.sidesteps],
        "detours": [{"step": k, "robot": r, "longer_m": number(m, 6)} for k, r, m in apart.detours],
        "cost_before": number(apart.cost_before, 9),
        "makespan_before": number(apart.makespan_before, 6),
        "clock_runs": apart.runs,
    }


def plan_document(report: PlanReport) -> dict[str, JSON]:
    """The JSON-ready document of a :class:`~tmpnav.results.PlanReport` (schema in docs/plan-json.md)."""
    sc = report.scenario
    windows = step_windows(report.schedule, len(report.actions))
    makespan, objective = _objective(report)
    seconds = report.times.seconds
    timings: dict[str, JSON] = {stage: number(seconds.get(stage, 0.0), 6) for stage in (*STAGES, OTHER, "total")}
    timings.update({k: number(v, 6) for k, v in report.times.seconds.items() if k not in timings})
    weights = sc.cost
    doc: dict[str, JSON] = {
        "schema": SCHEMA,
        "tmpnav_version": __version__,
        "scenario": {"name": sc.name, "file": str(sc.source), "description": sc.description},
        "encoding": report.encoding,
        "planner": report.planner,
        "status": report.status.value,
        "mutual_observations": bool(sc.models.mutual_observations),
        "observations": sc.models.observations.value,
        "dt": number(sc.models.dt),
        "cost_weights": {
            "M_u": number(weights.M_u),
            "M_G": number(weights.M_G),
            "M_Sigma": number(weights.M_Sigma),
            "M_T": number(weights.M_T),
        },
        "goals": _goals(report),
        "cost": {"planner": number(report.planner_cost), "resimulated": number(report.resimulated_cost)},
        "makespan": makespan,
        "objective": objective,
        "risk": risk_section(report),
        "robots": [{"name": r.name, "radius": number(r.radius), "speed": number(r.speed)} for r in sc.robots],
        "actions": [_action(a, report.roadmap, windows[k]) for k, a in enumerate(report.actions)],
        "schedule": schedule_section(report.schedule),
        "trajectories": {robot: _trajectory(report, robot, steps) for robot, steps in report.trajectories.items()},
        "roadmap": _roadmap(report.roadmap),
        "timings": timings,
        "cache": _cache(report.cache),
        "oracle": {k: _plain(v) for k, v in report.oracle.as_dict().items()},
        "task": {k: _plain(v) for k, v in asdict(report.task.counts).items()},
        "search": _search(report),
        "bound": _bound(report),
        "warnings": [
            {"kind": w.kind, "robot": w.robot, "value": number(w.value), "limit": number(w.limit), "message": w.message}
            for w in plan_warnings(report)
        ],
    }
    if report.revision is not None:
        r = report.revision
        doc["revision"] = {
            "number": r.number,
            "start_time": number(r.start_time, 9),
            "previous": r.previous,
            "done": list(r.done),
            "down": list(r.down),
            "unreachable": [{"room": room, "why": why} for room, why in r.unreachable],
            "held": {robot: {"room": room, "seconds": number(sec, 9)} for robot, room, sec in r.held},
            "rule": r.rule,
            "doors": {door: "open" if is_open else "closed" for door, is_open in r.doors},
        }
    return doc


def _search(report: PlanReport) -> JSON:
    s = report.task.search
    if s is None:
        return None
    return {
        "mode": s.mode,
        "costs": s.costs,
        "stopped": s.stopped,
        "start": s.start,
        "subproblems": s.subproblems,
        "improvements": s.improvements,
        "seconds": number(s.seconds, 6),
        "history": [[number(t, 6), number(c)] for t, c in s.history],
        "work_budget": s.work,
        "capped": list(s.capped),
    }


def _bound(report: PlanReport) -> JSON:
    b = bound_values(report)
    if b is None:
        return None
    return {
        "value": number(b.value),
        "units": b.units,
        "relaxation": b.relaxation,
        "gap": number(b.gap),
        "proved_optimal": b.proved_optimal,
    }


def _cache(cache: CacheUse) -> JSON:
    return {
        "enabled": cache.enabled,
        "directory": None if cache.directory is None else str(cache.directory),
        "hits": cache.hits,
        "misses": cache.misses,
        "roadmap_hit": cache.roadmap_hit,
        "plan_hit": cache.plan_hit,
        "warnings": list(cache.warnings),
    }


def _plain(value: object) -> JSON:
    """Counters as plain JSON scalars (numpy integers and floats included)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        return number(float(value))
    raise TypeError(f"not a counter: {value!r}")


def dumps(document: JSON, width: int = 120) -> str:
    """The document as strict JSON text, indented, with every short array or object on one line.

    Trajectory steps and paths stay one line each, so a plan of a few hundred steps reads
    (and diffs) well; the text parses to exactly ``document``.
    """
    return _format(document, 0, width) + "\n"


def _format(value: JSON, indent: int, width: int) -> str:
    flat = json.dumps(value, allow_nan=False, separators=(", ", ": "), ensure_ascii=False)
    if not isinstance(value, dict | list) or indent + len(flat) <= width or _numeric(value):
        return flat
    pad = " " * (indent + 1)
    if isinstance(value, list):
        items = [pad + _format(v, indent + 1, width) for v in value]
        return "[\n" + ",\n".join(items) + "\n" + " " * indent + "]"
    items = [f"{pad}{json.dumps(k, ensure_ascii=False)}: {_format(v, indent + 1, width)}" for k, v in value.items()]
    return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"


def _numeric(value: JSON) -> bool:
    """An array of numbers or of arrays of numbers (a pose, a covariance): never split across lines."""
    return isinstance(value, list) and all(
        isinstance(v, int | float) or (isinstance(v, list) and all(isinstance(w, int | float) for w in v))
        for v in value
    )


def without_timings(doc: dict[str, JSON]) -> dict[str, JSON]:
    """plan.json without what measures the machine: the stage times, the search's seconds and the
    times of its improvements (their costs kept). Two runs of one scenario and options agree on
    the rest (docs/planning.md)."""
    search = doc["search"]
    assert isinstance(search, dict)
    history = search["history"]
    assert isinstance(history, list)
    costs: list[JSON] = []
    for step in history:
        assert isinstance(step, list)
        costs.append(step[1])
    kept = {k: v for k, v in search.items() if k != "seconds"} | {"history": costs}
    return {k: v for k, v in doc.items() if k != "timings"} | {"search": kept}
