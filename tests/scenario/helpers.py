"""A small valid scenario built in code, and the tools to break it one key at a time.

``base_scenario()`` is the scenario every broken-scenario case starts from::

    y=6 +-------------------+-------------------+
        |  A      printer   |  B                |
        |    r1             |                   |
    y=3 +----door-A---------+--------door-B-----+
        |  hall          [table]        r2      |
        |                               plant   |
    y=0 +---------------------------------------+
        x=0      2  3       5         7  8      x=10

Two rooms (A, B) open onto a hall through two doors; a table stands in the hall; r1 starts
in A, r2 in the hall. Closing door-B walls room B off from both robots.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import numpy as np
import yaml

BASE: dict[str, Any] = {
    "name": "two-rooms-and-hall",
    "map": {
        "bounds": [0, 0, 10, 6],
        "resolution": 0.1,
        "walls": [
            [[0, 0], [10, 0], [10, 6], [0, 6], [0, 0]],
            [[0, 3], [2, 3]],
            [[3, 3], [7, 3]],
            [[8, 3], [10, 3]],
            [[5, 3], [5, 6]],
        ],
        "obstacles": [[[4, 1], [6, 1], [6, 2], [4, 2]]],
    },
    "rooms": [
        {"name": "A", "polygon": [[0.2, 3.2], [4.8, 3.2], [4.8, 5.8], [0.2, 5.8]]},
        {"name": "B", "polygon": [[5.2, 3.2], [9.8, 3.2], [9.8, 5.8], [5.2, 5.8]]},
        {"name": "hall", "polygon": [[0.2, 0.2], [9.8, 0.2], [9.8, 2.8], [0.2, 2.8]]},
    ],
    "doors": [
        {"name": "door-A", "segment": [[2, 3], [3, 3]], "state": "open"},
        {"name": "door-B", "segment": [[7, 3], [8, 3]], "state": "open"},
    ],
    "landmarks": [
        {"name": "printer", "kind": "printer", "position": [1.0, 5.5]},
        {"name": "plant", "kind": "plant", "position": [9.5, 0.5]},
    ],
    "robots": [
        {"name": "r1", "pose": [2.5, 4.5, -1.5708], "radius": 0.25, "speed": 0.5},
        {"name": "r2", "pose": [7.5, 1.5, 1.5708], "radius": 0.25, "speed": "50 cm/s"},
    ],
    "models": {"landmark_sensor": {"range": 4.0, "fov": "360 deg"}},
    "roadmap": {"samples": 200, "instantiations": 2, "seed": 1},
    "goals": {"robots": {"r1": ["B"], "r2": ["A"]}},
}


def base_scenario() -> dict[str, Any]:
    """A fresh deep copy of :data:`BASE`, free to mutate."""
    return copy.deepcopy(BASE)


def item(doc: dict[str, Any], section: str, name: str) -> dict[str, Any]:
    """The item called ``name`` of a named list (``item(doc, "robots", "r1")``)."""
    return next(x for x in doc[section] if x.get("name") == name)


def write_yaml(path: Path, data: Any) -> Path:
    """Dump ``data`` as block-style YAML (keys in insertion order) and return the path."""
    path.write_text(yaml.safe_dump(data, sort_keys=False, default_flow_style=None), encoding="utf-8")
    return path


def write_pgm(path: Path, pixels: np.ndarray, maxval: int = 255) -> Path:
    """Write grey levels (rows, cols) 0..maxval as a binary PGM (P5), top row first, as ROS
    does: one byte per pixel, or two (big-endian) when maxval is above 255."""
    rows, cols = np.shape(pixels)
    data = np.asarray(pixels, dtype=">u2" if maxval > 255 else np.uint8).tobytes()
    path.write_bytes(f"P5\n{cols} {rows}\n{maxval}\n".encode("ascii") + data)
    return path


def ros_map_yaml(image: str = "map.pgm", **overrides: Any) -> dict[str, Any]:
    """The keys of a map_server YAML file with ROS's usual values (``overrides`` replace them;
    an override of None removes the key)."""
    meta: dict[str, Any] = {
        "image": image,
        "resolution": 0.1,
        "origin": [0.0, 0.0, 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        "mode": "trinary",
    }
    meta.update(overrides)
    return {k: v for k, v in meta.items() if v is not None}


def base_as_ros_map(doc: dict[str, Any], folder: Path, maxval: int = 255, **overrides: Any) -> None:
    """Replace the polygonal map of ``doc`` by the same map drawn as a ROS map_server image
    (folder/map.yaml + folder/map.pgm): free 254, occupied 0, like map_saver writes (scaled
    to ``maxval`` for a 16-bit image)."""
    from tmpnav.types import PolygonMap
    from tmpnav.world.build import rasterize

    m = doc["map"]
    grid = rasterize(PolygonMap(tuple(m["bounds"]), m["resolution"], 0.15, m["walls"], m["obstacles"]))
    pixels = np.where(grid.occupied[::-1], 0, 254)  # image rows run from the top (highest y) down
    write_pgm(folder / "map.pgm", pixels * maxval // 255, maxval)
    write_yaml(folder / "map.yaml", ros_map_yaml(**{"resolution": m["resolution"], **overrides}))
    doc["map"] = {"ros": "map.yaml"}


def build_world(folder: Path, doc: dict[str, Any] | None = None):  # type: ignore[no-untyped-def]
    """Write ``doc`` (default: the base scenario) to folder/scenario.yaml, load it and build
    its world without the geometric checks: (Scenario, World)."""
    from tmpnav.scenario import load
    from tmpnav.world import build

    scenario = load(write_yaml(folder / "scenario.yaml", base_scenario() if doc is None else doc))
    return scenario, build(scenario)
