"""A plan -> the files a ROS 2 (nav2) user feeds a team of robots: each robot's waypoints with their
times (this module) and its moves as ``NavigateThroughPoses`` goals (:mod:`tmpnav.export.moves`).

The input is the plan document (plan.json, docs/plan-json.md; schema ``tmpnav-plan/2``, or the
older ``tmpnav-plan/1``), so a plan saved earlier exports the same as one just made. Each
robot's waypoints are its start pose, then for each plan step it takes part in, the roadmap
nodes of its path after the first (``via``) ending at the step's goal pose in the target room
(``goal``). A via waypoint faces the next one (tmpnav's robots turn on the spot at roadmap
nodes); a goal has the planned heading.

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
  ``waypoints: {waypoint0: {pose: [x, y, z], orientation: [w, x, y, z]}, ...}``;
- ``<robot>.moves.yaml`` and the team's ``schedule.yaml``: see :mod:`tmpnav.export.move_files`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from tmpnav.atomic import write_files
from tmpnav.export import move_files, moves
from tmpnav.export.plan_times import (
    FRAME,
    UNITS,
    MoveTimes,
    arrivals,
    makespan,
    move_times,
    read_plan,
    robot_moves,
)

CSV_COLUMNS = ("index", "x", "y", "yaw", "frame", "step", "kind", "room", "t", "sync", "partner", "depart", "wait")


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


def waypoints(doc: dict[str, Any]) -> dict[str, list[Waypoint]]:
    """Each robot's waypoints (robot order of the plan), with their times, from a plan document."""
    return read_plan(doc, _waypoints)


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


def _or(value: float | None, default: float | None) -> float | None:
    return default if value is None else value


def _header(doc: dict[str, Any], robot: str, what: str) -> str:
    sc = doc["scenario"]
    planned = makespan(doc)
    return (
        f"# {what} of robot {robot}: tmpnav plan of scenario {sc['name']} ({sc['file']}), {doc['status']}.\n"
        f"# Frame: {FRAME} (of the ROS map; for a polygonal map, the scenario's coordinates). Units: {UNITS}.\n"
        "# Times on the team's clock, seconds from the plan's start: t, when the plan has the robot at the\n"
        "# waypoint; depart, when the move that leaves from it starts (never leave earlier); wait, how long\n"
        "# the plan has the robot stand there before it (for its partner, or held back).\n"
        "# A waypoint marked sync step-K: wait there for the partner to reach its own step-K waypoint,\n"
        "# then both go on together (a paired move: the robots observe each other on the way).\n"
        + ("" if planned is None else f"# Planned makespan: {planned:g} s (when the last robot is done).\n")
    )


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


def files(doc: dict[str, Any], tag: str = "") -> dict[str, str]:
    """File name -> text of every file of the export: per robot its waypoint files and its move
    requests (:mod:`tmpnav.export.move_files`), and the team's schedule. A ``tag`` (a revision's
    ``.rev1``) goes before each file's suffix, in the names and in the schedule's references:
    ``r1.rev1.csv``, ``r1.moves.rev1.yaml``, ``schedule.rev1.yaml``."""
    requests = move_files.files(moves.team(doc), tag)
    out = {}
    for robot, points in waypoints(doc).items():
        out[f"{robot}{tag}.csv"] = csv_text(doc, robot, points)
        out[f"{robot}.follow_waypoints{tag}.yaml"] = follow_waypoints_yaml(doc, robot, points)
        out[f"{robot}.rviz_waypoints{tag}.yaml"] = rviz_waypoints_yaml(doc, robot, points)
        name = move_files.robot_file_name(robot, tag)
        out[name] = requests.pop(name)
    return out | requests


def write_nav2(doc: dict[str, Any], directory: Path) -> list[Path]:
    """Write the export into ``directory`` (created if missing), all files or none; returns them."""
    return write_files(directory, files(doc))
