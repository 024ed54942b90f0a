"""Occupancy maps with known rooms and doors, for testing the room segmentation.

A building is a set of axis-aligned rectangular rooms whose walls are drawn on a grid, joined
by doors cut into the shared walls; unknown space surrounds it, as in a map saved by a SLAM
run. The ground truth is each room's interior rectangle (wall face to wall face) and each
door's centre, width and the two rooms it joins. What makes a map hard is added on top, each
part from the same seeded generator: furniture along walls, tables and pillars inside rooms,
sensor speckles in free space, and gaps (missed laser hits) in walls.

Layouts:

- ``corridor``: two rows of rooms along a corridor (the corridor is a room too), every room
  with a door to the corridor, some with a door to their neighbour;
- ``bsp``: a rectangle split recursively into rooms (binary space partition), joined by a
  spanning tree of doors plus a few more;
- ``hall``: one open hall with pillars and shelving, and a row of small offices on one side:
  the hall must come out as one room, not one per bay.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

FREE, OCCUPIED, UNKNOWN = 254, 0, 205

Rect = tuple[float, float, float, float]  # xmin, ymin, xmax, ymax (m)


@dataclass(frozen=True)
class TrueDoor:
    rooms: tuple[str, str]
    centre: tuple[float, float]
    width: float  # m


@dataclass
class Building:
    """The ground truth: rooms as interior rectangles, doors, and the walls' thickness."""

    rooms: dict[str, Rect]
    doors: list[TrueDoor] = field(default_factory=list)
    wall: float = 0.15  # m


@dataclass
class GeneratedMap:
    """A map_server-style image (top row = highest y) with its ground truth."""

    pixels: np.ndarray  # (rows, cols) uint8: FREE, OCCUPIED, UNKNOWN; row 0 is the top of the image
    resolution: float
    origin: tuple[float, float]
    truth: Building

    @property
    def occupied(self) -> np.ndarray:
        """Occupied-or-unknown cells with row 0 at the lowest y (tmpnav's grid convention)."""
        return np.ascontiguousarray(self.pixels[::-1] != FREE)

    def room_mask(self, name: str) -> np.ndarray:
        """Cells (row 0 = lowest y) whose centres lie in the true room's interior rectangle."""
        return rect_mask(self.truth.rooms[name], self.pixels.shape, self.origin, self.resolution)

    def write_ros(self, folder: Path, name: str = "map") -> Path:
        """Write ``name.pgm`` and ``name.yaml`` (map_server format) to ``folder``; return the YAML."""
        from PIL import Image

        folder.mkdir(parents=True, exist_ok=True)
        Image.fromarray(self.pixels, mode="L").save(folder / f"{name}.pgm")
        x0, y0 = self.origin
        (folder / f"{name}.yaml").write_text(
            f"image: {name}.pgm\nresolution: {self.resolution}\norigin: [{x0}, {y0}, 0.0]\n"
            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n",
            encoding="utf-8",
        )
        return folder / f"{name}.yaml"


def rect_mask(rect: Rect, shape: tuple[int, int], origin: tuple[float, float], resolution: float) -> np.ndarray:
    """Cells (row 0 = lowest y) whose centres lie inside ``rect``."""
    rows, cols = shape
    xs = origin[0] + (np.arange(cols) + 0.5) * resolution
    ys = origin[1] + (np.arange(rows) + 0.5) * resolution
    inx = (xs >= rect[0]) & (xs <= rect[2])
    iny = (ys >= rect[1]) & (ys <= rect[3])
    return iny[:, None] & inx[None, :]


class Canvas:
    """A grid in metres, row 0 at the lowest y, on which walls and objects are drawn."""

    def __init__(self, width: float, height: float, resolution: float, margin: float):
        self.r = resolution
        self.origin = (-margin, -margin)
        cols = round((width + 2 * margin) / resolution)
        rows = round((height + 2 * margin) / resolution)
        self.cells = np.full((rows, cols), UNKNOWN, dtype=np.uint8)
        self.xs = self.origin[0] + (np.arange(cols) + 0.5) * resolution
        self.ys = self.origin[1] + (np.arange(rows) + 0.5) * resolution

    def fill(self, rect: Rect, value: int) -> None:
        inx = (self.xs >= rect[0]) & (self.xs < rect[2])
        iny = (self.ys >= rect[1]) & (self.ys < rect[3])
        self.cells[np.ix_(iny, inx)] = value

    def image(self) -> np.ndarray:
        return np.ascontiguousarray(self.cells[::-1])


def _draw(canvas: Canvas, cells: dict[str, Rect], building: Building, doors: list[tuple[str, str, Rect]]) -> None:
    """Rooms (partition cells, walls centred on their edges) and door openings."""
    half = building.wall / 2
    for rect in cells.values():
        canvas.fill((rect[0] - half, rect[1] - half, rect[2] + half, rect[3] + half), OCCUPIED)
    for rect in cells.values():
        canvas.fill((rect[0] + half, rect[1] + half, rect[2] - half, rect[3] - half), FREE)
    for _, _, opening in doors:
        canvas.fill(opening, FREE)


def _door_on_shared_wall(
    a: Rect, b: Rect, rng: np.random.Generator, width: float, wall: float
) -> tuple[Rect, tuple[float, float]] | None:
    """An opening of ``width`` in the wall shared by partition cells a and b, or None."""
    clear = 0.35 + wall  # keep the door away from the corners
    for horizontal in (False, True):
        if horizontal:  # a below b (or above): shared wall along x
            if abs(a[3] - b[1]) < 1e-9 or abs(b[3] - a[1]) < 1e-9:
                y = a[3] if abs(a[3] - b[1]) < 1e-9 else a[1]
                lo, hi = max(a[0], b[0]) + clear, min(a[2], b[2]) - clear
                if hi - lo >= width:
                    x = rng.uniform(lo, hi - width)
                    rect = (x, y - wall, x + width, y + wall)
                    return rect, (x + width / 2, y)
        else:  # side by side: shared wall along y
            if abs(a[2] - b[0]) < 1e-9 or abs(b[2] - a[0]) < 1e-9:
                x = a[2] if abs(a[2] - b[0]) < 1e-9 else a[0]
                lo, hi = max(a[1], b[1]) + clear, min(a[3], b[3]) - clear
                if hi - lo >= width:
                    y = rng.uniform(lo, hi - width)
                    rect = (x - wall, y, x + wall, y + width)
                    return rect, (x, y + width / 2)
    return None


def _interiors(cells: dict[str, Rect], wall: float) -> dict[str, Rect]:
    h = wall / 2
    return {k: (r[0] + h, r[1] + h, r[2] - h, r[3] - h) for k, r in cells.items()}


def corridor_layout(rng: np.random.Generator, wall: float) -> tuple[dict[str, Rect], list[tuple[str, str]]]:
    """Two rows of rooms along a corridor; the pairs of cells that get a door."""
    corridor_w = rng.uniform(1.8, 2.6)
    depth_lo, depth_hi = rng.uniform(3.0, 5.0), rng.uniform(3.0, 5.0)
    cells: dict[str, Rect] = {}
    pairs: list[tuple[str, str]] = []
    width = 0.0
    for row, (y0, y1) in enumerate(((0.0, depth_lo), (depth_lo + corridor_w, depth_lo + corridor_w + depth_hi))):
        x, k = 0.0, 0
        while True:
            w = rng.uniform(3.0, 6.0)
            name = f"{'AB'[row]}{k}"
            cells[name] = (x, y0, x + w, y1)
            pairs.append((name, "C"))
            if k > 0 and rng.random() < 0.3:
                pairs.append((f"{'AB'[row]}{k - 1}", name))
            x += w
            k += 1
            if x > 14.0:
                break
        width = max(width, x)
    for name, r in list(cells.items()):  # the last room of each row reaches the building's width
        if r[2] == max(c[2] for n, c in cells.items() if n[0] == name[0]):
            cells[name] = (r[0], r[1], width, r[3])
    cells["C"] = (0.0, depth_lo, width, depth_lo + corridor_w)
    return cells, pairs


def bsp_layout(rng: np.random.Generator, wall: float) -> tuple[dict[str, Rect], list[tuple[str, str]]]:
    """A rectangle split recursively; doors on a spanning tree of the adjacency plus extras."""
    W, H = rng.uniform(12.0, 22.0), rng.uniform(9.0, 15.0)
    rects: list[Rect] = [(0.0, 0.0, W, H)]
    min_side = 3.0
    target = int(rng.integers(5, 10))
    while len(rects) < target:
        rects.sort(key=lambda r: (r[2] - r[0]) * (r[3] - r[1]))
        r = rects[-1]
        w, h = r[2] - r[0], r[3] - r[1]
        if max(w, h) < 2 * min_side:
            break
        rects.pop()
        if w >= h:
            s = rng.uniform(r[0] + min_side, r[2] - min_side)
            rects += [(r[0], r[1], s, r[3]), (s, r[1], r[2], r[3])]
        else:
            s = rng.uniform(r[1] + min_side, r[3] - min_side)
            rects += [(r[0], r[1], r[2], s), (r[0], s, r[2], r[3])]
    cells = {f"P{i}": r for i, r in enumerate(sorted(rects, key=lambda r: (r[1], r[0])))}
    names = list(cells)
    adjacent = [
        (a, b)
        for i, a in enumerate(names)
        for b in names[i + 1 :]
        if _door_on_shared_wall(cells[a], cells[b], np.random.default_rng(0), 1.2, wall)
    ]
    order = rng.permutation(len(adjacent))
    parent = {n: n for n in names}

    def root(n: str) -> str:
        while parent[n] != n:
            n = parent[n]
        return n

    pairs = []
    for k in order:
        a, b = adjacent[k]
        if root(a) != root(b):
            parent[root(a)] = root(b)
            pairs.append((a, b))
        elif rng.random() < 0.25:
            pairs.append((a, b))
    return cells, pairs


def hall_layout(rng: np.random.Generator, wall: float) -> tuple[dict[str, Rect], list[tuple[str, str]]]:
    """A large open hall with a row of offices along its top side."""
    W, H = rng.uniform(16.0, 24.0), rng.uniform(10.0, 14.0)
    depth = rng.uniform(3.0, 4.0)
    cells: dict[str, Rect] = {"H": (0.0, 0.0, W, H)}
    pairs = []
    x, k = 0.0, 0
    while x < W - 0.1:
        w = min(rng.uniform(3.5, 5.5), W - x)
        if W - x - w < 3.0:
            w = W - x
        cells[f"O{k}"] = (x, H, x + w, H + depth)
        pairs.append((f"O{k}", "H"))
        x += w
        k += 1
    return cells, pairs


LAYOUTS = {"corridor": corridor_layout, "bsp": bsp_layout, "hall": hall_layout}


def generate(
    layout: str,
    seed: int,
    resolution: float = 0.05,
    clutter: bool = True,
    noise: float = 0.002,
    wall_gaps: float = 0.01,
) -> GeneratedMap:
    """A map of the given layout; ``noise`` is the share of free cells turned into speckles and
    ``wall_gaps`` the share of wall cells left free (a laser that missed them)."""
    rng = np.random.default_rng(seed)
    wall = float(rng.choice([0.1, 0.15, 0.2]))
    cells, pairs = LAYOUTS[layout](rng, wall)
    width = max(r[2] for r in cells.values())
    height = max(r[3] for r in cells.values())
    canvas = Canvas(width, height, resolution, margin=1.0)
    building = Building(rooms=_interiors(cells, wall), wall=wall)
    openings = []
    for a, b in pairs:
        w = float(rng.uniform(0.8, 1.1))
        found = _door_on_shared_wall(cells[a], cells[b], rng, w, wall)
        if found is None:
            continue
        rect, centre = found
        openings.append((a, b, rect))
        building.doors.append(TrueDoor((a, b), centre, w))
    _draw(canvas, cells, building, openings)
    if clutter:
        _clutter(canvas, building, rng, layout == "hall")
    _noise(canvas, rng, noise, wall_gaps)
    return GeneratedMap(canvas.image(), resolution, canvas.origin, building)


def _clutter(canvas: Canvas, building: Building, rng: np.random.Generator, hall: bool) -> None:
    """Shelves along walls (away from doors), tables and pillars inside rooms."""
    door_zones = [(d.centre[0] - 1.0, d.centre[1] - 1.0, d.centre[0] + 1.0, d.centre[1] + 1.0) for d in building.doors]

    def clear_of_doors(rect: Rect) -> bool:
        return all(rect[2] < z[0] or rect[0] > z[2] or rect[3] < z[1] or rect[1] > z[3] for z in door_zones)

    for name, (x0, y0, x1, y1) in building.rooms.items():
        w, h = x1 - x0, y1 - y0
        if min(w, h) < 2.5:
            continue
        if rng.random() < 0.6:  # a shelf against the bottom or top wall
            length = rng.uniform(0.3, 0.6) * w
            sx = rng.uniform(x0, x1 - length)
            shelf = (sx, y0, sx + length, y0 + 0.4) if rng.random() < 0.5 else (sx, y1 - 0.4, sx + length, y1)
            if clear_of_doors(shelf):
                canvas.fill(shelf, OCCUPIED)
        if rng.random() < 0.5 and min(w, h) > 3.2:  # a table in the middle
            tw, th = rng.uniform(0.6, 1.2), rng.uniform(0.5, 0.8)
            cx, cy = rng.uniform(x0 + 1.3, x1 - 1.3), rng.uniform(y0 + 1.3, y1 - 1.3)
            canvas.fill((cx - tw / 2, cy - th / 2, cx + tw / 2, cy + th / 2), OCCUPIED)
        if name.startswith("H") and hall:  # pillars on a grid and shelving islands in the hall
            for px in np.arange(x0 + 4.0, x1 - 2.0, 4.0):
                for py in np.arange(y0 + 3.5, y1 - 2.0, 3.5):
                    canvas.fill((px - 0.15, py - 0.15, px + 0.15, py + 0.15), OCCUPIED)
            for k in range(3):
                sx = x0 + 2.0 + k * (w - 4.0) / 3
                canvas.fill((sx, y0 + 1.5, sx + 0.5, y0 + 1.5 + 0.35 * h), OCCUPIED)


def _noise(canvas: Canvas, rng: np.random.Generator, noise: float, wall_gaps: float) -> None:
    """Speckles in free space, and pinholes through walls where the laser missed a cell or two
    (a gap one or two cells wide joining two rooms, never the building and its surroundings)."""
    cells = canvas.cells
    free = cells == FREE
    cells[free & (rng.random(cells.shape) < noise)] = OCCUPIED
    rows, cols = cells.shape
    face = (cells == OCCUPIED) & (np.roll(free, 1, 0) | np.roll(free, 1, 1))
    for i, j in np.argwhere(face & (rng.random(cells.shape) < wall_gaps)):
        for di, dj in ((1, 0), (0, 1)):
            if not free[(i - di) % rows, (j - dj) % cols]:
                continue
            run = [(i + k * di, j + k * dj) for k in range(6)]
            end = next((k for k, (a, b) in enumerate(run) if a >= rows or b >= cols or cells[a, b] != OCCUPIED), None)
            if end is not None and run[end][0] < rows and run[end][1] < cols and free[run[end]]:
                width = int(rng.integers(1, 3))
                for a, b in run[:end]:
                    cells[a : a + (width if dj else 1), b : b + (width if di else 1)] = FREE
            break


def polygon_mask(
    polygon: np.ndarray, shape: tuple[int, int], origin: tuple[float, float], resolution: float
) -> np.ndarray:
    """Cells (row 0 = lowest y) whose centres lie inside ``polygon`` (k, 2)."""
    from tmpnav.world.geometry import points_in_polygon

    rows, cols = shape
    xs = origin[0] + (np.arange(cols) + 0.5) * resolution
    ys = origin[1] + (np.arange(rows) + 0.5) * resolution
    gx, gy = np.meshgrid(xs, ys)
    inside = points_in_polygon(np.column_stack([gx.ravel(), gy.ravel()]), np.asarray(polygon, dtype=float))
    return inside.reshape(shape)


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two cell masks."""
    union = np.count_nonzero(a | b)
    return np.count_nonzero(a & b) / union if union else 0.0
