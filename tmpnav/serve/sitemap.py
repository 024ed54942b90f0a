"""The site as the live view draws it: its bounds, rooms, doors, landmarks and stations as plain
JSON, and its occupancy grid as a PNG image."""

from __future__ import annotations

import functools
import io
from typing import Any

import numpy as np

from tmpnav.serve.site import Site


def site_geometry(site: Site) -> dict[str, Any]:
    """The site's geometry in the map frame (m, rad)."""
    s = site.scenario
    x0, y0, x1, y1 = site.world.grid.extent
    return {
        "name": s.name,
        "description": s.description,
        "bounds": [x0, y0, x1, y1],
        "rooms": [{"name": r.name, "polygon": [list(map(float, p)) for p in r.polygon]} for r in s.places],
        "doors": [
            {"name": d.name, "segment": [list(map(float, p)) for p in d.segment], "open": d.open} for d in s.doors
        ],
        "landmarks": [{"name": m.name, "kind": m.kind, "position": list(map(float, m.position))} for m in s.landmarks],
        "stations": [
            {"name": j.room, "pose": list(map(float, j.pose)), "service": j.service}
            for j in s.goals.jobs
            if j.pose is not None
        ],
        "robots": [{"name": r.name, "start": [r.pose.x, r.pose.y, r.pose.theta], "radius": r.radius} for r in s.robots],
    }


@functools.cache
def _png(site_id: int, occupied: bytes, shape: tuple[int, int]) -> bytes:
    from PIL import Image

    grid = np.frombuffer(occupied, dtype=bool).reshape(shape)
    pixels = np.where(grid[::-1], 60, 255).astype(np.uint8)  # row 0 of the grid is the lowest y
    out = io.BytesIO()
    Image.fromarray(pixels, mode="L").save(out, format="PNG", optimize=True)
    return out.getvalue()


def map_png(site: Site) -> bytes:
    """The occupancy grid, one pixel per cell, walls dark, north up."""
    occupied = np.ascontiguousarray(site.world.grid.occupied, dtype=bool)
    return _png(id(site), occupied.tobytes(), occupied.shape)
