"""Import a ROS map_server map (YAML + image) as an occupancy grid.

Pixel values follow map_server: with ``negate: 0`` the occupancy probability of a pixel
is p = (255 - value) / 255 (white free, black occupied), with ``negate: 1`` it is
value / 255. ``trinary`` and ``scale``: p > occupied_thresh is occupied, p < free_thresh
is free, anything else (unknown, or a grey level in between) counts as occupied, as does
a transparent pixel. ``raw``: the pixel value itself is the occupancy in percent (0 free,
100 occupied), other values (such as 255, unknown) are occupied.

Images of 16 bits per pixel (a PGM with maxval above 255, a 16-bit PNG) are scaled to
0..255 by their maximum value first; other pixel formats (32-bit or floating-point TIFF)
are refused with the reason, never misread.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from scipy import ndimage

from tmpnav.errors import Problem
from tmpnav.scenario import display_path
from tmpnav.scenario.limits import MAP_CELLS
from tmpnav.types import RosMap
from tmpnav.world.grid import OccupancyGrid


class MapImageError(Exception):
    """The image of a ROS map cannot be used; carries the problem to report."""

    def __init__(self, problem: Problem):
        self.problem = problem
        super().__init__(str(problem))


#: image modes with 8 bits per channel: PIL converts them to grey (and alpha)
EIGHT_BIT = frozenset({"1", "L", "LA", "La", "P", "PA", "RGB", "RGBA", "RGBa", "RGBX", "CMYK", "YCbCr"})
#: 16-bit grey: PNG opens as I;16, a PGM with maxval above 255 as I scaled to 0..65535
SIXTEEN_BIT = frozenset({"I;16", "I;16B", "I;16L", "I;16N"})
SIXTEEN_BIT_FORMATS = frozenset({"PPM", "PNG"})


@contextmanager
def _own_size_cap() -> Iterator[None]:
    """PIL's decompression-bomb guard off: the map_cells cap, checked on the header
    before any pixel is decoded, replaces it (and PIL's warning never reaches users)."""
    from PIL import Image

    saved = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = None
    try:
        yield
    finally:
        Image.MAX_IMAGE_PIXELS = saved


def read_image(spec: RosMap) -> np.ndarray:
    """Grey levels (rows, cols) as float32 0..255 whatever the bit depth, and
    transparency as NaN. The image's size is checked against the map_cells cap first."""
    from PIL import Image, UnidentifiedImageError

    where = display_path(spec.yaml_path)
    image = display_path(spec.image_path)
    if not spec.image_path.is_file():
        why = "is not a regular file" if spec.image_path.exists() else "not found"
        raise MapImageError(Problem(where, "image", f"image file {why}: {image}"))
    try:
        with _own_size_cap(), Image.open(spec.image_path) as img:
            cols, rows = img.size
            cells = float(cols) * float(rows)
            if cells > MAP_CELLS.value():
                message = f"{image} has {cols} x {rows} pixels: " + MAP_CELLS.refusal(
                    cells, "a smaller image, cropped to the building"
                )
                raise MapImageError(Problem(where, "image", message))
            img.load()
            grey = _grey_levels(img, spec, where, image)
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as err:
        raise MapImageError(Problem(where, "image", f"cannot read image {image}: {err}")) from None
    if grey.size == 0:
        raise MapImageError(Problem(where, "image", "image is empty"))
    return grey


def _grey_levels(img: Any, spec: RosMap, where: str, image: str) -> np.ndarray:
    """An opened PIL image as grey levels 0..255 (float32), NaN where transparent.

    8-bit images average their colour channels (as map_server does); 16-bit grey images
    are scaled by their maximum value, so a 16-bit map means what its 8-bit copy means.
    """
    mode = img.mode
    if mode in SIXTEEN_BIT or (mode == "I" and img.format in SIXTEEN_BIT_FORMATS):
        if spec.mode == "raw":
            raise MapImageError(
                Problem(where, "mode", f"raw needs an 8-bit image (pixel values 0..100); {image} has 16-bit pixels")
            )
        return np.asarray(img, dtype=np.float32) * np.float32(255.0 / 65535.0)
    if mode not in EIGHT_BIT:
        raise MapImageError(
            Problem(
                where,
                "image",
                f"{image} has pixels of mode {mode} ({img.format}); expected 8- or 16-bit grey levels "
                "(PGM or PNG, as map_saver writes)",
            )
        )
    has_alpha = mode in ("RGBA", "LA", "La", "PA", "RGBa") or (mode == "P" and "transparency" in img.info)
    pixels = np.asarray(img.convert("RGBA" if has_alpha else "RGB"))
    grey = pixels[..., :3].sum(axis=2, dtype=np.uint16).astype(np.float32) / np.float32(3.0)
    if has_alpha:
        grey[pixels[..., 3] == 0] = np.nan
    return grey


def occupancy_from_image(grey: np.ndarray, spec: RosMap) -> np.ndarray:
    """Occupied cells (rows, cols) with row 0 at the image's top row (not yet flipped)."""
    unknown = np.isnan(grey)
    value = np.nan_to_num(grey, nan=0.0)
    if spec.mode == "raw":
        free = (value < spec.free_thresh * 100.0) & ~unknown
        return ~free
    p = value / 255.0 if spec.negate else (255.0 - value) / 255.0
    free = (p < spec.free_thresh) & ~unknown
    return ~free  # occupied, unknown and in-between grey levels all block


def load_ros_map(spec: RosMap) -> OccupancyGrid:
    """The ROS map as an :class:`OccupancyGrid` (row 0 = lowest y, as the grid expects), its
    specks up to ``spec.despeckle`` wide cleared (:func:`specks`)."""
    occupied = occupancy_from_image(read_image(spec), spec)
    if spec.despeckle > 0:
        occupied &= ~specks(occupied, spec.despeckle, spec.resolution)
    return OccupancyGrid(
        occupied=np.ascontiguousarray(occupied[::-1]),
        origin=(spec.origin[0], spec.origin[1]),
        resolution=spec.resolution,
    )


#: the width (m) of the specks ``tmpnav rooms`` clears and the chance constraint's error counts
SPECK_WIDTH = 0.1


def speck_count(occupied: np.ndarray, width: float, resolution: float) -> int:
    """How many specks (:func:`specks`) the map has."""
    return _specks(occupied, width, resolution)[1]


def specks(occupied: np.ndarray, width: float, resolution: float) -> np.ndarray:
    """The cells of the map's specks: groups of occupied cells (8-connected) whose extent along
    each axis is at most ``width`` (m), with free cells all around them (not on the image's edge).
    On a map made by SLAM most are noise (a reflection, a person mapped in passing), and every path
    must pass them; a thin pole is one too, which is why clearing them is the scenario's choice
    (``map.despeckle``; 0 keeps them)."""
    return _specks(occupied, width, resolution)[0]


def _specks(occupied: np.ndarray, width: float, resolution: float) -> tuple[np.ndarray, int]:
    """:func:`specks`' cells and how many specks they are."""
    out, found = np.zeros_like(occupied), 0
    cells = math.floor(width / resolution + 1e-9)
    if cells < 1:
        return out, found
    labels, _ = ndimage.label(occupied, structure=np.ones((3, 3), dtype=bool))
    rows, cols = occupied.shape
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        r, c = box
        small = r.stop - r.start <= cells and c.stop - c.start <= cells
        inside = r.start > 0 and c.start > 0 and r.stop < rows and c.stop < cols
        if small and inside:
            out[box] |= labels[box] == k
            found += 1
    return out, found
