"""Can the roadmap serve the goals? Checked before any cost is computed.

The roadmap keeps a room when any robot reaches one of its pose instantiations. A room
behind a door the samples never crossed may still be cut off from the robot that must go
there; the planner then answered "no plan ... (a goal room that its robot cannot reach?)"
(exit 6) for a scenario that has a plan. When free space joins the robot and the room,
that is the roadmap's fault, and worth saying before every move is costed. When free
space does not join them either (a closed door), no plan exists, and the planner says so.

Separate from :mod:`tmpnav.roadmap.graph`, whose code decides cached costs (a change here
must not invalidate them).
"""

from __future__ import annotations

import numpy as np

from tmpnav.errors import RoadmapError
from tmpnav.roadmap.graph import RoadmapGraph
from tmpnav.types import Roadmap, Scenario
from tmpnav.world import World


def check_reachable(scenario: Scenario, world: World, roadmap: Roadmap) -> None:
    """Raise RoadmapError (exit 2) when the roadmap cuts a goal room off from the robot that
    must visit it though free space joins them, instead of costing every move and hearing
    "no plan" from ENHSP."""
    why = roadmap_cuts(scenario, world, roadmap)
    if why is not None:
        raise RoadmapError(why)


def roadmap_cuts(scenario: Scenario, world: World, roadmap: Roadmap) -> str | None:
    """Why the roadmap cannot serve the scenario's goals although free space can, or None."""
    from scipy.sparse.csgraph import connected_components

    _, labels = connected_components(RoadmapGraph(roadmap).matrix, directed=False)

    def reaches(robot: str, room: str) -> bool:
        start = labels[roadmap.starts[robot]]
        return any(labels[i] == start for i in roadmap.instantiations.get(room, ()))

    goals = scenario.goals
    robots = [r.name for r in scenario.robots]
    cut: list[tuple[str | None, str]] = [
        (r, room) for r in robots for room in goals.for_robot(r) if not reaches(r, room)
    ]
    cut += [(None, room) for room in goals.visit if not any(reaches(r, room) for r in robots)]
    for robot, room in cut:
        joined = [r for r in (robots if robot is None else [robot]) if free_space_joins(scenario, world, r, room)]
        if joined:
            whose = "a robot's" if robot is None else f"robot {robot}'s"
            return (
                f"room {room!r}: none of its pose instantiations connects to {whose} start through the roadmap, "
                f"though free space joins them, with the roadmap grown from roadmap.samples "
                f"{scenario.roadmap.samples} as far as it grows; raise roadmap.samples or roadmap.neighbors"
            )
    return None


def free_space_joins(scenario: Scenario, world: World, robot: str, room: str) -> bool:
    """Is there room for ``robot`` all the way from its start into the room (the free space
    the roadmap samples, tmpnav.roadmap.prm.reachable_free_space)?"""
    spec = scenario.robot(robot)
    labels = world.free_components(spec.radius)
    i, j, _ = world.grid.cells(np.array([[spec.pose.x, spec.pose.y]]))
    start = labels[i[0], j[0]]
    inside = world.free_cells_in_room(room, spec.radius)
    if start == 0 or len(inside) == 0:
        return False
    ri, rj, _ = world.grid.cells(inside)
    return bool((labels[ri, rj] == start).any())
