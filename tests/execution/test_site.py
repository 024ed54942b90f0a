"""The site the simulator scans (tmpnav/execution/site.py): the map exactly, walls off by their
std, clutter clear of the robots' paths, people who occlude and walk, and the ``--site`` form."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tmpnav.execution.scans import ScanSimulator
from tmpnav.execution.site import Site, SiteNoise
from tmpnav.pipeline import load_world
from tmpnav.shipped import configs_dir
from tmpnav.types import RangeSensor
from tmpnav.world import World
from tmpnav.world.grid import OccupancyGrid, clearance

LIDAR = RangeSensor(
    range=12.0, fov=2 * math.pi, beams=60, sigma_range=0.03, min_range=0.1, max_incidence=math.radians(75)
)
RES = 0.05
WALL = 3 * RES  # the corridor's walls are three cells thick: its free space starts there


def corridor(length: float = 60.0, width: float = 8.0, pillar: bool = False) -> World:
    """A corridor ``length`` x ``width`` m of free space inside walls three cells thick."""
    rows, cols = round(width / RES) + 6, round(length / RES) + 6
    occupied = np.zeros((rows, cols), dtype=bool)
    occupied[:3], occupied[-3:], occupied[:, :3], occupied[:, -3:] = True, True, True, True
    if pillar:
        occupied[60:80, 200:230] = True
    grid = OccupancyGrid(occupied, (0.0, 0.0), RES)
    return World(grid, clearance(grid), (), (), np.zeros((0, 2)), "corridor")


def free_poses(world: World, n: int, seed: int = 0, margin: float = 0.5) -> np.ndarray:
    """n poses (n, 3) at cell centres at least ``margin`` from the map's walls, random headings."""
    rng = np.random.default_rng(seed)
    i, j = np.nonzero(world.signed_distance > margin)
    pick = rng.integers(len(i), size=n)
    x0, y0 = world.grid.origin
    return np.column_stack([x0 + (j[pick] + 0.5) * RES, y0 + (i[pick] + 0.5) * RES, rng.uniform(-math.pi, math.pi, n)])


def test_the_site_none_is_the_map_exactly() -> None:
    scenario, world = load_world(configs_dir() / "office-ros.yaml")[:2]
    sensor = scenario.models.range_sensor
    assert sensor is not None
    for w, s in ((world, sensor), (corridor(pillar=True), LIDAR)):
        site, simulator = Site(w, SiteNoise.parse("none"), 3), ScanSimulator(w, s)
        for k, pose in enumerate(free_poses(w, 40)):
            expected = simulator.ranges(pose)[0]
            assert np.array_equal(site.ranges(pose, s.beam_angles(), s, 0.5 * k), expected, equal_nan=True)


def test_walls_are_off_by_about_the_stated_std_and_whole_stretches_move_together() -> None:
    world, std = corridor(), 0.03
    noise = SiteNoise(clutter=0, wall_offset=std, people=0)
    xs = np.arange(1.0, 59.0, 0.25)
    poses = np.column_stack([xs, np.full(xs.size, WALL + 4.0), np.zeros(xs.size)])
    down_up = np.array([-math.pi / 2, math.pi / 2])  # straight at the long walls, 4 m away
    offsets = []
    for session in range(8):
        site = Site(world, noise, session)
        offsets.append(np.array([site.ranges(p, down_up, LIDAR, 0.0) - 4.0 for p in poses]))
    off = np.array(offsets)  # (sessions, poses, 2 walls)
    assert np.isfinite(off).all()
    assert 0.8 * std < off.std() < 1.2 * std
    assert abs(off.mean()) < 0.25 * std
    # 25 cm along a wall its offset hardly changes; 15 m along it is another stretch's
    near = np.corrcoef(off[:, :-1].ravel(), off[:, 1:].ravel())[0, 1]
    far = np.corrcoef(off[:, :-60].ravel(), off[:, 60:].ravel())[0, 1]
    assert near > 0.95 and abs(far) < 0.3


def _box_distance(points: np.ndarray, box: np.ndarray, size: float) -> np.ndarray:
    """Distance (K,) m from points (K, 2) to the square box (x, y, theta) of side ``size``."""
    c, s = math.cos(box[2]), math.sin(box[2])
    d = points - box[:2]
    local = np.abs(np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])) - size / 2
    return np.hypot(*np.maximum(local, 0.0).T)


def test_clutter_keeps_clear_of_the_paths_and_shows_in_scans() -> None:
    world = corridor()
    noise = SiteNoise(clutter=4, wall_offset=0, people=0)
    path = np.column_stack([np.arange(1.0, 59.0, 0.2), np.full(290, WALL + 4.0)])
    site = Site(world, noise, 1, keep_clear=path)
    assert len(site.boxes) == round(4 * site.free_area / 100)
    for box in site.boxes:
        assert _box_distance(path, box, noise.clutter_size).min() >= 0.6
    # polylines are kept clear all along their segments, not only at their points
    lines = [np.array([[1.0, 2.0], [30.0, 6.0]]), np.array([[30.0, 6.0], [59.0, 2.0]])]
    sparse = Site(world, noise, 2, keep_clear=lines)
    along = np.concatenate([a + np.linspace(0, 1, 2000)[:, None] * (b - a) for a, b in lines])
    assert all(_box_distance(along, box, noise.clutter_size).min() >= 0.6 for box in sparse.boxes)
    # the lidar sees the boxes: from the path, beams end short of the map's walls, never beyond them
    simulator, angles = ScanSimulator(world, LIDAR), LIDAR.beam_angles()
    shorter = 0
    for pose in np.column_stack([path[::10], np.zeros(29)]):
        mapped, seen = simulator.ranges(pose)[0], site.ranges(pose, angles, LIDAR, 0.0)
        both = ~np.isnan(mapped) & ~np.isnan(seen)
        assert (seen[both] <= mapped[both] + 1e-9).all()
        shorter += int((seen[both] < mapped[both] - 0.3).sum())
    assert shorter > 50


def test_people_occlude_beams_and_walk_on() -> None:
    world = corridor()
    noise = SiteNoise(clutter=0, wall_offset=0, people=1)  # 480 m²: one person
    site = Site(world, noise, 4)
    here = site.people_at(0.0)
    assert here.shape == (1, 2)
    c = here[0]
    step = site.people_at(0.1)[0] - c
    assert np.hypot(*step) == pytest.approx(0.1, abs=1e-9)  # 1 m/s, away from the line's ends
    walk = step / np.hypot(*step)
    side = np.array([-walk[1], walk[0]])
    if world.signed_distance[world.grid.cells(c + 1.5 * side)[:2]] < 0.3:
        side = -side
    heading = math.atan2(-side[1], -side[0])  # looking back at the person
    radius, zero = noise.person_radius, np.array([0.0])
    assert site.ranges(np.r_[c + 1.5 * side, heading], zero, LIDAR, 0.0)[0] == pytest.approx(1.5 - radius, abs=1e-9)
    # off centre by half the radius: the disc's near side; past the largest incidence: no return
    off = site.ranges(np.r_[c + 1.5 * side + 0.5 * radius * walk, heading], zero, LIDAR, 0.0)[0]
    assert off == pytest.approx(1.5 - radius * math.sqrt(1 - 0.25), abs=1e-9)
    assert math.isnan(site.ranges(np.r_[c + 1.5 * side + 0.98 * radius * walk, heading], zero, LIDAR, 0.0)[0])
    # two seconds on, the person has walked away and the beam reaches the wall behind
    later = site.ranges(np.r_[c + 1.5 * side, heading], zero, LIDAR, 2.0)[0]
    assert np.hypot(*(site.people_at(2.0)[0] - c)) > 2 * radius and later > 1.5 + radius
    # where people are is a function of the seeds and the time only
    again = Site(world, noise, 4)
    assert np.array_equal(again.people_at(7.3), site.people_at(7.3))
    assert not np.array_equal(Site(world, noise, 5).people_at(7.3), site.people_at(7.3))


def test_a_closed_door_closes_on_the_same_site() -> None:
    world = corridor()
    site = Site(world, SiteNoise(wall_offset=0.01), 6)
    grid = world.grid
    closed = grid.occupied.copy()
    closed[:, 600:603] = True
    shut = World(OccupancyGrid(closed, grid.origin, grid.resolution), world.clearance, (), (), world.landmark_xy, "x")
    other = site.with_world(shut)
    assert np.array_equal(other.boxes, site.boxes) and np.array_equal(other.people_at(3.0), site.people_at(3.0))
    assert (other.field[3:-3, 601] < 0).all() and (site.field[3:-3, 601] > 0).all()


def test_the_site_parses_the_command_line_form() -> None:
    assert SiteNoise.parse("none") == SiteNoise.none()
    assert SiteNoise.parse("typical") == SiteNoise()
    assert SiteNoise.parse("clutter=1, people=0") == dataclasses.replace(SiteNoise(), clutter=1.0, people=0.0)
    assert SiteNoise.parse("none,people=5,seed=3") == dataclasses.replace(SiteNoise.none(), people=5.0, seed=3)
    assert SiteNoise.none().exact and not SiteNoise().exact
    assert SiteNoise().text() == (
        "clutter 2 per 100 m² (40 cm boxes), walls off by 3 cm (std), 3 people per 1000 m² walking at 1 m/s"
    )
    for text, words in [
        ("clutr=1", ["clutr", "clutter", "people"]),
        ("clutter=many", ["clutter", "'many'", "number"]),
        ("clutter=-1", ["clutter", ">= 0"]),
        ("wall_offset=2", ["wall_offset", "0.5"]),
        ("person_radius=0", ["person_radius", "> 0"]),
        ("seed=1.5", ["seed", "integer"]),
        ("people=nan", ["people"]),
        ("typical,,people=1", ["empty"]),
        ("people", ["people", "people=VALUE"]),
        ("clutter=1,none", ["'none'", "first"]),
    ]:
        with pytest.raises(ValueError) as e:
            SiteNoise.parse(text)
        message = str(e.value)
        assert "\n" not in message and all(w in message for w in words), message
