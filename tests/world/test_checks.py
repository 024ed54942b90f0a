"""Geometric checks of a scenario against its world (world/checks.py).

Each test breaks (or bends) the base scenario of tests/scenario/helpers.py and asks
``check`` directly; test_broken_scenarios.py shows the same problems on the command line.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.scenario.helpers import base_scenario, build_world, item
from tmpnav.errors import Problem
from tmpnav.world import check


def problems_after(tmp_path: Path, *edits: Callable[[dict[str, Any]], Any]) -> list[Problem]:
    doc = base_scenario()
    for edit in edits:
        edit(doc)
    scenario, world = build_world(tmp_path, doc)
    problems = check(scenario, world)
    for p in problems:  # every problem points at the line of its key
        assert p.line == scenario.line_of(p.path) and p.line is not None, p
    return problems


def paths(problems: list[Problem]) -> list[str]:
    return [p.path for p in problems]


def robot(name: str, **values: Any) -> Callable[[dict[str, Any]], None]:
    return lambda doc: item(doc, "robots", name).update(values)


def door(name: str, state: str) -> Callable[[dict[str, Any]], None]:
    return lambda doc: item(doc, "doors", name).update(state=state)


def test_the_base_scenario_has_no_problem(tmp_path: Path) -> None:
    assert problems_after(tmp_path) == []


def test_problems_name_the_file_as_the_user_typed_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    [problem] = problems_after(tmp_path, robot("r2", pose=[5.0, 1.5, 0.0]))
    assert problem.file == "scenario.yaml"
    assert str(problem).startswith("scenario.yaml:")


@pytest.mark.parametrize(
    ("edit", "path", "message"),
    [
        (robot("r2", pose=[5.0, 1.5, 0.0]), "robots.r2.pose",
         "[5.0, 1.5] is in collision (a disc of radius 0.25 m overlaps a wall or obstacle); expected a free start"),
        (robot("r2", pose=[10.5, 1.5, 0.0]), "robots.r2.pose",
         "[10.5, 1.5] is outside the map [0, 0, 10, 6]; expected a start inside the map"),
        (lambda doc: item(doc, "landmarks", "plant").update(position=[-0.5, 0.5]), "landmarks.plant.position",
         "[-0.5, 0.5] is outside the map [0, 0, 10, 6]; expected a point inside the map"),
        (lambda doc: item(doc, "doors", "door-A").update(segment=[[2, 3], [2, 7]]), "doors.door-A.segment",
         "point [2.0, 7.0] is outside the map [0, 0, 10, 6]; expected a door inside the map"),
        (lambda doc: item(doc, "rooms", "B").update(polygon=[[5.2, 3.2], [9.8, 3.2], [9.8, 6.5]]), "rooms.B.polygon",
         "point [9.8, 6.5] is outside the map [0, 0, 10, 6]; expected a room inside the map"),
        (lambda doc: item(doc, "rooms", "B").update(polygon=[[6, 4], [7, 4], [7, 4.001], [6, 4.001]]),
         "rooms.B.polygon", "has (almost) zero area; expected a polygon enclosing a region"),
        (door("door-B", "closed"), "rooms.B",
         "no robot can reach this room through free space (closed door or too narrow passage?); "
         "expected a room connected to some robot's start"),
        (lambda doc: item(doc, "rooms", "B").update(polygon=[[9.6, 5.6], [9.85, 5.6], [9.85, 5.85], [9.6, 5.85]]),
         "rooms.B", "has no free space large enough for any robot; expected a room a robot fits in"),
    ],
    ids=["collision", "robot-outside", "landmark-outside", "door-outside", "room-outside", "zero-area",
         "walled-off", "cramped"],
)  # fmt: skip
def test_each_geometric_problem(tmp_path: Path, edit: Callable[[dict[str, Any]], Any], path: str, message: str) -> None:
    [problem] = problems_after(tmp_path, edit)
    assert (problem.path, problem.message) == (path, message)


def test_a_landmark_mounted_on_a_wall_is_fine(tmp_path: Path) -> None:
    assert problems_after(tmp_path, lambda doc: item(doc, "landmarks", "printer").update(position=[5.0, 4.5])) == []


def test_a_robot_touching_a_wall_is_in_collision(tmp_path: Path) -> None:
    # the wall x = 0 fills cells up to x = 0.1; a 0.25 m robot at x = 0.3 has clearance 0.3 < 0.25 + 0.1
    assert paths(problems_after(tmp_path, robot("r1", pose=[0.3, 4.5, 0.0]))) == ["robots.r1.pose"]
    assert problems_after(tmp_path, robot("r1", pose=[0.45, 4.5, 0.0])) == []


def test_a_robot_in_collision_reaches_nothing(tmp_path: Path) -> None:
    # r1 is A's only way in once door-A is closed; stuck in a wall, it does not count
    problems = problems_after(tmp_path, door("door-A", "closed"), robot("r1", pose=[0.05, 4.5, 0.0]))
    assert paths(problems) == ["robots.r1.pose", "rooms.A"]


def test_each_room_needs_one_robot_not_every_robot(tmp_path: Path) -> None:
    # door-A closed: r1 stays in A, r2 has the hall and B. That r2 cannot reach its goal A is
    # the planner's to prove (exit code 6), not a problem of the scenario file.
    assert problems_after(tmp_path, door("door-A", "closed")) == []


def test_reachability_depends_on_the_robot_radius(tmp_path: Path) -> None:
    wide = robot("r2", radius=0.8)  # too wide for the 1 m doors: stuck in the hall
    assert problems_after(tmp_path, wide) == []  # r1 still reaches everything
    assert paths(problems_after(tmp_path, wide, robot("r1", radius=0.8))) == ["rooms.B"]


def test_rooms_outside_the_map_skip_the_reachability_check(tmp_path: Path) -> None:
    # reachability needs every room on the grid; B also walled off is not reported twice
    problems = problems_after(
        tmp_path,
        door("door-B", "closed"),
        lambda doc: item(doc, "rooms", "B").update(polygon=[[5.2, 3.2], [10.5, 3.2], [10.5, 5.8], [5.2, 5.8]]),
    )
    assert paths(problems) == ["rooms.B.polygon"]


def test_every_problem_is_reported_at_once(tmp_path: Path) -> None:
    problems = problems_after(
        tmp_path,
        robot("r2", pose=[5.0, 1.5, 0.0]),
        lambda doc: item(doc, "landmarks", "plant").update(position=[11, 0.5]),
        lambda doc: item(doc, "doors", "door-A").update(segment=[[2, 3], [2, -1]]),
        door("door-B", "closed"),
    )
    assert sorted(paths(problems)) == ["doors.door-A.segment", "landmarks.plant.position", "robots.r2.pose", "rooms.B"]


# ------------------------------------------------------------------- room outlines


@pytest.mark.parametrize(
    ("polygon", "crossing"),
    [
        ([[0, 0], [4, 0], [4, 3], [0, 3]], None),  # a rectangle
        ([[0, 0], [4, 0], [4, 3], [2, 1], [0, 3]], None),  # concave, still simple
        ([[0, 0], [1, 0], [1, 1]], None),  # a triangle cannot cross itself
        ([[0, 0], [4, 3], [4, 0], [0, 3]], (0, 2)),  # a bow tie
        ([[0, 0], [4, 0], [4, 3], [0, 3], [2, -1]], (0, 3)),  # the last point pokes back across
        ([[0, 0], [2, 4], [4, 0], [0, 3], [4, 3]], (0, 2)),  # a pentagram
    ],
    ids=["rectangle", "concave", "triangle", "bow-tie", "poke", "star"],
)
def test_self_intersection_finds_the_first_crossing_edges(polygon: list[list[float]], crossing: object) -> None:
    from tmpnav.world.checks import _self_intersection

    assert _self_intersection(np.array(polygon, dtype=float)) == crossing
