"""show and roadmap draw a ROS map's known free space, not the unknown around it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tmpnav.pipeline import load_world
from tmpnav.report.figures import free_extent, scenario_extent
from tmpnav.world.grid import OccupancyGrid

ROOT = Path(__file__).resolve().parents[2]


def test_free_extent_is_the_free_space_plus_a_margin() -> None:
    occupied = np.ones((200, 300), dtype=bool)
    occupied[20:60, 30:100] = False  # 3.5 m x 2 m of free space, from x = -0.5 m, y = 1 m
    occupied[150, 250] = False  # a speck of free space in the unknown
    grid = OccupancyGrid(occupied, (-2.0, 0.0), 0.05)
    assert free_extent(grid, margin=1.0) == pytest.approx((-1.5, 0.0, 4.0, 4.0))
    assert free_extent(OccupancyGrid(np.ones((10, 10), dtype=bool), (0.0, 0.0), 1.0)) == (0.0, 0.0, 10.0, 10.0)


def test_scenario_extent_covers_what_the_scenario_places() -> None:
    scenario, world = load_world(ROOT / "configs" / "office-ros.yaml")
    x0, y0, x1, y1 = scenario_extent(scenario, world)  # type: ignore[misc]
    gx0, gy0, gx1, gy1 = world.grid.extent
    assert gx0 <= x0 < 0.5 and gy0 <= y0 < 0.5 and x1 <= gx1 and y1 <= gy1
    for room in scenario.rooms:
        xy = np.array(room.polygon)
        assert (xy[:, 0] >= x0).all() and (xy[:, 0] <= x1).all() and (xy[:, 1] >= y0).all() and (xy[:, 1] <= y1).all()
    polygonal, world = load_world(ROOT / "configs" / "corridor.yaml")
    assert scenario_extent(polygonal, world) is None  # a polygonal map's bounds are the user's choice
