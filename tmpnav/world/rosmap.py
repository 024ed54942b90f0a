"""Import a ROS map_server map (YAML + image) as an occupancy grid.

Pixel values follow map_server: with ``negate: 0`` the occupancy probability of a pixel
is p = (255 - value) / 255 (white free, black occupied), with ``negate: 1`` it is
value / 255. ``trinary`` and ``scale``: p > occupied_thresh is occupied, p < free_thresh
is free, anything else (unknown, or a grey level in between) counts as occupied, as does
a transparent pixel. ``raw``: the pixel value itself is the occupancy in percent (0 free,
100 occupied), other values (such as 255, unknown) are occupied.
"""

from __future__ import annotations

import numpy as np

from tmpnav.errors import Problem
from tmpnav.scenario import display_path
from tmpnav.types import RosMap
from tmpnav.world.grid import OccupancyGrid


class MapImageError(Exception):
    """The image of a ROS map cannot be used; carries the problem to report."""

    def __init__(self, problem: Problem):
        self.problem = problem
        super().__init__(str(problem))


def read_image(spec: RosMap) -> np.ndarray:
    """Grey levels (rows, cols) as float 0..255, and transparency as NaN."""
    from PIL import Image, UnidentifiedImageError

    where = display_path(spec.yaml_path)
    if not spec.image_path.is_file():
        raise MapImageError(Problem(where, "image", f"image file not found: {display_path(spec.image_path)}"))
    try:
        with Image.open(spec.image_path) as img:
            img.load()
            has_alpha = img.mode in ("RGBA", "LA") or (img.mode == "P" and "transparency" in img.info)
            rgba = np.asarray(img.convert("RGBA" if has_alpha else "RGB"), dtype=float)
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as err:
        raise MapImageError(
            Problem(where, "image", f"cannot read image {display_path(spec.image_path)}: {err}")
        ) from None
    grey = rgba[..., :3].mean(axis=2)
    if has_alpha:
        grey[rgba[..., 3] == 0] = np.nan
    if grey.size == 0:
        raise MapImageError(Problem(where, "image", "image is empty"))
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
    """The ROS map as an :class:`OccupancyGrid` (row 0 = lowest y, as the grid expects)."""
    occupied = occupancy_from_image(read_image(spec), spec)
    return OccupancyGrid(
        occupied=np.ascontiguousarray(occupied[::-1]),
        origin=(spec.origin[0], spec.origin[1]),
        resolution=spec.resolution,
    )
