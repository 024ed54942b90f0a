"""``tmpnav validate`` on broken scenarios: one line per problem, the key path, exit code 2.

Every case starts from the small valid scenario of ``helpers.base_scenario()`` (two rooms
and a hall, two doors, a table, two landmarks, two robots), breaks exactly one thing and
runs the real command line on it. What a user must see, for every case:

- exit code 2 and no ``ok`` line;
- one ``error: <file>:<line>: <key.path>: <message>`` line per problem on stderr, and
  nothing else (no traceback, no ``internal error``);
- the file, the exact key path and a message that says what is wrong and what is expected.

Most cases run in-process through click's CliRunner (fast); a few run ``python -m tmpnav``
in a subprocess, the closest check that nothing else reaches the terminal.

Why one module of more than 400 lines: it is a catalogue, one short case per broken key, run
by the same few checks; split, the cases of one section of the format would be apart.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
import yaml
from click.testing import CliRunner

from tests.scenario.helpers import base_as_ros_map, base_scenario, item, write_yaml
from tmpnav.cli import cli

REPO = Path(__file__).resolve().parents[2]

#: doc, folder -> None (doc edited in place) or the text to write instead of the doc
Mutation = Callable[[dict[str, Any], Path], "str | None"]


@dataclass(frozen=True)
class Case:
    id: str
    mutate: Mutation
    path: str  # the key path the message must name ("" for the whole file)
    fragment: str  # a part of the message
    file: str = "scenario.yaml"  # the file the message must name
    line: int | None = None  # the line the message must name, when the case fixes it


# ---------------------------------------------------------------------- mutations


def change(section: str, which: str, /, **values: Any) -> Mutation:
    """Set keys of one named item: ``change("robots", "r1", radius="30 deg")``."""
    return lambda doc, folder: item(doc, section, which).update(values)


def delete(section: str, which: str, key: str) -> Mutation:
    """Remove a key of one named item: ``delete("robots", "r2", "pose")``."""

    def mutate(doc: dict[str, Any], folder: Path) -> None:
        del item(doc, section, which)[key]

    return mutate


def top(**values: Any) -> Mutation:
    """Set top-level keys (a value of ... deletes the key)."""

    def mutate(doc: dict[str, Any], folder: Path) -> None:
        for key, value in values.items():
            if value is ...:
                del doc[key]
            else:
                doc[key] = value

    return mutate


def nested(path: str, value: Any) -> Mutation:
    """Set a key of a mapping section: ``nested("map.resolution", 2)``; ... deletes it."""

    def mutate(doc: dict[str, Any], folder: Path) -> None:
        *parents, key = path.split(".")
        node = doc
        for k in parents:
            node = node.setdefault(k, {})
        if value is ...:
            del node[key]
        else:
            node[key] = value

    return mutate


def append(section: str, entry: dict[str, Any]) -> Mutation:
    return lambda doc, folder: doc[section].append(entry)


def text(content: str) -> Mutation:
    """Write ``content`` as the whole file (for what a dict cannot express)."""
    return lambda doc, folder: content


def edit_text(old: str, new: str) -> Mutation:
    """Replace text in the YAML of the base scenario (``old`` must occur once)."""

    def mutate(doc: dict[str, Any], folder: Path) -> str:
        content = yaml.safe_dump(doc, sort_keys=False, default_flow_style=None)
        assert content.count(old) == 1, old
        return content.replace(old, new)

    return mutate


def both(*mutations: Mutation) -> Mutation:
    def mutate(doc: dict[str, Any], folder: Path) -> str | None:
        out = None
        for m in mutations:
            out = m(doc, folder) or out
        return out

    return mutate


def ros_map(**meta: Any) -> Mutation:
    """Draw the base map as a ROS map_server map (map.yaml + map.pgm); ``meta`` overrides
    keys of map.yaml (None removes one)."""
    return lambda doc, folder: base_as_ros_map(doc, folder, **meta)


def ros_image(content: bytes | None) -> Mutation:
    """A ROS map whose image file holds ``content`` (None: no image file at all)."""

    def mutate(doc: dict[str, Any], folder: Path) -> None:
        base_as_ros_map(doc, folder)
        if content is None:
            (folder / "map.pgm").unlink()
        else:
            (folder / "map.pgm").write_bytes(content)

    return mutate


def ros_map_text(content: str) -> Mutation:
    """A ROS map whose map.yaml holds ``content``."""

    def mutate(doc: dict[str, Any], folder: Path) -> None:
        base_as_ros_map(doc, folder)
        (folder / "map.yaml").write_text(content)

    return mutate


EXPECTED_TOP_KEYS = "expected a mapping with keys name, description, map, rooms, doors, landmarks, robots"
R1_COV = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.003]]

CASES = [
    # --- the file as a whole
    Case("yaml-syntax-unclosed-list", text("name: x\nmap:\n  bounds: [0, 0, 10, 6\n  resolution: 0.1\n"), "",
         "YAML syntax error: expected ',' or ']', but got ':'", line=4),
    Case("yaml-syntax-indentation", text("map:\n  bounds: [0, 0, 10, 6]\n   resolution: 0.1\n"), "",
         "YAML syntax error: expected <block end>", line=3),
    Case("yaml-syntax-tab", text("map:\n\tbounds: [0, 0, 10, 6]\n"), "",
         "YAML syntax error: found character '\\t' that cannot start any token", line=2),
    Case("yaml-python-tag", text("name: !!python/object:os.system ls\n"), "",
         "YAML syntax error: could not determine a constructor", line=1),
    Case("empty-file", text(""), "", "is empty; " + EXPECTED_TOP_KEYS, line=1),
    Case("comments-only", text("# to do: draw the office\n"), "", "is empty; " + EXPECTED_TOP_KEYS),
    Case("top-level-list", text("- name: A\n- name: B\n"), "", "is a list; " + EXPECTED_TOP_KEYS),
    Case("top-level-scalar", text("corridor\n"), "", "is a str; " + EXPECTED_TOP_KEYS),
    Case("duplicate-top-level-key", lambda doc, folder: yaml.safe_dump(doc, sort_keys=False) + "name: again\n",
         "name", "duplicate key; a key may appear once"),
    Case("duplicate-key-in-robot", edit_text("  speed: 0.5\n", "  speed: 0.5\n  speed: 0.6\n"),
         "robots.r1.speed", "duplicate key; a key may appear once"),
    # --- keys
    Case("unknown-key-typo", change("robots", "r1", radus=0.3), "robots.r1.radus",
         "unknown key (did you mean 'radius'?); expected one of name, pose, covariance, radius, speed, turn_rate"),
    Case("unknown-top-level-key", top(landmark=[]), "landmark", "unknown key (did you mean 'landmarks'?)"),
    Case("unknown-key-in-sensor", nested("models.landmark_sensor.sigma_rnge", 0.2),
         "models.landmark_sensor.sigma_rnge", "unknown key (did you mean 'sigma_range'?)"),
    Case("unknown-key-no-hint", nested("map.colour", "red"), "map.colour",
         "unknown key; expected one of ros, despeckle, bounds, resolution, wall_thickness, walls, obstacles"),
    Case("missing-goals", top(goals=...), "goals", "is missing; expected a mapping with keys visit, robots"),
    Case("missing-rooms", top(rooms=...), "rooms", "is missing; expected a list of rooms"),
    Case("missing-robot-pose", delete("robots", "r2", "pose"), "robots.r2.pose",
         "is missing; expected a list of 3 numbers [x, y, theta] in (m, m, rad)"),
    Case("missing-room-polygon", delete("rooms", "hall", "polygon"), "rooms.hall.polygon",
         "is missing; expected a polygon: a list of 3 to 1000 points [x, y] in m"),
    Case("goals-name-no-room", top(goals={}), "goals",
         "names no room to visit; expected rooms in goals.visit, goals.robots or goals.ends"),
    # --- types
    Case("wrong-type-number", change("robots", "r1", radius="big"), "robots.r1.radius",
         "'big' is not a number; expected a number > 0 in m (or a string such as '1.5 m')"),
    Case("wrong-type-boolean-radius", change("robots", "r1", radius=True), "robots.r1.radius", "True is a boolean"),
    Case("wrong-type-list", top(rooms={"A": [[0, 0], [1, 0], [1, 1]]}), "rooms",
         "is not a list of rooms, each a mapping with keys name, polygon"),
    Case("wrong-type-flag", nested("models.mutual_observations", "yes"), "models.mutual_observations",
         "'yes' is not a boolean; expected true or false"),
    Case("wrong-type-section", top(roadmap=5), "roadmap",
         "5 is not a mapping; expected a mapping with keys samples, instantiations, seed, neighbors"),
    Case("wrong-type-point", change("landmarks", "plant", position="corner"), "landmarks.plant.position",
         "'corner' is not a list of 2 numbers [x, y] in (m, m)"),
    Case("pose-too-short", change("robots", "r2", pose=[7.5, 1.5]), "robots.r2.pose",
         "[7.5, 1.5] is not a list of 3 numbers [x, y, theta] in (m, m, rad)"),
    Case("polygon-too-few-points", change("rooms", "hall", polygon=[[0.2, 0.2], [9.8, 2.8]]), "rooms.hall.polygon",
         "is not a polygon: a list of 3 to 1000 points [x, y] in m"),
    Case("not-an-integer", nested("roadmap.samples", 10.5), "roadmap.samples",
         "10.5 is not an integer; expected an integer >= 10 and <= 200000"),
    Case("out-of-range", nested("map.resolution", 2), "map.resolution",
         "2 is out of range; expected a number > 0 and <= 1 in m"),
    Case("negative-speed", change("robots", "r2", speed="-1 m/s"), "robots.r2.speed",
         "'-1 m/s' is out of range; expected a number > 0 in m/s"),
    Case("choice-typo", change("doors", "door-B", state="opn"), "doors.door-B.state",
         "'opn' is not allowed (did you mean 'open'?); expected one of open, closed"),
    Case("encoding-typo", top(planner={"encoding": "mixd"}), "planner.encoding",
         "'mixd' is not allowed (did you mean 'mixed'?); expected one of paper, single, mixed"),
    # --- units
    Case("speed-in-kg", change("robots", "r1", speed="3 kg"), "robots.r1.speed",
         "'3 kg' has unit 'kg', which is not a unit of speed (m/s, cm/s); expected a number > 0 in m/s"),
    Case("angle-for-a-length", change("robots", "r1", radius="30 deg"), "robots.r1.radius",
         "'30 deg' has unit 'deg', which is not a unit of length (m, cm, mm)"),
    Case("length-for-an-angle", change("robots", "r1", pose=[2.5, 4.5, "90 m"]), "robots.r1.pose",
         "element 2 '90 m' has unit 'm', which is not a unit of angle (rad, deg)"),
    Case("angle-for-a-fov-too-wide", nested("models.landmark_sensor.fov", "400 deg"), "models.landmark_sensor.fov",
         "'400 deg' is out of range; expected a number > 0 and <= 6.28319 in rad"),
    Case("unit-on-a-plain-number", nested("roadmap.seed", "3 m"), "roadmap.seed",
         "'3 m' has a unit 'm' but is a plain number; expected an integer >= 0"),
    Case("unit-on-a-covariance", change("robots", "r1", covariance=[["1 cm", 0, 0], [0, 0.01, 0], [0, 0, 0.003]]),
         "robots.r1.covariance", "is not a symmetric positive-definite 3x3 matrix"),
    # --- covariances
    Case("covariance-not-symmetric", change("robots", "r1", covariance=[[0.01, 0.005, 0], [0, 0.01, 0], [0, 0, 0.003]]),
         "robots.r1.covariance", "is not symmetric; expected a symmetric positive-definite 3x3 matrix"),
    Case("covariance-negative-variance", change("robots", "r2", covariance=[[0.01, 0, 0], [0, -0.01, 0], [0, 0, 1]]),
         "robots.r2.covariance", "is not positive definite; expected a symmetric positive-definite 3x3 matrix"),
    Case("covariance-correlation-above-one", change("robots", "r2", covariance=[[0.01, 0.02, 0], [0.02, 0.01, 0],
         [0, 0, 0.003]]), "robots.r2.covariance", "is not positive definite"),
    Case("covariance-2x2", change("robots", "r2", covariance=[[0.01, 0], [0, 0.01]]), "robots.r2.covariance",
         "[[0.01, 0], [0, 0.01]] is not a symmetric positive-definite 3x3 matrix (m², m², rad² on the diagonal)"),
    # --- NaN and inf (yaml.safe_dump writes float("nan") as .nan and float("inf") as .inf)
    Case("nan-in-pose", change("robots", "r1", pose=[float("nan"), 4.5, 0.0]), "robots.r1.pose",
         "element 0 nan is not finite; expected a list of 3 numbers [x, y, theta] in (m, m, rad)"),
    Case("inf-radius", change("robots", "r1", radius=float("inf")), "robots.r1.radius",
         "inf is not finite; expected a number > 0 in m"),
    Case("minus-inf-landmark", change("landmarks", "plant", position=[9.5, float("-inf")]),
         "landmarks.plant.position", "element 1 -inf is not finite"),
    Case("nan-in-covariance", change("robots", "r1", covariance=[[float("nan"), 0, 0], *R1_COV[1:]]),
         "robots.r1.covariance", "has NaN or infinite entries"),
    Case("nan-as-text", edit_text("resolution: 0.1", "resolution: .NaN"), "map.resolution",
         "nan is not finite; expected a number > 0 and <= 1 in m"),
    Case("inf-bounds", nested("map.bounds", [0, 0, float("inf"), 6]), "map.bounds", "element 2 inf is not finite"),
    # --- names
    Case("duplicate-room", append("rooms", {"name": "A", "polygon": [[1, 1], [2, 1], [2, 2]]}), "rooms[3].name",
         "duplicate room name 'A'; expected unique names"),
    Case("duplicate-robot", append("robots", {"name": "r1", "pose": [1, 1, 0]}), "robots[2].name",
         "duplicate robot name 'r1'; expected unique names"),
    Case("duplicate-landmark", append("landmarks", {"name": "plant", "position": [1, 1]}), "landmarks[2].name",
         "duplicate landmark name 'plant'; expected unique names"),
    Case("duplicate-door", append("doors", {"name": "door-A", "segment": [[2, 3], [3, 3]]}), "doors[2].name",
         "duplicate door name 'door-A'; expected unique names"),
    Case("robot-named-like-a-room", both(change("robots", "r2", name="hall"), nested("goals.robots.r2", ...)),
         "robots.hall.name", "'hall' is also a room name; expected names unique among rooms and robots"),
    Case("reserved-room-name", append("rooms", {"name": "r1-start", "polygon": [[1, 1], [2, 1], [2, 2]]}), "rooms",
         "room name 'r1-start' is reserved for the start location of robot 'r1'"),
    Case("name-with-spaces", change("landmarks", "printer", name="big printer"), "landmarks.big printer.name",
         "'big printer' is not a valid name; expected a string (letters, digits, '_' or '-', starting with a letter)"),
    Case("name-starting-with-a-digit", change("rooms", "hall", name="2nd-floor"), "rooms.2nd-floor.name",
         "'2nd-floor' is not a valid name"),
    # --- goals
    Case("goal-undefined-room", nested("goals.robots.r1", ["C"]), "goals.robots.r1[0]",
         "'C' is not a room; expected one of A, B, hall"),
    Case("goal-room-typo", nested("goals.robots.r1", ["B", "hal"]), "goals.robots.r1[1]",
         "'hal' is not a room (did you mean 'hall'?); expected one of A, B, hall"),
    Case("goal-visit-undefined-room", nested("goals.visit", ["kitchen"]), "goals.visit[0]",
         "'kitchen' is not a room; expected one of A, B, hall"),
    Case("goal-undefined-robot", nested("goals.robots.r3", ["A"]), "goals.robots.r3",
         "'r3' is not a robot; expected one of r1, r2"),
    Case("goal-robots-not-a-mapping", nested("goals.robots", ["r1"]), "goals.robots",
         "['r1'] is not a mapping from robot names to a list of room names"),
    # --- the map
    Case("map-neither-bounds-nor-ros", nested("map.bounds", ...), "map",
         "must have exactly one of 'ros' (a ROS map_server YAML file) or 'bounds' (a polygonal map)"),
    Case("map-empty-bounds", nested("map.bounds", [0, 0, -10, 6]), "map.bounds",
         "[0.0, 0.0, -10.0, 6.0] is empty; expected [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax"),
    Case("map-grid-too-large", nested("map.resolution", "0.1 mm"), "map.resolution",
         "makes 6,000,000,000 grid cells; the cap is 64,000,000 (a coarser resolution or smaller bounds, "
         "or raise the cap: TMPNAV_MAX_MAP_CELLS=6000000000)"),
    Case("wall-with-one-point", nested("map.walls", [[[0, 0]]]), "map.walls[0]",
         "[[0, 0]] is not a polyline: a list of at least 2 points [x, y] in m"),
    # --- geometry (world/checks.py)
    Case("robot-on-the-table", change("robots", "r2", pose=[5.0, 1.5, 0.0]), "robots.r2.pose",
         "[5.0, 1.5] is in collision (a disc of radius 0.25 m overlaps a wall or obstacle); expected a free start"),
    Case("robot-in-a-wall", change("robots", "r1", pose=[5.0, 4.5, 0.0]), "robots.r1.pose", "is in collision"),
    Case("robot-grazing-a-wall", change("robots", "r1", pose=[0.3, 4.5, 0.0]), "robots.r1.pose", "is in collision"),
    Case("robot-outside-the-map", change("robots", "r2", pose=[12.0, 1.5, 0.0]), "robots.r2.pose",
         "[12.0, 1.5] is outside the map [0, 0, 10, 6]; expected a start inside the map"),
    Case("room-outside-the-map", change("rooms", "B", polygon=[[5.2, 3.2], [11, 3.2], [11, 5.8], [5.2, 5.8]]),
         "rooms.B.polygon", "point [11.0, 3.2] is outside the map [0, 0, 10, 6]; expected a room inside the map"),
    Case("landmark-outside-the-map", change("landmarks", "plant", position=[9.5, -1]), "landmarks.plant.position",
         "[9.5, -1.0] is outside the map [0, 0, 10, 6]; expected a point inside the map"),
    Case("door-outside-the-map", change("doors", "door-B", segment=[[7, 3], [18, 3]]), "doors.door-B.segment",
         "point [18.0, 3.0] is outside the map [0, 0, 10, 6]; expected a door inside the map"),
    Case("degenerate-room", change("rooms", "hall", polygon=[[1, 1], [2, 1], [3, 1]]), "rooms.hall.polygon",
         "has (almost) zero area; expected a polygon enclosing a region"),
    Case("room-walled-off-by-a-closed-door", change("doors", "door-B", state="closed"), "rooms.B",
         "no robot can reach this room through free space (closed door or too narrow passage?)"),
    Case("robots-too-wide-for-the-doors", both(change("robots", "r1", radius=0.8), change("robots", "r2", radius=0.8)),
         "rooms.B", "no robot can reach this room through free space"),
    Case("room-too-cramped", change("rooms", "A", polygon=[[4.6, 5.6], [4.85, 5.6], [4.85, 5.85], [4.6, 5.85]]),
         "rooms.A", "has no free space large enough for any robot; expected a room a robot fits in"),
    # --- ROS map_server maps: problems of map.yaml and its image name that file
    Case("ros-map-file-missing", top(map={"ros": "office.yaml"}), "map.ros",
         "'office.yaml': map file not found (office.yaml)"),
    Case("ros-image-missing", ros_image(None), "image", "image file not found: map.pgm", file="map.yaml"),
    Case("ros-image-truncated", ros_image(b"P5\n100 60\n255\n" + bytes(10)), "image",
         "cannot read image map.pgm: image file is truncated", file="map.yaml"),
    Case("ros-image-not-an-image", ros_image(b"this is not an image"), "image",
         "cannot read image map.pgm: cannot identify image file", file="map.yaml"),
    Case("ros-image-empty", ros_image(b""), "image", "cannot read image map.pgm", file="map.yaml"),
    Case("ros-missing-resolution", ros_map(resolution=None), "resolution",
         "is missing; expected a number > 0 and <= 1 in m", file="map.yaml", line=1),
    Case("ros-missing-image-key", ros_map(image=None), "image", "is missing; expected a string", file="map.yaml"),
    Case("ros-threshold-above-one", ros_map(occupied_thresh=1.5), "occupied_thresh",
         "1.5 is out of range; expected a number >= 0 and <= 1", file="map.yaml", line=5),
    Case("ros-thresholds-swapped", ros_map(free_thresh=0.7), "free_thresh",
         "0.7 is not below occupied_thresh 0.65; expected free_thresh < occupied_thresh", file="map.yaml", line=6),
    Case("ros-rotated-origin", ros_map(origin=[0, 0, "90 deg"]), "origin",
         "yaw 1.5708 is not supported; expected 0 (an axis-aligned map)", file="map.yaml"),
    Case("ros-mode-typo", ros_map(mode="trinery"), "mode",
         "'trinery' is not allowed (did you mean 'trinary'?); expected one of trinary, scale, raw", file="map.yaml"),
    Case("ros-unknown-key", ros_map(ocupied_thresh=0.6), "ocupied_thresh",
         "unknown key (did you mean 'occupied_thresh'?)", file="map.yaml"),
    Case("ros-negate-two", ros_map(negate=2), "negate", "2 is out of range; expected an integer >= 0 and <= 1",
         file="map.yaml"),
    Case("ros-map-yaml-syntax", ros_map_text("image: [map.pgm\n"), "", "YAML syntax error", file="map.yaml", line=2),
    Case("ros-map-yaml-is-a-list", ros_map_text("- map.pgm\n"), "",
         "is not a mapping; expected a ROS map_server YAML file", file="map.yaml"),
    Case("ros-map-with-walls", both(ros_map(), nested("map.walls", [[[0, 0], [1, 1]]])), "map",
         "'walls' and 'obstacles' belong to polygonal maps; a ROS map takes its walls from the image"),
]  # fmt: skip

#: the cases that also run as a real subprocess (python -m tmpnav): one of each kind
SUBPROCESS = [
    "yaml-syntax-unclosed-list",
    "empty-file",
    "nan-in-pose",
    "robot-on-the-table",
    "room-walled-off-by-a-closed-door",
    "ros-image-truncated",
]

PROBLEM_LINE = re.compile(r"^error: (?P<file>[^:]+?)(?::(?P<line>\d+))?: (?P<rest>.*)$")


@dataclass(frozen=True)
class Reported:
    file: str
    line: int | None
    rest: str  # "<key.path>: <message>", or "<message>" for the whole file

    def message_at(self, path: str) -> str | None:
        """The message when this problem is reported at ``path``, else None."""
        if not path:
            return self.rest
        return self.rest[len(path) + 2 :] if self.rest.startswith(path + ": ") else None


def write_case(case: Case, folder: Path) -> Path:
    doc = base_scenario()
    content = case.mutate(doc, folder)
    path = folder / "scenario.yaml"
    if content is None:
        write_yaml(path, doc)
    else:
        path.write_text(content, encoding="utf-8")
    return path


def reported(exit_code: int, stdout: str, stderr: str) -> list[Reported]:
    """Check what every failed validation must look like; return its problems."""
    assert exit_code == 2, stderr
    assert "Traceback" not in stdout + stderr
    assert "internal error" not in stderr
    assert stdout == ""  # no "ok" line
    lines = stderr.splitlines()
    assert lines, "no problem reported"
    out = []
    for line in lines:
        match = PROBLEM_LINE.match(line)
        assert match, f"not an 'error: <file>:<line>: ...' line: {line!r}"
        out.append(Reported(match["file"], int(match["line"]) if match["line"] else None, match["rest"]))
    return out


def check_case(case: Case, folder: Path, problems: list[Reported]) -> None:
    # one thing broken, one problem: no follow-up errors about what the loader had to skip
    assert len(problems) == 1, "\n".join(p.rest for p in problems)
    [p] = problems
    assert p.file == case.file
    message = p.message_at(case.path)
    assert message is not None, f"expected key path {case.path!r}: {p.rest}"
    if case.path:
        assert case.fragment in message, message
    else:  # a problem of the whole file: no key path before the message
        assert message.startswith(case.fragment), message
    if case.line is not None:
        assert p.line == case.line
    if p.line is not None:  # the line is in the file (or just past it: "unexpected end of file")
        assert 1 <= p.line <= len((folder / p.file).read_text().splitlines()) + 1, p


@pytest.fixture
def runner(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> CliRunner:
    monkeypatch.chdir(tmp_path)  # messages name files relative to the working directory
    return CliRunner()


def test_the_suite_has_at_least_twenty_distinct_cases() -> None:
    ids = [c.id for c in CASES]
    assert len(set(ids)) == len(ids) >= 20
    assert set(SUBPROCESS) <= set(ids)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_broken_scenario_is_reported(case: Case, tmp_path: Path, runner: CliRunner) -> None:
    write_case(case, tmp_path)
    result = runner.invoke(cli, ["validate", "scenario.yaml"])
    assert isinstance(result.exception, SystemExit), result.exception  # sys.exit(2), nothing raised
    check_case(case, tmp_path, reported(result.exit_code, result.stdout, result.stderr))


@pytest.mark.parametrize(
    ("case_id", "literal"), [("nan-in-pose", ".nan"), ("inf-radius", ".inf"), ("minus-inf-landmark", "-.inf")]
)
def test_nan_and_inf_cases_are_yaml_literals(case_id: str, literal: str, tmp_path: Path) -> None:
    """The NaN/inf cases are written as YAML's own .nan and .inf, what a user would type."""
    case = next(c for c in CASES if c.id == case_id)
    assert literal in write_case(case, tmp_path).read_text()


@pytest.mark.parametrize("case", [c for c in CASES if c.id in SUBPROCESS], ids=lambda c: c.id)
def test_broken_scenario_from_a_real_process(case: Case, tmp_path: Path) -> None:
    write_case(case, tmp_path)
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "validate", "scenario.yaml"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    check_case(case, tmp_path, reported(proc.returncode, proc.stdout, proc.stderr))


# ---------------------------------------------------------------------- all at once


def several_problems(doc: dict[str, Any], folder: Path) -> None:
    item(doc, "robots", "r1")["radus"] = 0.3  # schema: unknown key
    item(doc, "robots", "r2")["speed"] = "3 kg"  # schema: unit
    item(doc, "robots", "r2")["covariance"] = [[0.01, 0.005, 0], [0, 0.01, 0], [0, 0, 0.003]]  # schema: matrix
    item(doc, "robots", "r2")["pose"] = [5.0, 1.5, 0.0]  # world: on the table
    item(doc, "landmarks", "plant")["position"] = [9.5, -1]  # world: outside the map
    item(doc, "doors", "door-B")["state"] = "closed"  # world: room B walled off
    doc["goals"]["robots"]["r1"] = ["B", "C"]  # cross-reference: no room C


SEVERAL = {
    "robots.r1.radus": "unknown key (did you mean 'radius'?)",
    "robots.r2.speed": "'3 kg' has unit 'kg'",
    "robots.r2.covariance": "is not symmetric",
    "goals.robots.r1[1]": "'C' is not a room",
    "landmarks.plant.position": "is outside the map",
    "robots.r2.pose": "is in collision",
    "rooms.B": "no robot can reach this room",
}


def check_several(problems: list[Reported]) -> None:
    assert len(problems) == len(SEVERAL)
    for path, fragment in SEVERAL.items():
        messages = [p.message_at(path) for p in problems if p.message_at(path) is not None]
        assert len(messages) == 1, path
        assert fragment in (messages[0] or ""), messages
    assert {p.file for p in problems} == {"scenario.yaml"}
    assert all(p.line is not None for p in problems)


def test_several_problems_are_reported_together(tmp_path: Path, runner: CliRunner) -> None:
    """Schema, cross-reference and geometric problems all come out of one run."""
    write_case(Case("several", several_problems, "", ""), tmp_path)
    result = runner.invoke(cli, ["validate", "scenario.yaml"])
    check_several(reported(result.exit_code, result.stdout, result.stderr))


def test_several_problems_from_a_real_process(tmp_path: Path) -> None:
    write_case(Case("several", several_problems, "", ""), tmp_path)
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "validate", str(tmp_path / "scenario.yaml")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    check_several(reported(proc.returncode, proc.stdout, proc.stderr))


# ---------------------------------------------------------------------- valid scenarios


def test_the_base_scenario_is_valid(tmp_path: Path, runner: CliRunner) -> None:
    write_yaml(tmp_path / "scenario.yaml", base_scenario())
    result = runner.invoke(cli, ["validate", "scenario.yaml"])
    assert (result.exit_code, result.stderr) == (0, "")
    assert result.stdout == ("scenario.yaml: ok: 3 rooms, 2 doors, 2 landmarks, 2 robots, map 100x60 cells of 0.1 m\n")


def test_the_base_scenario_is_valid_from_a_real_process(tmp_path: Path) -> None:
    write_yaml(tmp_path / "scenario.yaml", base_scenario())
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "validate", "scenario.yaml"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert (proc.returncode, proc.stderr) == (0, "")
    assert proc.stdout.startswith("scenario.yaml: ok: ")


@pytest.mark.parametrize("config", sorted((REPO / "configs").glob("*.yaml")), ids=lambda p: p.name)
def test_shipped_configs_are_valid(config: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)
    result = CliRunner().invoke(cli, ["validate", str(config.relative_to(REPO))])
    assert (result.exit_code, result.stderr) == (0, "")
    assert " ok: " in result.stdout


def test_the_paper_corridor_is_valid() -> None:
    # named explicitly, so removing the file fails rather than shrinking the list above
    result = CliRunner().invoke(cli, ["validate", str(REPO / "configs" / "corridor.yaml")])
    assert result.exit_code == 0, result.stderr
    assert "ok: 10 rooms, 10 doors, 10 landmarks, 2 robots, map 1000x260 cells of 0.05 m" in result.stdout
