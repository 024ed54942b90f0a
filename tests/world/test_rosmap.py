"""ROS map_server maps: a map.yaml and its image, generated here pixel by pixel.

map_server's convention: the image's top row is the highest y, ``origin`` is the pose of the
lower-left pixel, and with ``negate: 0`` the occupancy probability of a grey level v is
p = (255 - v) / 255: white (254) is free, black (0) occupied, 205 (map_saver's unknown)
is neither and tmpnav treats it as occupied.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from tests.scenario.helpers import base_as_ros_map, base_scenario, build_world, ros_map_yaml, write_pgm, write_yaml
from tmpnav.cli import cli
from tmpnav.scenario import load
from tmpnav.types import RosMap
from tmpnav.world.rosmap import MapImageError, load_ros_map, speck_count, specks

FREE, OCCUPIED, UNKNOWN = 254, 0, 205

#: 4 rows x 6 columns, top row first, as in the image file
PIXELS = np.array(
    [
        [OCCUPIED, OCCUPIED, OCCUPIED, OCCUPIED, OCCUPIED, OCCUPIED],
        [OCCUPIED, FREE, FREE, UNKNOWN, FREE, OCCUPIED],
        [OCCUPIED, FREE, OCCUPIED, FREE, FREE, UNKNOWN],
        [OCCUPIED, FREE, FREE, FREE, FREE, OCCUPIED],
    ],
    dtype=np.uint8,
)
RESOLUTION = 0.5
ORIGIN = (-1.0, 2.0)


def ros_spec(folder: Path, image: str = "map.pgm", **meta: Any) -> RosMap:
    """Write folder/map.yaml and a scenario naming it; the loader reads map.yaml into a RosMap."""
    write_yaml(folder / "map.yaml", ros_map_yaml(image, resolution=RESOLUTION, origin=[*ORIGIN, 0.0], **meta))
    scenario = {
        "map": {"ros": "map.yaml"},
        "rooms": [{"name": "A", "polygon": [[0, 3], [1, 3], [1, 3.5]]}],
        "robots": [{"name": "r1", "pose": [0.5, 3.2, 0]}],
        "goals": {"visit": ["A"]},
    }
    spec = load(write_yaml(folder / "scenario.yaml", scenario)).map
    assert isinstance(spec, RosMap)
    return spec


def pixel_centres(pixels: np.ndarray) -> np.ndarray:
    """World (x, y) of the centre of every pixel (rows, cols, 2), top row first."""
    rows, cols = pixels.shape
    r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    x = ORIGIN[0] + (c + 0.5) * RESOLUTION
    y = ORIGIN[1] + (rows - 1 - r + 0.5) * RESOLUTION  # the top row is the highest y
    return np.stack([x, y], axis=-1)


def test_trinary_map_matches_the_image_cell_by_cell(tmp_path: Path) -> None:
    write_pgm(tmp_path / "map.pgm", PIXELS)
    grid = load_ros_map(ros_spec(tmp_path))
    assert grid.shape == PIXELS.shape
    assert grid.resolution == RESOLUTION
    assert grid.extent == (-1.0, 2.0, 2.0, 4.0)
    # row 0 of the grid is the lowest y: the image's last row
    assert np.array_equal(grid.occupied, (PIXELS != FREE)[::-1])
    # the same, asked through world coordinates: each pixel centre lands in its own cell
    expected = PIXELS != FREE  # occupied and unknown pixels block
    assert np.array_equal(grid.is_occupied(pixel_centres(PIXELS)), expected)


def test_origin_and_resolution_place_a_point_in_its_cell(tmp_path: Path) -> None:
    write_pgm(tmp_path / "map.pgm", PIXELS)
    grid = load_ros_map(ros_spec(tmp_path))
    # (-0.3, 2.2): column floor((-0.3 + 1) / 0.5) = 1, row floor((2.2 - 2) / 0.5) = 0 -> the image's
    # bottom row (row 3), column 1: free; one cell up (row 2 of the image, column 2) is occupied
    i, j, inside = grid.cells(np.array([[-0.3, 2.2], [0.2, 2.7]]))
    assert (i.tolist(), j.tolist(), inside.tolist()) == ([0, 1], [1, 2], [True, True])
    assert grid.is_occupied(np.array([[-0.3, 2.2], [0.2, 2.7]])).tolist() == [False, True]
    assert grid.is_occupied(np.array([[-1.01, 3.0], [2.0, 3.0], [0.0, 4.0]])).all()  # outside the image


def test_negate_swaps_black_and_white(tmp_path: Path) -> None:
    write_pgm(tmp_path / "map.pgm", 255 - PIXELS.astype(int))  # the same map, drawn inverted
    grid = load_ros_map(ros_spec(tmp_path, negate=1))
    assert np.array_equal(grid.occupied, (PIXELS != FREE)[::-1])


def test_scale_mode_thresholds_grey_levels(tmp_path: Path) -> None:
    # p = (255 - v) / 255: 230 -> 0.098 free, 128 -> 0.50 between the thresholds, 60 -> 0.76 occupied
    grey = np.array([[254, 230, 205, 128, 60, 0]], dtype=np.uint8)
    write_pgm(tmp_path / "map.pgm", grey)
    grid = load_ros_map(ros_spec(tmp_path, mode="scale"))
    assert grid.occupied[0].tolist() == [False, False, True, True, True, True]


def test_thresholds_come_from_map_yaml(tmp_path: Path) -> None:
    grey = np.array([[254, 230, 205, 128, 60, 0]], dtype=np.uint8)
    write_pgm(tmp_path / "map.pgm", grey)
    grid = load_ros_map(ros_spec(tmp_path, free_thresh=0.55, occupied_thresh=0.9))
    assert grid.occupied[0].tolist() == [False, False, False, False, True, True]


def test_raw_mode_reads_occupancy_percent(tmp_path: Path) -> None:
    # the value is the occupancy in percent: below free_thresh (19.6 %) free, 255 unknown
    raw = np.array([[0, 19, 20, 50, 100, 255]], dtype=np.uint8)
    write_pgm(tmp_path / "map.pgm", raw)
    grid = load_ros_map(ros_spec(tmp_path, mode="raw"))
    assert grid.occupied[0].tolist() == [False, False, True, True, True, True]


@pytest.mark.parametrize("mode", ["LA", "RGBA"])
def test_transparent_pixels_are_unknown_and_occupied(tmp_path: Path, mode: str) -> None:
    grey = np.full((2, 3), FREE, dtype=np.uint8)
    alpha = np.array([[255, 0, 255], [255, 255, 0]], dtype=np.uint8)
    if mode == "LA":
        image = Image.fromarray(np.stack([grey, alpha], axis=-1), mode="LA")
    else:
        image = Image.fromarray(np.stack([grey, grey, grey, alpha], axis=-1), mode="RGBA")
    image.save(tmp_path / "map.png")
    grid = load_ros_map(ros_spec(tmp_path, image="map.png"))
    assert np.array_equal(grid.occupied, (alpha == 0)[::-1])


def test_an_rgb_png_is_averaged_to_grey(tmp_path: Path) -> None:
    rgb = np.array([[[254, 254, 254], [0, 0, 0], [254, 0, 254]]], dtype=np.uint8)  # white, black, magenta
    Image.fromarray(rgb, mode="RGB").save(tmp_path / "map.png")
    grid = load_ros_map(ros_spec(tmp_path, image="map.png"))
    assert grid.occupied[0].tolist() == [False, True, True]  # magenta averages to 169: p = 0.34, between


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (None, "image file not found: "),
        (b"P5\n6 4\n255\n" + bytes(5), "image file is truncated"),
        (b"not an image at all", "cannot identify image file"),
    ],
    ids=["missing", "truncated", "garbage"],
)
def test_unreadable_images_are_map_image_errors(tmp_path: Path, content: bytes | None, fragment: str) -> None:
    if content is not None:
        (tmp_path / "map.pgm").write_bytes(content)
    spec = ros_spec(tmp_path)
    with pytest.raises(MapImageError) as info:
        load_ros_map(spec)
    problem = info.value.problem
    assert (Path(problem.file).name, problem.path) == ("map.yaml", "image")
    assert fragment in problem.message


def test_a_scenario_on_a_ros_map_validates(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The base scenario on its own map drawn as a map_server image: exit 0, and the world
    is the one the polygons make."""
    (tmp_path / "polygons").mkdir()
    _, polygon_world = build_world(tmp_path / "polygons")
    doc = base_scenario()
    base_as_ros_map(doc, tmp_path)
    write_yaml(tmp_path / "scenario.yaml", doc)
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(cli, ["validate", "scenario.yaml"])
    assert (result.exit_code, result.stderr) == (0, "")
    assert result.stdout == "scenario.yaml: ok: 3 rooms, 2 doors, 2 landmarks, 2 robots, map 100x60 cells of 0.1 m\n"

    _, ros_world = build_world(tmp_path, doc)
    assert ros_world.grid.extent == polygon_world.grid.extent
    assert np.array_equal(ros_world.grid.occupied, polygon_world.grid.occupied)


# ------------------------------------------------------------------- bit depths and sizes


@pytest.mark.parametrize("maxval", [65535, 4095, 1023])
def test_a_16_bit_pgm_means_what_its_8_bit_copy_means(tmp_path: Path, maxval: int) -> None:
    """A PGM with maxval above 255 has two bytes per pixel; grey levels are read relative to
    maxval, so unknown (205/255) stays unknown instead of turning free."""
    write_pgm(tmp_path / "map.pgm", np.round(PIXELS.astype(float) * maxval / 255), maxval)
    grid = load_ros_map(ros_spec(tmp_path))
    assert np.array_equal(grid.occupied, (PIXELS != FREE)[::-1])


def test_a_16_bit_png_means_what_its_8_bit_copy_means(tmp_path: Path) -> None:
    Image.fromarray(PIXELS.astype(np.uint16) * 257).save(tmp_path / "map.png")
    assert Image.open(tmp_path / "map.png").mode == "I;16"
    grid = load_ros_map(ros_spec(tmp_path, image="map.png"))
    assert np.array_equal(grid.occupied, (PIXELS != FREE)[::-1])


def test_a_mostly_unknown_16_bit_map_stays_mostly_occupied(tmp_path: Path) -> None:
    """The reported case: map_saver's unknown grey in 16 bits read as free (0.6 % occupied
    instead of 94.6 %)."""
    pixels = np.full((40, 50), UNKNOWN, dtype=np.uint16)
    pixels[10:20, 10:20] = FREE
    write_pgm(tmp_path / "map.pgm", pixels * 257, 65535)
    grid = load_ros_map(ros_spec(tmp_path))
    assert grid.occupied.mean() == pytest.approx(1 - 100 / 2000)


@pytest.mark.parametrize(
    ("array", "mode", "fragment"),
    [
        (np.zeros((4, 6), dtype=np.float32), "F", "has pixels of mode F (TIFF); expected 8- or 16-bit grey levels"),
        (np.zeros((4, 6), dtype=np.int32), "I", "has pixels of mode I (TIFF); expected 8- or 16-bit grey levels"),
    ],
    ids=["float", "int32"],
)
def test_other_pixel_formats_are_refused_with_the_reason(
    tmp_path: Path, array: np.ndarray, mode: str, fragment: str
) -> None:
    Image.fromarray(array, mode=mode).save(tmp_path / "map.tiff")
    with pytest.raises(MapImageError) as info:
        load_ros_map(ros_spec(tmp_path, image="map.tiff"))
    assert (info.value.problem.path, fragment in info.value.problem.message) == ("image", True)


def test_raw_mode_needs_an_8_bit_image(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # messages name files relative to the working directory
    write_pgm(tmp_path / "map.pgm", np.zeros((4, 6)), 65535)
    with pytest.raises(MapImageError) as info:
        load_ros_map(ros_spec(tmp_path, mode="raw"))
    assert info.value.problem.path == "mode"
    assert "raw needs an 8-bit image (pixel values 0..100); map.pgm has 16-bit pixels" in info.value.problem.message


@pytest.mark.parametrize("side", [12000, 20000, 100000])
def test_an_image_larger_than_the_cap_is_refused_from_its_header(
    tmp_path: Path, side: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Only the header is read: the file here has no pixel data at all. PIL's own
    decompression-bomb warning or error never reaches the user."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "map.pgm").write_bytes(f"P5\n{side} {side}\n255\n".encode())
    import warnings

    with warnings.catch_warnings(record=True) as caught, pytest.raises(MapImageError) as info:
        warnings.simplefilter("always")
        load_ros_map(ros_spec(tmp_path))
    assert caught == []
    assert info.value.problem.message == (
        f"map.pgm has {side} x {side} pixels: {side * side:,} grid cells; the cap is 64,000,000 "
        f"(a smaller image, cropped to the building, or raise the cap: TMPNAV_MAX_MAP_CELLS={side * side})"
    )


def test_the_map_cells_cap_can_be_lifted_and_lowered(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    write_pgm(tmp_path / "map.pgm", PIXELS)
    spec = ros_spec(tmp_path)
    monkeypatch.setenv("TMPNAV_MAX_MAP_CELLS", "23")
    with pytest.raises(MapImageError, match="24 grid cells; the cap is 23"):
        load_ros_map(spec)
    monkeypatch.setenv("TMPNAV_MAX_MAP_CELLS", "24")
    assert load_ros_map(spec).shape == PIXELS.shape


# ------------------------------------------------------------------- specks


def test_specks_are_small_groups_of_occupied_cells_free_all_around() -> None:
    occupied = np.zeros((12, 12), dtype=bool)
    occupied[0, :] = True  # a wall along the edge
    occupied[3, 3] = True  # one cell
    occupied[6, 6:8] = occupied[7, 7] = True  # three cells, two wide: one speck (8-connected)
    occupied[9, 2:5] = True  # three wide: past 0.1 m at 0.05 m
    occupied[2, 9] = occupied[1, 9] = True  # touches the wall: part of it
    occupied[11, 11] = True  # on the image's edge: kept (what lies beyond is unknown)
    found = specks(occupied, 0.1, 0.05)
    assert set(zip(*np.nonzero(found), strict=True)) == {(3, 3), (6, 6), (6, 7), (7, 7)}
    assert speck_count(occupied, 0.1, 0.05) == 2
    assert not specks(occupied, 0.04, 0.05).any()  # narrower than a cell: none


def test_despeckle_clears_the_specks_of_the_world(tmp_path: Path) -> None:
    doc = base_scenario()
    base_as_ros_map(doc, tmp_path)
    pixels = np.asarray(Image.open(tmp_path / "map.pgm")).copy()
    row, col = next(
        (r, c)
        for r, c in np.argwhere(pixels[2:-2, 2:-2] == 254) + 2
        if (pixels[r - 2 : r + 3, c - 2 : c + 3] == 254).all()
    )
    pixels[row, col] = 0  # a speck in the middle of free space
    write_pgm(tmp_path / "map.pgm", pixels)
    kept = build_world(tmp_path, doc)[1].grid.occupied
    doc["map"]["despeckle"] = 0.1
    cleared = build_world(tmp_path, doc)[1].grid.occupied
    assert kept.sum() == cleared.sum() + 1 and kept[::-1][row, col] and not cleared[::-1][row, col]


def test_despeckle_on_a_polygonal_map_is_one_line(tmp_path: Path) -> None:
    doc = base_scenario()
    doc["map"]["despeckle"] = 0.1
    write_yaml(tmp_path / "scenario.yaml", doc)
    result = CliRunner().invoke(cli, ["validate", str(tmp_path / "scenario.yaml")])
    assert result.exit_code == 2 and len(result.stderr.strip().splitlines()) == 1
    assert "map.despeckle: belongs to ROS maps" in result.stderr
