"""Each robot's queue of moves, read from a plan's schedule: what ``tmpnav simulate`` executes.

The plan's schedule (:attr:`tmpnav.results.PlanReport.schedule`) lists every robot's moves on
the team's clock; the plan's actions give their roadmap paths. A robot's queue is its moves
in the order it makes them, each with its path, its partner (a paired move), when the plan
starts it (a move is never started earlier: the planner may hold one back to keep clear of
another robot) and when the plan expects the robot at each node of its path.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tmpnav.execution.recovery import Recovery
from tmpnav.execution.rpp import RppFollower
from tmpnav.results import PlanReport, TimedMove
from tmpnav.types import TrajectoryStep

_T_TOL = 1e-6  # s: trajectory times are rounded to 1e-9 s
#: control steps of the planned track searched ahead for the point a driving robot has come to
LOOKAHEAD = 20


@dataclass(frozen=True, eq=False)
class QueuedMove:
    """One move of a robot's queue: its path and when the plan makes it."""

    step: int  # the plan step (0-based) it belongs to
    robot: str
    origin: str  # the room it leaves (or ``<robot>-start``)
    target: str  # the room it goes to
    partner: str | None  # the other robot of a paired move
    nodes: tuple[int, ...]  # roadmap path, the start node first
    points: np.ndarray  # (len(nodes), 2) m: the path's positions
    start: int  # control steps: the planned start on the team's clock (never started earlier)
    steps: int  # control steps: the planned duration
    arrivals: tuple[float | None, ...]  # s: planned arrival at each node after the first (None: not found)
    planned_covs: tuple[np.ndarray | None, ...] = ()  # (2, 2) m²: the planned position covariance there
    #: (T + 1, 2, 2) m²: the planned position covariance at each control step of the move, its start first
    planned_track: np.ndarray | None = None
    #: (T + 1, 2) m: the planned mean position at those steps
    planned_means: np.ndarray | None = None
    #: how the plan drives it (models.controller): "rpp" or "turn-then-drive"
    controller: str = "turn-then-drive"

    def planned_from(self, k: int, xy: np.ndarray) -> int:
        """The step of the planned track a robot at ``xy`` has come to, from step ``k`` on: the
        nearest of the next :data:`LOOKAHEAD` planned steps (the later one at a tie), so that an
        execution that drives slower or faster than planned is compared at the same point of its
        path, not at the same time. The window, not only the next step, carries the match past a
        stretch where the planned mean first moves away from where the robot goes (a turn on the
        spot that swings it back, a path that leaves a room before it heads down the corridor)."""
        means = self.planned_means
        if means is None:
            return k
        ahead = means[k : k + LOOKAHEAD + 1]
        d2 = np.sum((ahead - xy) ** 2, axis=1)
        return k + int(len(d2) - 1 - np.argmin(d2[::-1]))

    def planned_at(self, k: int) -> np.ndarray | None:
        """The plan's position covariance (2, 2) at step k of the move (its last past the end);
        None when the plan has none."""
        track = self.planned_track
        if track is None or not len(track):
            return None
        return track[min(max(k, 0), len(track) - 1)]

    @property
    def waypoints(self) -> list[np.ndarray]:
        """The positions to drive to: the path after its start node."""
        return [np.asarray(p, dtype=float) for p in self.points[1:]]


def queues(report: PlanReport) -> dict[str, tuple[QueuedMove, ...]]:
    """Robot -> its moves in the order it makes them (every robot of the scenario, idle ones too)."""
    dt = report.scenario.models.dt
    out: dict[str, tuple[QueuedMove, ...]] = {}
    for robot in (r.name for r in report.scenario.robots):
        steps = report.trajectories.get(robot, [])
        out[robot] = tuple(_queued(report, m, steps, dt) for m in report.schedule.timeline(robot))
    return out


def _queued(report: PlanReport, move: TimedMove, steps: Sequence[TrajectoryStep], dt: float) -> QueuedMove:
    action = report.actions[move.step]
    robots = [m[0] for m in action.moves]
    if move.robot not in robots:
        raise ValueError(f"the schedule's move of {move.robot} in step {move.step} is not in the plan's step")
    nodes = tuple(int(n) for n in action.paths[robots.index(move.robot)])
    points = np.array([report.roadmap.nodes[n] for n in nodes], dtype=float).reshape(-1, 2)
    controller = action.controllers[robots.index(move.robot)] if action.controllers else "turn-then-drive"
    return _move(move, nodes, points, steps, dt, controller)


def _move(
    move: TimedMove,
    nodes: tuple[int, ...],
    points: np.ndarray,
    steps: Sequence[TrajectoryStep],
    dt: float,
    controller: str = "turn-then-drive",
) -> QueuedMove:
    return QueuedMove(
        controller=controller,
        step=move.step,
        robot=move.robot,
        origin=move.origin,
        target=move.target,
        partner=move.partner,
        nodes=nodes,
        points=points,
        start=round(move.start / dt),
        steps=round((move.end - move.start) / dt),
        arrivals=planned_arrivals(steps, nodes[1:], move.start, move.end),
        planned_covs=tuple(
            None if k is None else np.array(steps[k].cov, dtype=float)[:2, :2]
            for k in _arrival_steps(steps, nodes[1:], move.start, move.end)
        ),
        **_track(steps, move.start, move.end),
    )


def queues_of_document(doc: Mapping[str, Any]) -> dict[str, tuple[QueuedMove, ...]]:
    """:func:`queues` of a plan read from its plan.json (docs/plan-json.md): the schedule's moves,
    the actions' paths and the trajectories are all there, so a plan made elsewhere (by
    ``tmpnav serve``) is executed as one made in this process (tests/execution/test_moves.py
    holds the two together)."""
    dt = float(doc["dt"])
    out: dict[str, tuple[QueuedMove, ...]] = {}
    for robot, part in doc["schedule"]["robots"].items():
        steps = [
            TrajectoryStep(float(s["t"]), tuple(s["mean"]), tuple(tuple(row) for row in s["cov"]), s.get("node"))
            for s in doc["trajectories"].get(robot, [])
        ]
        queue = []
        for m in part["moves"]:
            action = doc["actions"][int(m["step"]) - 1]
            found = [x for x in action["moves"] if x["robot"] == robot]
            if not found:
                raise ValueError(f"the schedule's move of {robot} in step {m['step']} is not in the plan's step")
            timed = TimedMove(
                int(m["step"]) - 1, robot, m["from"], m["to"], m["partner"], float(m["ready"]), float(m["start"]),
                float(m["end"]), float(m.get("service", 0.0)), float(m.get("opens", 0.0)),
            )  # fmt: skip
            nodes = tuple(int(n) for n in found[0]["path_nodes"])
            points = np.array(found[0]["path_points"], dtype=float).reshape(-1, 2)
            queue.append(_move(timed, nodes, points, steps, dt, found[0].get("controller", "turn-then-drive")))
        out[robot] = tuple(queue)
    return out


def _track(steps: Sequence[TrajectoryStep], start: float, end: float) -> dict[str, np.ndarray | None]:
    """The position covariances (T + 1, 2, 2) and means (T + 1, 2) of the trajectory's steps from
    ``start`` to ``end`` (s): QueuedMove.planned_track and planned_means."""
    within = [s for s in steps if start - _T_TOL <= s.t <= end + _T_TOL]
    if not within:
        return {"planned_track": None, "planned_means": None}
    return {
        "planned_track": np.array([np.asarray(s.cov, dtype=float)[:2, :2] for s in within]),
        "planned_means": np.array([s.mean[:2] for s in within], dtype=float),
    }


def planned_arrivals(
    steps: Sequence[TrajectoryStep], nodes: Sequence[int], start: float, end: float
) -> tuple[float | None, ...]:
    """When the plan's trajectory reaches each of ``nodes`` in order between ``start`` and ``end``
    (s); None for a node it does not mark there."""
    return tuple(None if k is None else float(steps[k].t) for k in _arrival_steps(steps, nodes, start, end))


def _arrival_steps(steps: Sequence[TrajectoryStep], nodes: Sequence[int], start: float, end: float) -> list[int | None]:
    """The index in ``steps`` at which the trajectory reaches each of ``nodes`` in order between
    ``start`` and ``end`` (s); None for a node it does not mark there."""
    out: list[int | None] = []
    j = 0
    while j < len(steps) and steps[j].t <= start + _T_TOL:
        j += 1
    for node in nodes:
        k = next((k for k in range(j, len(steps)) if steps[k].t <= end + _T_TOL and steps[k].node == node), None)
        out.append(k)
        if k is not None:
            j = k + 1
    return out


@dataclass
class RobotQueue:
    """Where one robot is in its queue: the move under way, its waypoints left, when it was free."""

    queue: tuple[QueuedMove, ...]
    started: int = 0  # moves started so far
    move: QueuedMove | None = None  # the move under way
    waypoints: list[np.ndarray] = field(default_factory=list)  # of the move under way, not reached yet
    previous: np.ndarray | None = None  # the last waypoint reached
    ready: int = 0  # step at which it ended its latest move, its job's service included
    since: int = 0  # step at which the move under way started
    aligned: bool = False  # it has turned towards its next waypoint (the segment's start is behind it)
    track: int = 0  # the step of the move's planned track it has come to (QueuedMove.planned_from)
    rpp: RppFollower | None = None  # with --follower rpp: nav2's RPP along the move under way
    recovery: Recovery | None = None  # with nav2's recoveries: the move's navigation (tmpnav.execution.recovery)

    @property
    def next(self) -> QueuedMove | None:
        """The next move to start (None when under way or when its queue is done)."""
        if self.move is not None or self.started >= len(self.queue):
            return None
        return self.queue[self.started]
