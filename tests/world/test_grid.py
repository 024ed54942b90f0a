"""The occupancy grid: rasterised walls, obstacles and doors, clearance, collision and line of sight.

Conventions under test (grid.py): cell (i, j) covers x in [x0 + j r, x0 + (j+1) r) and
y in [y0 + i r, y0 + (i+1) r), row 0 is the lowest y, everything outside is occupied, and
a disc of radius rho at p is free when the clearance of p's cell is >= rho + r.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.scenario.helpers import base_scenario, build_world, item
from tmpnav.types import PolygonMap
from tmpnav.world.build import World, rasterize
from tmpnav.world.geometry import distance_to_segment
from tmpnav.world.grid import OccupancyGrid, clearance, line_of_sight, line_of_sight_traced

R = 0.1  # cell size of every grid below


def world_of(grid: OccupancyGrid) -> World:
    """A World around a bare grid (no rooms, no landmarks)."""
    return World(grid, clearance(grid), (), (), np.zeros((0, 2)), "test")


@pytest.fixture(scope="module")
def base_world(tmp_path_factory: pytest.TempPathFactory) -> World:
    return build_world(tmp_path_factory.mktemp("base"))[1]


# --------------------------------------------------------------------------- cells


def test_cells_run_from_the_lower_left_corner() -> None:
    grid = OccupancyGrid(np.zeros((3, 4), dtype=bool), origin=(-1.0, 2.0), resolution=0.5)
    assert grid.extent == (-1.0, 2.0, 1.0, 3.5)
    xs, ys = grid.cell_centers()
    assert xs.tolist() == [-0.75, -0.25, 0.25, 0.75]
    assert ys.tolist() == [2.25, 2.75, 3.25]
    i, j, inside = grid.cells(np.array([[-1.0, 2.0], [0.99, 3.49], [0.1, 2.6], [1.0, 2.0], [-1.01, 3.0]]))
    assert i[:3].tolist() == [0, 2, 1] and j[:3].tolist() == [0, 3, 2]
    assert inside.tolist() == [True, True, True, False, False]  # the upper/right edges are outside


def test_outside_the_grid_is_occupied() -> None:
    grid = OccupancyGrid(np.zeros((2, 2), dtype=bool), origin=(0.0, 0.0), resolution=1.0)
    points = np.array([[0.5, 0.5], [-0.1, 0.5], [0.5, 2.0], [1.9, 1.9]])
    assert grid.is_occupied(points).tolist() == [False, True, True, False]
    # any leading shape: (2, 2, 2) points -> (2, 2)
    assert grid.is_occupied(points.reshape(2, 2, 2)).shape == (2, 2)


# --------------------------------------------------------------------------- rasterisation


def test_walls_are_thick_polylines_and_obstacles_are_filled() -> None:
    spec = PolygonMap(
        bounds=(0.0, 0.0, 2.0, 1.0),
        resolution=R,
        wall_thickness=0.15,
        walls=(((0.5, 0.5), (1.5, 0.5)),),
        obstacles=(((0.0, 0.0), (0.3, 0.0), (0.3, 0.3), (0.0, 0.3)),),
    )
    grid = rasterize(spec)
    assert grid.shape == (10, 20) and grid.origin == (0.0, 0.0)
    occ = grid.occupied
    # the wall: cell centres within 0.075 m of the segment, round caps included
    # (rows 4, 5 have centres y = 0.45, 0.55; columns 4..15 have centres x = 0.45..1.55)
    wall = np.zeros_like(occ)
    wall[4:6, 4:16] = True
    # the obstacle: the 3 x 3 cells whose centres lie inside the 0.3 m square
    obstacle = np.zeros_like(occ)
    obstacle[0:3, 0:3] = True
    assert np.array_equal(occ, wall | obstacle)


def test_grid_size_ignores_floating_point_noise_in_the_bounds() -> None:
    # (0.2 - -2.7) / 0.1 = 29.000000000000004 used to make 30 columns, a grid wider than the map
    spec = PolygonMap(bounds=(-2.7, 0.0, 0.2, 1.0), resolution=R, wall_thickness=0.15, walls=(), obstacles=())
    grid = rasterize(spec)
    assert grid.shape == (10, 29)
    assert grid.extent == pytest.approx((-2.7, 0.0, 0.2, 1.0))


def test_base_map(base_world: World) -> None:
    grid = base_world.grid
    assert grid.shape == (60, 100)
    occupied = lambda *p: bool(grid.is_occupied(np.array(p, dtype=float))[0])  # noqa: E731
    assert occupied([5.0, 1.5])  # the table
    assert occupied([4.0, 3.0])  # the wall between room A and the hall
    assert occupied([5.0, 4.5])  # the wall between rooms A and B
    assert not occupied([2.5, 3.0])  # door-A
    assert not occupied([7.5, 3.0])  # door-B
    assert not occupied([2.5, 4.5])  # inside room A


# --------------------------------------------------------------------------- doors


def test_an_open_door_is_carved_through_a_wall(tmp_path: Path) -> None:
    doc = base_scenario()
    doc["map"]["walls"][1:4] = [[[0, 3], [10, 3]]]  # one wall with no gaps: only the doors open it
    _, world = build_world(tmp_path, doc)
    on_door = np.array([[2.05, 3.0], [2.5, 3.0], [2.95, 3.0], [7.5, 2.95], [7.5, 3.05]])
    assert not world.grid.is_occupied(on_door).any()
    assert world.grid.is_occupied(np.array([[1.5, 3.0], [4.0, 3.0], [8.5, 3.0]])).all()  # the wall elsewhere
    assert world.is_free(np.array([[2.5, 3.0]]), 0.25)[0]  # a robot fits through


def test_a_closed_door_is_a_wall(tmp_path: Path) -> None:
    doc = base_scenario()
    item(doc, "doors", "door-B")["state"] = "closed"
    _, world = build_world(tmp_path, doc)
    across = np.array([[7.0, 3.0], [7.5, 2.97], [7.5, 3.03], [8.0, 3.0]])
    assert world.grid.is_occupied(across).all()
    assert not world.line_of_sight(np.array([[7.5, 2.0]]), np.array([[7.5, 4.0]]))[0]


# --------------------------------------------------------------------------- clearance


def test_clearance_is_the_distance_to_the_nearest_occupied_cell_or_the_border() -> None:
    occupied = np.zeros((5, 7), dtype=bool)
    occupied[2, 3] = True
    c = clearance(OccupancyGrid(occupied, (0.0, 0.0), R))
    assert c[2, 3] == 0.0
    assert c[2, 5] == pytest.approx(2 * R)  # two cells from the occupied one
    assert c[3, 4] == pytest.approx(np.sqrt(2) * R)
    assert c[0, 0] == pytest.approx(R)  # the border counts as occupied: nothing leaves the map
    assert c[2, 1] == pytest.approx(2 * R)  # tie between the obstacle and the left border
    assert c.shape == occupied.shape


def test_is_free_keeps_a_disc_of_the_radius_plus_one_cell_away_from_walls() -> None:
    occupied = np.zeros((40, 40), dtype=bool)
    occupied[:, 20] = True  # a wall at x in [2.0, 2.1)
    world = world_of(OccupancyGrid(occupied, (0.0, 0.0), R))
    # cell centres left of the wall: x = 1.95 - k r; clearance = (k + 1) r
    xs = np.array([1.55, 1.65, 1.75])  # clearances 0.5, 0.4, 0.3 (row 20 is far from the border)
    points = np.column_stack([xs, np.full(3, 2.05)])
    assert world.is_free(points, 0.3).tolist() == [True, True, False]  # needs clearance >= 0.4
    assert world.is_free(points, 0.4).tolist() == [True, False, False]
    assert not world.is_free(np.array([[2.05, 2.05]]), 0.01)[0]  # in the wall
    assert not world.is_free(np.array([[-1.0, 2.0]]), 0.01)[0]  # outside the map
    assert world.is_free(points.reshape(3, 1, 2), 0.3).shape == (3, 1)


# --------------------------------------------------------------------------- line of sight


def test_line_of_sight_ignores_the_cells_next_to_either_end() -> None:
    occupied = np.zeros((20, 40), dtype=bool)
    occupied[:, 10] = True  # a wall at x in [1.0, 1.1)
    grid = OccupancyGrid(occupied, (0.0, 0.0), R)
    clear = clearance(grid)
    a = np.array([[0.5, 1.0], [1.05, 1.0], [0.5, 1.0]])  # the second one is mounted on the wall
    b = np.array([[3.0, 1.0], [3.0, 1.0], [0.9, 1.0]])
    expected = [False, True, True]
    assert line_of_sight(grid, a, b).tolist() == expected
    assert line_of_sight_traced(grid, clear, a, b).tolist() == expected


def occupied_centres(world: World) -> np.ndarray:
    i, j = np.nonzero(world.grid.occupied)
    xs, ys = world.grid.cell_centers()
    return np.column_stack([xs[j], ys[i]])


def test_sampled_and_sphere_traced_line_of_sight_agree(base_world: World) -> None:
    """On random segments between free points of the base map, the sphere-traced line of
    sight (fast, used by the oracle) gives the answer of the half-cell sampling; they may
    differ only on segments that clip the corner of an occupied cell."""
    rng = np.random.default_rng(7)
    points = rng.uniform((0.0, 0.0), (10.0, 6.0), size=(4000, 2))
    points = points[~base_world.grid.is_occupied(points)]
    a, b = points[:1200], points[1200:2400]
    sampled = base_world.line_of_sight_sampled(a, b)
    traced = base_world.line_of_sight(a, b)
    assert 0.2 < sampled.mean() < 0.8  # a mix of visible and hidden segments
    assert (sampled == traced).mean() > 0.99

    centres = occupied_centres(base_world)
    nearest = np.array([distance_to_segment(centres, a[k], b[k]).min() for k in range(len(a))])
    # a segment farther than half a cell diagonal from every occupied centre touches no occupied cell
    far = nearest > R / np.sqrt(2)
    assert sampled[far].all() and traced[far].all()
    assert (nearest[sampled != traced] <= R / np.sqrt(2)).all()


def test_line_of_sight_across_the_base_map(base_world: World) -> None:
    a = np.array([[1.0, 1.5], [1.0, 1.5], [2.5, 1.5], [2.5, 4.5]])
    b = np.array([[3.5, 1.5], [8.0, 1.5], [2.5, 4.5], [7.5, 4.5]])
    # open hall; across the table; through door-A; through the wall between A and B
    expected = [True, False, True, False]
    assert base_world.line_of_sight(a, b).tolist() == expected
    assert base_world.line_of_sight_sampled(a, b).tolist() == expected


def test_an_open_door_is_exactly_as_wide_as_declared() -> None:
    """A 1 m door carved through a solid wall: free only between its two ends."""
    from tmpnav.world.grid import fill_segment

    grid = np.zeros((40, 60), dtype=bool)  # 3 m x 2 m at 5 cm
    og = OccupancyGrid(grid, (0.0, 0.0), 0.05)
    xs, ys = og.cell_centers()
    fill_segment(grid, xs, ys, np.array([0.0, 1.0]), np.array([3.0, 1.0]), 0.15, True)
    fill_segment(grid, xs, ys, np.array([1.0, 1.0]), np.array([2.0, 1.0]), 0.35, False, flat_caps=True)
    row = grid[int(1.0 / 0.05)]
    free = xs[~row]
    assert free.min() >= 1.0 and free.max() <= 2.0
    assert free.max() - free.min() == pytest.approx(0.95)  # cell centres from 1.025 to 1.975 m
    world = world_of(og)
    door = np.array([[1.5, 1.0]])
    assert world.is_free(door, 0.3)[0] and not world.is_free(door, 0.5)[0]
