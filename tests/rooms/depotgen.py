"""Open-floor maps with known aisles: a depot hall with rows of racks, for testing how
``tmpnav rooms`` splits a hall into places; and a small arena like the turtlebot3 sandbox.

Modelled on the public nav2 ``depot`` map (a 30 m x 15 m hall, racks, pillars): a hall whose
lower part is an open staging area with pillars and a few pallets, and whose upper part holds
rows of racks running along x. Every rack row is broken by gaps a robot fits through, so the
aisles between rows are joined across it; cross aisles run along both ends of the rows. An
office with a door opens onto the hall's top wall. The ground truth is the hall's and the
office's interiors, the office door, the racks and the aisles (the free rectangle between two
consecutive rows, as long as the rows).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from tests.rooms.mapgen import OCCUPIED, Building, Canvas, GeneratedMap, Rect, TrueDoor, _draw, _noise

PILLAR = 0.4  # m: side of a square pillar
PALLET = (1.2, 0.8)  # m: a pallet in the staging area (small enough to be a landmark candidate)


@dataclass
class Depot(GeneratedMap):
    """A generated depot: the map, its rooms (hall and office), and what is in the hall."""

    racks: tuple[Rect, ...] = ()
    aisles: dict[str, Rect] | None = None  # A1, A2, ... bottom up: free space between two rack rows


def depot(
    seed: int,
    width: float = 30.0,
    height: float = 15.0,
    resolution: float = 0.05,
    noise: float = 0.002,
    wall_gaps: float = 0.01,
    office: bool = True,
) -> Depot:
    """A depot hall of ``width`` x ``height`` m with racks, pillars, pallets and (unless not
    ``office``) an office on its top wall."""
    rng = np.random.default_rng(seed)
    wall = 0.15
    cells = {"H": (0.0, 0.0, width, height)}
    if office:
        cells["O"] = (0.0, height, min(6.0, width / 3), height + 4.0)
    canvas = Canvas(width, max(r[3] for r in cells.values()), resolution, margin=1.0)
    building = Building(rooms={k: _inside(r, wall) for k, r in cells.items()}, wall=wall)
    x = float(rng.uniform(1.0, min(6.0, width / 3) - 1.9))  # drawn either way: the same racks for a seed
    openings = []
    if office:
        openings.append(("O", "H", (x, height - wall, x + 0.9, height + wall)))
        building.doors.append(TrueDoor(("O", "H"), (x + 0.45, height), 0.9))
    _draw(canvas, cells, building, openings)
    hall = building.rooms["H"]
    racks, aisles, staging = _racks(rng, hall)
    for rack in racks:
        canvas.fill(rack, OCCUPIED)
    _staging(canvas, rng, staging)
    _noise(canvas, rng, noise, wall_gaps)
    return Depot(canvas.image(), resolution, canvas.origin, building, tuple(racks), aisles)


def _inside(rect: Rect, wall: float) -> Rect:
    h = wall / 2
    return (rect[0] + h, rect[1] + h, rect[2] - h, rect[3] - h)


def _racks(rng: np.random.Generator, hall: Rect) -> tuple[list[Rect], dict[str, Rect], Rect]:
    """Rack rows above a staging area; the racks, the aisles between rows and the staging area."""
    x0, y0, x1, y1 = hall
    cross = float(rng.uniform(2.4, 3.2))  # the cross aisles at both ends of the rows
    staging_top = y0 + (y1 - y0) * float(rng.uniform(0.28, 0.35))
    racks: list[Rect] = []
    rows: list[tuple[float, float]] = []
    y = staging_top
    while True:
        depth = float(rng.uniform(0.9, 1.2))
        aisle = float(rng.uniform(2.6, 3.2))
        if y + depth + 1.6 > y1:  # the last row keeps an aisle of at least 1.6 m to the top wall
            break
        rows.append((y, y + depth))
        racks += _row(rng, x0 + cross, x1 - cross, y, y + depth)
        y += depth + aisle
    pairs = enumerate(itertools.pairwise(rows))
    aisles = {f"A{k + 1}": (x0 + cross, lo[1], x1 - cross, hi[0]) for k, (lo, hi) in pairs}
    return racks, aisles, (x0, y0, x1, staging_top)


def _row(rng: np.random.Generator, xa: float, xb: float, ya: float, yb: float) -> list[Rect]:
    """One rack row from xa to xb, broken by gaps 1.4-2.2 m wide into racks at least 3 m long."""
    for n in range(int(rng.integers(2, 5)), 1, -1):  # fewer racks where they would be too short
        gaps = rng.uniform(1.4, 2.2, size=n - 1)
        lengths = rng.dirichlet(np.full(n, 4.0)) * (xb - xa - gaps.sum())
        if lengths.min() >= 3.0:
            starts = xa + np.concatenate([[0.0], np.cumsum(lengths[:-1] + gaps)])
            return [(float(s), ya, float(s + length), yb) for s, length in zip(starts, lengths, strict=True)]
    return [(xa, ya, xb, yb)]


def _staging(canvas: Canvas, rng: np.random.Generator, area: Rect) -> None:
    """Pillars on a 6 m grid and two pallets in the staging area, clear of its edges."""
    x0, y0, x1, y1 = area
    half = PILLAR / 2
    for px in np.arange(x0 + 6.0, x1 - 3.0, 6.0):
        py = (y0 + y1) / 2
        canvas.fill((px - half, py - half, px + half, py + half), OCCUPIED)
    for _ in range(2):
        cx, cy = rng.uniform(x0 + 2.0, x1 - 2.0), rng.uniform(y0 + 1.2, y1 - 1.6)
        w, h = PALLET
        canvas.fill((cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2), OCCUPIED)


def arena(radius: float = 2.6, resolution: float = 0.05) -> GeneratedMap:
    """A hexagonal arena (``radius`` from its centre to a corner, a 0.1 m wall) with nine round
    pillars 0.3 m across on a 1.1 m grid, like the turtlebot3 sandbox; unknown around it."""
    cells = int(2 * (radius + 1.0) / resolution)
    centre = (np.arange(cells) + 0.5) * resolution - (radius + 1.0)
    x, y = np.meshgrid(centre, centre[::-1])  # image rows run from the top (highest y) down
    inside = np.ones(x.shape, dtype=bool)
    inner = np.ones(x.shape, dtype=bool)
    for k in range(6):
        across = x * np.cos(k * np.pi / 3) + y * np.sin(k * np.pi / 3)
        inside &= across <= radius * np.cos(np.pi / 6)
        inner &= across <= radius * np.cos(np.pi / 6) - 0.1
    pixels = np.full(x.shape, 205, dtype=np.uint8)
    pixels[inside] = OCCUPIED
    pixels[inner] = 254
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            pixels[np.hypot(x - 1.1 * i, y - 1.1 * j) < 0.15] = OCCUPIED
    origin = (-(radius + 1.0), -(radius + 1.0))
    return GeneratedMap(pixels, resolution, origin, Building(rooms={}))
