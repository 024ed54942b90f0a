"""Halls split into places (issue 22): a depot-like hall gives aisle places, rooms stay rooms.

Acceptance: on generated depots (an open hall with rows of racks broken by gaps, pillars,
pallets and an office) at least 6 places, each reachable by the placeholder robot, and places
inside every aisle between two rack rows; rooms no larger than ``--max-area`` are not split.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests.rooms.depotgen import Depot, arena, depot
from tests.rooms.mapgen import FREE, OCCUPIED, generate, rect_mask
from tmpnav.rooms.medial import axis_graph, medial_axis
from tmpnav.rooms.places import PlaceParams, lloyd, merge_small, split_hall
from tmpnav.rooms.proposal import Proposal, propose, read_map, working_grid
from tmpnav.rooms.segment import SegmentParams, segment, speckle_cells, speckles
from tmpnav.world.grid import OccupancyGrid

REPO = Path(__file__).resolve().parents[2]


def proposal_of(g: Depot, folder: Path, **params: float) -> Proposal:
    spec, grid = read_map(g.write_ros(folder, "depot"))
    return propose(spec, grid, SegmentParams(**params))  # type: ignore[arg-type]


def aisle_places(p: Proposal, g: Depot, aisle: str) -> tuple[list[str], float]:
    """The places lying at least 60% in ``aisle``, and the share of the aisle they cover."""
    grid = p.segmentation.grid
    inside = rect_mask(g.aisles[aisle], grid.shape, grid.origin, grid.resolution) & ~grid.occupied  # type: ignore[index]
    names, covered = [], 0
    for place in p.places:
        cells = p.segmentation.labels == place.label
        shared = np.count_nonzero(cells & inside)
        if shared >= 0.6 * np.count_nonzero(cells):
            names.append(place.name)
            covered += shared
    return names, covered / np.count_nonzero(inside)


# --------------------------------------------------------------------------- acceptance


@pytest.mark.parametrize("seed", range(5))
def test_a_depot_hall_is_split_into_reachable_aisle_places(seed: int, tmp_path: Path) -> None:
    g = depot(seed)
    p = proposal_of(g, tmp_path)
    assert len(p.places) >= 6
    assert all(place.reachable for place in p.places)
    assert all(place.area <= p.max_area for place in p.places)
    assert [r.name for r in p.rooms if r.hall is None] == ["R1"]  # the office stays a room
    assert g.aisles
    for aisle in g.aisles:
        names, covered = aisle_places(p, g, aisle)
        assert names and covered >= 0.7, f"aisle {aisle}: places {names} cover {covered:.0%}"


def test_places_are_named_hall_by_hall_and_joined_by_connections(tmp_path: Path) -> None:
    p = proposal_of(depot(0), tmp_path)
    assert [h.name for h in p.halls] == ["H1"]
    assert [r.name for r in p.places] == [f"P{k}" for k in range(1, len(p.places) + 1)]
    assert set(p.halls[0].places) == {r.name for r in p.places}
    assert p.connections and p.connections < set(p.doors)
    for name in p.connections:  # between two places of the hall, not a room
        assert all(p.room(label).hall == "H1" for label in p.doors[name].rooms)
    (office_door,) = (p.doors[name] for name in set(p.doors) - p.connections)
    office, place = sorted((p.room(label) for label in office_door.rooms), key=lambda r: r.hall is not None)
    assert place.hall == "H1" and (office.name, office.hall) == ("R1", None)
    assert len(p.robots) == 2 and len(p.goals) == 4 and not {r.room for r in p.robots} & set(p.goals)


def test_connections_carve_nothing_out_of_racks_or_pillars(tmp_path: Path) -> None:
    """World.build carves every open door free: a connection must not cut a pillar or a rack
    (specks of noise it may clear, as a deep door does)."""
    from tmpnav.pipeline import load_world
    from tmpnav.rooms.skeleton import save, skeleton

    g = depot(1)
    p = proposal_of(g, tmp_path)
    target = tmp_path / "s.yaml"
    save(target, skeleton(p, target))
    _, world = load_world(target)
    solid = g.occupied & ~speckles(g.occupied, speckle_cells(g.resolution))
    carved = np.argwhere(solid & ~world.grid.occupied)
    office_door = next(d for name, d in p.doors.items() if name not in p.connections)
    xy = np.array(g.origin) + (carved[:, ::-1] + 0.5) * g.resolution
    assert np.all(np.hypot(*(xy - office_door.centre).T) < 1.0)  # only at the office's doorway


def test_rooms_no_larger_than_max_area_are_not_split(tmp_path: Path) -> None:
    """Maps of rooms: the office and generated buildings give the rooms they gave before."""
    spec, grid = read_map(REPO / "configs" / "office" / "office.yaml")
    office = propose(spec, grid)
    assert not office.halls and [r.name for r in office.rooms] == [f"R{k}" for k in range(1, 9)]
    assert len(office.robots) == 1 and len(office.goals) == 2
    for layout in ("corridor", "bsp"):
        for seed in range(3):
            folder = tmp_path / f"{layout}{seed}"
            spec, grid = read_map(generate(layout, seed).write_ros(folder, "m"))
            p = propose(spec, grid)
            assert not p.halls and not p.connections
            assert np.array_equal(p.segmentation.labels, _cropped(segment(grid).labels, grid, p.segmentation.grid))


def _cropped(labels: np.ndarray, grid: OccupancyGrid, box: OccupancyGrid) -> np.ndarray:
    """``labels`` of ``grid`` within the part ``box`` of it, nothing outside it."""
    top, left = (round((b - a) / grid.resolution) for a, b in zip(grid.origin[::-1], box.origin[::-1], strict=True))
    rows, cols = box.shape
    inside = np.zeros(labels.shape, dtype=bool)
    inside[top : top + rows, left : left + cols] = True
    assert not labels[~inside].any()
    return labels[top : top + rows, left : left + cols]


def test_max_area_decides_what_is_a_hall(tmp_path: Path) -> None:
    g = generate("hall", 2)  # a 231 m² hall with offices along it
    spec, grid = read_map(g.write_ros(tmp_path, "hall"))
    split = propose(spec, grid)
    assert len(split.halls) == 1 and len(split.places) >= 2
    whole = propose(spec, grid, SegmentParams(max_area=1000.0))
    assert not whole.halls and len(whole.rooms) == len(g.truth.rooms)
    joined = propose(spec, grid, SegmentParams(max_rooms=2))  # --max-rooms: rooms as asked, none split
    assert not joined.halls and len(joined.rooms) == 2


def test_a_small_arena_is_one_room_unless_max_area_says_otherwise(tmp_path: Path) -> None:
    """The turtlebot3 sandbox: a hexagon some 5 m across with nine pillars (filled in: they split
    nothing), about 16 m² of floor."""
    from tmpnav.pipeline import load_world
    from tmpnav.rooms.skeleton import save, skeleton

    spec, grid = read_map(arena().write_ros(tmp_path, "arena"))
    assert not propose(spec, grid).halls
    p = propose(spec, grid, SegmentParams(max_area=5.0))
    assert len(p.places) >= 3 and all(place.reachable for place in p.places)
    assert len(p.robots) == 2 and p.connections
    target = tmp_path / "arena-rooms.yaml"
    save(target, skeleton(p, target))
    scenario, _ = load_world(target)  # validates
    assert len(scenario.rooms) == len(p.places)


# --------------------------------------------------------------------------- parts


def test_spurs_into_corners_are_pruned() -> None:
    """The skeleton of a 6 m x 2 m room is its centre line, not a line with four forks."""
    space = np.zeros((60, 140), dtype=bool)
    space[10:50, 10:130] = True
    from scipy import ndimage

    clear = ndimage.distance_transform_edt(space) * 0.05
    axis = medial_axis(space, clear, 0.05)
    assert axis.n_junctions == 0 and axis.n_branches == 1
    rows = axis.cells[:, 0]
    assert rows.min() >= 28 and rows.max() <= 31  # along the middle


def test_axis_graph_finds_junctions_and_branches() -> None:
    cross = np.zeros((11, 11), dtype=bool)
    cross[5, :] = cross[:, 5] = True
    axis = axis_graph(np.argwhere(cross), cross.shape)
    assert axis.n_junctions == 1 and axis.n_branches == 4


def test_an_aisle_between_two_racks_is_one_place() -> None:
    """A hall: an open area below, two racks above with a 3 m aisle between them."""
    from scipy import ndimage

    r = 0.05
    free = np.ones((300, 400), dtype=bool)  # 20 m x 15 m
    free[:, :2] = free[:, -2:] = free[:2] = free[-2:] = False
    free[140:160, 40:360] = False  # rack 1: y 7-8 m
    free[220:240, 40:360] = False  # rack 2: y 11-12 m, so the aisle is y 8-11 m
    clear = ndimage.distance_transform_edt(free) * r
    labels = split_hall(free, clear, r, PlaceParams(max_area=100.0))
    aisle = labels[160:220, 40:360]
    values, counts = np.unique(aisle, return_counts=True)
    assert counts.max() >= 0.9 * aisle.size  # one place holds the aisle
    owner = values[np.argmax(counts)]
    assert np.count_nonzero(labels == owner) <= 1.3 * aisle.size  # and little else


def test_a_large_open_area_is_split_into_equal_places() -> None:
    region = np.ones((100, 400), dtype=bool)
    parts = lloyd(region, region, 4)
    sizes = np.bincount(parts.ravel())[1:]
    assert len(sizes) == 4 and sizes.min() >= 0.7 * sizes.max()


def test_small_places_join_the_neighbour_they_share_most_with() -> None:
    labels = np.array([[1, 1, 1, 2], [1, 1, 1, 2], [3, 3, 3, 3]])
    merged = merge_small(labels, min_cells=3, max_cells=100)
    assert merged[0, 3] == merged[0, 0] and merged[2, 0] == 3


def test_a_robot_too_large_for_any_place_leaves_the_hall_whole() -> None:
    free = np.ones((40, 40), dtype=bool)
    clear = np.full(free.shape, 0.1)  # nowhere a robot of 0.25 m fits
    assert (split_hall(free, clear, 0.05, PlaceParams(max_area=1.0)) == 1).all()


def test_depot_pixels_are_a_map() -> None:
    g = depot(0)
    assert set(np.unique(g.pixels)) <= {FREE, OCCUPIED, 205}
    assert g.racks and all(x1 - x0 >= 3.0 for x0, _, x1, _ in g.racks)


def test_a_large_map_is_segmented_around_its_free_space_on_coarser_cells() -> None:
    occupied = np.ones((2500, 2500), dtype=bool)  # unknown around a 90 m x 100 m building
    occupied[100:1900, 200:2200] = False
    occupied[1001, 1001] = True  # a speck: its block of 2 x 2 cells is occupied
    work = working_grid(OccupancyGrid(occupied, (-5.0, -5.0), 0.05))
    assert work.resolution == pytest.approx(0.1) and work.occupied.size <= 1_000_000
    assert work.origin == pytest.approx((-5.0 + 190 * 0.05, -5.0 + 90 * 0.05))  # 10 cells of margin
    i, j, _ = work.cells(np.array([-5.0 + 1001.5 * 0.05, -5.0 + 1001.5 * 0.05]))
    assert work.occupied[i, j] and np.count_nonzero(~work.occupied) == 900 * 1000 - 1
    small = OccupancyGrid(occupied[:400, :400], (0.0, 0.0), 0.05)
    assert working_grid(small).resolution == 0.05


def test_a_hall_filling_its_box_keeps_every_place() -> None:
    """A rectangular hall has no cell outside it in its box: every cell still gets a place."""
    from scipy import ndimage

    free = np.ones((200, 400), dtype=bool)  # 10 m x 20 m
    clear = ndimage.distance_transform_edt(np.pad(free, 1))[1:-1, 1:-1] * 0.05
    labels = split_hall(free, clear, 0.05, PlaceParams(max_area=60.0))
    assert (labels > 0).all() and labels.max() == 4
