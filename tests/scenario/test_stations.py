"""Stations (``goals.jobs[].place``): several named goal poses in one room or place. The
scenario gets each as a goal of its own (a ``Room`` with its place), the roadmap holds its
pose as a node, and a bad station gets one line naming the file and the key."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.scenario.helpers import base_scenario, write_yaml
from tmpnav.errors import Problem
from tmpnav.scenario import load_partial
from tmpnav.world import build, check

#: two stations in room A, one in B, r2's dock in the hall (where it starts)
STATIONS: list[dict[str, Any]] = [
    {"name": "A-west", "place": "A", "pose": [1.0, 4.5, 0.0], "service": "10 s"},
    {"name": "A-east", "place": "A", "pose": [4.0, 4.5, 1.5708], "window": ["0 s", "300 s"]},
    {"name": "B-desk", "place": "B", "pose": [7.5, 5.0, 0.0], "robots": ["r2"]},
    {"name": "dock2", "place": "hall", "pose": [8.5, 1.5, 0.0]},
]


def with_stations(*edits: Callable[[dict[str, Any]], Any]) -> dict[str, Any]:
    doc = base_scenario()
    doc["goals"] = {
        "visit": ["A-west", "A-east", "B-desk"],
        "ends": {"r2": "dock2"},
        "jobs": [dict(s) for s in STATIONS],
    }
    for edit in edits:
        edit(doc)
    return doc


def station(which: str, /, **values: Any) -> Callable[[dict[str, Any]], None]:
    return lambda doc: next(j for j in doc["goals"]["jobs"] if j["name"] == which).update(values)


def problems_of(tmp_path: Path, doc: dict[str, Any]) -> list[Problem]:
    """The load stage's problems and the world's checks of what loaded, as `tmpnav validate`
    reports them all: a bad station must not be reported twice."""
    scenario, problems = load_partial(write_yaml(tmp_path / "scenario.yaml", doc))
    return problems + ([] if scenario is None else check(scenario, build(scenario)))


def only(problems: list[Problem], path: str) -> Problem:
    assert [p.path for p in problems] == [path], problems
    p = problems[0]
    assert p.file.endswith("scenario.yaml") and p.line is not None
    return p


def test_stations_are_goals_of_their_own_in_their_places(tmp_path: Path) -> None:
    scenario, problems = load_partial(write_yaml(tmp_path / "scenario.yaml", with_stations()))
    assert not problems and scenario is not None
    assert [r.name for r in scenario.places] == ["A", "B", "hall"]
    places = {"A-west": "A", "A-east": "A", "B-desk": "B", "dock2": "hall"}
    assert {r.name: r.place for r in scenario.stations} == places
    assert scenario.room("A-west").polygon == scenario.room("A").polygon
    # each station's pose is its one pose instantiation
    assert ("A-east", 4.0, 4.5) in scenario.roadmap.poses
    assert scenario.goals.service("A-west") == 10.0 and scenario.goals.may_visit("r1", "B-desk") is False
    assert not check(scenario, build(scenario))


def test_a_robot_in_a_station_s_place_has_not_done_it(tmp_path: Path) -> None:
    # r1 starts in room A, which holds two stations: unlike a job at room A, that is no problem
    doc = with_stations()
    assert problems_of(tmp_path, doc) == []
    doc["goals"] = {"visit": ["A", "B"], "jobs": [{"name": "A", "service": "10 s"}]}
    only(problems_of(tmp_path, doc), "goals.jobs.A")


@pytest.mark.parametrize(
    ("edit", "path", "words"),
    [
        (station("A-east", name="B"), "goals.jobs.B.name", "has the name of a room"),
        (station("A-east", name="r1"), "goals.jobs.r1.name", "has the name of a robot"),
        (station("A-east", place="kitchen"), "goals.jobs.A-east.place", "'kitchen' is not a room"),
        (station("A-east", place="A-west"), "goals.jobs.A-east.place", "'A-west' is a station"),
        (station("A-east", pose=None), "goals.jobs.A-east.pose", "has no pose"),
        (station("A-east", pose=[7.5, 4.5, 0.0]), "goals.jobs.A-east.pose", "not inside room 'A'"),
        (station("A-east", pose=[4.75, 4.5, 0.0]), "goals.jobs.A-east.pose", "touches a wall"),
        (station("A-east", pose=[1.0, 4.5, 0.0]), "goals.jobs.A-east.pose", "station 'A-west''s pose too"),
    ],
)
def test_a_bad_station_gets_one_line_with_its_key(
    tmp_path: Path, edit: Callable[[dict[str, Any]], Any], path: str, words: str
) -> None:
    doc = with_stations(edit)
    if "name" in path:  # the renamed station is still the goal
        doc["goals"]["visit"] = [path.split(".")[2] if x == "A-east" else x for x in doc["goals"]["visit"]]
    if doc["goals"]["jobs"][1].get("pose") is None:
        del doc["goals"]["jobs"][1]["pose"]
    problems = problems_of(tmp_path, doc)
    assert words in only(problems, path).message


def test_duplicate_station_names_are_named(tmp_path: Path) -> None:
    doc = with_stations(station("A-east", name="A-west"))
    doc["goals"]["visit"].remove("A-east")
    assert "duplicate job name 'A-west'" in only(problems_of(tmp_path, doc), "goals.jobs[1].name").message


def test_the_roadmap_holds_each_station_pose_as_its_node(tmp_path: Path) -> None:
    from tmpnav.roadmap import build_roadmap

    scenario, _ = load_partial(write_yaml(tmp_path / "scenario.yaml", with_stations()))
    assert scenario is not None
    roadmap = build_roadmap(build(scenario), scenario.robots, scenario.roadmap)
    for s in STATIONS:
        (node,) = roadmap.instantiations[s["name"]]
        assert np.allclose(roadmap.nodes[node], s["pose"][:2])
    # the places keep their sampled instantiations
    assert len(roadmap.instantiations["A"]) == 2


def test_a_point_at_a_station_lies_in_its_place(tmp_path: Path) -> None:
    """room_of gives the room or place (never a station, which shares its place's outline), and
    place_of the place a goal lies in: what a replan compares a robot's pose with."""
    scenario, _ = load_partial(write_yaml(tmp_path / "scenario.yaml", with_stations()))
    assert scenario is not None
    world = build(scenario)
    assert world.room_of(np.array([4.0, 4.5])) == "A" == world.place_of("A-east")
    assert world.place_of("A") == "A" and world.place_of("dock2") == "hall"
