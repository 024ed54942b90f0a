"""Geometric checks of a scenario against its world, each problem naming its key path.

Run by ``tmpnav validate`` and before every plan: things outside the map, robots starting
in collision, rooms that are degenerate, too cramped for a robot, or unreachable.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from tmpnav.errors import Problem
from tmpnav.scenario import display_path
from tmpnav.types import Scenario
from tmpnav.world.build import World
from tmpnav.world.geometry import polygon_area


def check(scenario: Scenario, world: World) -> list[Problem]:
    """Every geometric problem of the scenario in this world (empty when all is well)."""
    file = display_path(scenario.source)

    def problem(path: str, message: str) -> Problem:
        return Problem(file, path, message, scenario.line_of(path))

    xmin, ymin, xmax, ymax = world.grid.extent
    extent = f"[{xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}]"

    def inside(p: tuple[float, float]) -> bool:
        return xmin <= p[0] <= xmax and ymin <= p[1] <= ymax

    problems: list[Problem] = []
    for room in scenario.rooms:
        path = f"rooms.{room.name}.polygon"
        outside = [p for p in room.polygon if not inside(p)]
        if outside:
            problems.append(
                problem(path, f"point {list(outside[0])} is outside the map {extent}; expected a room inside the map")
            )
        elif abs(polygon_area(np.array(room.polygon))) < world.grid.resolution**2:
            problems.append(problem(path, "has (almost) zero area; expected a polygon enclosing a region"))
    for lm in scenario.landmarks:
        if not inside(lm.position):
            problems.append(
                problem(
                    f"landmarks.{lm.name}.position",
                    f"{list(lm.position)} is outside the map {extent}; expected a point inside the map",
                )
            )
    for door in scenario.doors:
        for p in door.segment:
            if not inside(p):
                problems.append(
                    problem(
                        f"doors.{door.name}.segment",
                        f"point {list(p)} is outside the map {extent}; expected a door inside the map",
                    )
                )
                break
    starts_ok = []
    for robot in scenario.robots:
        path = f"robots.{robot.name}.pose"
        xy = np.array([robot.pose.x, robot.pose.y])
        if not inside((robot.pose.x, robot.pose.y)):
            problems.append(
                problem(
                    path, f"{[robot.pose.x, robot.pose.y]} is outside the map {extent}; expected a start inside the map"
                )
            )
        elif not world.is_free(xy[None, :], robot.radius)[0]:
            problems.append(
                problem(
                    path,
                    f"{[robot.pose.x, robot.pose.y]} is in collision (a disc of radius {robot.radius:g} m overlaps "
                    "a wall or obstacle); expected a free start",
                )
            )
        else:
            starts_ok.append(robot)
    if any(p.path.startswith("rooms.") for p in problems):
        return problems
    problems += _reachability(scenario, world, starts_ok, problem)
    return problems


def _reachability(scenario: Scenario, world: World, robots: list, problem) -> list[Problem]:
    """Rooms no robot can reach.

    A room some robot reaches but not the robot that goals.robots sends there is left to
    the planner, which proves the task unsolvable (exit code 6).

    Free space for a robot of radius rho is the set of cells with clearance >= rho + r;
    its 8-connected components are what a robot can drive through.
    """
    problems: list[Problem] = []
    reach: dict[str, set[str]] = {room.name: set() for room in scenario.rooms}
    cramped: dict[str, list[str]] = {room.name: [] for room in scenario.rooms}
    by_radius: dict[float, list] = {}
    for robot in robots:
        by_radius.setdefault(robot.radius, []).append(robot)
    for radius, group in by_radius.items():
        free = world.clearance >= radius + world.grid.resolution
        labels, _ = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
        for room in scenario.rooms:
            cells = world.free_cells_in_room(room.name, radius)
            if cells.shape[0] == 0:
                cramped[room.name] += [r.name for r in group]
                continue
            i, j, _ = world.grid.cells(cells)
            room_labels = set(np.unique(labels[i, j]).tolist()) - {0}
            for robot in group:
                si, sj, _ = world.grid.cells(np.array([[robot.pose.x, robot.pose.y]]))
                if int(labels[si[0], sj[0]]) in room_labels:
                    reach[room.name].add(robot.name)
    if not robots:
        return problems
    for room in scenario.rooms:
        if reach[room.name]:
            continue
        if len(cramped[room.name]) == len(robots):
            problems.append(
                problem(
                    f"rooms.{room.name}",
                    "has no free space large enough for any robot; expected a room a robot fits in",
                )
            )
        else:
            problems.append(
                problem(
                    f"rooms.{room.name}",
                    "no robot can reach this room through free space (closed door or too narrow passage?); "
                    "expected a room connected to some robot's start",
                )
            )
    return problems
