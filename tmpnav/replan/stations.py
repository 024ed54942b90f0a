"""The robots at their stations when the team replans, and the jobs the state adds
(docs/replan.md): a robot at its station at the state's ``time`` in the plan (waiting for its
job's window, or serving) is held there for the rest of it (``Goals.held``), unless the state
says its service was interrupted; the jobs of ``goals.add`` are checked against the scenario
as its own ``goals.jobs`` are."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from tmpnav.errors import InputError
from tmpnav.replan.state import TeamState
from tmpnav.types import Goals, RobotSpec, Scenario
from tmpnav.world import World

#: seconds by which two times on the plan's clock may differ and still count as one
TIME_TOL = 1e-6


def _serving(
    doc: dict[str, Any],
    robot: str,
    t: float,
    inside: str | None = None,
    place_of: Callable[[str], str] = lambda name: name,
) -> tuple[str, float] | None:
    """Where ``robot`` is at its station at ``t`` in the plan (waiting for the window, then
    serving), and when it is free: (room, free); None when it is not at a station then. A
    robot whose move under way ends in ``inside``, the room it stands in (or a station of that
    place: ``place_of``), is there already: it ends its move, then waits and serves. A
    revision's own hold counts as a service at its start room."""
    entry = doc["schedule"]["robots"].get(robot)
    if entry is None:
        return None
    moves = entry["moves"]
    ended = [m for m in moves if m["end"] <= t + TIME_TOL]
    under_way = [m for m in moves if m["start"] <= t + TIME_TOL < m["end"]]
    if under_way and inside is not None and place_of(under_way[0]["to"]) == inside:
        ended = under_way
    if ended:
        m = ended[-1]
        free = float(m["end"]) + float(m.get("opens") or 0.0) + float(m.get("service") or 0.0)
        return (m["to"], free) if free > t + TIME_TOL else None
    held = ((doc.get("revision") or {}).get("held") or {}).get(robot)
    if held is not None and float(held["seconds"]) > t + TIME_TOL:
        return str(held["room"]), float(held["seconds"])
    return None


def in_service(
    doc: dict[str, Any], t: float, state: TeamState, robots: tuple[RobotSpec, ...], world: World
) -> tuple[tuple[str, str, float], ...]:
    """(robot, room, s) for each robot at its station at ``t`` (or already inside the room its
    move under way ends in) whose service the state does not say was interrupted: it stays
    there the rest of its move, wait and service (``Goals.held``)."""
    out = []
    for spec in robots:
        given = state.robots.get(spec.name)
        if given is not None and given.interrupted:
            continue
        inside = world.room_of([spec.pose.x, spec.pose.y])  # type: ignore[arg-type]
        serving = _serving(doc, spec.name, t, inside, world.place_of)
        if serving is not None:
            out.append((spec.name, serving[0], serving[1] - t))
    return tuple(out)


def standing_service(
    goals: Goals, robots: tuple[RobotSpec, ...], world: World, held: tuple[tuple[str, str, float], ...]
) -> tuple[tuple[str, str, float], ...]:
    """(robot, room, s) for each robot that stands in a goal room left to do whose job asks a
    service it may do (driving through it on the way elsewhere when the team replans), and that
    is not held already: a room where a robot stands is done, so the robot does its job there
    first, waiting for the window to open and then serving (``goals`` on the revision's clock;
    none where the window has closed). Without this the station would count done with its
    service never done."""
    out = []
    busy = {robot for robot, _, _ in held}
    served = {room for _, room, _ in held}
    for spec in robots:
        room = world.room_of([spec.pose.x, spec.pose.y])  # type: ignore[arg-type]
        job = goals.job(room) if room is not None else None
        if room is None or job is None or job.service <= 0 or spec.name in busy or room in served:
            continue
        if room not in goals.all_rooms or not goals.may_visit(spec.name, room):
            continue
        wait = 0.0 if job.window is None else max(0.0, job.window[0])
        if job.window is not None and job.window[1] < -TIME_TOL:
            continue
        out.append((spec.name, room, wait + job.service))
        busy.add(spec.name)
        served.add(room)
    return tuple(out)


def interrupted(doc: dict[str, Any], t: float, state: TeamState, robots: tuple[RobotSpec, ...]) -> set[str]:
    """The stations whose service the state says was cut short at ``t`` (``interrupted: true``):
    they are to be served again, whether the robot has left them or still stands there (then
    :func:`standing_service` has it serve its room's job again from the start, since a room
    where a robot stands counts visited; a station of a place is planned again)."""
    out = set()
    for spec in robots:
        given = state.robots.get(spec.name)
        serving = _serving(doc, spec.name, t) if given is not None and given.interrupted else None
        if serving is not None:
            out.add(serving[0])
    return out


def check_jobs(scenario: Scenario, world: World, state: TeamState) -> None:
    """The jobs of ``goals.add`` name robots of the team and a goal pose inside their room where
    a robot fits; InputError naming the entry otherwise."""
    names = [r.name for r in scenario.robots]
    for i, job in enumerate(state.jobs):
        where = f"{state.source}: goals.add[{state.add.index(job.room) if job.room in state.add else i}]"
        for k, robot in enumerate(job.robots):
            if robot not in names:
                raise InputError(f"{where}.robots[{k}]: {robot!r} is not a robot; expected one of {', '.join(names)}")
        if job.pose is not None:
            x, y, _ = job.pose
            radius = max((r.radius for r in scenario.robots if not job.robots or r.name in job.robots), default=0.0)
            room = world.place_of(job.room)  # a station's pose lies in its place
            if world.room_of([x, y]) != room:  # type: ignore[arg-type]
                raise InputError(
                    f"{where}.pose: [{x:g}, {y:g}] is not inside room {room!r}; expected a goal pose inside the "
                    "job's room (a station's: its place)"
                )
            if not bool(world.is_free(np.array([[x, y]]), radius)[0]):
                raise InputError(
                    f"{where}.pose: a robot of radius {radius:g} m at [{x:g}, {y:g}] touches a wall or an obstacle; "
                    "expected a goal pose with room for the robot"
                )
