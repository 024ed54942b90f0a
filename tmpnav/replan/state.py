"""Where the team is when it replans: the STATE file of ``tmpnav replan`` (docs/replan.md).

A YAML or JSON mapping::

    time: 95.5                      # s since the plan's start
    robots:
      r1: {pose: [12.0, 3.1, 0.2], covariance: [[...], [...], [...]]}   # or a 6x6 (36) from AMCL
      r2: {status: down}
      r3: {interrupted: true}       # its service under way was cut short: the station is not done
    visited: [L3, L7]               # optional: else what the plan had done by `time`
    doors: {door-B6: closed}
    goals:
      add: [L12, {name: L14, service: 30 s, pose: [4.0, 9.5, 90 deg], window: [300 s, 600 s]}]
      remove: [L4]

This module reads and checks the file's shape and values on their own (numbers, a covariance
that is positive semi-definite, AMCL's 6x6 row-major array reduced to x, y, yaw); what the
names refer to is checked against the scenario and the plan in :mod:`tmpnav.replan.revise`.
Every problem is one line naming the file and the key.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tmpnav.errors import InputError
from tmpnav.types import Job

#: the indices of x, y and yaw in a ROS PoseWithCovariance's 6x6 covariance (x, y, z, roll, pitch, yaw)
AMCL_AXES = (0, 1, 5)
#: how far below 0 an eigenvalue of a covariance may be and still count as semi-definite (rounding)
PSD_TOL = 1e-9


@dataclass(frozen=True)
class RobotState:
    """A robot as the state gives it: its belief's mean and covariance, or down."""

    name: str
    pose: tuple[float, float, float] | None = None  # x, y (m), heading (rad); None: where the plan has it
    covariance: tuple[tuple[float, float, float], ...] | None = None  # 3x3; None: the plan's at `time`
    down: bool = False
    #: its service under way at ``time`` was cut short: no hold, and its station is not done
    interrupted: bool = False


@dataclass(frozen=True)
class TeamState:
    """Where the team is at ``time`` (s since the plan's start) and what changed."""

    source: Path
    time: float
    robots: dict[str, RobotState] = field(default_factory=dict)
    visited: tuple[str, ...] | None = None  # None: what the plan had done by `time`
    doors: dict[str, bool] = field(default_factory=dict)  # door -> open
    add: tuple[str, ...] = ()
    remove: tuple[str, ...] = ()
    #: the jobs of ``goals.add`` entries given with job fields (windows on the first plan's clock)
    jobs: tuple[Job, ...] = ()

    @property
    def down(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.robots.values() if r.down)


def state_document(team: TeamState) -> dict[str, Any]:
    """``team`` as a state file's mapping (the module docstring's format, JSON-ready): what
    ``tmpnav simulate --events --server`` posts to ``tmpnav serve``. Reading it back gives
    ``team`` (its ``source`` aside)."""
    robots: dict[str, Any] = {}
    for name, r in team.robots.items():
        if r.down:
            robots[name] = {"status": "down"}
            continue
        entry: dict[str, Any] = {}
        if r.pose is not None:
            entry["pose"] = [float(v) for v in r.pose]
        if r.covariance is not None:
            entry["covariance"] = [[float(v) for v in row] for row in r.covariance]
        if r.interrupted:
            entry["interrupted"] = True
        robots[name] = entry
    jobs = {j.room: j for j in team.jobs}
    add: list[Any] = [name if name not in jobs else _job_entry(jobs[name]) for name in team.add]
    doc: dict[str, Any] = {"time": float(team.time), "robots": robots}
    if team.visited is not None:
        doc["visited"] = list(team.visited)
    if team.doors:
        doc["doors"] = {name: "open" if is_open else "closed" for name, is_open in team.doors.items()}
    if add or team.remove:
        doc["goals"] = {"add": add, "remove": list(team.remove)}
    return doc


def _job_entry(job: Job) -> dict[str, Any]:
    """A ``goals.add`` entry with the job's fields, in the scenario's units (s, m, rad)."""
    entry: dict[str, Any] = {"name": job.room, "service": job.service}
    if job.robots:
        entry["robots"] = list(job.robots)
    if job.pose is not None:
        entry["pose"] = list(job.pose)
    if job.window is not None:
        entry["window"] = list(job.window)
    if job.penalty is not None:
        entry["penalty"] = job.penalty
    return entry


def read_state(path: Path) -> TeamState:
    """The team's state in ``path`` (YAML or JSON); InputError naming the file and key otherwise."""
    return state_of(path, read_document(path, "state"))


def read_document(path: Path, what: str) -> Any:
    """The data of a YAML or JSON file (JSON by its suffix) that the user gives tmpnav (a ``what``
    file: state, events); InputError, one line naming the file, when it cannot be read or parsed."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise InputError(f"{path}: cannot read the {what} file: {err.strerror or err}") from None
    try:
        return json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError) as err:
        first = str(err).splitlines()[0] if str(err) else type(err).__name__
        raise InputError(f"{path}: not a readable {what} file ({first}); expected YAML or JSON") from None


def state_of(path: Path, data: Any) -> TeamState:
    """The team's state in ``data``, a state file's mapping read already (a service's request body),
    its problems named as in the file ``path``; InputError otherwise."""

    def bad(key: str, what: str) -> InputError:
        return InputError(f"{path}: {key}: {what}")

    if not isinstance(data, dict):
        raise bad("(top level)", "expected a mapping with time, robots, visited, doors, goals")
    unknown = sorted(set(map(str, data)) - {"time", "robots", "visited", "doors", "goals"})
    if unknown:
        raise bad(unknown[0], "unknown key; expected time, robots, visited, doors or goals")
    if "time" not in data:
        raise bad("time", "missing; expected the seconds since the plan's start")
    t = _number(data["time"], lambda what: bad("time", what))
    robots: dict[str, RobotState] = {}
    for name, entry in _mapping(data.get("robots"), lambda what: bad("robots", what)).items():
        robots[str(name)] = _robot(str(name), entry, lambda key, what, n=name: bad(f"robots.{n}{key}", what))
    visited = None
    if data.get("visited") is not None:
        visited = _names(data["visited"], lambda what: bad("visited", what))
    doors: dict[str, bool] = {}
    for name, value in _mapping(data.get("doors"), lambda what: bad("doors", what)).items():
        if value not in ("open", "closed"):
            raise bad(f"doors.{name}", f"{value!r} is not a door state; expected open or closed")
        doors[str(name)] = value == "open"
    goals = _mapping(data.get("goals"), lambda what: bad("goals", what))
    extra = sorted(set(map(str, goals)) - {"add", "remove"})
    if extra:
        raise bad(f"goals.{extra[0]}", "unknown key; expected add or remove")
    add, jobs = _added(goals.get("add") or [], path)
    remove = _names(goals.get("remove") or [], lambda what: bad("goals.remove", what))
    return TeamState(path, t, robots, visited, doors, add, remove, jobs)


def _added(value: Any, path: Path) -> tuple[tuple[str, ...], tuple[Job, ...]]:
    """The rooms of ``goals.add`` and the jobs of its entries given as a scenario's ``goals.jobs``
    entries (name, service, pose, window, robots, penalty), checked as the scenario's are."""
    from tmpnav.scenario.format import JOB
    from tmpnav.scenario.schema import Ctx

    if not isinstance(value, list):
        raise InputError(
            f"{path}: goals.add: {value!r} is not a list; expected room names or jobs ({{name: ROOM, service: ...}})"
        )
    names, jobs = [], []
    for i, entry in enumerate(value):
        where = f"goals.add[{i}]"
        if isinstance(entry, str):
            names.append(entry)
            continue
        if not isinstance(entry, dict):
            raise InputError(
                f"{path}: {where}: {entry!r} is neither a room name nor a job; expected a name or a mapping with name, "
                "service, pose, window, robots, penalty"
            )
        ctx = Ctx()
        job = JOB.check(entry, ctx, where, ("goals", "add", i))
        if ctx.issues:
            issue = ctx.issues[0]
            raise InputError(f"{path}: {issue.path}: {issue.message}")
        names.append(job["name"])
        jobs.append(Job(job["name"], job["service"], tuple(job["robots"]), job["pose"], job["window"], job["penalty"]))
    return tuple(names), tuple(jobs)


def _robot(name: str, entry: Any, bad: Any) -> RobotState:
    if not isinstance(entry, dict):
        raise bad("", "expected a mapping with pose and covariance, or status: down")
    unknown = sorted(set(map(str, entry)) - {"pose", "covariance", "status", "interrupted"})
    if unknown:
        raise bad(f".{unknown[0]}", "unknown key; expected pose, covariance, status or interrupted")
    interrupted = entry.get("interrupted", False)
    if not isinstance(interrupted, bool):
        raise bad(".interrupted", f"{interrupted!r} is not true or false; expected true for a service cut short")
    if "status" in entry:
        if entry["status"] != "down":
            raise bad(".status", f"{entry['status']!r} is not a status; expected down")
        if "pose" in entry or "covariance" in entry or "interrupted" in entry:
            raise bad(".status", "a robot that is down has no pose, covariance or service; expected one or the other")
        return RobotState(name, down=True)
    pose = None
    if "pose" in entry:
        raw = entry["pose"]
        if not isinstance(raw, list) or len(raw) != 3:
            raise bad(".pose", f"{raw!r} is not a pose; expected [x, y, heading] in m, m, rad")
        pose = tuple(_number(v, lambda what: bad(".pose", what)) for v in raw)
    cov = None
    if "covariance" in entry:
        cov = covariance_of(entry["covariance"], lambda what: bad(".covariance", what))
    return RobotState(name, pose, cov, interrupted=interrupted)  # type: ignore[arg-type]


def covariance_of(raw: Any, bad: Any) -> tuple[tuple[float, float, float], ...]:
    """A 3x3 covariance of (x, y, heading) from a 3x3 matrix, or from the 36 numbers (a 6x6
    row-major array, or 6 rows of 6) of a ROS PoseWithCovariance as nav2's AMCL publishes it."""
    try:
        m = np.array(raw, dtype=float)
    except (TypeError, ValueError):
        raise bad("not a matrix of numbers; expected 3x3, or AMCL's 6x6 (36 numbers, row-major)") from None
    if m.shape == (36,):
        m = m.reshape(6, 6)
    if m.shape == (6, 6):
        m = m[np.ix_(AMCL_AXES, AMCL_AXES)]
    if m.shape != (3, 3):
        raise bad(f"a matrix of shape {m.shape}; expected 3x3, or AMCL's 6x6 (36 numbers, row-major)")
    if not np.all(np.isfinite(m)):
        raise bad("holds a number that is not finite")
    if not np.allclose(m, m.T, atol=1e-9, rtol=1e-6):
        raise bad("is not symmetric; expected a covariance")
    if float(np.linalg.eigvalsh((m + m.T) / 2).min()) < -PSD_TOL:
        raise bad("is not positive semi-definite (an eigenvalue below 0); expected a covariance")
    sym = (m + m.T) / 2
    a, b, c = ([float(v) for v in row] for row in sym)
    return ((a[0], a[1], a[2]), (b[0], b[1], b[2]), (c[0], c[1], c[2]))


def _number(value: Any, bad: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise bad(f"{value!r} is not a finite number")
    return float(value)


def _names(value: Any, bad: Any) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise bad(f"{value!r} is not a list of names")
    return tuple(value)


def _mapping(value: Any, bad: Any) -> dict[Any, Any]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise bad(f"{value!r} is not a mapping")
    return value
