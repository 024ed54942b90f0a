"""What happens to a team while it works: the EVENTS file of ``tmpnav simulate --events``
(docs/replan.md, "Closed loop").

A YAML or JSON mapping::

    late: 15                                   # optional: s a robot may fall behind its plan
    events:
      - {at: 40, robot: r2, stop: 20}          # r2 stands still for 20 s (a person in the way)
      - {at: 60, robot: r1, slow: 0.5, for: 30}  # r1 drives at half speed for 30 s
      - {at: 80, robot: r3, down: true}        # r3 stops for good (battery, fault)
      - {at: 50, close: door-B6}               # a door is closed (``open:`` opens one)
      - {at: 90, add: [L12], remove: [L4]}     # goals arrive or are cancelled

``at`` is seconds on the team's clock since the first plan's start. Each event is one of the
kinds above; this module checks the file's shape and every name against the scenario, one line
naming the file and the key for each problem.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tmpnav.errors import InputError
from tmpnav.replan.state import read_document
from tmpnav.types import Scenario

#: s a robot may fall behind its plan before the team replans, unless the file says otherwise
LATE = 15.0
#: the kinds of event, each with the keys it takes besides ``at``
KINDS = {
    "stop": ("robot", "stop"),
    "slow": ("robot", "slow", "for"),
    "down": ("robot", "down"),
    "close": ("close",),
    "open": ("open",),
    "goals": ("add", "remove"),
}


@dataclass(frozen=True)
class Event:
    """One event: at ``at`` s, ``kind`` happens (see the module docstring)."""

    at: float
    kind: str  # stop, slow, down, close, open, goals
    robot: str | None = None
    seconds: float = 0.0  # how long a stop or a slowdown lasts
    factor: float = 1.0  # a slowdown's share of the robot's speed
    door: str | None = None
    add: tuple[str, ...] = ()
    remove: tuple[str, ...] = ()

    @property
    def replans(self) -> bool:
        """Whether the team replans at once: the problem changed (a robot down, a door, goals). A
        stop or a slowdown shows in the robots' lateness, which makes the team replan when it
        passes the threshold, as a fleet manager watching its robots would."""
        return self.kind in ("down", "close", "open", "goals")

    def text(self) -> str:
        if self.kind == "stop":
            return f"{self.robot} stopped for {self.seconds:g} s"
        if self.kind == "slow":
            return f"{self.robot} at {self.factor:g}x speed for {self.seconds:g} s"
        if self.kind == "down":
            return f"{self.robot} down"
        if self.kind in ("close", "open"):
            return f"{self.door} {'closed' if self.kind == 'close' else 'opened'}"
        parts = [f"+{x}" for x in self.add] + [f"-{x}" for x in self.remove]
        return "goals " + " ".join(parts)


@dataclass(frozen=True)
class Events:
    """The events of a closed-loop simulation, in time order, and its lateness threshold."""

    source: Path
    events: tuple[Event, ...]
    late: float = LATE


def read_events(path: Path, scenario: Scenario) -> Events:
    """The events in ``path`` (YAML or JSON), checked against ``scenario``; InputError naming the
    file and the key otherwise."""
    data = read_document(path, "events")
    if not isinstance(data, dict):
        raise InputError(f"{path}: not an events file; expected a mapping with an 'events' list")
    unknown = sorted(set(data) - {"events", "late"})
    if unknown:
        raise InputError(f"{path}: {unknown[0]}: unknown key; expected events and, optionally, late")
    late = data.get("late", LATE)
    if isinstance(late, bool) or not isinstance(late, int | float) or not math.isfinite(late) or late <= 0:
        raise InputError(f"{path}: late: {late!r} is not a number of seconds above 0")
    raw = data.get("events")
    if not isinstance(raw, list) or not raw:
        raise InputError(f"{path}: events: expected a non-empty list of events")
    events = [_event(path, f"events[{k}]", entry, scenario) for k, entry in enumerate(raw)]
    return Events(path, tuple(sorted(events, key=lambda e: e.at)), float(late))


def _event(path: Path, key: str, entry: Any, scenario: Scenario) -> Event:
    def bad(sub: str, what: str) -> InputError:
        return InputError(f"{path}: {key}{'.' + sub if sub else ''}: {what}")

    if not isinstance(entry, dict):
        raise bad("", f"{entry!r} is not a mapping; expected for example {{at: 40, robot: r2, stop: 20}}")
    if "at" not in entry:
        raise bad("at", "missing; expected the event's time in s since the plan's start")
    at = _seconds(entry["at"], bad, "at", zero=True)
    known = {"at", *(key for keys in KINDS.values() for key in keys), *KINDS}
    unknown = sorted(k for k in entry if k not in known)
    if unknown:
        raise bad(
            str(unknown[0]),
            "not a key of an event; expected at and one of stop, slow (with for), down, close, open, add/remove",
        )
    kinds = [k for k in ("stop", "slow", "down", "close", "open") if k in entry]
    if "add" in entry or "remove" in entry:
        kinds.append("goals")
    if len(kinds) != 1:
        raise bad(
            "",
            ("two kinds of event in one: " + ", ".join(kinds) if kinds else "no kind of event")
            + "; expected one of stop, slow (with for), down, close, open, add/remove",
        )
    kind = kinds[0]
    allowed = {"at", *KINDS[kind]}
    extra = sorted(set(entry) - allowed)
    if extra:
        raise bad(extra[0], f"not a key of a {kind} event; expected {', '.join(sorted(allowed))}")
    robots = [r.name for r in scenario.robots]
    robot = None
    if "robot" in KINDS[kind]:
        robot = entry.get("robot")
        if robot not in robots:
            raise bad(
                "robot", f"{robot!r} is not a robot of scenario {scenario.name!r}; expected one of {', '.join(robots)}"
            )
    if kind == "stop":
        return Event(at, kind, robot, seconds=_seconds(entry["stop"], bad, "stop"))
    if kind == "slow":
        factor = entry["slow"]
        if isinstance(factor, bool) or not isinstance(factor, int | float) or not 0 < factor < 1:
            raise bad("slow", f"{factor!r} is not a share of the speed; expected a number above 0 and below 1")
        if "for" not in entry:
            raise bad("for", "missing; expected how long the slowdown lasts, in s")
        return Event(at, kind, robot, seconds=_seconds(entry["for"], bad, "for"), factor=float(factor))
    if kind == "down":
        if entry["down"] is not True:
            raise bad("down", f"{entry['down']!r}; expected true")
        return Event(at, kind, robot)
    if kind in ("close", "open"):
        doors = [d.name for d in scenario.doors]
        door = entry[kind]
        if door not in doors:
            some = ", ".join(doors[:8]) + (", ..." if len(doors) > 8 else "")
            raise bad(kind, f"{door!r} is not a door of scenario {scenario.name!r}; expected one of {some or 'none'}")
        return Event(at, kind, door=door)
    rooms = {r.name for r in scenario.rooms}
    lists = {}
    for sub in ("add", "remove"):
        value = entry.get(sub, [])
        if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
            raise bad(sub, f"{value!r}; expected a list of room names")
        for room in value:
            if room not in rooms:
                raise bad(sub, f"{room!r} is not a room of scenario {scenario.name!r}")
        lists[sub] = tuple(value)
    return Event(at, kind, add=lists["add"], remove=lists["remove"])


def _seconds(value: Any, bad: Any, key: str, zero: bool = False) -> float:
    ok = not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)
    if not ok or value < 0 or (value == 0 and not zero):
        raise bad(key, f"{value!r} is not a number of seconds {'at least' if zero else 'above'} 0")
    return float(value)
