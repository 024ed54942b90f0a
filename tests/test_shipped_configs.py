"""Every scenario shipped in configs/: valid through ``tmpnav validate``, with the sizes promised.

The scenarios of real size (building-*, warehouse-*, sparse-warehouse) are written by
benchmarks/scenarios/generate.py; a test here reruns it and compares the bytes, so an edit
of a generated file by hand (or a generator that is not deterministic) fails.
"""

from __future__ import annotations

import itertools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from tmpnav.cli import cli
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap
from tmpnav.scenario import load
from tmpnav.types import PolygonMap, RosMap, Scenario
from tmpnav.world.geometry import points_in_polygon
from tmpnav.world.visibility import LandmarkVisibility

REPO = Path(__file__).resolve().parent.parent
CONFIGS = REPO / "configs"
GENERATOR = REPO / "benchmarks" / "scenarios" / "generate.py"

#: what `tmpnav validate` says of each shipped scenario; a new file in configs/ must be added here
EXPECTED = {
    "corridor.yaml": "10 rooms, 10 doors, 10 landmarks, 2 robots, map 1000x260 cells of 0.05 m",
    "corridor-2robots.yaml": "10 rooms, 10 doors, 10 landmarks, 2 robots, map 1000x260 cells of 0.05 m",
    "corridor-3robots.yaml": "10 rooms, 10 doors, 10 landmarks, 3 robots, map 1000x260 cells of 0.05 m",
    "corridor-4robots.yaml": "10 rooms, 10 doors, 10 landmarks, 4 robots, map 1000x260 cells of 0.05 m",
    "corridor-6robots.yaml": "10 rooms, 10 doors, 10 landmarks, 6 robots, map 1000x260 cells of 0.05 m",
    "office-ros.yaml": "7 rooms, 0 doors, 4 landmarks, 3 robots, map 480x280 cells of 0.05 m",
    "office-rooms.yaml": "8 rooms, 7 doors, 9 landmarks, 2 robots, map 480x280 cells of 0.05 m",
    "two-rooms.yaml": "3 rooms, 2 doors, 2 landmarks, 2 robots, map 240x160 cells of 0.05 m",
    "building-20.yaml": "20 rooms, 20 doors, 11 landmarks, 2 robots, map 2000x260 cells of 0.05 m",
    "building-2robots.yaml": "72 rooms, 72 doors, 29 landmarks, 2 robots, map 1440x870 cells of 0.05 m",
    "building-4robots.yaml": "72 rooms, 72 doors, 29 landmarks, 4 robots, map 1440x870 cells of 0.05 m",
    "building-8robots.yaml": "72 rooms, 72 doors, 29 landmarks, 8 robots, map 1440x870 cells of 0.05 m",
    "warehouse-2robots.yaml": "45 rooms, 0 doors, 27 landmarks, 2 robots, map 1320x840 cells of 0.05 m",
    "warehouse-4robots.yaml": "45 rooms, 0 doors, 27 landmarks, 4 robots, map 1320x840 cells of 0.05 m",
    "warehouse-8robots.yaml": "45 rooms, 0 doors, 27 landmarks, 8 robots, map 1320x840 cells of 0.05 m",
    "sparse-warehouse.yaml": "8 rooms, 0 doors, 8 landmarks, 3 robots, map 1040x1040 cells of 0.05 m",
    "depot-jobs.yaml": (
        "15 rooms, 28 doors, 9 landmarks, 4 robots, map 640x420 cells of 0.05 m, specks up to 0.1 m cleared"
    ),
}
GENERATED = [
    "building-20.yaml",
    *(f"building-{n}robots.yaml" for n in (2, 4, 8)),
    *(f"warehouse-{n}robots.yaml" for n in (2, 4, 8)),
    "sparse-warehouse.yaml",
]


def scenario(name: str) -> Scenario:
    return load(CONFIGS / name)


def test_every_shipped_config_has_its_expected_sizes() -> None:
    assert sorted(p.name for p in CONFIGS.glob("*.yaml")) == sorted(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_validate_reports_the_promised_sizes(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)
    result = CliRunner().invoke(cli, ["validate", f"configs/{name}"])
    assert (result.exit_code, result.stderr) == (0, "")
    assert result.stdout == f"configs/{name}: ok: {EXPECTED[name]}\n"


def test_the_generator_rewrites_the_shipped_files_byte_for_byte(tmp_path: Path) -> None:
    run = [sys.executable, str(GENERATOR)]
    first = subprocess.run([*run, "--out", str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert first.returncode == 0, first.stderr
    written = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    assert written == sorted(
        [*GENERATED, "warehouse/map.pgm", "warehouse/map.yaml", "sparse-warehouse/map.pgm", "sparse-warehouse/map.yaml"]
    )
    for rel in written:
        assert (tmp_path / rel).read_bytes() == (CONFIGS / rel).read_bytes(), f"configs/{rel} differs"
    check = subprocess.run([*run, "--check"], capture_output=True, text=True, timeout=300)
    assert (check.returncode, check.stderr) == (0, "")


def test_building_20_is_two_rows_of_ten_rooms_off_a_100_m_corridor() -> None:
    sc = scenario("building-20.yaml")
    assert isinstance(sc.map, PolygonMap) and sc.map.bounds == (0, 0, 100, 13)
    sizes = {tuple(np.ptp(np.array(r.polygon), axis=0).round(2)) for r in sc.rooms}
    assert sizes == {(9.8, 4.8)}  # 10 m x 5 m between wall centre lines
    rows = {r.polygon[0][1] for r in sc.rooms}
    assert rows == {0.1, 8.1} and len(sc.rooms) == 20
    assert len(sc.doors) == 20 and all(d.open for d in sc.doors)
    assert all(5 <= lm.position[1] <= 8 for lm in sc.landmarks)  # along the corridor
    assert len(sc.robots) == 2
    assert sorted(sc.goals.visit) == sorted(r.name for r in sc.rooms)


def nearest(points: np.ndarray, landmarks: np.ndarray) -> np.ndarray:
    """Distance (n,) from each point (n, 2) to the nearest landmark (L, 2)."""
    return np.linalg.norm(points[:, None, :] - landmarks[None, :, :], axis=2).min(axis=1)


def starts_in_rooms(sc: Scenario) -> list[str]:
    xy = np.array([[r.pose.x, r.pose.y] for r in sc.robots])
    return [r.name for r in sc.rooms if points_in_polygon(xy, np.array(r.polygon)).any()]


@pytest.mark.parametrize("family", ["building", "warehouse"])
def test_the_robot_variants_share_one_world_and_grow_one_team(family: str) -> None:
    teams = {n: scenario(f"{family}-{n}robots.yaml") for n in (2, 4, 8)}
    for n, sc in teams.items():
        assert len(sc.robots) == n
        assert (sc.map, sc.rooms, sc.doors, sc.landmarks, sc.goals) == (
            teams[8].map,
            teams[8].rooms,
            teams[8].doors,
            teams[8].landmarks,
            teams[8].goals,
        )
        assert sc.robots == teams[8].robots[:n]
        assert starts_in_rooms(sc) == []  # every room to visit needs a real visit
        assert len(sc.goals.visit) == 20


def test_the_office_has_60_rooms_or_more_on_three_corridors_with_sparse_stretches() -> None:
    sc = scenario("building-8robots.yaml")
    assert len(sc.rooms) >= 60
    by_corridor = {c: [r for r in sc.rooms if r.name.startswith(c)] for c in "ABC"}
    assert all(len(v) >= 15 for v in by_corridor.values())
    areas = [np.ptp(np.array(r.polygon), axis=0).prod() for r in sc.rooms]
    assert max(areas) > 3 * min(areas)  # rooms of varied sizes
    lm = np.array([m.position for m in sc.landmarks])
    inside = sum(bool(points_in_polygon(lm, np.array(r.polygon)).any()) for r in sc.rooms)
    assert inside >= 5  # landmarks in some rooms
    # corridor C east of the cross corridor: 20 m of its centre line see no landmark at 5 m
    line_c = np.column_stack([np.linspace(45, 65, 41), np.full(41, 35.25)])
    assert nearest(line_c, lm).min() > 5.0
    # while corridor A is covered along its whole length
    line_a = np.column_stack([np.linspace(1, 71, 141), np.full(141, 7.25)])
    assert nearest(line_a, lm).max() <= 5.0


@pytest.mark.parametrize("name", ["warehouse/map.yaml", "sparse-warehouse/map.yaml"])
def test_the_ros_maps_are_nav2_style_trinary_maps(name: str) -> None:
    spec = yaml.safe_load((CONFIGS / name).read_text())
    assert spec == {
        "image": "map.pgm",
        "mode": "trinary",
        "resolution": 0.05,
        "origin": [-1.0, -1.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    head = (CONFIGS / name).with_name("map.pgm").read_bytes()[:2]
    assert head == b"P5"


def test_the_warehouse_has_40_goal_places_or_more() -> None:
    sc, world = load_world(CONFIGS / "warehouse-2robots.yaml")
    assert isinstance(sc.map, RosMap) and sc.map.resolution == 0.05
    assert len(sc.rooms) >= 40
    kinds = {r.name.rstrip("0123456789sn") for r in sc.rooms}
    assert {"dock", "stage", "a", "pick", "charge"} <= kinds
    assert sum(m.kind == "rack end" for m in sc.landmarks) >= 10
    assert sum(m.kind == "pillar" for m in sc.landmarks) >= 4
    # from the middle of an aisle no landmark is in sight of the landmark sensor
    aisles = np.array([[*np.array(r.polygon).mean(axis=0), 0.0] for r in sc.rooms if r.name[0] == "a"])
    seen = LandmarkVisibility(world, sc.models.landmark_sensor.range).visible(aisles, 2 * math.pi)
    assert len(aisles) == 18 and not seen.any()


def test_the_sparse_warehouse_has_landmarks_only_on_its_south_west_and_east_sides() -> None:
    """Eight tagged pillars at least 7 m apart along three sides of the hall; the middle and
    the north have none, and every place is out of every landmark's range."""
    sc, world = load_world(CONFIGS / "sparse-warehouse.yaml")
    xmin, ymin, xmax, ymax = world.grid.extent
    assert 50 <= xmax - xmin <= 53 and 50 <= ymax - ymin <= 53
    assert len(sc.robots) == 3 and len(sc.rooms) == 8 == len(sc.goals.visit)
    pillars = np.array([m.position for m in sc.landmarks if m.kind == "pillar"])
    assert len(pillars) == len(sc.landmarks) == 8
    gaps = np.linalg.norm(pillars[:, None, :] - pillars[None, :, :], axis=2)
    np.fill_diagonal(gaps, math.inf)
    assert gaps.min(axis=1).min() >= 7.0
    assert all(y < 10 or x < 10 or x > 40 for x, y in pillars)  # south row, west and east columns
    assert not any(15 < x < 35 and y > 15 for x, y in pillars)  # nothing in the middle and north
    centres = np.array([np.array(r.polygon).mean(axis=0) for r in sc.rooms])
    assert nearest(centres, pillars).min() > sc.models.landmark_sensor.range
    spread = max(math.dist(a, b) for a, b in itertools.combinations(centres, 2))
    assert spread > 35  # the places spread over the hall


@pytest.mark.slow
@pytest.mark.parametrize(
    "name", ["building-20.yaml", "building-8robots.yaml", "warehouse-8robots.yaml", "sparse-warehouse.yaml"]
)
def test_the_roadmap_reaches_every_room_with_every_instantiation(name: str) -> None:
    sc, world = load_world(CONFIGS / name)
    roadmap = build_roadmap(world, sc.robots, sc.roadmap)
    assert {k: len(v) for k, v in roadmap.instantiations.items()} == {
        r.name: sc.roadmap.instantiations for r in sc.rooms
    }
