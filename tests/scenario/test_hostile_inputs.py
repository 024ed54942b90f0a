"""Inputs a careless user or an attacker would try, through the real command line.

Each numbered item of the reliability report on tmpnav's inputs has its cases here:
(1) 16-bit map images, (2) YAML alias bombs, (4) resource caps, (7) extreme values,
(8) overflow and deep nesting, (9) YAML 1.2 numbers, (11) what validate used to miss.
A refused input is exit code 2 and one ``error: <file>:<line>: <key.path>: <message>``
line, checked by the same machinery as test_broken_scenarios.py; the few cases that
need a real process (time, memory, what reaches the terminal) run ``python -m tmpnav``.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from tests.scenario.helpers import base_as_ros_map, base_scenario, item, ros_map_yaml, write_yaml
from tests.scenario.test_broken_scenarios import (
    Case,
    change,
    check_case,
    edit_text,
    nested,
    reported,
    ros_image,
    text,
    write_case,
)
from tmpnav.cli import cli


def alias_bomb(levels: int) -> str:
    """The 'billion laughs' file: each anchor is a list of nine aliases of the previous one."""
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels)]
    return "\n".join([*lines, f"name: *a{levels - 1}", ""])


def ros_16_bit(unknown_under: str | None = None) -> Any:
    """The base map as a 16-bit PGM (maxval 65535); with ``unknown_under`` a robot's start
    is painted map_saver's unknown grey (205/255)."""

    def mutate(doc: dict[str, Any], folder: Path) -> None:
        x, y = item(doc, "robots", unknown_under)["pose"][:2] if unknown_under else (None, None)
        base_as_ros_map(doc, folder, maxval=65535)
        if x is None:
            return
        data = bytearray((folder / "map.pgm").read_bytes())
        header = len(b"P5\n100 60\n65535\n")
        pixels = np.frombuffer(bytes(data[header:]), dtype=">u2").reshape(60, 100).copy()
        row, col = 60 - 1 - int(y / 0.1), int(x / 0.1)
        pixels[row - 5 : row + 5, col - 5 : col + 5] = 205 * 257
        (folder / "map.pgm").write_bytes(bytes(data[:header]) + pixels.tobytes())

    return mutate


COV = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.003]]

CASES = [
    # (1) a 16-bit map: unknown grey stays unknown, so a robot standing in it is refused
    Case("16-bit-pgm-robot-in-unknown-space", ros_16_bit("r1"), "robots.r1.pose", "is in collision"),
    # (2) alias bombs and (8) deep nesting are refused before anything is built
    Case("yaml-alias-bomb", text(alias_bomb(9)), "",
         "YAML expands to at least 539,750 values (aliases expanded); the cap is 500,000 (fewer aliases of "
         "aliases, or a smaller file, or raise the cap above 539,750 with TMPNAV_MAX_YAML_NODES)"),
    Case("yaml-alias-recursive", text("name: &x [1, *x]\n"), "",
         "YAML alias *x refers to a collection that contains it"),
    Case("yaml-nested-100000-deep", text("name: " + "[" * 100_000 + "]" * 100_000 + "\n"), "",
         "YAML nested deeper than 32 levels"),
    Case("yaml-tagged-value-unreadable", text("name: !!timestamp noon\n"), "",
         "YAML value 'noon' tagged !!timestamp is not a valid timestamp"),
    # (4) caps, estimated before any work
    Case("dt-1e-6", nested("models.dt", 1e-6), "models.dt",
         "1e-06 s makes robot r1 take about 44,566,371 control steps for a move across the map; the cap is 100,000 "
         "(a longer dt, or faster robots, or raise the cap: TMPNAV_MAX_MOVE_STEPS=44566371)"),
    Case("speed-1e-5", change("robots", "r1", speed=1e-5), "robots.r1.speed",
         "1e-05 m/s with models.dt 0.5 s makes about 3,200,026 control steps for a move across the map"),
    Case("turn-rate-1e-6", change("robots", "r2", turn_rate=1e-6), "robots.r2.turn_rate",
         "1e-06 rad/s with models.dt 0.5 s makes about 25,132,806 control steps"),
    Case("ros-image-20000-square", ros_image(b"P5\n20000 20000\n255\n"), "image",
         "map.pgm has 20000 x 20000 pixels: 400,000,000 grid cells; the cap is 64,000,000", file="map.yaml"),
    Case("ros-image-a-device", lambda doc, folder: base_as_ros_map(doc, folder, image="/dev/zero"), "image",
         "image file is not a regular file: /dev/zero", file="map.yaml"),
    Case("ros-map-yaml-a-device", nested("map", {"ros": "/dev/zero"}), "map.ros",
         "'/dev/zero': map file is not a regular file (/dev/zero)"),
    # (7) values beyond where the model means anything
    Case("covariance-1e100", change("robots", "r1", covariance=[[1e100, 0, 0], [0, 1e100, 0], [0, 0, 0.003]]),
         "robots.r1.covariance", "position variance 1e+100 m² (standard deviation 1e+50 m) is wider than the map "
         "(diagonal 11.7 m); expected at most 136 m² on x and y"),
    Case("covariance-1e160", change("robots", "r2", covariance=[[0.01, 0, 0], [0, 1e160, 0], [0, 0, 0.003]]),
         "robots.r2.covariance", "position variance 1e+160 m²"),
    Case("heading-variance-beyond-a-half-turn", change("robots", "r2", covariance=[*COV[:2], [0, 0, 12.0]]),
         "robots.r2.covariance", "heading variance 12 rad² (standard deviation 198 deg) is beyond a half turn"),
    Case("m-sigma-1e300", nested("cost.M_Sigma", 1e300), "cost.M_Sigma",
         "1e+300 is out of range; expected a number >= 0 and <= 1e+06"),
    Case("all-weights-zero", nested("cost", {"M_u": 0, "M_G": 0, "M_Sigma": 0}), "cost",
         "weights M_u, M_G and M_Sigma are all 0"),
    Case("motion-noise-above-the-command", nested("models.motion_noise", {"alpha3": 4}), "models.motion_noise.alpha3",
         "4 is out of range; expected a number >= 0 and <= 1; beyond 1 the noise's standard deviation"),
    Case("range-noise-above-the-range", nested("models.landmark_sensor.sigma_range", 5),
         "models.landmark_sensor.sigma_range", "5 m is larger than the sensor's range 4 m"),
    Case("bearing-noise-beyond-a-half-turn", nested("models.mutual_sensor", {"sigma_bearing": "200 deg"}),
         "models.mutual_sensor.sigma_bearing", "'200 deg' is out of range; expected a number >= 1e-06 and <= 3.14159"),
    Case("sensor-noise-1e-300", nested("models.landmark_sensor.sigma_bearing", 1e-300),
         "models.landmark_sensor.sigma_bearing", "1e-300 is out of range; expected a number >= 1e-06 and <= 3.14159 in "
         "rad (or a string such as '1.5 rad'); a sensor more precise than 1e-6 drives the filter below float"),
    Case("lidar-negative-range", nested("models.range_sensor", {"range": -3}), "models.range_sensor.range",
         "-3 is out of range; expected a number > 0 in m"),
    Case("lidar-zero-beams", nested("models.range_sensor", {"beams": 0}), "models.range_sensor.beams",
         "0 is out of range; expected an integer >= 1 and <= 2000; a scan needs at least one beam"),
    Case("lidar-blind-beyond-its-range", nested("models.range_sensor", {"range": 5, "min_range": 6}),
         "models.range_sensor.min_range", "6 m is not below the sensor's range 5 m"),
    Case("floor-of-every-beam", nested("models.range_sensor", {"beams": 40, "localiser": {"floor_beams": 40}}),
         "models.range_sensor.localiser.floor_beams", "40 is not below the 40 beams the localiser weighs"),
    Case("lidar-along-the-wall", nested("models.range_sensor", {"max_incidence": "90 deg"}),
         "models.range_sensor.max_incidence", "'90 deg' is out of range; expected a number > 0 and <= 1.55334 in rad"),
    Case("sensor-range-1e9", nested("models.mutual_sensor", {"range": 1e9}), "models.mutual_sensor.range",
         "1e+09 m is longer than the map's diagonal 11.7 m; expected at most 11.7 m"),
    Case("one-control-step-crosses-the-map", change("robots", "r2", speed=100), "robots.r2.speed",
         "100 m/s covers 50 m in one control step (models.dt 0.5 s), more than the map's diagonal 11.7 m"),
    Case("seed-beyond-32-bits", nested("roadmap.seed", 2**64), "roadmap.seed", "is out of range"),
    Case("timeout-1e300", nested("planner.timeout", 1e300), "planner.timeout", "is out of range"),
    # (8) overflow
    Case("map-bounds-1e308", nested("map.bounds", [0, 0, 1e308, 6]), "map.bounds",
         "element 2 1e+308 is out of range; expected coordinates within +-1e+07 m"),
    Case("integer-with-5000-digits", edit_text("samples: 200", "samples: " + "9" * 5000), "roadmap.samples",
         "inf is not finite"),
    # (11) what validate used to miss
    Case("robots-on-the-same-spot", change("robots", "r2", pose=[2.5, 4.5, 0.0]), "robots.r2.pose",
         "[2.5, 4.5] is 0 m from robot r1's start, closer than their radii 0.25 + 0.25 m"),
    Case("robots-overlapping", change("robots", "r2", pose=[2.5, 4.1, 0.0]), "robots.r2.pose",
         "is 0.4 m from robot r1"),
    Case("self-intersecting-room", change("rooms", "A", polygon=[[0.2, 3.2], [4.8, 5.8], [4.8, 3.2], [0.2, 5.8]]),
         "rooms.A.polygon", "edge 0 (point 0 to 1) crosses edge 2 (point 2 to 3); expected a simple polygon"),
]  # fmt: skip


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_hostile_scenario_is_refused_in_one_line(case: Case, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_case(case, tmp_path)
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert isinstance(result.exception, SystemExit), result.exception
    check_case(case, tmp_path, reported(result.exit_code, result.stdout, result.stderr))


def run(
    args: list[str], cwd: Path, env: dict[str, str] | None = None, memory_gb: float = 4.0
) -> tuple[int, str, str, float]:
    """``python -m tmpnav ARGS`` in a process limited to ``memory_gb`` of address space:
    (exit code, stdout, stderr, seconds)."""
    limit = int(memory_gb * 2**30)

    def cap_memory() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    start = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, **(env or {})},
        preexec_fn=cap_memory,
    )
    return proc.returncode, proc.stdout, proc.stderr, time.monotonic() - start


@pytest.mark.parametrize(
    ("case_id", "seconds"),
    [("yaml-alias-bomb", 30), ("yaml-nested-100000-deep", 30), ("ros-image-20000-square", 30), ("dt-1e-6", 60)],
)
def test_refusals_take_little_time_and_memory(case_id: str, seconds: float, tmp_path: Path) -> None:
    """Before: 44 s and 3.7 GB (alias bomb), RecursionError (deep nesting), PIL's
    decompression-bomb error (20000 x 20000 image), 6-9 GB (dt 1e-6). Now each is refused
    within 1 GB of address space beyond the interpreter's, in seconds."""
    case = next(c for c in CASES if c.id == case_id)
    write_case(case, tmp_path)
    code, out, err, took = run(["validate", "scenario.yaml"], tmp_path, memory_gb=2.0)
    check_case(case, tmp_path, reported(code, out, err))
    assert took < seconds
    assert "DecompressionBomb" not in err


def test_a_scenario_that_never_ends_is_refused_after_the_cap(tmp_path: Path) -> None:
    """/dev/zero has no size to check first: it used to be read until memory ran out
    (MemoryError after 3.5 GB, exit 1). Now it is read no further than the yaml_bytes cap."""
    code, out, err, took = run(["validate", "/dev/zero"], tmp_path, memory_gb=2.0)
    [problem] = reported(code, out, err)
    assert (problem.file, problem.line) == ("/dev/zero", None)
    assert problem.rest.startswith(
        "is at least 16,000,001 bytes of YAML; the cap is 16,000,000 (a YAML file this large is not a scenario"
    )
    assert took < 30


@pytest.mark.parametrize(
    "case_id", ["dt-1e-6", "covariance-1e160", "m-sigma-1e300", "sensor-noise-1e-300", "robots-on-the-same-spot"]
)
def test_plan_refuses_the_same_inputs_before_any_work(case_id: str, tmp_path: Path) -> None:
    """`plan` runs the same checks before the roadmap: exit 2, never 1 (a crash in the
    compiled kernel, a LinAlgError for sensor noise of 1e-300) or 6 (a wrong "goal room
    unreachable?")."""
    case = next(c for c in CASES if c.id == case_id)
    write_case(case, tmp_path)
    code, out, err, _ = run(["plan", "scenario.yaml", "--no-cache", "--timeout", "30"], tmp_path)
    check_case(case, tmp_path, reported(code, out, err))


def many_goal_rooms(rooms: int, robots: int) -> dict[str, Any]:
    """The base scenario with ``rooms`` goal rooms (all drawn over the hall: reachable)."""
    doc = base_scenario()
    hall = item(doc, "rooms", "hall")["polygon"]
    doc["rooms"] = [{"name": f"R{i}", "polygon": hall} for i in range(rooms)]
    doc["robots"] = [{"name": f"r{k}", "pose": [0.7 + 1.2 * k, 0.6 if k % 2 else 2.5, 0.0]} for k in range(robots)]
    doc["goals"] = {"visit": [f"R{i}" for i in range(rooms)]}
    return doc


@pytest.mark.parametrize(
    ("rooms", "robots", "message"),
    [
        (200, 2, "goals: with the mixed encoding and the exact search needs about 1,600,080,000 cost-table "
         "entries; the cap is 5,000,000 (--search anytime, fewer goal rooms or robots, or the single encoding, "
         "or raise the cap: TMPNAV_MAX_TABLE_ENTRIES=1600080000)"),
        (1700, 3, "goals: names 1700 goal rooms for 3 robots: 5,100 goal rooms x robots; the cap is 5,000 "
         "(fewer goal rooms or robots, or raise the cap: TMPNAV_MAX_GOAL_ASSIGNMENTS=5100)"),
    ],
    ids=["200-goal-rooms", "goal-rooms-x-robots"],
)  # fmt: skip
def test_too_many_goal_rooms_are_refused_before_the_oracle(
    rooms: int, robots: int, message: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Before: 200 goal rooms took 9.3 GB, then MemoryError after 85 s (the exact search with
    table costs lists every pair of moves first)."""
    monkeypatch.chdir(tmp_path)
    doc = many_goal_rooms(rooms, robots)
    doc["planner"] = {"costs": "table", "search": "exact"}
    write_yaml(tmp_path / "scenario.yaml", doc)
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    [problem] = reported(result.exit_code, result.stdout, result.stderr)
    assert problem.rest == message


def test_the_encoding_of_the_command_line_is_held_to_the_cap(tmp_path: Path) -> None:
    """The caps were checked against the scenario's own encoding only: a scenario of 100 goal
    rooms with the single encoding validated, and `plan --encoding mixed` listed 100 million
    pairs of moves until memory ran out (MemoryError at 3.7 GB, exit 1). The oracle checks
    the scenario in force, before it lists a move."""
    doc = many_goal_rooms(100, 2)
    doc["planner"] = {"encoding": "single"}
    write_yaml(tmp_path / "scenario.yaml", doc)
    assert run(["validate", "scenario.yaml"], tmp_path)[0] == 0
    command = ["plan", "scenario.yaml", "--encoding", "mixed", "--costs", "table", "--search", "exact", "--no-cache"]
    code, out, err, took = run(command, tmp_path, memory_gb=2.0)
    [problem] = reported(code, out, err)
    assert problem.rest == (
        "goals: with the mixed encoding and the exact search needs about 100,020,000 cost-table entries; the cap is "
        "5,000,000 (--search anytime, fewer goal rooms or robots, or the single encoding, or raise the cap: "
        "TMPNAV_MAX_TABLE_ENTRIES=100020000)"
    )
    assert took < 60


def test_the_anytime_search_takes_200_goal_rooms(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The searches other than the exact one with table costs cost paired moves only as they
    need them: only the single moves count against the cap."""
    monkeypatch.chdir(tmp_path)
    write_yaml(tmp_path / "scenario.yaml", many_goal_rooms(200, 2))
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert (result.exit_code, result.stderr) == (0, "")


def test_60_rooms_and_8_robots_fit_the_goal_cap(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The size the planner is meant to reach: the single encoding passes every cap."""
    monkeypatch.chdir(tmp_path)
    doc = many_goal_rooms(60, 8)
    doc["planner"] = {"encoding": "single"}
    write_yaml(tmp_path / "scenario.yaml", doc)
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert (result.exit_code, result.stderr) == (0, "")


def test_a_cap_is_lifted_by_its_environment_variable(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_case(next(c for c in CASES if c.id == "speed-1e-5"), tmp_path)
    monkeypatch.setenv("TMPNAV_MAX_MOVE_STEPS", "3200026")
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert (result.exit_code, result.stderr) == (0, "")


@pytest.mark.parametrize("value", ["lots", "-5", "0", "1.5", "inf"])
def test_a_bad_cap_in_the_environment_is_one_line(value: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    write_yaml(tmp_path / "scenario.yaml", base_scenario())
    monkeypatch.setenv("TMPNAV_MAX_MAP_CELLS", value)
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert result.exit_code == 2
    assert result.stderr == (
        f"error: environment variable TMPNAV_MAX_MAP_CELLS={value!r} is not a positive whole number; "
        "expected a cap such as 64000000 (the default)\n"
    )


# ------------------------------------------------------------------- (9) YAML 1.2 numbers


def test_scientific_notation_is_a_number_in_scenarios_and_ros_maps(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """YAML 1.1 reads 1e-3 as a string (a float needs a dot): it used to be refused with
    "'1e-3' is not a number". tmpnav reads YAML 1.2 numbers."""
    monkeypatch.chdir(tmp_path)
    doc = base_scenario()
    base_as_ros_map(doc, tmp_path)
    doc["models"] = {"dt": "DT", "motion_noise": {"alpha1": "A1", "alpha2": "1e-3"}}  # a quoted one too
    scenario = write_yaml(tmp_path / "scenario.yaml", doc)
    scenario.write_text(scenario.read_text().replace("DT", "25e-2").replace("A1", "1E-2"))
    # the map YAML with its resolution in scientific notation
    write_yaml(tmp_path / "map.yaml", ros_map_yaml(resolution="RES"))
    (tmp_path / "map.yaml").write_text((tmp_path / "map.yaml").read_text().replace("RES", "1e-1"))
    assert "resolution: 1e-1\n" in (tmp_path / "map.yaml").read_text()
    assert "dt: 25e-2\n" in scenario.read_text()
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert (result.exit_code, result.stderr) == (0, ""), result.stderr
    from tmpnav.scenario import load

    loaded = load(scenario)
    assert (loaded.models.dt, loaded.models.motion_noise[:2]) == (0.25, (0.01, 0.001))
    assert loaded.map.resolution == 0.1  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("literal", "value"),
    [("1e3", 1000), ("010", 10), ("0o17", 15), ("0x1F", 31), ("1.0e+3", 1000)],
)
def test_integers_follow_yaml_1_2(literal: str, value: int, tmp_path: Path) -> None:
    from tmpnav.scenario import load

    doc = base_scenario()
    text = write_yaml(tmp_path / "s.yaml", doc).read_text().replace("samples: 200", f"samples: {literal}")
    (tmp_path / "s.yaml").write_text(text)
    assert load(tmp_path / "s.yaml").roadmap.samples == value


def test_yaml_1_1_booleans_are_names(tmp_path: Path) -> None:
    """`on`, `no`, `yes` are strings in YAML 1.2: a room may be called `no` (Norway)."""
    from tmpnav.scenario import load

    text = write_yaml(tmp_path / "s.yaml", base_scenario()).read_text()
    (tmp_path / "s.yaml").write_text(text.replace("name: hall", "name: no"))
    assert [r.name for r in load(tmp_path / "s.yaml").rooms] == ["A", "B", "no"]


@pytest.mark.parametrize("key", ["\x1e", "a\nb", "\u2028", "x\u202ey", "k" * 500])
def test_a_key_never_breaks_the_one_line_message(key: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Found by the fuzzer: an unknown key holding a record separator (which Python's
    splitlines, and some terminals, take for a line break) was printed as it was."""
    monkeypatch.chdir(tmp_path)
    doc = base_scenario()
    doc[key] = 0
    item(doc, "robots", "r1")[key] = 1
    write_yaml(tmp_path / "scenario.yaml", doc)
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    problems = reported(result.exit_code, result.stdout, result.stderr)  # each line an error: line
    assert len(problems) == 2 == len(result.stderr.splitlines())
    assert all(len(p.rest) < 300 for p in problems)


OPEN_FLOOR = """\
name: open-floor
map: {bounds: [0, 0, 100, 100], resolution: 0.1}
rooms:
  - {name: A, polygon: [[40, 40], [45, 40], [45, 45], [40, 45]]}
  - {name: B, polygon: [[55, 55], [60, 55], [60, 60], [55, 60]]}
robots:
  - {name: r1, pose: [50, 50, 0]}
models:
  range_sensor: {range: 12}
goals: {visit: [A, B]}
"""


def test_a_range_sensor_that_sees_no_wall_is_refused_and_nothing_is_written(tmp_path: Path) -> None:
    """An open floor whose walls are 40 m from every start and room: a 12 m lidar never returns."""
    scenario = tmp_path / "open.yaml"
    scenario.write_text(OPEN_FLOOR)
    result = CliRunner().invoke(cli, ["plan", str(scenario), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert (
        len(lines) == 1 and "models.range_sensor.range: 12 m reaches no wall from any robot's start or room" in lines[0]
    )
    assert "the nearest wall is 40" in lines[0] and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()
