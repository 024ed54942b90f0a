"""The scenario loader (load.py) and the schema engine it runs (schema.py).

The broken-scenario suite (test_broken_scenarios.py) checks what a user sees on the command
line; these tests check the pieces: conversion to SI units, defaults, key paths, line
numbers, and that a bad value never stops the loader from reporting the other problems.
"""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

import pytest

from tests.scenario.helpers import base_as_ros_map, base_scenario, item, write_yaml
from tmpnav.errors import Problem, ScenarioError
from tmpnav.pipeline import load_world
from tmpnav.scenario import load, load_partial
from tmpnav.scenario.format import ROBOT, SCENARIO
from tmpnav.scenario.limits import MAP_CELLS
from tmpnav.scenario.schema import (
    MISSING,
    Covariance,
    Ctx,
    Field,
    Name,
    NamedList,
    Number,
    Section,
    Vector,
)
from tmpnav.types import ObservationMode, PolygonMap, RosMap


def check(spec: Any, value: Any) -> tuple[Any, list[str]]:
    """Run one spec on a value: (converted value, ["path: message", ...])."""
    ctx = Ctx()
    out = spec.check(value, ctx, "x", ("x",))
    return out, [f"{i.path}: {i.message}" for i in ctx.issues]


# --------------------------------------------------------------------------- a valid file


def test_base_scenario_loads_with_si_units_and_defaults(tmp_path: Path) -> None:
    sc = load(write_yaml(tmp_path / "s.yaml", base_scenario()))
    assert sc.name == "two-rooms-and-hall"
    assert sc.source == (tmp_path / "s.yaml").resolve()
    assert isinstance(sc.map, PolygonMap)
    assert sc.map.bounds == (0, 0, 10, 6)
    assert sc.map.wall_thickness == 0.15  # default
    assert [r.name for r in sc.rooms] == ["A", "B", "hall"]
    assert [(d.name, d.open, d.thickness) for d in sc.doors] == [("door-A", True, 0.15), ("door-B", True, 0.15)]
    r1, r2 = sc.robots
    assert r2.speed == pytest.approx(0.5)  # "50 cm/s"
    assert r1.pose.theta == pytest.approx(-1.5708)
    assert r1.covariance == ((0.01, 0.0, 0.0), (0.0, 0.01, 0.0), (0.0, 0.0, 0.003))  # default
    assert r1.turn_rate == 1.0
    assert sc.models.landmark_sensor.range == 4.0
    assert sc.models.landmark_sensor.fov == pytest.approx(2 * math.pi)  # "360 deg"
    assert sc.models.mutual_sensor.range == 4.0  # default of the other sensor
    assert sc.models.landmark_sensor.sigma_bearing == pytest.approx(math.radians(3))
    assert sc.models.observations is ObservationMode.NOISY
    assert sc.roadmap.samples == 200 and sc.roadmap.neighbors == 10
    assert sc.goals.per_robot == (("r1", ("B",)), ("r2", ("A",)))
    assert sc.planner.encoding == "mixed"


def test_name_defaults_to_the_file_name(tmp_path: Path) -> None:
    doc = base_scenario()
    del doc["name"]
    assert load(write_yaml(tmp_path / "office-3.yaml", doc)).name == "office-3"


def test_key_lines_let_later_stages_point_at_the_file(tmp_path: Path) -> None:
    text = """\
map: {bounds: [0, 0, 4, 4]}
rooms:
  - name: A
    polygon: [[1, 1], [3, 1], [3, 3]]
robots:
  - name: r1
    pose: [2, 1.5, 0]
goals: {visit: [A]}
"""
    (tmp_path / "s.yaml").write_text(text)
    sc = load(tmp_path / "s.yaml")
    assert sc.line_of("robots.r1.pose") == 7
    assert sc.line_of("rooms.A.polygon") == 4
    assert sc.line_of("rooms.A") == 3
    assert sc.line_of("robots.r1.pose.nothing.below") == 7  # nearest ancestor


def test_ros_map_paths_are_relative_to_the_scenario_file(tmp_path: Path) -> None:
    (tmp_path / "maps").mkdir()
    doc = base_scenario()
    base_as_ros_map(doc, tmp_path / "maps", origin=[-1.0, "50 cm", 0])
    doc["map"]["ros"] = "maps/map.yaml"
    sc = load(write_yaml(tmp_path / "s.yaml", doc))
    assert isinstance(sc.map, RosMap)
    assert sc.map.yaml_path == (tmp_path / "maps" / "map.yaml").resolve()
    assert sc.map.image_path == (tmp_path / "maps" / "map.pgm").resolve()
    assert sc.map.origin == (-1.0, 0.5, 0.0)
    assert (sc.map.negate, sc.map.occupied_thresh, sc.map.free_thresh, sc.map.mode) == (
        False,
        0.65,
        0.196,
        "trinary",
    )
    assert sc.doors[0].thickness == 0.15  # a ROS map has no wall_thickness


# --------------------------------------------------------------------------- line numbers


def problems_of(tmp_path: Path, text: str) -> list[Problem]:
    (tmp_path / "s.yaml").write_text(text)
    with pytest.raises(ScenarioError) as info:
        load(tmp_path / "s.yaml")
    return info.value.problems


def test_each_problem_names_file_line_and_key_path(tmp_path: Path) -> None:
    problems = problems_of(
        tmp_path,
        """\
map: {bounds: [0, 0, 4, 4]}
rooms:
  - name: A
    polygon: [[1, 1], [3, 1], [3, 3]]
robots:
  - name: r1
    pose: [2, 1.5, 0]
    speed: 3 kg
goals: {visit: [A]}
""",
    )
    assert len(problems) == 1
    p = problems[0]
    assert (p.path, p.line) == ("robots.r1.speed", 8)
    assert p.file.endswith("s.yaml")
    assert str(p) == f"{p.file}:8: robots.r1.speed: {p.message}"
    assert p.message.startswith("'3 kg' has unit 'kg', which is not a unit of speed")


def test_yaml_syntax_error_has_the_line(tmp_path: Path) -> None:
    problems = problems_of(tmp_path, "map:\n  bounds: [0, 0, 4, 4]\n rooms: []\n")
    assert len(problems) == 1
    assert problems[0].path == ""
    assert problems[0].line == 3
    assert problems[0].message.startswith("YAML syntax error: ")


def test_duplicate_keys_are_reported_where_they_repeat(tmp_path: Path) -> None:
    # yaml.safe_load keeps the last value silently; the loader does not
    problems = problems_of(
        tmp_path,
        """\
map: {bounds: [0, 0, 4, 4]}
rooms:
  - name: A
    polygon: [[1, 1], [3, 1], [3, 3]]
    polygon: [[1, 1], [3, 1], [3, 2]]
robots: [{name: r1, pose: [2, 1.5, 0]}]
goals: {visit: [A]}
""",
    )
    assert [(p.path, p.line, p.message) for p in problems] == [
        ("rooms.A.polygon", 5, "duplicate key; a key may appear once")  # list items by name, as everywhere
    ]


def test_a_missing_file_is_one_problem(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError) as info:
        load(tmp_path / "nope.yaml")
    assert [p.message for p in info.value.problems] == ["file not found"]


def test_a_binary_file_is_one_problem(tmp_path: Path) -> None:
    (tmp_path / "s.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    with pytest.raises(ScenarioError) as info:
        load(tmp_path / "s.yaml")
    assert info.value.problems[0].message.startswith("cannot be read: ")


# --------------------------------------------------------------------------- schema specs


def test_number_range_integer_and_units() -> None:
    spec = Number("length", minimum=0.0, exclusive_minimum=True, maximum=1.0)
    assert check(spec, "5 cm") == (pytest.approx(0.05), [])
    _, issues = check(spec, 0)
    assert issues == ["x: 0 is out of range; expected a number > 0 and <= 1 in m (or a string such as '1.5 m')"]
    _, issues = check(Number(None, minimum=1, integer=True), 2.5)
    assert issues == ["x: 2.5 is not an integer; expected an integer >= 1"]
    _, issues = check(spec, float("nan"))
    assert issues == ["x: nan is not finite; expected a number > 0 and <= 1 in m (or a string such as '1.5 m')"]


def test_vector_reports_the_bad_element() -> None:
    spec = Vector(dimensions=("length", "length", "angle"), names="x, y, theta")
    assert check(spec, [1, "20 cm", "90 deg"])[0] == pytest.approx((1.0, 0.2, math.pi / 2))
    _, issues = check(spec, [1, 2, "3 m"])
    assert issues == [
        "x: element 2 '3 m' has unit 'm', which is not a unit of angle (rad, deg); "
        "expected a list of 3 numbers [x, y, theta] in (m, m, rad)"
    ]
    _, issues = check(spec, [1, 2])
    assert issues == ["x: [1, 2] is not a list of 3 numbers [x, y, theta] in (m, m, rad)"]


@pytest.mark.parametrize(
    ("matrix", "fragment"),
    [
        ([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "is not symmetric"),
        ([[1, 0, 0], [0, -1, 0], [0, 0, 1]], "is not positive definite"),
        ([[1, 1, 0], [1, 1, 0], [0, 0, 1]], "is not positive definite"),  # PSD but singular
        ([[1, 0, 0], [0, float("inf"), 0], [0, 0, 1]], "has NaN or infinite entries"),
        ([[1, 0], [0, 1]], "is not a symmetric positive-definite 3x3 matrix"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, "1 m"]], "is not a symmetric positive-definite 3x3 matrix"),
    ],
)
def test_covariance_must_be_symmetric_positive_definite(matrix: list[list[Any]], fragment: str) -> None:
    out, issues = check(Covariance(), matrix)
    assert out is MISSING
    assert len(issues) == 1 and fragment in issues[0]


def test_name_allows_pddl_identifiers_only() -> None:
    assert check(Name(), "door-L1_b")[0] == "door-L1_b"
    assert check(Name(), 7)[1] == [
        "x: '7' is not a valid name; expected a string (letters, digits, '_' or '-', starting with a letter)"
    ]
    for bad in ("room A", "1st", "a.b", "", "  "):
        assert check(Name(), bad)[0] is MISSING, bad


def test_section_reports_unknown_keys_with_a_hint_and_missing_keys() -> None:
    out, issues = check(ROBOT, {"name": "r1", "radus": 0.3})
    assert issues == [
        "x.radus: unknown key (did you mean 'radius'?); "
        "expected one of name, pose, covariance, radius, speed, turn_rate",
        "x.pose: is missing; expected a list of 3 numbers [x, y, theta] in (m, m, rad)",
    ]
    assert out["pose"] is MISSING
    assert out["radius"] == 0.25  # the default stands in for the unknown key


def test_a_bad_optional_value_falls_back_to_its_default() -> None:
    # later checks (geometry, reachability) still run on the rest of the file
    out, issues = check(ROBOT, {"name": "r1", "pose": [1, 1, 0], "speed": "fast"})
    assert out["speed"] == 0.5 and len(issues) == 1


def test_a_bad_optional_section_falls_back_to_its_defaults() -> None:
    out, issues = check(SCENARIO, {"roadmap": 5, "models": ["dt"]})
    assert out["roadmap"] == {"samples": 1500, "instantiations": 4, "seed": 1, "neighbors": 10, "clearance": None}
    assert out["models"]["dt"] == 0.5
    # in the order of the schema's fields: the required ones are missing too
    assert [i.split(":")[0] for i in issues] == ["x.map", "x.rooms", "x.robots", "x.models", "x.roadmap", "x.goals"]


def test_post_checks_run_only_on_complete_sections() -> None:
    calls = []
    spec = Section(
        fields={"a": Field(Number(None), "a", required=True)}, post=lambda s, ctx, path, raw: calls.append(s)
    )
    check(spec, {"a": "x"})
    assert calls == []
    check(spec, {"a": 1})
    assert calls == [{"a": 1.0}]


def test_named_lists_use_names_in_paths_and_indices_for_duplicates() -> None:
    spec = NamedList(item=Section(fields={"name": Field(Name(), "", required=True), "v": Field(Number(), "")}))
    out, issues = check(spec, [{"name": "a", "v": "x"}, {"name": "a"}, {"v": 1}])
    assert issues == [
        "x.a.v: 'x' is not a number; expected a number",
        "x[1].name: duplicate item name 'a'; expected unique names",
        "x[2].name: is missing; expected a string (letters, digits, '_' or '-', starting with a letter)",
    ]
    assert [i["name"] for i in out] == ["a", "a"]  # the checker reports; it does not drop duplicates


# --------------------------------------------------------------------------- whole files


def test_load_partial_keeps_the_scenario_for_later_checks(tmp_path: Path) -> None:
    doc = base_scenario()
    item(doc, "robots", "r1")["speed"] = "fast"
    scenario, problems = load_partial(write_yaml(tmp_path / "s.yaml", doc))
    assert scenario is not None and scenario.robot("r1").speed == 0.5
    assert [p.path for p in problems] == ["robots.r1.speed"]


@pytest.mark.parametrize(
    ("mutate", "path"),
    [
        (lambda d: d["map"].pop("bounds"), "map"),
        (lambda d: d["map"].update(bounds=[0, 0, -1, 6]), "map.bounds"),
        (lambda d: d["map"].update(bounds=[0, 0, ".inf", 6]), "map.bounds"),
        (lambda d: d["map"].update(bounds=[0, 0, 1e5, 1e5]), "map.resolution"),
    ],
    ids=["no-bounds", "empty-bounds", "infinite-bounds", "grid-too-large"],
)
def test_a_map_that_cannot_be_built_stops_before_the_world(tmp_path: Path, mutate: Any, path: str) -> None:
    # (these used to crash in the world stage, or allocate a grid of 10^10 cells)
    doc = base_scenario()
    mutate(doc)
    scenario, problems = load_partial(write_yaml(tmp_path / "s.yaml", doc))
    assert scenario is None
    assert [p.path for p in problems] == [path]


def test_grid_limit_is_stated_in_the_message(tmp_path: Path) -> None:
    doc = base_scenario()
    doc["map"]["resolution"] = "1 mm"
    doc["map"]["bounds"] = [0, 0, 100, 1000]
    _, problems = load_partial(write_yaml(tmp_path / "s.yaml", doc))
    assert problems[0].message == (
        f"0.001 m over bounds [0.0, 0.0, 100.0, 1000.0] makes 100,000,000,000 grid cells; "
        f"the cap is {MAP_CELLS.default:,} (a coarser resolution or smaller bounds, "
        "or raise the cap: TMPNAV_MAX_MAP_CELLS=100000000000)"
    )


def test_goals_naming_an_item_with_other_problems_are_not_reported_twice(tmp_path: Path) -> None:
    doc = base_scenario()
    del item(doc, "robots", "r2")["pose"]  # r2 exists, but cannot be loaded
    item(doc, "rooms", "A")["polygon"] = [[1, 1], [2, 2]]  # so does room A
    _, problems = load_partial(write_yaml(tmp_path / "s.yaml", doc))
    assert [p.path for p in problems] == ["rooms.A.polygon", "robots.r2.pose"]  # not goals.robots.r2


def test_goals_with_no_room_defined_still_say_what_is_expected(tmp_path: Path) -> None:
    doc = base_scenario()
    doc["rooms"] = []
    _, problems = load_partial(write_yaml(tmp_path / "s.yaml", doc))
    assert [str(p).split(": ", 1)[1] for p in problems] == [
        "rooms: has 0 rooms; expected at least 1",
        "goals.robots.r1[0]: 'B' is not a room; expected a room defined in rooms (there is none)",
        "goals.robots.r2[0]: 'A' is not a room; expected a room defined in rooms (there is none)",
    ]


# --------------------------------------------------------------------------- robustness

GARBAGE: list[Any] = [
    None, [], {}, "", "x y", "3 kg", "90 deg", 0, -1, 1e9, math.nan, math.inf, True,
    [1], [[1, 2]], {"a": 1}, "A", "r1", [0, 0, 0], [[0, 0], [1, 0], [1, 1]], [None], [[]],
]  # fmt: skip


def key_paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    out = [prefix] if prefix else []
    children = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else []
    for key, child in children:
        out += key_paths(child, (*prefix, key))
    return out


def test_garbage_anywhere_is_reported_never_raised(tmp_path: Path) -> None:
    """Replace or delete 1-3 random keys of the base scenario with values of the wrong
    kind: loading must end in a ScenarioError (exit code 2), never in another exception."""
    rng = random.Random(20240611)
    for _ in range(120):
        doc = base_scenario()
        for _ in range(rng.randint(1, 3)):
            *parents, key = rng.choice(key_paths(doc))
            parent = doc
            for k in parents:
                parent = parent[k]
            if isinstance(parent, dict) and rng.random() < 0.2:
                del parent[key]
            else:
                parent[key] = rng.choice(GARBAGE)
        path = write_yaml(tmp_path / "s.yaml", doc)
        try:
            load_world(path)
        except ScenarioError as err:
            assert err.problems, doc
