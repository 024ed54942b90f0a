"""Per robot and per move, the nav2 ``NavigateThroughPoses`` goal that drives it, with the move's
times, wait and sync on the team's clock as data: what a fleet adapter sends, and when.

:func:`team` builds them from a plan document (plan.json, docs/plan-json.md);
:mod:`tmpnav.export.move_files` writes and reads them (``<robot>.moves.yaml``, ``schedule.yaml``)
and :mod:`tmpnav.export.executor` runs them. docs/nav2.md describes them for users.

A goal's poses are the move's via points, each facing the next pose, then its goal pose with
the planned heading. The via points are roadmap nodes of the move's path where it turns
(:func:`turns`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from tmpnav.export.plan_times import FRAME, MoveTimes, makespan, move_times, read_plan, robot_moves

ROUTE_TOLERANCE = 0.5  # m: how far a leg between two poses of a goal may pass from the roadmap path it replaces


@dataclass(frozen=True)
class Pose:
    """A pose in the map frame: x, y (m) and the heading ``yaw`` (rad, about +z from +x)."""

    x: float
    y: float
    yaw: float

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """(x, y, z, w) of a rotation by ``yaw`` about +z: a unit quaternion."""
        return 0.0, 0.0, math.sin(self.yaw / 2.0), math.cos(self.yaw / 2.0)

    def message(self, frame: str) -> dict[str, Any]:
        """This pose as the fields of a ``geometry_msgs/PoseStamped`` (the header's stamp left 0)."""
        qx, qy, qz, qw = self.quaternion
        return {
            "header": {"frame_id": frame},
            "pose": {
                "position": {"x": self.x, "y": self.y, "z": 0.0},
                "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
            },
        }


@dataclass(frozen=True)
class NavigateThroughPoses:
    """The goal of nav2's ``NavigateThroughPoses`` action: drive through ``poses`` in order and
    stop at the last one, the move's goal pose."""

    poses: tuple[Pose, ...]
    frame: str = FRAME
    behavior_tree: str = ""  # empty: the navigator's default tree

    def message(self) -> dict[str, Any]:
        """The goal's fields as ``nav2_msgs/action/NavigateThroughPoses`` has them (ROS 2 Humble to
        Jazzy: ``poses`` a list of ``geometry_msgs/PoseStamped``), the form ``ros2 action
        send_goal`` and ``rosidl_runtime_py.set_message_fields`` read."""
        return {"poses": [p.message(self.frame) for p in self.poses], "behavior_tree": self.behavior_tree}


@dataclass(frozen=True)
class MoveRequest:
    """One robot's move of the plan: the goal that drives it and when the plan makes it.

    Times are seconds on the team's clock (0: the plan's start, one instant for every robot);
    None where the plan document does not say. A paired move (``partner`` set) starts at the
    same time as its partner's move of the same plan ``step``: both robots leave together once
    both have reached the poses they leave from (the sync point ``step-K``)."""

    robot: str
    index: int  # 1-based position among the robot's moves
    step: int  # the plan step (plan.json's actions[].index) the move belongs to
    origin: str  # where the robot leaves from: a room, or <robot>-start
    target: str  # the room it goes to
    partner: str | None
    ready: float | None  # its previous move ends (0 for its first)
    depart: float | None  # the planned start: never earlier
    arrive: float | None  # the planned end: the robot at its goal pose
    goal: NavigateThroughPoses
    roadmap_nodes: int  # nodes of the roadmap path the via points were thinned from (its start included)
    service: float = 0.0  # s the robot stands at the goal after it arrives, for the room's job
    #: s on the team's clock: the job's window opens then, and the robot waits at the goal until it
    #: does before its service (None: no wait planned)
    opens_at: float | None = None

    @property
    def name(self) -> str:
        """``<robot>/<index>``: how the schedule names the move."""
        return f"{self.robot}/{self.index}"

    @property
    def wait(self) -> float | None:
        """How long the plan has the robot stand before the move: ``depart - ready``."""
        return None if self.depart is None or self.ready is None else round(self.depart - self.ready, 9)

    @property
    def sync(self) -> str | None:
        """``step-K`` for a paired move (the sync point the two robots leave together from), else None."""
        return None if self.partner is None else f"step-{self.step}"


@dataclass(frozen=True)
class Team:
    """Every robot's moves, in the order each makes them, and the plan they come from."""

    robots: tuple[str, ...]
    moves: Mapping[str, tuple[MoveRequest, ...]]
    makespan: float | None  # s: when the plan has the last robot done
    scenario: str  # the plan's scenario name

    def all_moves(self) -> Iterator[MoveRequest]:
        """Every move, robot by robot."""
        for robot in self.robots:
            yield from self.moves[robot]

    def partner_move(self, move: MoveRequest) -> MoveRequest | None:
        """The partner's move of the same step of a paired move (None for a move alone)."""
        if move.partner is None:
            return None
        return next((m for m in self.moves.get(move.partner, ()) if m.step == move.step), None)

    def after(self, move: MoveRequest) -> tuple[MoveRequest, ...]:
        """The moves whose arrival ``move`` waits for: its robot's previous move, and for a paired
        move its partner's previous one (the partner reaching the sync point)."""
        out = [self.moves[move.robot][move.index - 2]] if move.index > 1 else []
        other = self.partner_move(move)
        if other is not None and other.index > 1:
            out.append(self.moves[other.robot][other.index - 2])
        return tuple(out)


# ---------------------------------------------------------------- via points


def turns(points: Sequence[tuple[float, float]], tolerance: float = ROUTE_TOLERANCE) -> list[int]:
    """Indices of the nodes of a roadmap path (``points[0]`` where the robot leaves, the last its
    goal) that a goal keeps as via points: the fewest that keep every leg, the straight line from
    one kept node to the next, within ``tolerance`` (m) of the part of the path it replaces.

    The rule: a via point is kept only where it is needed to keep the route on the roadmap's
    path, where the path bends away from a straight line by more than the tolerance: a turn.
    Since no fewer via points keep the route within the tolerance, no turn gets two (found as
    the shortest chain over the path's admissible shortcuts, Imai and Iri's method). The
    roadmap's paths are collision-free and keep the scenario's clearance from the walls where
    they can (``roadmap.clearance``, 0.5 m beyond the robot's radius with a range sensor or a
    risk threshold), so a leg stays in the band the path was planned in; between the poses nav2's
    own planner and costmap keep the robot off the walls.

    A heading tolerance is not used: a roadmap's nodes are random samples, so its paths change
    heading by some degrees at almost every node; a tolerance below that keeps nearly every
    node, and one above it drops every node of a gradual bend, letting the legs cut across it.
    """
    last = len(points) - 1
    if last < 2:
        return []
    came_from = {0: -1}
    frontier = [0]
    while last not in came_from:  # breadth first: each level one more via point
        reached = []
        for i in frontier:
            for j in range(i + 1, last + 1):
                if j not in came_from and _leg_fits(points, i, j, tolerance):
                    came_from[j] = i
                    reached.append(j)
        frontier = sorted(reached)
    chain = []
    node = came_from[last]
    while node > 0:
        chain.append(node)
        node = came_from[node]
    return chain[::-1]


def _leg_fits(points: Sequence[tuple[float, float]], i: int, j: int, tolerance: float) -> bool:
    """Whether every node between ``i`` and ``j`` is within ``tolerance`` of the segment from i to j
    (then the whole path between them is: the band around a segment is convex)."""
    return all(segment_distance(points[k], points[i], points[j]) <= tolerance for k in range(i + 1, j))


def segment_distance(p: Sequence[float], a: Sequence[float], b: Sequence[float]) -> float:
    """Distance (m) from point ``p`` to the segment from ``a`` to ``b``."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0.0 else min(1.0, max(0.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(a[0] + t * dx - p[0], a[1] + t * dy - p[1])


def route_points(move: Mapping[str, Any]) -> list[tuple[float, float]]:
    """The positions a move's path goes through: its roadmap nodes, and the goal pose's position
    after them when it is not the last node's."""
    points = [(float(x), float(y)) for x, y in move["path_points"]]
    gx, gy, _ = (float(v) for v in move["goal_pose"])
    if not points or math.dist(points[-1], (gx, gy)) > 1e-9:
        points.append((gx, gy))
    return points


def goal(move: Mapping[str, Any], tolerance: float = ROUTE_TOLERANCE) -> NavigateThroughPoses:
    """The ``NavigateThroughPoses`` goal of a plan.json move: its via points (:func:`turns`), each
    facing the next pose, then the goal pose with the planned heading."""
    points = route_points(move)
    kept = turns(points, tolerance)
    gx, gy, gyaw = (float(v) for v in move["goal_pose"])
    poses = []
    for k, node in enumerate(kept):
        (x0, y0), (x1, y1) = points[node], points[kept[k + 1]] if k + 1 < len(kept) else (gx, gy)
        poses.append(Pose(x0, y0, math.atan2(y1 - y0, x1 - x0)))
    return NavigateThroughPoses((*poses, Pose(gx, gy, gyaw)))


# ---------------------------------------------------------------- from a plan


def team(doc: dict[str, Any], tolerance: float = ROUTE_TOLERANCE) -> Team:
    """Every robot's move requests from a plan document (robot order of the plan)."""
    return read_plan(doc, lambda d: _team(d, tolerance))


def _team(doc: dict[str, Any], tolerance: float) -> Team:
    times = move_times(doc)
    robots = tuple(r["name"] for r in doc["robots"])
    moves = {}
    for robot in robots:
        pairs = zip(robot_moves(doc, robot), times[robot], strict=True)
        moves[robot] = tuple(_request(robot, k, a, m, when, tolerance) for k, ((a, m), when) in enumerate(pairs, 1))
    return Team(robots, moves, makespan(doc), str(doc["scenario"]["name"]))


def _request(
    robot: str, index: int, action: dict[str, Any], move: dict[str, Any], when: MoveTimes, tolerance: float
) -> MoveRequest:
    robots = action["robots"]
    return MoveRequest(
        robot=robot,
        index=index,
        step=int(action["index"]),
        origin=str(move["from"]),
        target=str(move["to"]),
        partner=robots[1 - robots.index(robot)] if len(robots) == 2 else None,
        ready=when.ready,
        depart=when.start,
        arrive=when.end,
        goal=goal(move, tolerance),
        roadmap_nodes=len(move["path_points"]),
        service=when.service,
        opens_at=round(when.end + when.opens, 9) if when.opens > 0 and when.end is not None else None,
    )
