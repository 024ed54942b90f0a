"""A plan -> each robot's ordered waypoints with their times, in the files a ROS 2 (nav2) user feeds a robot.

The input is the plan document (plan.json, docs/plan-json.md; schema ``tmpnav-plan/2``, or
``tmpnav-plan/1`` written before plans were schedules), so a plan saved earlier exports the
same as one just made. Each robot's waypoints are its start pose, then for each plan step it
takes part in, the roadmap nodes of its path after the first (``via``) ending at the step's
goal pose in the target room (``goal``). A via waypoint faces the next one (tmpnav's robots
turn on the spot at roadmap nodes); a goal has the planned heading.

Times, on the team's shared clock (seconds from the plan's start): ``t``, when the plan has
the robot at a waypoint; on the waypoint a move leaves from (the start pose, or the goal of
the robot's previous move), ``depart``, the move's planned start (a robot never leaves
earlier: the planner may hold a move back to keep clear of another robot), and ``wait``, how
long the plan has the robot stand there first (for its partner, or held back). They come
from the document's ``schedule`` (``tmpnav-plan/2``); a ``tmpnav-plan/1`` document has none,
and they are computed from its actions and trajectories.

Paired moves: the two robots of a paired step move together and observe each other. The
waypoint each of them leaves from is a synchronisation point, marked ``sync: step-K`` with
the partner's name: there a robot waits for its partner to reach its own ``step-K``
waypoint, then both go on.

Files, per robot (units: metres, radians and seconds, yaw about +z from +x; poses in the
``map`` frame, which for a ROS map is the frame of its map_server map):

- ``<robot>.csv``: ``index,x,y,yaw,frame,step,kind,room,t,sync,partner,depart,wait``;
- ``<robot>.follow_waypoints.yaml``: the goal of nav2's ``FollowWaypoints`` action, a list of
  ``geometry_msgs/PoseStamped`` (``ros2 action send_goal /follow_waypoints
  nav2_msgs/action/FollowWaypoints "$(cat r1.follow_waypoints.yaml)"``), one comment per pose
  with its times;
- ``<robot>.rviz_waypoints.yaml``: the file the Nav2 RViz panel loads ("Load WPs"):
  ``waypoints: {waypoint0: {pose: [x, y, z], orientation: [w, x, y, z]}, ...}``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from tmpnav.atomic import write_files
from tmpnav.errors import InputError

SCHEMAS = ("tmpnav-plan/1", "tmpnav-plan/2")
FRAME = "map"
UNITS = "metres and radians (yaw about +z, 0 along +x), times in seconds"
CSV_COLUMNS = ("index", "x", "y", "yaw", "frame", "step", "kind", "room", "t", "sync", "partner", "depart", "wait")
_T_TOL = 1e-6  # s: trajectory times are rounded to 1e-9 s


@dataclass(frozen=True)
class Waypoint:
    """One pose a robot drives to, in the map frame, with its planned times."""

    index: int  # position in the robot's list, from 0 (the start pose)
    x: float  # m
    y: float  # m
    yaw: float  # rad
    step: int  # the plan step (action index) it belongs to; 0 for the start pose
    kind: str  # start | via | goal
    room: str  # the target room of a goal, the start location of the start pose, else ""
    t: float | None  # s: when the plan has the robot here (None if not found)
    sync: str = ""  # "step-K": wait here for ``partner``, then both go on to step K together
    partner: str = ""
    depart: float | None = None  # s: planned start of the move that leaves from here (never earlier)
    wait: float | None = None  # s: how long the plan has the robot stand here before that move

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """(x, y, z, w) of a rotation by ``yaw`` about +z."""
        return 0.0, 0.0, math.sin(self.yaw / 2.0), math.cos(self.yaw / 2.0)


@dataclass(frozen=True)
class MoveTimes:
    """When the plan has a robot make one move (s, on the team's clock; None: not known)."""

    ready: float | None  # its previous move ended (0 for its first)
    start: float | None  # the move starts
    end: float | None  # the move ends

    @property
    def wait(self) -> float | None:
        """Seconds between ready and start (rounded to 1e-9 s: both are on the clock's steps)."""
        return None if self.start is None or self.ready is None else round(self.start - self.ready, 9)


def robot_moves(doc: dict[str, Any], robot: str) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """(action, move) of each move of ``robot``, in plan order (the order it makes them)."""
    return [(a, m) for a in doc["actions"] for m in a["moves"] if m["robot"] == robot]


def waypoints(doc: dict[str, Any]) -> dict[str, list[Waypoint]]:
    """Each robot's waypoints (robot order of the plan), with their times, from a plan document."""
    if doc.get("schema") not in SCHEMAS:
        raise InputError(
            f"not a tmpnav plan document: schema {doc.get('schema')!r}, expected {' or '.join(map(repr, SCHEMAS))}"
        )
    try:
        return _waypoints(doc)
    except (KeyError, IndexError, TypeError, ValueError) as err:
        what = f"no {err.args[0]!r}" if isinstance(err, KeyError) else str(err)
        raise InputError(f"not a complete tmpnav plan document ({doc['schema']}): {what}") from None


def _waypoints(doc: dict[str, Any]) -> dict[str, list[Waypoint]]:
    times = move_times(doc)
    out: dict[str, list[Waypoint]] = {}
    for robot in (r["name"] for r in doc["robots"]):
        steps = doc["trajectories"].get(robot, [])
        x, y, yaw = steps[0]["mean"] if steps else (math.nan, math.nan, math.nan)
        moves = robot_moves(doc, robot)
        start = moves[0][0]["from"][moves[0][0]["robots"].index(robot)] if moves else ""
        points = [Waypoint(0, x, y, yaw, 0, "start", start, 0.0)]
        cursor = 0  # trajectory step up to which arrivals were matched
        for (action, move), when in zip(moves, times[robot], strict=True):
            points[-1] = _departure(points[-1], action, robot, when)
            new, cursor = _move_waypoints(steps, action["index"], move, len(points), cursor, when)
            points += new
        out[robot] = points
    return out


def _departure(w: Waypoint, action: dict[str, Any], robot: str, when: MoveTimes) -> Waypoint:
    """The waypoint a move leaves from: its planned start and the wait before it, and the sync
    point of a paired move."""
    w = replace(w, depart=when.start, wait=when.wait)
    robots = action["robots"]
    if len(robots) == 2:
        w = replace(w, sync=f"step-{action['index']}", partner=robots[1 - robots.index(robot)])
    return w


def _move_waypoints(
    steps: list[dict[str, Any]], step: int, move: dict[str, Any], first: int, cursor: int, when: MoveTimes
) -> tuple[list[Waypoint], int]:
    """The waypoints of one robot's move (via nodes facing the next, then the goal pose) with
    the times its trajectory reaches them, and the trajectory step matched last."""
    points = move["path_points"]
    times, cursor = arrivals(steps, move["path_nodes"][1:], cursor, when.start, when.end)
    out: list[Waypoint] = []
    for k in range(1, len(points)):
        if k < len(points) - 1:
            (x0, y0), (x1, y1) = points[k], points[k + 1]
            out.append(Waypoint(first + len(out), x0, y0, math.atan2(y1 - y0, x1 - x0), step, "via", "", times[k - 1]))
        else:
            gx, gy, gyaw = move["goal_pose"]
            out.append(Waypoint(first + len(out), gx, gy, gyaw, step, "goal", move["to"], _or(when.end, times[-1])))
    if not out:  # already at the goal node: the goal pose is still the step's end
        gx, gy, gyaw = move["goal_pose"]
        out.append(Waypoint(first, gx, gy, gyaw, step, "goal", move["to"], when.end))
    return out, cursor


def arrivals(
    steps: list[dict[str, Any]], nodes: list[int], cursor: int, start: float | None, end: float | None
) -> tuple[list[float | None], int]:
    """When a robot's trajectory reaches each of ``nodes`` in order, after step ``cursor`` and
    within the move's ``start`` and ``end`` when known (None: not marked there); and the step
    matched last."""
    while start is not None and cursor + 1 < len(steps) and steps[cursor + 1]["t"] <= start + _T_TOL:
        cursor += 1  # the move's nodes are reached after it starts
    out: list[float | None] = []
    for node in nodes:
        t = None
        for j in range(cursor + 1, len(steps)):
            if end is not None and steps[j]["t"] > end + _T_TOL:
                break
            if steps[j]["node"] == node:
                cursor, t = j, float(steps[j]["t"])
                break
        out.append(t)
    return out, cursor


# ---------------------------------------------------------------- when each move is made


def move_times(doc: dict[str, Any]) -> dict[str, list[MoveTimes]]:
    """Robot -> the times of its moves, in the order it makes them: from the document's
    ``schedule`` when it has one, else computed from its actions and trajectories."""
    robots = [r["name"] for r in doc["robots"]]
    if doc.get("schedule") is not None:
        return {r: _scheduled(doc, r) for r in robots}
    return _from_steps(doc, robots)


def _scheduled(doc: dict[str, Any], robot: str) -> list[MoveTimes]:
    """A robot's move times from plan.json's ``schedule`` (``robots``: by name, or a list of
    entries that name their robot), checked against its actions."""
    entries = doc["schedule"].get("robots")
    entry = entries.get(robot) if isinstance(entries, dict) else None
    if isinstance(entries, list):
        entry = next((e for e in entries if robot in (e.get("name"), e.get("robot"))), None)
    moves = robot_moves(doc, robot)
    timed = entry.get("moves", []) if isinstance(entry, dict) else []
    where = f"plan.json's schedule of robot {robot}"
    if len(timed) != len(moves):
        raise InputError(f"{where} has {len(timed)} moves, its actions {len(moves)}: not the same plan")
    out = []
    for k, (entry_k, (_, move)) in enumerate(zip(timed, moves, strict=True)):
        if (entry_k.get("from", move["from"]), entry_k.get("to", move["to"])) != (move["from"], move["to"]):
            raise InputError(
                f"{where}: move {k + 1} goes {entry_k.get('from')} -> {entry_k.get('to')}, "
                f"its action {move['from']} -> {move['to']}"
            )
        try:
            ready, start, end = (_seconds(entry_k.get(key)) for key in ("ready", "start", "end"))
        except (TypeError, ValueError):
            raise InputError(f"{where}: move {k + 1} has times that are not numbers") from None
        out.append(MoveTimes(ready, start, end))
    return out


def _from_steps(doc: dict[str, Any], robots: list[str]) -> dict[str, list[MoveTimes]]:
    """Move times of a document without a schedule (``tmpnav-plan/1``), from its actions and
    trajectories: a move ends when its robot's trajectory reaches the goal node, a robot is
    ready when its previous move ended, and a step starts at its ``t_start`` (its steps ran one
    after the other), or when its robots are ready if it has none or that does not fit the
    trajectories (before its robots are ready, or after they reach their first node)."""
    out: dict[str, list[MoveTimes]] = {r: [] for r in robots}
    cursor, ready = dict.fromkeys(robots, 0), dict.fromkeys(robots, 0.0)
    for action in doc["actions"]:
        matched = {}
        for move in action["moves"]:
            robot = move["robot"]
            steps = doc["trajectories"].get(robot, [])
            matched[robot], cursor[robot] = arrivals(steps, move["path_nodes"][1:], cursor[robot], None, None)
        together = max(ready[r] for r in matched)
        first = min((t[0] for t in matched.values() if t and t[0] is not None), default=None)
        start = _fitting(_seconds(action.get("t_start")), together, first)
        for robot, times in matched.items():
            end = times[-1] if times else start
            out[robot].append(MoveTimes(ready[robot], start, end))
            ready[robot] = ready[robot] if end is None else end
    return out


def _fitting(given: float | None, ready: float, first: float | None) -> float:
    """A step's ``t_start`` if it fits between its robots being ready and their first node, else ``ready``."""
    if given is None or given < ready - _T_TOL or (first is not None and given > first + _T_TOL):
        return ready
    return given


def _seconds(value: Any) -> float | None:
    """A time of the document (a number, or null)."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"{value!r} is not a number")
    return float(value)


def _or(value: float | None, default: float | None) -> float | None:
    return default if value is None else value


def _header(doc: dict[str, Any], robot: str, what: str) -> str:
    sc = doc["scenario"]
    makespan = _makespan(doc)
    return (
        f"# {what} of robot {robot}: tmpnav plan of scenario {sc['name']} ({sc['file']}), {doc['status']}.\n"
        f"# Frame: {FRAME} (of the ROS map; for a polygonal map, the scenario's coordinates). Units: {UNITS}.\n"
        "# Times on the team's clock, seconds from the plan's start: t, when the plan has the robot at the\n"
        "# waypoint; depart, when the move that leaves from it starts (never leave earlier); wait, how long\n"
        "# the plan has the robot stand there before it (for its partner, or held back).\n"
        "# A waypoint marked sync step-K: wait there for the partner to reach its own step-K waypoint,\n"
        "# then both go on together (a paired move: the robots observe each other on the way).\n"
        + ("" if makespan is None else f"# Planned makespan: {makespan:g} s (when the last robot is done).\n")
    )


def _makespan(doc: dict[str, Any]) -> float | None:
    """When the plan has the last robot done: the schedule's makespan, else the last step's end."""
    schedule = doc.get("schedule")
    if isinstance(schedule, dict) and isinstance(schedule.get("makespan"), int | float):
        return float(schedule["makespan"])
    ends = [a["t_end"] for a in doc["actions"] if isinstance(a.get("t_end"), int | float)]
    return float(max(ends)) if ends else None


def csv_text(doc: dict[str, Any], robot: str, points: list[Waypoint]) -> str:
    """The CSV file of one robot (comment lines start with '#')."""
    lines = [_header(doc, robot, "Waypoints").rstrip("\n"), ",".join(CSV_COLUMNS)]
    for w in points:
        t, depart, wait = (_cell(v) for v in (w.t, w.depart, w.wait))
        lines.append(
            f"{w.index},{w.x!r},{w.y!r},{w.yaw!r},{FRAME},{w.step},{w.kind},{w.room},{t},{w.sync},{w.partner},"
            f"{depart},{wait}"
        )
    return "\n".join(lines) + "\n"


def follow_waypoints_yaml(doc: dict[str, Any], robot: str, points: list[Waypoint]) -> str:
    """nav2_msgs/action/FollowWaypoints goal: ``poses``, a list of geometry_msgs/PoseStamped."""
    lines = [_header(doc, robot, "nav2 FollowWaypoints goal").rstrip("\n"), "poses:"]
    for w in points:
        qx, qy, qz, qw = w.quaternion
        lines += [
            f"  # {_describe(w)}",
            f"  - header: {{frame_id: {FRAME}}}",
            "    pose:",
            f"      position: {{x: {w.x!r}, y: {w.y!r}, z: 0.0}}",
            f"      orientation: {{x: {qx!r}, y: {qy!r}, z: {qz!r}, w: {qw!r}}}",
        ]
    return "\n".join(lines) + "\n"


def rviz_waypoints_yaml(doc: dict[str, Any], robot: str, points: list[Waypoint]) -> str:
    """The Nav2 RViz panel's waypoint file: position [x, y, z], orientation [w, x, y, z]."""
    lines = [_header(doc, robot, "Nav2 RViz panel waypoints").rstrip("\n"), "waypoints:"]
    for w in points:
        qx, qy, qz, qw = w.quaternion
        lines += [
            f"  waypoint{w.index}:  # {_describe(w)}",
            f"    pose: [{w.x!r}, {w.y!r}, 0.0]",
            f"    orientation: [{qw!r}, {qx!r}, {qy!r}, {qz!r}]",
        ]
    return "\n".join(lines) + "\n"


def _describe(w: Waypoint) -> str:
    text = f"{w.index}: step {w.step}, {w.kind}" + (f" {w.room}" if w.room else "")
    if w.t is not None:
        text += f", t = {w.t:g} s"
    if w.sync:
        text += f", sync {w.sync} with {w.partner}"
    if w.depart is not None:
        text += f", depart at t = {w.depart:g} s"
    if w.wait:
        text += f" after a wait of {w.wait:g} s"
    return text


def _cell(value: float | None) -> str:
    return "" if value is None else repr(value)


def files(doc: dict[str, Any]) -> dict[str, str]:
    """File name -> text of every file of the export."""
    out = {}
    for robot, points in waypoints(doc).items():
        out[f"{robot}.csv"] = csv_text(doc, robot, points)
        out[f"{robot}.follow_waypoints.yaml"] = follow_waypoints_yaml(doc, robot, points)
        out[f"{robot}.rviz_waypoints.yaml"] = rviz_waypoints_yaml(doc, robot, points)
    return out


def write_nav2(doc: dict[str, Any], directory: Path) -> list[Path]:
    """Write the export into ``directory`` (created if missing), all files or none; returns them."""
    return write_files(directory, files(doc))
