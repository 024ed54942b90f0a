"""The move requests of a team as files, and back: ``<robot>.moves.yaml`` per robot (its moves'
``NavigateThroughPoses`` goals with their times) and the team's ``schedule.yaml`` (every move by
planned departure, with the moves it waits for). :func:`files` renders them, written beside the
waypoint files of :mod:`tmpnav.export.nav2`; :func:`read_team` reads them back for the executor.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path
from typing import Any

import yaml

from tmpnav.errors import InputError
from tmpnav.export.moves import MoveRequest, NavigateThroughPoses, Pose, Team
from tmpnav.export.plan_times import FRAME, UNITS

FORMAT = "tmpnav-nav2/1"  # the ``format`` of the files: bump it when a reader of the old one would misread them
SCHEDULE_FILE = "schedule.yaml"  # a first plan's (a revision's: schedule_file_name)


def export_id(plan: Team) -> str:
    """A digest of a team's moves: the files of one export carry the same one."""
    data = [_move_entry(m) for m in plan.all_moves()]
    text = json.dumps([plan.robots, data, plan.makespan], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def files(plan: Team, tag: str = "") -> dict[str, str]:
    """File name -> text: ``<robot>.moves.yaml`` per robot and ``schedule.yaml`` for the team;
    with a ``tag`` (a revision's ``.rev2``) before each suffix, and the schedule naming its
    robots' files so tagged."""
    export = export_id(plan)
    out = {robot_file_name(robot, tag): _robot_file(plan, robot, export) for robot in plan.robots}
    out[schedule_file_name(tag)] = _schedule_file(plan, export, tag)
    return out


def robot_file_name(robot: str, tag: str = "") -> str:
    """``<robot>.moves<tag>.yaml``: a robot's move requests."""
    return f"{robot}.moves{tag}.yaml"


def schedule_file_name(tag: str = "") -> str:
    """``schedule<tag>.yaml``: the team's schedule (``schedule.rev1.yaml`` for revision 1)."""
    return f"schedule{tag}.yaml"


_TIMES = (
    "# Times on the team's clock, seconds from the plan's start (one instant for every robot): depart,\n"
    "# the move's planned start (never send it earlier); ready, when the robot's previous move ends; wait,\n"
    "# depart - ready; arrive, the planned end; opens_at, when the job's window opens (it waits until then);\n"
    "# service, then the time at the station for its job.\n"
    "# A paired move (partner, sync step-K) starts when both\n"
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


def _schedule_file(plan: Team, export: str, tag: str) -> str:
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
        "robots": {r: {"file": robot_file_name(r, tag), "moves": len(plan.moves[r])} for r in plan.robots},
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
        "service": m.service,
        "opens_at": m.opens_at,
    }


def _move_entry(m: MoveRequest) -> dict[str, Any]:
    return {**_timing(m), "roadmap_nodes": m.roadmap_nodes, "goal": m.goal.message()}


def _dump(data: dict[str, Any]) -> str:
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=120, allow_unicode=True)


# ---------------------------------------------------------------- reading them back


def read_team(folder: str | Path, revision: int | None = None) -> Team:
    """The moves of an export in ``folder``: its schedule file and the robot files it names. The
    schedule is ``schedule.rev<revision>.yaml`` (``schedule.yaml`` for revision 0, a first plan);
    with no ``revision``, the newest in the folder (the highest revision's, else
    ``schedule.yaml``). A file that is missing, malformed or of another export raises
    :class:`InputError`."""
    folder = Path(folder)
    schedule_name = schedule_file_name(_tag(revision) if revision is not None else _newest(folder))
    schedule = _load(folder / schedule_name)
    robots = _get(schedule, "robots", dict, schedule_name)
    moves = {}
    for robot, entry in robots.items():
        name = _get(_expect(entry, dict, schedule_name, f"robots.{robot}"), "file", str, schedule_name)
        doc = _load(folder / name)
        if doc.get("export") != schedule.get("export") or doc.get("robot") != robot:
            raise InputError(f"{folder / name} is not robot {robot}'s file of {schedule_name}'s export: export again")
        frame = _get(doc, "frame", str, name)
        entries = _get(doc, "moves", list, name)
        moves[str(robot)] = tuple(_read_move(str(robot), k, e, frame, name) for k, e in enumerate(entries, 1))
    planned = schedule.get("makespan")
    return Team(
        tuple(map(str, robots)),
        moves,
        None if planned is None else _number(planned, schedule_name, "makespan"),
        str(schedule.get("scenario", "")),
    )


def _tag(revision: int) -> str:
    """The tag of a revision's file names: "" for a first plan (0), else ``.rev<revision>``."""
    return f".rev{revision}" if revision else ""


def _newest(folder: Path) -> str:
    """The tag of the newest schedule in ``folder`` ("" when it holds no revision's)."""
    found = (re.fullmatch(r"schedule\.rev(\d+)\.yaml", p.name) for p in folder.glob("schedule.rev*.yaml"))
    numbers = [int(m[1]) for m in found if m is not None]
    return _tag(max(numbers)) if numbers else ""


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
        service=_time(e, "service", name, where) or 0.0,
        opens_at=_time(e, "opens_at", name, where),
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
