"""A plan -> each robot's ordered waypoints, in the files a ROS 2 (nav2) user feeds a robot.

The input is the plan document (plan.json, schema ``tmpnav-plan/1``, docs/plan-json.md), so a
plan saved earlier exports the same as one just made. Each robot's waypoints are its start
pose, then for each plan step it takes part in, the roadmap nodes of its path after the first
(``via``) ending at the step's goal pose in the target room (``goal``). A via waypoint faces the
next one (tmpnav's robots turn on the spot at roadmap nodes); a goal has the planned heading.

Paired moves: the two robots of a paired step move together and observe each other. The
waypoint each of them reaches just before such a step is a synchronisation point, marked
``sync: step-K`` with the partner's name: there a robot waits for its partner to reach its own
``step-K`` waypoint, then both go on.

Files, per robot (units: metres and radians, yaw about +z from +x; poses in the ``map`` frame,
which for a ROS map is the frame of its map_server map):

- ``<robot>.csv``: ``index,x,y,yaw,frame,step,kind,room,t,sync,partner``, ``t`` the planned
  arrival time (s) in the re-simulated plan;
- ``<robot>.follow_waypoints.yaml``: the goal of nav2's ``FollowWaypoints`` action, a list of
  ``geometry_msgs/PoseStamped`` (``ros2 action send_goal /follow_waypoints
  nav2_msgs/action/FollowWaypoints "$(cat r1.follow_waypoints.yaml)"``), one comment per pose;
- ``<robot>.rviz_waypoints.yaml``: the file the Nav2 RViz panel loads ("Load WPs"):
  ``waypoints: {waypoint0: {pose: [x, y, z], orientation: [w, x, y, z]}, ...}``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from tmpnav.errors import InputError

SCHEMA = "tmpnav-plan/1"
FRAME = "map"
UNITS = "metres and radians (yaw about +z, 0 along +x), times in seconds"
CSV_COLUMNS = ("index", "x", "y", "yaw", "frame", "step", "kind", "room", "t", "sync", "partner")


@dataclass(frozen=True)
class Waypoint:
    """One pose a robot drives to, in the map frame."""

    index: int  # position in the robot's list, from 0 (the start pose)
    x: float  # m
    y: float  # m
    yaw: float  # rad
    step: int  # the plan step (action index) it belongs to; 0 for the start pose
    kind: str  # start | via | goal
    room: str  # the target room of a goal, the start location of the start pose, else ""
    t: float | None  # s: planned arrival in the re-simulated plan (None if not found)
    sync: str = ""  # "step-K": wait here for ``partner``, then both go on to step K together
    partner: str = ""

    @property
    def quaternion(self) -> tuple[float, float, float, float]:
        """(x, y, z, w) of a rotation by ``yaw`` about +z."""
        return 0.0, 0.0, math.sin(self.yaw / 2.0), math.cos(self.yaw / 2.0)


def waypoints(doc: dict[str, Any]) -> dict[str, list[Waypoint]]:
    """Each robot's waypoints (robot order of the plan), from a plan document."""
    if doc.get("schema") != SCHEMA:
        raise InputError(f"not a tmpnav plan document: schema {doc.get('schema')!r}, expected {SCHEMA!r}")
    out: dict[str, list[Waypoint]] = {}
    for robot in (r["name"] for r in doc["robots"]):
        steps = doc["trajectories"].get(robot, [])
        x, y, yaw = steps[0]["mean"] if steps else (math.nan, math.nan, math.nan)
        start = next((a["from"][a["robots"].index(robot)] for a in doc["actions"] if robot in a["robots"]), "")
        out[robot] = [Waypoint(0, x, y, yaw, 0, "start", start, 0.0)]
    clock = {robot: 0 for robot in out}  # trajectory step up to which arrivals were matched
    for action in doc["actions"]:
        robots = action["robots"]
        for move in action["moves"]:
            robot = move["robot"]
            if len(robots) == 2:
                partner = robots[1 - robots.index(robot)]
                out[robot][-1] = replace(out[robot][-1], sync=f"step-{action['index']}", partner=partner)
            out[robot] += _move_waypoints(doc, action["index"], move, len(out[robot]), clock)
    return out


def _move_waypoints(
    doc: dict[str, Any], step: int, move: dict[str, Any], first: int, clock: dict[str, int]
) -> list[Waypoint]:
    """The waypoints of one robot's move: via nodes facing the next, then the goal pose."""
    robot, points, nodes = move["robot"], move["path_points"], move["path_nodes"]
    steps = doc["trajectories"].get(robot, [])
    out: list[Waypoint] = []
    for k in range(1, len(points)):
        t = None
        for j in range(clock[robot] + 1, len(steps)):
            if steps[j]["node"] == nodes[k]:
                clock[robot], t = j, float(steps[j]["t"])
                break
        if k < len(points) - 1:
            (x0, y0), (x1, y1) = points[k], points[k + 1]
            out.append(Waypoint(first + len(out), x0, y0, math.atan2(y1 - y0, x1 - x0), step, "via", "", t))
        else:
            gx, gy, gyaw = move["goal_pose"]
            out.append(Waypoint(first + len(out), gx, gy, gyaw, step, "goal", move["to"], t))
    if not out:  # already at the goal node: the goal pose is still the step's end
        gx, gy, gyaw = move["goal_pose"]
        out.append(Waypoint(first, gx, gy, gyaw, step, "goal", move["to"], None))
    return out


def _header(doc: dict[str, Any], robot: str, what: str) -> str:
    sc = doc["scenario"]
    return (
        f"# {what} of robot {robot}: tmpnav plan of scenario {sc['name']} ({sc['file']}), {doc['status']}.\n"
        f"# Frame: {FRAME} (of the ROS map; for a polygonal map, the scenario's coordinates). Units: {UNITS}.\n"
        "# A waypoint marked sync step-K: wait there for the partner to reach its own step-K waypoint,\n"
        "# then both go on together (a paired move: the robots observe each other on the way).\n"
    )


def csv_text(doc: dict[str, Any], robot: str, points: list[Waypoint]) -> str:
    """The CSV file of one robot (comment lines start with '#')."""
    lines = [_header(doc, robot, "Waypoints").rstrip("\n"), ",".join(CSV_COLUMNS)]
    for w in points:
        t = "" if w.t is None else repr(w.t)
        lines.append(f"{w.index},{w.x!r},{w.y!r},{w.yaw!r},{FRAME},{w.step},{w.kind},{w.room},{t},{w.sync},{w.partner}")
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
    return text


def files(doc: dict[str, Any]) -> dict[str, str]:
    """File name -> text of every file of the export."""
    out = {}
    for robot, points in waypoints(doc).items():
        out[f"{robot}.csv"] = csv_text(doc, robot, points)
        out[f"{robot}.follow_waypoints.yaml"] = follow_waypoints_yaml(doc, robot, points)
        out[f"{robot}.rviz_waypoints.yaml"] = rviz_waypoints_yaml(doc, robot, points)
    return out


def write_nav2(doc: dict[str, Any], directory: Path) -> list[Path]:
    """Write the export into ``directory`` (created if missing), all files or none
    (tmpnav.atomic); returns them."""
    from tmpnav.atomic import write_files

    return write_files(directory, files(doc))
