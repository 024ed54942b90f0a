"""The names a scenario's sections give each other, checked: goals name rooms, stations and
robots of the scenario; a robot's end, a job and a station (a job with a place) name what they
may. Each problem names its file, key path and line."""

from __future__ import annotations

from typing import Any, Protocol

from tmpnav.errors import Problem
from tmpnav.scenario.schema import MISSING


class Doc(Protocol):
    """A YAML file's data and the line of every key path in it (``load.YamlDoc``)."""

    name: str
    data: Any

    def line(self, raw: tuple[Any, ...]) -> int | None: ...


def cross_references(doc: Doc, data: dict[str, Any]) -> list[Problem]:
    """Names must be unique across rooms, stations and robots (all are PDDL objects); goals
    must name defined rooms, stations and robots."""
    problems = []
    # declared names, including those of items with other problems (reported already):
    # a goal naming a robot whose pose is bad should not also be told the robot does not exist
    rooms = set(_declared(doc, "rooms"))
    robots = list(dict.fromkeys(_declared(doc, "robots")))
    for i, robot in enumerate(doc.data.get("robots") or []):
        name = robot.get("name") if isinstance(robot, dict) else None
        if isinstance(name, str) and name in rooms:  # a list or mapping is unhashable (reported already)
            problems.append(
                Problem(
                    doc.name,
                    f"robots.{name}.name",
                    f"{name!r} is also a room name; expected names unique among rooms and robots",
                    doc.line(("robots", i, "name")),
                )
            )
    for robot in robots:
        if f"{robot}-start" in rooms:
            problems.append(
                Problem(
                    doc.name,
                    "rooms",
                    f"room name '{robot}-start' is reserved for the start location of robot {robot!r}",
                    doc.line(("rooms",)),
                )
            )
    goals = data["goals"]
    if goals is MISSING:
        return problems
    stations, station_problems = _stations(doc, goals, rooms, robots)
    problems += station_problems
    rooms = rooms | set(stations)  # a station is a goal as a room is
    for i, room in enumerate(goals.get("visit") or ()):
        if room not in rooms:
            problems.append(
                Problem(
                    doc.name,
                    f"goals.visit[{i}]",
                    f"{room!r} is not a room{_hint(room, rooms)}; expected {_one_of('room', sorted(rooms))}",
                    doc.line(("goals", "visit", i)),
                )
            )
    for robot, targets in (goals.get("robots") or {}).items():
        if robot not in robots:
            problems.append(
                Problem(
                    doc.name,
                    f"goals.robots.{robot}",
                    f"{robot!r} is not a robot{_hint(robot, robots)}; expected {_one_of('robot', robots)}",
                    doc.line(("goals", "robots", robot)),
                )
            )
        for i, room in enumerate(targets):
            if room not in rooms:
                problems.append(
                    Problem(
                        doc.name,
                        f"goals.robots.{robot}[{i}]",
                        f"{room!r} is not a room{_hint(room, rooms)}; expected {_one_of('room', sorted(rooms))}",
                        doc.line(("goals", "robots", robot, i)),
                    )
                )
    return problems + _end_problems(doc, data, rooms, robots) + _job_problems(doc, goals, robots)


def _end_problems(doc: Doc, data: dict[str, Any], rooms: set[str], robots: list[str]) -> list[Problem]:
    """A robot's end is a room of the map, no goal of another kind, nobody else's end; the
    paper's encoding (both robots move in every action) has no ends."""
    goals = data["goals"]
    problems: list[Problem] = []
    goal_rooms = set(goals.get("visit") or ()).union(*(set(xs) for xs in (goals.get("robots") or {}).values()))
    taken: dict[str, str] = {}
    for robot, room in (goals.get("ends") or {}).items():
        where, path = ("goals", "ends", robot), f"goals.ends.{robot}"
        why = None
        if robot not in robots:
            why = f"{robot!r} is not a robot{_hint(robot, robots)}; expected {_one_of('robot', robots)}"
        elif room not in rooms:
            why = f"{room!r} is not a room{_hint(room, rooms)}; expected {_one_of('room', sorted(rooms))}"
        elif room in goal_rooms:
            why = f"{room!r} is also a goal room (goals.visit or goals.robots); expected a room only {robot} ends in"
        elif room in taken:
            why = f"{taken[room]} ends in {room!r} too; expected one robot per end room"
        elif isinstance(data.get("planner"), dict) and data["planner"].get("encoding") == "paper":
            why = (
                "the paper's encoding moves two robots in every action and has no end; "
                "expected planner.encoding mixed or single"
            )
        if why is not None:
            problems.append(Problem(doc.name, path, why, doc.line(where)))
        taken.setdefault(room, robot)
    return problems


def _job_problems(doc: Doc, goals: dict[str, Any], robots: list[str]) -> list[Problem]:
    """A job names a goal room and robots of the team; a robot that goals.robots sends to a
    room must be one its job allows."""
    problems: list[Problem] = []
    visit = set(goals.get("visit") or ())
    per_robot = {r: set(xs) for r, xs in (goals.get("robots") or {}).items()}
    goal_rooms = visit.union(*per_robot.values()) | set((goals.get("ends") or {}).values())
    for i, job in enumerate(goals.get("jobs") or ()):
        room, allowed = job["name"], list(job["robots"])
        where = ("goals", "jobs", i)
        if job.get("penalty") is not None and room in goal_rooms and room not in visit:
            problems.append(
                Problem(
                    doc.name,
                    f"goals.jobs.{room}.penalty",
                    f"{room!r} is a robot's target or end, which every plan must reach; expected a penalty only for "
                    "a room of goals.visit",
                    doc.line((*where, "penalty")),
                )
            )
        if room not in goal_rooms:
            problems.append(
                Problem(
                    doc.name,
                    f"goals.jobs.{room}",
                    f"{room!r} is no goal room; expected a room named in goals.visit, goals.robots or goals.ends",
                    doc.line(where),
                )
            )
        for k, robot in enumerate(allowed):
            if robot not in robots:
                problems.append(
                    Problem(
                        doc.name,
                        f"goals.jobs.{room}.robots[{k}]",
                        f"{robot!r} is not a robot{_hint(robot, robots)}; expected {_one_of('robot', robots)}",
                        doc.line((*where, "robots", k)),
                    )
                )
        for robot, targets in per_robot.items():
            if allowed and room in targets and robot not in allowed:
                problems.append(
                    Problem(
                        doc.name,
                        f"goals.jobs.{room}.robots",
                        f"goals.robots sends {robot} to {room!r}, which its job allows only to "
                        f"{', '.join(allowed)}; expected {robot} among them, or the room in goals.visit",
                        doc.line((*where, "robots")),
                    )
                )
    return problems


def stations_of(goals: dict[str, Any]) -> dict[str, str]:
    """Station -> its place, for the jobs of ``goals`` (checked data) that name a place."""
    return {j["name"]: j["place"] for j in goals.get("jobs") or () if j.get("place") is not None}


def _stations(
    doc: Doc, goals: dict[str, Any], rooms: set[str], robots: list[str]
) -> tuple[dict[str, str], list[Problem]]:
    """The stations (station -> place) and their problems: a station's name is new (no room,
    robot or other station has it), its place is a room of the map, and it has a pose."""
    problems: list[Problem] = []
    stations = stations_of(goals)
    for i, job in enumerate(goals.get("jobs") or ()):
        name, place = job["name"], job.get("place")
        if place is None:
            continue
        where, path = ("goals", "jobs", i), f"goals.jobs.{name}"
        if name in rooms or name in robots:
            kind = "room" if name in rooms else "robot"
            problems.append(
                Problem(
                    doc.name,
                    f"{path}.name",
                    f"station {name!r} has the name of a {kind}; expected a station name unique among rooms, "
                    "robots and stations",
                    doc.line((*where, "name")),
                )
            )
        if place not in rooms:
            why = "a station" if place in stations else "not a room"
            problems.append(
                Problem(
                    doc.name,
                    f"{path}.place",
                    f"{place!r} is {why}{_hint(place, rooms)}; expected the room or place the station stands in, "
                    f"{_one_of('room', sorted(rooms))}",
                    doc.line((*where, "place")),
                )
            )
        if job.get("pose") is None:
            problems.append(
                Problem(
                    doc.name,
                    f"{path}.pose",
                    f"station {name!r} has no pose; expected pose: [x, y, theta] inside its place {place!r}",
                    doc.line(where),
                )
            )
    return stations, problems


def _declared(doc: Doc, section: str) -> list[str]:
    """The names given to the items of a named list (rooms, robots), valid or not."""
    items = doc.data.get(section)
    if not isinstance(items, list):
        return []
    return [str(x["name"]) for x in items if isinstance(x, dict) and isinstance(x.get("name"), (str, int, float))]


def _one_of(what: str, names: list[str]) -> str:
    return f"one of {', '.join(names)}" if names else f"a {what} defined in {what}s (there is none)"


def _hint(word: str, options: Any) -> str:
    import difflib

    close = difflib.get_close_matches(word, list(options), n=1, cutoff=0.6)
    return f" (did you mean '{close[0]}'?)" if close else ""
