"""A plan document's moves and when each is made, on the team's clock: what every nav2 file is
built from.

The input is the plan document (plan.json, docs/plan-json.md; schema ``tmpnav-plan/2``, or
``tmpnav-plan/1`` written before plans were schedules). :func:`read_plan` checks the schema and
turns a document with a missing or mistyped field into one :class:`~tmpnav.errors.InputError`.
The times come from the document's ``schedule`` (``tmpnav-plan/2``); a ``tmpnav-plan/1``
document has none, and they are computed from its actions and trajectories.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from tmpnav.errors import InputError

SCHEMAS = ("tmpnav-plan/1", "tmpnav-plan/2")
FRAME = "map"  # the frame of every pose: the ROS map's (for a polygonal map, the scenario's coordinates)
UNITS = "metres and radians (yaw about +z, 0 along +x), times in seconds"
_T_TOL = 1e-6  # s: trajectory times are rounded to 1e-9 s

T = TypeVar("T")


def read_plan(doc: dict[str, Any], build: Callable[[dict[str, Any]], T]) -> T:
    """``build(doc)`` for a plan document of a known schema; a document of another schema, or one
    that lacks a field ``build`` reads, raises :class:`InputError` with one line."""
    if not isinstance(doc, dict) or doc.get("schema") not in SCHEMAS:
        schema = doc.get("schema") if isinstance(doc, dict) else None
        raise InputError(f"not a tmpnav plan document: schema {schema!r}, expected {' or '.join(map(repr, SCHEMAS))}")
    try:
        return build(doc)
    except (KeyError, IndexError, TypeError, ValueError) as err:
        what = f"no {err.args[0]!r}" if isinstance(err, KeyError) else str(err)
        raise InputError(f"not a complete tmpnav plan document ({doc['schema']}): {what}") from None


@dataclass(frozen=True)
class MoveTimes:
    """When the plan has a robot make one move (s, on the team's clock; None: not known)."""

    ready: float | None  # its previous move ended (0 for its first)
    start: float | None  # the move starts
    end: float | None  # the move ends
    service: float = 0.0  # s the robot then stands at the target for the room's job
    opens: float = 0.0  # s it first waits there for the job's window to open

    @property
    def wait(self) -> float | None:
        """Seconds between ready and start (rounded to 1e-9 s: both are on the clock's steps)."""
        return None if self.start is None or self.ready is None else round(self.start - self.ready, 9)


def robot_moves(doc: dict[str, Any], robot: str) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """(action, move) of each move of ``robot``, in plan order (the order it makes them)."""
    return [(a, m) for a in doc["actions"] for m in a["moves"] if m["robot"] == robot]


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
        try:
            service = _seconds(entry_k.get("service", 0.0)) or 0.0
            opens = _seconds(entry_k.get("opens", 0.0)) or 0.0
        except (TypeError, ValueError):
            raise InputError(f"{where}: move {k + 1} has a service or window time that is not a number") from None
        out.append(MoveTimes(ready, start, end, service, opens))
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


def makespan(doc: dict[str, Any]) -> float | None:
    """When the plan has the last robot done: the schedule's makespan, else the last step's end."""
    schedule = doc.get("schedule")
    if isinstance(schedule, dict) and isinstance(schedule.get("makespan"), int | float):
        return float(schedule["makespan"])
    ends = [a["t_end"] for a in doc["actions"] if isinstance(a.get("t_end"), int | float)]
    return float(max(ends)) if ends else None
