"""Room outlines: simple, counter-clockwise polygons along the cells' edges."""

from __future__ import annotations

import numpy as np

from tmpnav.rooms.polygon import is_simple, outline
from tmpnav.world.geometry import polygon_area
from tmpnav.world.grid import OccupancyGrid


def grid(shape: tuple[int, int]) -> OccupancyGrid:
    return OccupancyGrid(np.zeros(shape, dtype=bool), (-1.0, 2.0), 0.1)


def test_a_rectangle_of_cells_is_its_four_corners() -> None:
    mask = np.zeros((20, 30), dtype=bool)
    mask[5:15, 10:25] = True  # rows 5..14 (y 2.5..3.5), columns 10..24 (x 0..1.5)
    polygon = outline(mask, grid(mask.shape))
    assert polygon.shape == (4, 2)
    assert polygon_area(polygon) > 0  # counter-clockwise
    assert np.allclose(sorted(set(polygon[:, 0].round(6))), [0.0, 1.5], atol=0.06)
    assert np.allclose(sorted(set(polygon[:, 1].round(6))), [2.5, 3.5], atol=0.06)
    assert abs(polygon_area(polygon) - 1.5) < 0.1


def test_holes_are_ignored_and_an_l_shape_keeps_its_corner() -> None:
    mask = np.zeros((40, 40), dtype=bool)
    mask[5:35, 5:15] = True
    mask[5:15, 5:35] = True
    mask[8:10, 8:10] = False  # a pillar: a hole in the room
    polygon = outline(mask, grid(mask.shape))
    assert len(polygon) == 6
    assert is_simple(polygon)
    assert abs(polygon_area(polygon) - (30 * 10 + 20 * 10) * 0.01) < 0.25


def test_is_simple() -> None:
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    bowtie = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])
    touching = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])  # a vertex on an edge
    assert is_simple(square)
    assert not is_simple(bowtie)
    assert not is_simple(touching)
