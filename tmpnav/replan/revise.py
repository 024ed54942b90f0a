"""A plan revised from where the team is: the scenario of the rest of the work.

Given the scenario, the plan being executed (its plan.json) and the team's state
(:mod:`tmpnav.replan.state`), :func:`revise` writes the scenario the next plan solves:

- **the robots** start where the state puts them, with its covariance (a robot the state leaves
  out: its belief in the plan at ``time``, the last control step at or before it; a robot given
  a pose but no covariance: the plan's covariance then). A robot that is down leaves the team;
  its own targets go to the others (``goals.visit``), its end is dropped.
- **the goals** are those not done yet: the rooms visited (the state's ``visited``, or the rooms
  the plan's schedule had robots arrive in by ``time``, and those done before the plan being
  revised, for a revision of a revision) are done, ``goals.remove`` drops rooms,
  ``goals.add`` adds rooms to visit, with their jobs where it gives them. A job's window moves
  with the clock: the revision's clock starts at the plan's ``time`` (plus the plan's own
  start, for a revision of a revision).
- **a robot at its station** stays there for the rest of its service (:mod:`tmpnav.replan.stations`).
- **the doors** the state names are opened or closed.
- a goal **no robot can reach any more** (behind a closed door: free space no longer joins any
  robot allowed there to it; its window closed; the only robots allowed to do it are down) is
  named and left out; the rest is planned (the caller exits with its own code).
- **the incumbent**: the rest of the old plan, each live robot's moves not yet ended in their
  order, without the rooms now done or removed: the search's warm start.

Bad input (an unknown robot, room or door; a pose inside a wall; a time outside the plan; a
covariance that is not positive semi-definite; a plan.json of another scenario) is one line
naming the file and the key (InputError, exit 2).
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from tmpnav.errors import InputError
from tmpnav.replan.state import TeamState
from tmpnav.replan.stations import check_jobs, in_service, interrupted, standing_service
from tmpnav.results import Revision
from tmpnav.roadmap.reach import free_space_joins
from tmpnav.types import Goals, Pose, RobotSpec, Scenario
from tmpnav.world import World

#: a 3x3 covariance of (x, y, heading)
Cov3 = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]

#: seconds by which the state's time may pass the plan's makespan and still count as within it
TIME_TOL = 1e-6


class NothingLeft(InputError):
    """The state leaves no goal to plan (every one done, removed or out of reach)."""

    #: the RFC 9457 problem type of tmpnav serve's answer to such a state (docs/serve.md, "Errors")
    problem_type = "tmpnav:nothing-left"


def revise(
    scenario: Scenario, world_of: Any, plan_path: Path, doc: dict[str, Any], state: TeamState, within: bool = True
) -> tuple[Scenario, World, Revision]:
    """The scenario of the rest of the work, its world (rebuilt by ``world_of`` when doors change)
    and the revision (see the module docstring). ``within=False`` lets the state's time pass the
    plan's makespan (a simulated team running late, tmpnav.replan.loop)."""
    _same_scenario(scenario, plan_path, doc)
    t = state.time
    makespan = float(doc["schedule"]["makespan"]) if within else math.inf
    if not 0.0 <= t <= makespan + TIME_TOL:
        raise InputError(
            f"{state.source}: time: {t:g} s is outside the plan ({plan_path.name}: 0 to {makespan:g} s); expected a "
            "time since the plan's start within its makespan"
        )
    names = [r.name for r in scenario.robots]
    rooms = {r.name for r in scenario.rooms}
    for name in state.robots:
        if name not in names:
            raise InputError(
                f"{state.source}: robots.{name}: not a robot of scenario {scenario.name!r}; "
                f"expected one of {', '.join(names)}"
            )
    for key, listed in (("visited", state.visited or ()), ("goals.add", state.add), ("goals.remove", state.remove)):
        for room in listed:
            if room not in rooms:
                raise InputError(f"{state.source}: {key}: {room!r} is not a room of scenario {scenario.name!r}")
    check_jobs(scenario, world_of(None), state)
    doors = {d.name: d for d in scenario.doors}
    for name in state.doors:
        if name not in doors:
            some = ", ".join(sorted(doors)[:8]) + (", ..." if len(doors) > 8 else "")
            raise InputError(
                f"{state.source}: doors.{name}: not a door of scenario {scenario.name!r}"
                + (f"; expected one of {some}" if doors else "")
            )
    # the doors as the plan being revised had them (a revision's), then as the state changes them
    earlier = (doc.get("revision") or {}).get("doors") or {}
    carried = {str(k): v == "open" for k, v in earlier.items() if str(k) in doors and str(k) not in state.doors}
    if carried:
        state = replace(state, doors={**carried, **state.doors})
    # robots down now, and those down before the plan being revised (not in its team)
    down = tuple(dict.fromkeys((*state.down, *(r for r in names if r not in doc["trajectories"]))))
    if len(down) == len(names):
        raise InputError(f"{state.source}: robots: every robot is down; expected at least one robot to plan for")
    revised = scenario
    if state.doors:
        revised = replace(
            revised, doors=tuple(replace(d, open=state.doors.get(d.name, d.open)) for d in scenario.doors)
        )
    world = world_of(revised) if state.doors else world_of(None)
    # a pose in the map as it is; then none of the doors the state closes closed on a robot
    as_it_is = world_of(None)
    robots = tuple(_robot(spec, doc, state, as_it_is) for spec in scenario.robots if spec.name not in down)
    if state.doors:
        _doors_clear(robots, world, state)
    held = in_service(doc, t, state, robots, as_it_is)
    again = interrupted(doc, t, state, robots)
    now = state.visited if state.visited is not None else _arrived(doc, t, again)
    # a revision of a revision: the goals done before the plan being revised stay done
    before = [str(x) for x in (doc.get("revision") or {}).get("done", ())]
    done = tuple(dict.fromkeys((*before, *now)))
    offset = float((doc.get("revision") or {}).get("start_time", 0.0)) + t
    revised = replace(revised, robots=robots)
    closed_off: tuple[str, ...] = ()
    if state.doors:  # rooms no robot can get into any more leave the world (the roadmap samples every room)
        closed_off = tuple(
            r.name for r in revised.rooms if not any(free_space_joins(revised, world, x.name, r.name) for x in robots)
        )
        if closed_off:
            revised = replace(revised, rooms=tuple(r for r in revised.rooms if r.name not in closed_off))
            world = world_of(revised)
    goals, unreachable = _goals(scenario.goals, set(done), state, down, offset)
    why = "no robot allowed there can reach it (a closed door, or no way through)"
    unreachable += [(x, why) for x in closed_off if x in goals.all_rooms]
    goals = _without(goals, set(closed_off))
    revised = replace(revised, goals=goals)
    goals, cut = _reachable(revised, world)
    unreachable += cut
    if not goals.all_rooms:
        raise NothingLeft(
            f"{state.source}: no goal is left to plan"
            + (f" ({len(unreachable)} no robot can reach any more)" if unreachable else "")
            + "; expected goals not yet done"
        )
    held = (*held, *standing_service(goals, robots, world, held))
    roadmap = replace(revised.roadmap, poses=_poses(goals))
    goals = replace(goals, held=tuple((r, s) for r, _, s in held))
    revised = replace(revised, goals=goals, roadmap=roadmap)
    number = int((doc.get("revision") or {}).get("number", 0)) + 1
    incumbent = _rest(doc, t, set(done) | set(state.remove), set(down), goals)
    changed = tuple((d.name, state.doors[d.name]) for d in scenario.doors if state.doors.get(d.name, d.open) != d.open)
    revision = Revision(
        number, offset, str(plan_path), tuple(done), down, tuple(unreachable), incumbent, held, doors=changed
    )
    return revised, world, revision


def leave_out(
    revised: Scenario, revision: Revision, room: str, why: str, state: TeamState
) -> tuple[Scenario, Revision]:
    """The revised scenario without goal ``room``, and the revision naming it out of reach with
    ``why``; NothingLeft when no goal is left."""
    goals = _without(revised.goals, {room})
    unreachable = (*revision.unreachable, (room, why))
    if not goals.all_rooms:
        raise NothingLeft(
            f"{state.source}: no goal is left to plan ({len(unreachable)} no robot can reach any more); expected goals "
            "not yet done"
        )
    roadmap = replace(revised.roadmap, poses=_poses(goals))
    incumbent = tuple(s for s in (tuple(m for m in step if m[1] != room) for step in revision.incumbent) if s)
    revision = replace(revision, unreachable=unreachable, incumbent=incumbent)
    return replace(revised, goals=goals, roadmap=roadmap), revision


def _same_scenario(scenario: Scenario, plan_path: Path, doc: dict[str, Any]) -> None:
    """A plan.json of this scenario: its name, its robots, its rooms."""
    if not isinstance(doc, dict) or not {"scenario", "actions", "schedule", "trajectories"} <= set(doc):
        raise InputError(f"{plan_path}: not a plan.json of tmpnav plan (no scenario, actions, schedule, trajectories)")
    name = (doc.get("scenario") or {}).get("name")
    robots = sorted(doc["trajectories"])
    rooms = {r.name for r in scenario.rooms} | {f"{r.name}-start" for r in scenario.robots}
    entered = {m[k] for a in doc["actions"] for m in a["moves"] for k in ("from", "to")}
    # a revision's team: the scenario's robots but those down before it
    team = sorted(set(r.name for r in scenario.robots) - set((doc.get("revision") or {}).get("down", [])))
    if name != scenario.name or robots != team or not entered <= rooms:
        raise InputError(
            f"{plan_path}: a plan of scenario {name!r} with robots {', '.join(robots)}, not of {scenario.name!r}; "
            "expected the plan.json that tmpnav plan wrote for this scenario"
        )


def _belief_at(doc: dict[str, Any], robot: str, t: float) -> tuple[tuple[float, ...], Cov3]:
    """The robot's belief in the plan at ``t``: the last control step at or before it."""
    steps = doc["trajectories"][robot]
    step = steps[0]
    for s in steps:
        if s["t"] > t + TIME_TOL:
            break
        step = s
    a, b, c = (tuple(float(v) for v in row) for row in step["cov"])
    return tuple(step["mean"]), ((a[0], a[1], a[2]), (b[0], b[1], b[2]), (c[0], c[1], c[2]))


def _robot(spec: RobotSpec, doc: dict[str, Any], state: TeamState, world: World) -> RobotSpec:
    """The robot's spec with its start where the state (or the plan at ``time``) has it."""
    given = state.robots.get(spec.name)
    mean, cov = _belief_at(doc, spec.name, state.time)
    pose = given.pose if given is not None and given.pose is not None else mean
    covariance = given.covariance if given is not None and given.covariance is not None else cov
    x, y, theta = (float(v) for v in pose)
    if given is not None and given.pose is not None and not bool(world.is_free(np.array([[x, y]]), spec.radius)[0]):
        raise InputError(
            f"{state.source}: robots.{spec.name}.pose: a robot of radius {spec.radius:g} m at [{x:g}, {y:g}] is inside "
            "a wall or an obstacle, or off the map; expected a pose in free space"
        )
    return replace(spec, pose=Pose(x, y, math.remainder(theta, 2 * math.pi)), covariance=covariance)


def _doors_clear(robots: tuple[RobotSpec, ...], world: World, state: TeamState) -> None:
    """No door the state closes is closed on a robot: each robot fits where it stands in the
    map with those doors closed."""
    for spec in robots:
        x, y = spec.pose.x, spec.pose.y
        if not bool(world.is_free(np.array([[x, y]]), spec.radius)[0]):
            shut = ", ".join(d for d, is_open in state.doors.items() if not is_open) or "none"
            raise InputError(
                f"{state.source}: doors: a door closed on {spec.name}, which stands at [{x:.2f}, {y:.2f}] in the "
                f"way of the doors closed ({shut}); expected doors closed where no robot stands"
            )


def _arrived(doc: dict[str, Any], t: float, interrupted: Collection[str] = ()) -> tuple[str, ...]:
    """The rooms the plan's schedule has robots arrive in by ``t``, but ``interrupted`` (services
    cut short: their stations are to be served again)."""
    out = []
    for entry in doc["schedule"]["robots"].values():
        out += [m["to"] for m in entry["moves"] if m["end"] <= t + TIME_TOL and m["to"] not in interrupted]
    return tuple(dict.fromkeys(out))


def _goals(
    goals: Goals, done: set[str], state: TeamState, down: tuple[str, ...], offset: float
) -> tuple[Goals, list[tuple[str, str]]]:
    """The goals not done yet (module docstring); the goals left out, with why."""
    removed = set(state.remove)
    unreachable: list[tuple[str, str]] = []
    per_robot: list[tuple[str, tuple[str, ...]]] = []
    orphaned: list[str] = []
    for robot, targets in goals.per_robot:
        left = [x for x in targets if x not in done and x not in removed]
        if robot in down:
            orphaned += left  # a down robot's own targets: the others do them
        elif left:
            per_robot.append((robot, tuple(left)))
    visit = [x for x in (*goals.visit, *orphaned, *state.add) if x not in done and x not in removed]
    ends = tuple((r, x) for r, x in goals.ends if r not in down)
    jobs = []
    added = {j.room for j in state.jobs}  # an added job replaces the room's job in the scenario
    for job in (*(j for j in goals.jobs if j.room not in added), *state.jobs):
        allowed = tuple(r for r in job.robots if r not in down)
        if job.robots and not allowed:
            unreachable.append((job.room, f"only {', '.join(job.robots)} may do its job, and they are down"))
            continue
        window = job.window
        if window is not None:
            if window[1] < offset:
                if job.room in visit or any(job.room in xs for _, xs in per_robot):
                    unreachable.append((job.room, f"its window closed at {window[1]:g} s"))
                continue
            window = (max(0.0, window[0] - offset), window[1] - offset)
        jobs.append(replace(job, robots=allowed, window=window))
    gone = {room for room, _ in unreachable}
    visit = [x for x in dict.fromkeys(visit) if x not in gone]
    per_robot = [(r, tuple(x for x in xs if x not in gone)) for r, xs in per_robot]
    kept = set(visit) | {x for _, xs in per_robot for x in xs} | {x for _, x in ends}
    own = tuple((r, xs) for r, xs in per_robot if xs)
    return Goals(tuple(visit), own, tuple(j for j in jobs if j.room in kept), ends), unreachable


def _without(goals: Goals, rooms: set[str]) -> Goals:
    """The goals without ``rooms`` (the robots' holds kept)."""
    if not rooms:
        return goals
    return replace(
        goals,
        visit=tuple(x for x in goals.visit if x not in rooms),
        per_robot=tuple((r, tuple(x for x in xs if x not in rooms)) for r, xs in goals.per_robot if set(xs) - rooms),
        jobs=tuple(j for j in goals.jobs if j.room not in rooms),
        ends=tuple((r, x) for r, x in goals.ends if x not in rooms),
    )


def _reachable(scenario: Scenario, world: World) -> tuple[Goals, list[tuple[str, str]]]:
    """The goals free space still joins to a robot allowed there; those it does not, with why."""
    goals = scenario.goals
    robots = [r.name for r in scenario.robots]
    cut: list[tuple[str, str]] = []

    def joins(robot: str, room: str) -> bool:
        return goals.may_visit(robot, room) and free_space_joins(scenario, world, robot, room)

    visit = []
    for room in goals.visit:
        if any(joins(r, room) for r in robots):
            visit.append(room)
        else:
            cut.append((room, "no robot allowed there can reach it (a closed door, or no way through)"))
    per_robot = []
    for robot, targets in goals.per_robot:
        kept = []
        for room in targets:
            if joins(robot, room):
                kept.append(room)
            elif any(joins(r, room) for r in robots):
                visit.append(room)  # its robot cannot get there any more: another robot may
            else:
                cut.append((room, "no robot allowed there can reach it (a closed door, or no way through)"))
        if kept:
            per_robot.append((robot, tuple(kept)))
    ends = []
    for robot, room in goals.ends:
        if joins(robot, room):
            ends.append((robot, room))
        else:
            cut.append((room, f"{robot}'s end: it cannot get back there (a closed door, or no way through)"))
    gone = {room for room, _ in cut}
    jobs = tuple(j for j in goals.jobs if j.room not in gone)
    return Goals(tuple(dict.fromkeys(visit)), tuple(per_robot), jobs, tuple(ends)), cut


def _poses(goals: Goals) -> tuple[tuple[str, float, float], ...]:
    """The jobs' goal poses the roadmap holds: those of the goals left (an added job's too)."""
    return tuple((j.room, j.pose[0], j.pose[1]) for j in goals.jobs if j.pose is not None)


def _rest(
    doc: dict[str, Any], t: float, gone: set[str], down: set[str], goals: Goals
) -> tuple[tuple[tuple[str, str], ...], ...]:
    """The old plan's moves not yet ended, in plan order, as (robot, target) steps, without the
    rooms done or removed and the robots down."""
    ended = {
        (robot, m["step"])
        for robot, entry in doc["schedule"]["robots"].items()
        for m in entry["moves"]
        if m["end"] <= t + TIME_TOL
    }
    wanted = set(goals.all_rooms)
    out = []
    for action in doc["actions"]:
        step = tuple(
            (m["robot"], m["to"])
            for m in action["moves"]
            if (m["robot"], action["index"]) not in ended
            and m["robot"] not in down
            and m["to"] not in gone
            and m["to"] in wanted
        )
        if step:
            out.append(step)
    return tuple(out)
