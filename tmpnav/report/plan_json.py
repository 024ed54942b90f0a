"""plan.json: a task-motion plan as plain JSON data (schema ``tmpnav-plan/1``, see docs/plan-json.md).

The document holds what a reader needs to check or redraw a plan without tmpnav: the plan steps
with their roadmap paths, every robot's re-simulated belief at every control step, and the
counters and timings of the run. Means and covariances keep full float precision (Python's
shortest round-trip repr); only timings are rounded (to microseconds). Non-finite floats become
``null`` so the file is strict JSON.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict

import numpy as np

from tmpnav.report.quality import plan_warnings
from tmpnav.results import JSON, STAGES, CacheUse, PlanReport
from tmpnav.types import PlannedAction, Roadmap, TrajectoryStep
from tmpnav.version import __version__

SCHEMA = "tmpnav-plan/1"
_T_TOL = 1e-6  # s, trajectory times are rounded to 1e-9 s by the re-simulation


def number(value: float | int, digits: int | None = None) -> float | None:
    """A plain Python float (numpy scalars included), optionally rounded; None if not finite."""
    x = float(value)
    if not math.isfinite(x):
        return None
    return round(x, digits) if digits is not None else x


def action_spans(report: PlanReport) -> list[tuple[float, float]] | None:
    """(t_start, t_end) in seconds of every plan step, or None if the trajectories do not fit the paths.

    The re-simulation runs the steps one after the other; a step lasts as long as its slowest
    robot. Each moved robot's trajectory passes through its roadmap path's nodes in order, so
    the step ends when the last of its robots reaches its goal node.
    """
    trajectories: dict[str, list[TrajectoryStep]] = report.trajectories
    cursor = {robot: 0 for robot in trajectories}  # index of the last step consumed per robot
    t0 = min((steps[0].t for steps in trajectories.values() if steps), default=0.0)
    spans: list[tuple[float, float]] = []
    for action in report.actions:
        t_end = t0
        robots = [m[0] for m in action.moves]
        for robot, path in zip(robots, action.paths, strict=True):
            steps = trajectories.get(robot, [])
            i = cursor.get(robot, 0)
            for node in path[1:]:
                i = next((j for j in range(i + 1, len(steps)) if steps[j].node == node), -1)
                if i < 0:
                    return None
            cursor[robot] = i
            if path[1:]:
                t_end = max(t_end, steps[i].t)
        for robot in robots:  # a robot that arrived early waits in place until the step ends
            steps = trajectories[robot]
            while cursor[robot] + 1 < len(steps) and steps[cursor[robot] + 1].t <= t_end + _T_TOL:
                cursor[robot] += 1
        spans.append((t0, t_end))
        t0 = t_end
    return spans


def step_action(t: float, spans: Sequence[tuple[float, float]] | None) -> int | None:
    """The 1-based plan step a trajectory time belongs to: 0 for the initial belief, None if unknown."""
    if spans is None:
        return None
    if not spans or t <= spans[0][0] + _T_TOL:
        return 0
    for k, (start, end) in enumerate(spans, start=1):
        if start + _T_TOL < t <= end + _T_TOL:
            return k
    return None


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
        }
        for (robot, origin, target), goal, pose, path in zip(
            parts, action.goal_nodes, action.goal_poses, action.paths, strict=True
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


def _step(step: TrajectoryStep, spans: Sequence[tuple[float, float]] | None) -> JSON:
    return {
        "t": number(step.t, 9),
        "mean": [number(v) for v in step.mean],
        "cov": [[number(v) for v in row] for row in step.cov],
        "node": None if step.node is None else int(step.node),
        "action": step_action(step.t, spans),
    }


def _goals(report: PlanReport) -> JSON:
    goals = report.scenario.goals
    return {"visit": list(goals.visit), "per_robot": {robot: list(rooms) for robot, rooms in goals.per_robot}}


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


def plan_document(report: PlanReport) -> dict[str, JSON]:
    """The JSON-ready document of a :class:`~tmpnav.results.PlanReport` (schema in docs/plan-json.md)."""
    sc = report.scenario
    spans = action_spans(report)
    timings: dict[str, JSON] = {stage: number(report.times.seconds.get(stage, 0.0), 6) for stage in (*STAGES, "total")}
    timings.update({k: number(v, 6) for k, v in report.times.seconds.items() if k not in timings})
    return {
        "schema": SCHEMA,
        "tmpnav_version": __version__,
        "scenario": {"name": sc.name, "file": str(sc.source), "description": sc.description},
        "encoding": report.encoding,
        "planner": report.planner,
        "status": report.status.value,
        "mutual_observations": bool(sc.models.mutual_observations),
        "observations": sc.models.observations.value,
        "dt": number(sc.models.dt),
        "cost_weights": {"M_u": number(sc.cost.M_u), "M_G": number(sc.cost.M_G), "M_Sigma": number(sc.cost.M_Sigma)},
        "goals": _goals(report),
        "cost": {"planner": number(report.planner_cost), "resimulated": number(report.resimulated_cost)},
        "robots": [{"name": r.name, "radius": number(r.radius), "speed": number(r.speed)} for r in sc.robots],
        "actions": [
            _action(a, report.roadmap, None if spans is None else spans[k]) for k, a in enumerate(report.actions)
        ],
        "trajectories": {robot: [_step(s, spans) for s in steps] for robot, steps in report.trajectories.items()},
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
    }


def _bound(report: PlanReport) -> JSON:
    b = report.task.bound
    if b is None:
        return None
    return {
        "value": number(b.value),
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
