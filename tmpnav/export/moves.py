"""Per robot and per move, the nav2 ``NavigateThroughPoses`` goal that drives it, with the move's
times, wait and sync on the team's clock as data: what a fleet adapter sends, and when.

:func:`team` builds them from a plan document (plan.json, docs/plan-json.md), :func:`files`
renders them (``<robot>.moves.yaml`` per robot and the team's ``schedule.yaml``, written beside
the waypoint files of :mod:`tmpnav.export.nav2`), :func:`read_team` reads them back, and
:mod:`tmpnav.export.executor` runs them. docs/nav2.md describes the files for users.

A goal's poses are the move's via points, each facing the next pose, then its goal pose with
the planned heading. The via points are roadmap nodes of the move's path where it turns
(:func:`turns`).
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from tmpnav.errors import InputError
from tmpnav.export.plan_times import FRAME, UNITS, MoveTimes, makespan, move_times, read_plan, robot_moves

FORMAT = "tmpnav-nav2/1"  # the ``format`` of the files: bump it when a reader of the old one would misread them
ROUTE_TOLERANCE = 0.5  # m: how far a leg between two poses of a goal may pass from the roadmap path it replaces
SCHEDULE_FILE = "schedule.yaml"


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

    @property
    def export_id(self) -> str:
        """A digest of the moves: the files of one export carry the same one."""
        data = [_move_entry(m) for m in self.all_moves()]
        text = json.dumps([self.robots, data, self.makespan], sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()[:16]


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
    )


# ---------------------------------------------------------------- files


def files(plan: Team) -> dict[str, str]:
    """File name -> text: ``<robot>.moves.yaml`` per robot and ``schedule.yaml`` for the team."""
    export = plan.export_id
    out = {f"{robot}.moves.yaml": _robot_file(plan, robot, export) for robot in plan.robots}
    out[SCHEDULE_FILE] = _schedule_file(plan, export)
    return out


_TIMES = (
    "# Times on the team's clock, seconds from the plan's start (one instant for every robot): depart,\n"
    "# the move's planned start (never send it earlier); ready, when the robot's previous move ends; wait,\n"
    "# depart - ready; arrive, the planned end. A paired move (partner, sync step-K) starts when both\n"
    "# robots have reached the poses they leave from, together with the partner's move of the same step.\n"
)


def _robot_file(plan: Team, robot: str, export: str) -> str:
    header = (
        f"# nav2 NavigateThroughPoses goals of robot {robot}, one per move, with their times: tmpnav plan of\n"
        f"# scenario {plan.scenario}. Frame: {FRAME}. Units: {UNITS}.\n"
        + _TIMES
        + "# Send a move's goal: ros2 action send_goal /<robot>/navigate_through_poses\n"
        '#   nav2_msgs/action/NavigateThroughPoses "<its goal>"; tmpnav.export.executor sends them all in time.\n'
    )
    data = {
        "format": FORMAT,
        "export": export,
        "robot": robot,
        "frame": FRAME,
        "moves": [_move_entry(m) for m in plan.moves[robot]],
    }
    return header + _dump(data)


def _schedule_file(plan: Team, export: str) -> str:
    header = (
        f"# The team's moves by planned departure: tmpnav plan of scenario {plan.scenario}. Units: {UNITS}.\n"
        + _TIMES
        + "# after: the moves whose arrival a move waits for (its robot's previous one, its partner's).\n"
        "# The goals are in each robot's <robot>.moves.yaml.\n"
    )
    order = sorted(plan.all_moves(), key=lambda m: (math.inf if m.depart is None else m.depart, m.step, m.robot))
    data = {
        "format": FORMAT,
        "export": export,
        "scenario": plan.scenario,
        "frame": FRAME,
        "makespan": plan.makespan,
        "robots": {r: {"file": f"{r}.moves.yaml", "moves": len(plan.moves[r])} for r in plan.robots},
    }
    rows = (
        {"move": m.name, "robot": m.robot, **_timing(m), "after": [a.name for a in plan.after(m)]} for m in order
    )  # one line per move: the file reads as a table
    lines = "".join(f"- {yaml.safe_dump(row, sort_keys=False, default_flow_style=True, width=1 << 20)}" for row in rows)
    return header + _dump(data) + "moves:\n" + lines


def _timing(m: MoveRequest) -> dict[str, Any]:
    return {
        "index": m.index,
        "step": m.step,
        "from": m.origin,
        "to": m.target,
        "partner": m.partner,
        "sync": m.sync,
        "ready": m.ready,
        "wait": m.wait,
        "depart": m.depart,
        "arrive": m.arrive,
    }


def _move_entry(m: MoveRequest) -> dict[str, Any]:
    return {**_timing(m), "roadmap_nodes": m.roadmap_nodes, "goal": m.goal.message()}


def _dump(data: dict[str, Any]) -> str:
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=120, allow_unicode=True)


# ---------------------------------------------------------------- reading them back


def read_team(folder: str | Path) -> Team:
    """The moves of an export (``schedule.yaml`` and the robot files it names, in ``folder``);
    a file that is missing, malformed or of another export raises :class:`InputError`."""
    folder = Path(folder)
    schedule = _load(folder / SCHEDULE_FILE)
    robots = _get(schedule, "robots", dict, SCHEDULE_FILE)
    moves = {}
    for robot, entry in robots.items():
        name = _get(_expect(entry, dict, SCHEDULE_FILE, f"robots.{robot}"), "file", str, SCHEDULE_FILE)
        doc = _load(folder / name)
        if doc.get("export") != schedule.get("export") or doc.get("robot") != robot:
            raise InputError(f"{folder / name} is not robot {robot}'s file of {SCHEDULE_FILE}'s export: export again")
        frame = _get(doc, "frame", str, name)
        entries = _get(doc, "moves", list, name)
        moves[str(robot)] = tuple(_read_move(str(robot), k, e, frame, name) for k, e in enumerate(entries, 1))
    planned = schedule.get("makespan")
    return Team(
        tuple(map(str, robots)),
        moves,
        None if planned is None else _number(planned, SCHEDULE_FILE, "makespan"),
        str(schedule.get("scenario", "")),
    )


def _load(path: Path) -> dict[str, Any]:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as err:
        raise InputError(f"cannot read {path}: {err.strerror or err}") from None
    except yaml.YAMLError as err:
        raise InputError(f"{path} is not YAML: {str(err).splitlines()[0]}") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        found = data.get("format") if isinstance(data, dict) else None
        raise InputError(f"{path} is not a tmpnav nav2 move file: format {found!r}, expected {FORMAT!r}")
    return data


def _read_move(robot: str, index: int, e: Any, frame: str, name: str) -> MoveRequest:
    where = f"moves[{index - 1}]"
    e = _expect(e, dict, name, where)
    if e.get("index") != index:
        raise InputError(f"{name}: {where}.index is {e.get('index')!r}, expected {index} (the moves in order)")
    message = _expect(e.get("goal"), dict, name, f"{where}.goal")
    listed = _expect(message.get("poses"), list, name, f"{where}.goal.poses")
    poses = tuple(_read_pose(p, frame, name, f"{where}.goal.poses[{i}]") for i, p in enumerate(listed))
    if not poses:
        raise InputError(f"{name}: {where}.goal has no poses")
    partner = e.get("partner")
    return MoveRequest(
        robot=robot,
        index=index,
        step=_expect(e.get("step"), int, name, f"{where}.step"),
        origin=str(e.get("from", "")),
        target=str(e.get("to", "")),
        partner=None if partner is None else str(partner),
        ready=_time(e, "ready", name, where),
        depart=_time(e, "depart", name, where),
        arrive=_time(e, "arrive", name, where),
        goal=NavigateThroughPoses(poses, frame, str(message.get("behavior_tree") or "")),
        roadmap_nodes=_expect(e.get("roadmap_nodes", 0), int, name, f"{where}.roadmap_nodes"),
    )


def _read_pose(p: Any, frame: str, name: str, where: str) -> Pose:
    try:
        if p["header"]["frame_id"] != frame:
            raise InputError(f"{name}: {where} is in frame {p['header']['frame_id']!r}, the file's is {frame!r}")
        pos, q = p["pose"]["position"], p["pose"]["orientation"]
        x, y = _number(pos["x"], name, where), _number(pos["y"], name, where)
        qz, qw = _number(q["z"], name, where), _number(q["w"], name, where)
    except (KeyError, TypeError):
        raise InputError(f"{name}: {where} is not a geometry_msgs/PoseStamped") from None
    return Pose(x, y, 2.0 * math.atan2(qz, qw))


def _time(e: dict[str, Any], key: str, name: str, where: str) -> float | None:
    value = e.get(key)
    return None if value is None else _number(value, name, f"{where}.{key}")


def _number(value: Any, name: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise InputError(f"{name}: {where} is {value!r}, not a finite number")
    return float(value)


def _get(data: dict[str, Any], key: str, kind: type, name: str) -> Any:
    return _expect(data.get(key), kind, name, key)


def _expect(value: Any, kind: type, name: str, where: str) -> Any:
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise InputError(f"{name}: {where} is {value!r}, expected {'a mapping' if kind is dict else kind.__name__}")
    return value
