#!/usr/bin/env python3
"""Write tmpnav's scenarios of real size (configs/) and their ROS maps, byte for byte.

Rerun it from the repository root after changing a layout below, and commit what it wrote:

    .venv/bin/python benchmarks/scenarios/generate.py            # rewrites the files in configs/
    .venv/bin/python benchmarks/scenarios/generate.py --check    # exit 1 if a shipped file differs
    .venv/bin/python benchmarks/scenarios/generate.py --out DIR  # writes them under DIR instead

It writes:

    configs/building-20.yaml                  20 rooms off one 100 m corridor, 2 robots
    configs/building-{2,4,8}robots.yaml       72-room office on three corridors, 2/4/8 robots
    configs/warehouse/map.{pgm,yaml}          ROS map of a logistics floor (64 m x 40 m hall)
    configs/warehouse-{2,4,8}robots.yaml      its 45 goal places, 2/4/8 robots
    configs/sparse-warehouse/map.{pgm,yaml}   ROS map of an open hall (50 m x 50 m), few pillars
    configs/sparse-warehouse.yaml             8 places far from the pillars, 3 robots

Every run writes the same bytes: no clock, no random numbers, numbers formatted by hand.
Needs numpy and PyYAML (which re-reads every YAML file written, as a check).

Why one file of more than 400 lines: it is a script, not a module of tmpnav, and one file
that regenerates every shipped scenario is easier to rerun and review; each layout reads top
to bottom next to the comments it writes into its YAML file.
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parents[2]

#: PRM milestones and neighbours (k) per world, with the reason written above the roadmap
#: key of each file (benchmarks/scenarios/README.md: how they were measured). A door is a
#: narrow passage for a uniformly sampled PRM: a larger k connects it with fewer milestones.
ROADMAP = {
    "building-20": (
        1500,
        20,
        "the smallest roadmap that reached every room for each of 20 roadmap seeds (1200: 19 of 20);\n"
        "with the default 10 neighbours it takes 5000 milestones",
    ),
    "building": (
        6000,
        30,
        "the smallest roadmap that reached every room for each of 30 roadmap seeds (5000: 29 of 30);\n"
        "with 10 neighbours even 16000 milestones left a room cut off for 2 of 10 seeds",
    ),
    "warehouse": (
        2000,
        10,
        "the smallest roadmap that reached every place for each of 20 roadmap seeds (1500: 19 of 20;\n"
        "the narrow passages are the doors of the office and the qa room)",
    ),
    "sparse-warehouse": (
        250,
        10,
        "120 milestones already reach every place (open floor, 20 seeds); 250 keep roadmap paths\n"
        "within 3-5% of a 6000-milestone roadmap's, like the other scenarios' roadmaps",
    ),
}


def roadmap_lines(world: str) -> list[str]:
    """The roadmap key of a scenario file, with the reason for its size as a comment."""
    samples, k, why = ROADMAP[world]
    return [
        *(f"# {line}" for line in why.split("\n")),
        f"roadmap: {{samples: {samples}, instantiations: 4, seed: 1, neighbors: {k}}}",
    ]


# ------------------------------------------------------------------------ YAML text


def num(x: float) -> str:
    """A number as the YAML files show it: 12, 4.4, -1.5708 (at most 4 decimals)."""
    r = round(float(x), 4)
    if r == int(r):
        return str(int(r))
    return f"{r:.4f}".rstrip("0")


def pt(p: tuple[float, ...]) -> str:
    return "[" + ", ".join(num(v) for v in p) + "]"


def pts(points: list[tuple[float, float]]) -> str:
    return "[" + ", ".join(pt(p) for p in points) + "]"


def box(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    """The four corners of an axis-aligned rectangle, counter-clockwise."""
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


@dataclass
class Entry:
    """One item of a YAML list, written in flow style on one line, with a trailing comment."""

    text: str
    comment: str = ""
    name: str = ""


@dataclass
class Group:
    """Items of a YAML list under a comment line that says what they are."""

    title: str
    entries: list[Entry] = field(default_factory=list)


@dataclass
class Spec:
    """Everything a scenario file says, in the order it says it."""

    header: list[str]
    name: str
    description: str
    map_lines: list[str]
    rooms: list[Group]
    doors: list[Group]
    landmarks: list[Group]
    robots: list[Group]
    roadmap: list[str]
    goals: list[str]
    goals_comment: str
    models: list[str] = field(default_factory=list)


#: the robots' 2D lidar (docs/scenario.md, models.range_sensor), the same in every scenario that has one
LIDAR = [
    "# a typical 2D lidar: 12 m, all round, 60 beams, 3 cm of range noise, a spot that widens by",
    "# 10 mrad. The robots localise as nav2's AMCL does at its defaults (no localiser given:",
    '# docs/models.md, "What a localiser achieves"); plan with --no-range-sensor for the paper\'s',
    "# model (landmarks and partners only)",
    "models:",
    "  range_sensor: {range: 12, fov: 360 deg, beams: 60, sigma_range: 0.03, divergence: 0.01}",
]


def room(name: str, polygon: list[tuple[float, float]], comment: str = "") -> Entry:
    return Entry(f"{{name: {name}, polygon: {pts(polygon)}}}", comment, name)


def door(name: str, a: tuple[float, float], b: tuple[float, float]) -> Entry:
    return Entry(f"{{name: {name}, segment: {pts([a, b])}, state: open}}")


def landmark(name: str, kind: str, p: tuple[float, float], comment: str = "") -> Entry:
    return Entry(f"{{name: {name}, kind: {kind}, position: {pt(p)}}}", comment)


def robot(name: str, x: float, y: float, theta: float, comment: str = "") -> Entry:
    return Entry(f"{{name: {name}, pose: [{num(x)}, {num(y)}, {num(theta)}]}}", comment)


def section(key: str, groups: list[Group]) -> list[str]:
    lines = [f"{key}:"]
    for g in groups:
        if not g.entries:
            continue
        if g.title:
            lines.append(f"  # {g.title}")
        for e in g.entries:
            lines.append(f"  - {e.text}" + (f"  # {e.comment}" if e.comment else ""))
    return lines


def scenario_text(spec: Spec) -> str:
    """The scenario file: header comments, then the keys in the order of docs/scenario.md."""
    out = [f"# {line}".rstrip() for line in spec.header]
    out += [f"name: {spec.name}", f'description: "{spec.description}"', "", "map:", *spec.map_lines, ""]
    for key, groups in (("rooms", spec.rooms), ("doors", spec.doors), ("landmarks", spec.landmarks)):
        if any(g.entries for g in groups):
            out += [*section(key, groups), ""]
    out += [*section("robots", spec.robots), ""]
    out += [*spec.models, ""] if spec.models else []
    out += [
        *spec.roadmap,
        "",
        f"# {spec.goals_comment}",
        "goals:",
    ]
    out += wrap_names(spec.goals, "  visit: ")
    text = "\n".join(out) + "\n"
    yaml.safe_load(text)  # what we write must parse
    return text


def wrap_names(names: list[str], prefix: str, width: int = 96) -> list[str]:
    """``prefix`` and a flow list of names, wrapped: ``  visit: [A1, A5, ...]``."""
    lines, line = [], prefix + "["
    for i, n in enumerate(names):
        item = n + (", " if i < len(names) - 1 else "]")
        if len(line) + len(item) > width:
            lines.append(line.rstrip())
            line = " " * (len(prefix) + 1)
        line += item
    return [*lines, line]


def spread(names: list[str], k: int) -> list[str]:
    """k names evenly spaced through the list (the first one included), in list order."""
    n = len(names)
    return [names[(i * n * 2 + k) // (2 * k)] for i in range(k)]


# ------------------------------------------------------------------- ROS map images

FREE, UNKNOWN, OCCUPIED = 254, 205, 0  # the grey levels map_saver writes (trinary)
RESOLUTION = 0.05


class Raster:
    """A ROS map image being drawn in metres of the map frame (origin = lower-left pixel)."""

    def __init__(self, origin: tuple[float, float], size: tuple[float, float]):
        self.origin = origin
        self.cols, self.rows = (round(s / RESOLUTION) for s in size)
        self.pixels = np.full((self.rows, self.cols), UNKNOWN, dtype=np.uint8)

    def fill(self, x0: float, y0: float, x1: float, y1: float, value: int) -> None:
        """Paint the rectangle [x0, x1] x [y0, y1] (metres, on the 5 cm grid)."""
        c0, c1 = (round((x - self.origin[0]) / RESOLUTION) for x in (x0, x1))
        r0, r1 = (round((y - self.origin[1]) / RESOLUTION) for y in (y0, y1))
        # image row 0 is the top of the map (largest y)
        self.pixels[self.rows - r1 : self.rows - r0, c0:c1] = value

    def pgm(self, comment: str) -> bytes:
        head = f"P5\n# {comment}\n{self.cols} {self.rows}\n255\n".encode()
        return head + self.pixels.tobytes()

    def map_yaml(self, comment: list[str]) -> bytes:
        lines = [f"# {c}".rstrip() for c in comment] + [
            "image: map.pgm",
            "mode: trinary",
            f"resolution: {num(RESOLUTION)}",
            f"origin: [{self.origin[0]:.1f}, {self.origin[1]:.1f}, 0.0]",
            "negate: 0",
            "occupied_thresh: 0.65",
            "free_thresh: 0.196",
        ]
        text = "\n".join(lines) + "\n"
        yaml.safe_load(text)
        return text.encode()


def pillar_landmark(xc: float, yc: float, half: float, toward: tuple[float, float]) -> tuple[float, float]:
    """Where a pillar's landmark sits: 5 cm off the pillar's corner that faces ``toward``.

    tmpnav hides a landmark behind any occupied cell between it and the robot, so a point at
    the pillar's centre would be hidden by the pillar itself; the corner is seen from 270 deg.
    """
    sx = 1.0 if toward[0] >= xc else -1.0
    sy = 1.0 if toward[1] >= yc else -1.0
    return (xc + sx * (half + 0.05), yc + sy * (half + 0.05))


# ---------------------------------------------------------- polygonal office rows


@dataclass(frozen=True)
class Row:
    """Rooms side by side along one wall of a corridor.

    The rooms span x0.. (widths, west to east) and reach from the corridor wall at door_y
    back to back_y. ``back_wall`` is False when the back is the outer wall or is drawn by
    the row behind; ``ends`` says which end walls (west, east) this row draws.
    """

    names: tuple[str, ...]  # west to east
    x0: float
    door_y: float
    back_y: float
    widths: tuple[float, ...]
    back_wall: bool = True
    ends: tuple[bool, bool] = (True, True)
    door_width: float | None = None  # every door this wide and centred (None: door_span's mix)

    def boxes(self) -> list[tuple[float, float, float, float]]:
        """(xa, ya, xb, yb) of every room, wall centre lines."""
        edges = np.cumsum((self.x0, *self.widths))
        ylo, yhi = min(self.door_y, self.back_y), max(self.door_y, self.back_y)
        return [(float(a), ylo, float(b), yhi) for a, b in itertools.pairwise(edges)]


def door_span(k: int, xa: float, xb: float) -> tuple[float, float]:
    """The k-th room's door along its corridor wall: 1.2 m (1.8 m in rooms of 8 m or more),
    centred, near the west wall or near the east wall in turn."""
    width = 1.8 if xb - xa >= 8 else 1.2
    centre = ((xa + xb) / 2, xa + 0.6 + width / 2, xb - 0.6 - width / 2)[k % 3]
    return centre - width / 2, centre + width / 2


def row_parts(row: Row) -> tuple[list[list[tuple[float, float]]], list[Entry], list[Entry]]:
    """Walls (polylines), rooms and doors of a row; rooms are inset 10 cm from the walls."""
    walls: list[list[tuple[float, float]]] = []
    rooms, doors = [], []
    boxes = row.boxes()
    x = row.x0
    for k, (name, (xa, ylo, xb, yhi)) in enumerate(zip(row.names, boxes, strict=True)):
        if row.door_width is None:
            a, b = door_span(k, xa, xb)
        else:
            a, b = (xa + xb - row.door_width) / 2, (xa + xb + row.door_width) / 2
        walls.append([(x, row.door_y), (a, row.door_y)])
        x = b
        rooms.append(
            room(name, box(xa + 0.1, ylo + 0.1, xb - 0.1, yhi - 0.1), f"{num(xb - xa)} m x {num(yhi - ylo)} m")
        )
        doors.append(door(f"door-{name}", (a, row.door_y), (b, row.door_y)))
    end = boxes[-1][2]
    walls.append([(x, row.door_y), (end, row.door_y)])
    splits = [b[0] for b in boxes[1:]]
    ends = [e for e, keep in zip((row.x0, end), row.ends, strict=True) if keep]
    walls += [[(sx, row.door_y), (sx, row.back_y)] for sx in sorted([*splits, *ends])]
    if row.back_wall:
        walls.append([(row.x0, row.back_y), (end, row.back_y)])
    return walls, rooms, doors


def wall_lines(groups: list[tuple[str, list[list[tuple[float, float]]]]]) -> list[str]:
    lines = ["  walls:"]
    for title, polylines in groups:
        lines.append(f"    # {title}")
        lines += [f"    - {pts(p)}" for p in polylines]
    return lines


def polygon_map(bounds: tuple[float, ...], walls: list[str], obstacles: list[Entry]) -> list[str]:
    lines = [f"  bounds: {pt(bounds)}", "  resolution: 0.05", "  wall_thickness: 0.15", *walls]
    if obstacles:
        lines.append("  obstacles:")
        lines += [f"    - {o.text}" + (f"  # {o.comment}" if o.comment else "") for o in obstacles]
    return lines


# ------------------------------------------------------------------ building-20


#: short names of landmark kinds, for landmark names such as trash-4
SHORT = {
    "fire extinguisher": "extinguisher",
    "notice board": "board",
    "plant": "plant",
    "trash can": "trash",
    "water cooler": "cooler",
}


def building_20() -> dict[str, bytes]:
    """Two rows of ten 10 m x 5 m rooms off a 100 m corridor, 2 robots, visit every room."""
    rooms = (10.0,) * 10
    south = Row(tuple(f"S{i}" for i in range(1, 11)), 0, 5, 0, rooms, False, (False, False), door_width=1.2)
    north = Row(tuple(f"N{i}" for i in range(1, 11)), 0, 8, 13, rooms, False, (False, False), door_width=1.2)
    ws, rs, ds = row_parts(south)
    wn, rn, dn = row_parts(north)
    walls = wall_lines(
        [
            ("outer wall", [[(0, 0), (100, 0), (100, 13), (0, 13), (0, 0)]]),
            (
                "corridor walls (y = 5 south, y = 8 north) with a 1.2 m gap at each door, and the walls between rooms",
                ws,
            ),
            ("north side", wn),
        ]
    )
    kinds = ("fire extinguisher", "notice board", "plant", "trash can", "water cooler")
    marks = [landmark("plant-w", "plant", (0.4, 6.5), "west end of the corridor")]
    for i, x in enumerate(range(10, 100, 10)):
        y = 7.7 if i % 2 == 0 else 5.3
        kind = kinds[i % len(kinds)]
        marks.append(landmark(f"{SHORT[kind]}-{i + 1}", kind, (x, y), "corridor, between two doors"))
    marks.append(landmark("plant-e", "plant", (99.6, 6.5), "east end of the corridor"))
    spec = Spec(
        header=[
            "A building of 20 rooms: two rows of ten 10 m x 5 m rooms off a 100 m east-west corridor",
            "(3 m wide, y = 5..8). S1..S10 are the south rooms and N1..N10 the north rooms, both",
            "numbered from west to east; each opens onto the corridor through a 1.2 m door in the",
            "middle of its corridor wall. Eleven landmarks stand along the corridor, one every 10 m",
            "on alternating sides and one at each end: with the default 5 m landmark sensor the",
            "corridor sees one almost everywhere (gaps of a few decimetres midway between two), while",
            "in the rooms the walls hide them but for glimpses through the doors. The robots carry a",
            "2D lidar (models.range_sensor) and localise against the walls as well.",
            "Two robots start at the two ends of the corridor; the task is to visit every room.",
            "",
            "Written by benchmarks/scenarios/generate.py (edit that script, not this file).",
            "Units: metres, radians.",
        ],
        name="building-20",
        description="Two rows of ten 10 m x 5 m rooms off a 100 m corridor, 2 robots, visit every room",
        map_lines=polygon_map((0, 0, 100, 13), walls, []),
        rooms=[Group("south side, west to east", rs), Group("north side, west to east", rn)],
        doors=[Group("", ds + dn)],
        landmarks=[Group("along the corridor, west to east", marks)],
        robots=[
            Group(
                "",
                [
                    robot("r1", 1.5, 6.5, 0, "west end of the corridor, facing east"),
                    robot("r2", 98.5, 6.5, 3.1416, "east end of the corridor, facing west"),
                ],
            )
        ],
        roadmap=roadmap_lines("building-20"),
        goals=[f"S{i}" for i in range(1, 11)] + [f"N{i}" for i in range(1, 11)],
        goals_comment="every room",
        models=LIDAR,
    )
    return {"building-20.yaml": scenario_text(spec).encode()}


# --------------------------------------------------------- the 72-room office


# y of the walls, south to north: three double-loaded corridors A, B, C
A_ROOMS, A_CORR, A_BACK = (0.0, 6.0), (6.0, 8.5), 14.0
B_CORR, B_BACK = (19.5, 22.5), 28.5
C_CORR, C_TOP = (34.0, 36.5), 43.5
WIDTH = 72.0
CROSS = (34.0, 37.0)  # the north-south cross corridor joining A, the lobby and C
LOBBY = (28.0, 14.0, 43.0, 28.5)


def office_rows() -> list[tuple[str, Row]]:
    """The ten rows of rooms, numbered counter-clockwise around each corridor (as the paper's
    corridor): along the south side west to east, then back along the north side."""
    a_s = (6, 4, 4, 8, 5, 5, 6, 4, 4, 10, 6, 5, 5)
    a_nw, a_ne = (5, 5, 4, 8, 4, 4, 4), (6, 4, 4, 6, 5, 5, 5)
    b_sw, b_se = (4, 6, 4, 4, 5, 5), (5, 5, 4, 6, 5, 4)
    b_nw, b_ne = (8, 6, 6, 8), (7, 7, 5, 10)
    c_sw, c_se = (4, 4, 5, 5, 4, 4, 4, 4), (5,) * 7
    c_n = (12, 6, 6, 8, 4, 4, 4, 8, 10, 10)

    def names(prefix: str, first: int, n: int, reverse: bool = False) -> tuple[str, ...]:
        out = tuple(f"{prefix}{first + i}" for i in range(n))
        return out[::-1] if reverse else out

    return [
        ("corridor A, south side", Row(names("A", 1, 13), 0, 6, 0, a_s, back_wall=False)),
        ("corridor A, north side, east of the cross corridor", Row(names("A", 14, 7, True), 37, 8.5, 14, a_ne)),
        ("corridor A, north side, west of the cross corridor", Row(names("A", 21, 7, True), 0, 8.5, 14, a_nw)),
        ("corridor B, south side, west of the lobby", Row(names("B", 1, 6), 0, 19.5, 14, b_sw, back_wall=False)),
        ("corridor B, south side, east of the lobby", Row(names("B", 7, 6), 43, 19.5, 14, b_se, back_wall=False)),
        ("corridor B, north side, east of the lobby", Row(names("B", 13, 4, True), 43, 22.5, 28.5, b_ne, False)),
        ("corridor B, north side, west of the lobby", Row(names("B", 17, 4, True), 0, 22.5, 28.5, b_nw, False)),
        ("corridor C, south side, west of the cross corridor", Row(names("C", 1, 8), 0, 34, 28.5, c_sw)),
        ("corridor C, south side, east of the cross corridor", Row(names("C", 9, 7), 37, 34, 28.5, c_se)),
        ("corridor C, north side", Row(names("C", 16, 10, True), 0, 36.5, 43.5, c_n, back_wall=False)),
    ]


def office_world() -> tuple[list[str], list[Group], list[Group], list[Group], dict[str, tuple[float, ...]]]:
    """Map lines, rooms, doors, landmarks and the room boxes of the office building."""
    wall_groups: list[tuple[str, list[list[tuple[float, float]]]]] = [
        ("outer wall", [[(0, 0), (WIDTH, 0), (WIDTH, C_TOP), (0, C_TOP), (0, 0)]])
    ]
    rooms, doors = [], []
    boxes: dict[str, tuple[float, ...]] = {}
    for title, row in office_rows():
        w, r, d = row_parts(row)
        wall_groups.append((title, [p for p in w if not on_outer_wall(p)]))
        rooms.append(Group(title, r))
        doors += d
        boxes.update(zip(row.names, row.boxes(), strict=True))
    obstacles = [Entry(pts(box(38, 16, 41, 17)), "reception desk in the lobby")]
    for name, (xa, ya, xb, yb) in boxes.items():
        if xb - xa >= 8:  # meeting rooms and labs: a table in the middle
            cx, cy, half = (xa + xb) / 2, (ya + yb) / 2, (xb - xa - 4) / 2
            obstacles.append(Entry(pts(box(cx - half, cy - 0.6, cx + half, cy + 0.6)), f"table in {name}"))
    map_lines = polygon_map((0, 0, WIDTH, C_TOP), wall_lines(wall_groups), obstacles)
    return map_lines, rooms, [Group("", doors)], office_landmarks(boxes), boxes


def on_outer_wall(p: list[tuple[float, float]]) -> bool:
    (x0, y0), (x1, y1) = p
    return (x0 == x1 and x0 in (0, WIDTH)) or (y0 == y1 and y0 in (0, C_TOP))


def in_room(boxes: dict[str, tuple[float, ...]], name: str, corner: str) -> tuple[float, float]:
    """A point 0.4 m from two walls of a room, in its 'sw', 'se', 'nw' or 'ne' corner."""
    xa, ya, xb, yb = boxes[name]
    return (xa + 0.4 if "w" in corner else xb - 0.4, ya + 0.4 if "s" in corner else yb - 0.4)


def office_landmarks(boxes: dict[str, tuple[float, ...]]) -> list[Group]:
    """Dense along corridor A and the west of B and C, none along C east of the cross corridor
    and only one along B east of the lobby: the sparse stretches of this building."""
    kinds = ("fire extinguisher", "notice board", "plant", "trash can")
    corr_a = [
        landmark(f"{SHORT[kinds[i % 4]]}-a{i + 1}", kinds[i % 4], (x, 8.2 if i % 2 == 0 else 6.3))
        for i, x in enumerate((4, 12, 20, 28, 36, 44, 52, 60, 68))
    ]
    corr_b = [
        landmark(f"{SHORT[kinds[i % 4]]}-b{i + 1}", kinds[i % 4], (x, 22.2 if i % 2 == 0 else 19.8))
        for i, x in enumerate((4, 12, 20))
    ]
    corr_b.append(landmark("extinguisher-b4", "fire extinguisher", (71.6, 21), "east end; x 43..66 sees nothing"))
    corr_c = [
        landmark(f"{SHORT[kinds[i % 4]]}-c{i + 1}", kinds[i % 4], (x, 36.2 if i % 2 == 0 else 34.3))
        for i, x in enumerate((4, 16, 28))
    ]
    hub = [
        landmark("reception", "reception desk", (39.5, 17.1), "north face of the desk"),
        landmark("plant-lobby-sw", "plant", (28.4, 14.4)),
        landmark("plant-lobby-ne", "plant", (42.6, 28.1)),
        landmark("board-cross-s", "notice board", (34.3, 11.0), "cross corridor, between A and the lobby"),
        landmark("board-cross-n", "notice board", (36.7, 31.5), "cross corridor, between the lobby and C"),
    ]
    inside = [
        landmark("printer-a5", "printer", in_room(boxes, "A5", "sw"), "in A5"),
        landmark("fridge-a10", "fridge", in_room(boxes, "A10", "se"), "kitchen A10"),
        landmark("cabinet-a17", "cabinet", in_room(boxes, "A17", "ne"), "in A17"),
        landmark("whiteboard-b13", "whiteboard", in_room(boxes, "B13", "ne"), "meeting room B13"),
        landmark("cabinet-b20", "cabinet", in_room(boxes, "B20", "nw"), "lab B20"),
        landmark("printer-b3", "printer", in_room(boxes, "B3", "sw"), "in B3"),
        landmark("cabinet-c25", "cabinet", in_room(boxes, "C25", "nw"), "library C25"),
        landmark("printer-c3", "printer", in_room(boxes, "C3", "sw"), "in C3"),
    ]
    return [
        Group("corridor A, every 8 m, alternating sides", corr_a),
        Group("corridor B: west of the lobby every 8 m; east of it only at the far end", corr_b),
        Group("corridor C: west of the cross corridor only; the 35 m east of it have none", corr_c),
        Group("lobby and cross corridor", hub),
        Group("inside rooms", inside),
    ]


#: robot starts, all in corridors or the lobby (no robot starts in a room it could be sent to);
#: the 2- and 4-robot teams are the first robots of this list, spread to the building's corners
OFFICE_STARTS = (
    ("corridor A, west end", 1.5, 7.25, 0.0),
    ("corridor C, east end", 70.5, 35.25, 3.1416),
    ("corridor A, east end", 70.5, 7.25, 3.1416),
    ("corridor C, west end", 1.5, 35.25, 0.0),
    ("the lobby", 35.5, 21.0, 1.5708),
    ("corridor B, west end", 1.5, 21.0, 0.0),
    ("corridor B, east end", 70.5, 21.0, 3.1416),
    ("the cross corridor, between A and the lobby", 35.5, 11.0, 1.5708),
)


def office_building() -> dict[str, bytes]:
    """configs/building-{2,4,8}robots.yaml: the same 72-room office with 2, 4 and 8 robots."""
    map_lines, rooms, doors, landmarks, boxes = office_world()
    names = list(boxes)
    order = sorted(names, key=lambda n: (n[0], int(n[1:])))
    goals = spread(order, 20)
    files = {}
    for n in (2, 4, 8):
        robots = [robot(f"r{i + 1}", x, y, th, where) for i, (where, x, y, th) in enumerate(OFFICE_STARTS[:n])]
        spec = Spec(
            header=office_header(n, len(names), sum(len(g.entries) for g in landmarks)),
            name=f"building-{n}robots",
            description=f"Office of {len(names)} rooms on three corridors joined by a cross corridor and a lobby, "
            f"{n} robots",
            map_lines=map_lines,
            rooms=rooms,
            doors=doors,
            landmarks=landmarks,
            robots=[Group("", robots)],
            roadmap=roadmap_lines("building"),
            goals=goals,
            goals_comment="default task: 20 rooms spread over the three corridors (`tmpnav bench` draws its own)",
            models=LIDAR,
        )
        files[f"building-{n}robots.yaml"] = scenario_text(spec).encode()
    return files


def office_header(robots: int, rooms: int, landmarks: int) -> list[str]:
    return [
        f"An office building of {rooms} rooms on three east-west corridors, {robots} robots.",
        "",
        "Layout (72 m x 43.5 m, south to north): corridor A (y 6..8.5), corridor B (y 19.5..22.5) and",
        "corridor C (y 34..36.5), each with rooms on both sides; the rooms between two corridors",
        "stand back to back. A north-south cross corridor (x 34..37) joins A and C through a",
        "lobby (x 28..43, y 14..28.5) that B runs into from both sides. Rooms are 4 to 12 m wide",
        "and 5.5 to 7 m deep; each has a door on its corridor, 1.2 m wide (1.8 m in rooms of 8 m",
        "or more), in the middle, near its west wall or near its east wall in turn. Rooms of",
        "8 m or more have a table in the middle; the lobby has a reception desk.",
        "Rooms are named after their corridor and numbered counter-clockwise around it, as in",
        "the paper's corridor: A1..A13 along A's south side west to east, A14..A27 back along",
        "its north side; B1..B20 and C1..C25 the same way.",
        "",
        f"{landmarks} landmarks: every 8 m along corridor A and the west parts of B and C, in the",
        "lobby and cross corridor, and in eight rooms. Deliberately sparse: corridor C east of the",
        "cross corridor (35 m) and every room off it have none, and corridor B east of the lobby",
        "has one, at its far end (default 5 m landmark sensor). The robots carry a 2D lidar",
        "(models.range_sensor) and localise against the walls wherever the landmarks are sparse.",
        "",
        "Robots start in the corridors and the lobby, so every room to visit needs a real visit;",
        "building-2robots, -4robots and -8robots share the world, and each team is the first",
        "robots of the larger one. Used by `tmpnav bench --scenario",
        "configs/building-{robots}robots.yaml --robots 2,4,8 --rooms 10..60:10`.",
        "Default task (goals, at the end): visit 20 rooms spread evenly over A, B and C (tmpnav",
        "plans it with the anytime search); the bench draws its own rooms.",
        "",
        "Written by benchmarks/scenarios/generate.py (edit that script, not this file).",
        "Units: metres, radians.",
    ]


# ------------------------------------------------------------- the warehouse (ROS)

HALL = (64.0, 40.0)  # inside of the outer walls; the walls are 0.3 m thick, outside it
AISLES = 9
AISLE_X0, AISLE_W, RACK_W = 5.2, 3.0, 2.4  # first aisle's west side; double racks between aisles
RACKS_S, RACKS_N = (11.5, 21.5), (24.5, 34.0)  # rack blocks either side of the cross aisle


def aisle_x(i: int) -> float:
    return AISLE_X0 + i * (AISLE_W + RACK_W)


def warehouse_raster() -> Raster:
    """The floor: outer walls, docks' bumpers, racks, conveyor, chargers, pillars, two rooms."""
    r = Raster((-1.0, -1.0), (HALL[0] + 2, HALL[1] + 2))
    r.fill(-0.3, -0.3, HALL[0] + 0.3, HALL[1] + 0.3, OCCUPIED)
    r.fill(0, 0, *HALL, FREE)
    for k in range(8):  # dock bumpers either side of each dock door
        c = 6 + 7 * k
        r.fill(c - 1.6, 0, c - 1.3, 0.35, OCCUPIED)
        r.fill(c + 1.3, 0, c + 1.6, 0.35, OCCUPIED)
    for y0, y1 in (RACKS_S, RACKS_N):
        r.fill(4.0, y0, AISLE_X0, y1, OCCUPIED)  # single rack against the west strip
        for i in range(AISLES - 1):
            r.fill(aisle_x(i) + AISLE_W, y0, aisle_x(i + 1), y1, OCCUPIED)
        end = aisle_x(AISLES - 1) + AISLE_W
        r.fill(end, y0, end + 1.2, y1, OCCUPIED)  # single rack on the east side
    r.fill(6, 39.2, 50, 40, OCCUPIED)  # conveyor along the north wall
    for _, y in CHARGERS:
        r.fill(0, y - 0.3, 0.4, y + 0.3, OCCUPIED)
    for x, y in WAREHOUSE_PILLARS:
        r.fill(x - 0.25, y - 0.25, x + 0.25, y + 0.25, OCCUPIED)
    # office (north-east corner) and quality control room, walls 0.2 m, doors facing west
    r.fill(56, 30, 56.2, 40, OCCUPIED)
    r.fill(56, 30, 64, 30.2, OCCUPIED)
    r.fill(56, 31, 56.2, 32.5, FREE)
    r.fill(56, 19, 56.2, 27, OCCUPIED)
    r.fill(56, 19, 64, 19.2, OCCUPIED)
    r.fill(56, 26.8, 64, 27, OCCUPIED)
    r.fill(56, 22, 56.2, 23.5, FREE)
    return r


CHARGERS = ((1, 13.25), (2, 17.25), (3, 27.25), (4, 31.25))
WAREHOUSE_PILLARS = ((9.5, 5.0), (23.5, 5.0), (37.5, 5.0), (51.5, 5.0), (54.3, 10.0), (54.3, 29.5))


def warehouse_places() -> list[Group]:
    """The 45 goal places, as rooms (polygons in metres of the map frame)."""
    docks = [room(f"dock{k + 1}", box(4 + 7 * k, 0.4, 8 + 7 * k, 4.3)) for k in range(8)]
    stages = [room(f"stage{k + 1}", box(4 + 8 * k, 5.8, 10 + 8 * k, 9)) for k in range(6)]
    south = [room(f"a{i + 1}s", box(aisle_x(i) + 0.2, 12, aisle_x(i) + 2.8, 21)) for i in range(AISLES)]
    north = [room(f"a{i + 1}n", box(aisle_x(i) + 0.2, 25, aisle_x(i) + 2.8, 33.5)) for i in range(AISLES)]
    picks = [room(f"pick{k + 1}", box(7 + 7 * k, 36.6, 11 + 7 * k, 39)) for k in range(6)]
    charge = [room(f"charge{k}", box(0.5, y - 1.25, 3.5, y + 1.25)) for k, y in CHARGERS]
    other = [
        room("office", box(56.5, 30.5, 63.7, 39.7), "walled, door at x 56, y 31..32.5"),
        room("qa", box(56.5, 19.5, 63.7, 26.5), "quality control, walled, door at x 56, y 22..23.5"),
        room("returns", box(55, 10.5, 63, 16.5), "open floor"),
    ]
    return [
        Group("loading docks along the south wall, west to east (dock doors closed: wall)", docks),
        Group("staging lanes in front of the docks", stages),
        Group("aisles between the racks, south of the cross aisle (y 21.5..24.5), west to east", south),
        Group("the same aisles north of the cross aisle", north),
        Group("pick stations along the conveyor (north wall)", picks),
        Group("charging stations along the west wall", charge),
        Group("east side", other),
    ]


def warehouse_landmarks() -> list[Group]:
    ends = []
    for i in range(AISLES - 1):
        xc = aisle_x(i) + AISLE_W + RACK_W / 2
        if i % 2 == 0:  # rack ends on the cross aisle
            ends.append(landmark(f"rack{i + 1}-cs", "rack end", (xc, RACKS_S[1] + 0.05)))
            ends.append(landmark(f"rack{i + 1}-cn", "rack end", (xc, RACKS_N[0] - 0.05)))
        else:  # rack ends on the main aisles
            ends.append(landmark(f"rack{i + 1}-s", "rack end", (xc, RACKS_S[0] - 0.05)))
            ends.append(landmark(f"rack{i + 1}-n", "rack end", (xc, RACKS_N[1] + 0.05)))
    pillars = [
        landmark(f"pillar{k + 1}", "pillar", pillar_landmark(x, y, 0.25, (30, 20)), f"pillar at {pt((x, y))}")
        for k, (x, y) in enumerate(WAREHOUSE_PILLARS)
    ]
    others = [
        landmark("terminal-2", "pick terminal", (16.0, 39.15), "on the conveyor at pick2"),
        landmark("terminal-5", "pick terminal", (37.0, 39.15), "on the conveyor at pick5"),
        landmark("charger-1", "charger", (0.45, 13.25)),
        landmark("charger-3", "charger", (0.45, 27.25)),
        landmark("qa-sign", "sign", (55.95, 25.0), "west wall of the qa room"),
    ]
    return [
        Group("rack ends, alternately on the cross aisle and on the main aisles", ends),
        Group("pillars (a tag 5 cm off the pillar corner that faces the racks)", pillars),
        Group("", others),
    ]


WAREHOUSE_STARTS = (
    ("main aisle south, west end", 2.0, 10.2, 0.0),
    ("main aisle north, east end", 54.3, 35.2, 3.1416),
    ("cross aisle, middle", 31.0, 23.0, 0.0),
    ("east of the staging lanes", 60.0, 7.0, 3.1416),
    ("main aisle north, west end", 2.0, 35.2, 0.0),
    ("cross aisle, east", 45.0, 23.0, 3.1416),
    ("main aisle south", 20.0, 10.2, 0.0),
    ("main aisle north", 40.0, 35.2, 3.1416),
)


def warehouse() -> dict[str, bytes]:
    raster = warehouse_raster()
    files = {
        "warehouse/map.pgm": raster.pgm("tmpnav warehouse, 0.05 m/pixel, benchmarks/scenarios/generate.py"),
        "warehouse/map.yaml": raster.map_yaml(
            [
                "ROS map_server map (nav2 layout) of a logistics floor for tmpnav: a 64 m x 40 m hall,",
                "0.3 m outer walls, 1 m of unknown space around them. Pixels: 254 free, 0 occupied,",
                "205 unknown; free_thresh 0.196 keeps the unknown grey unknown (0.196 < 205's 0.1961).",
                "Written by benchmarks/scenarios/generate.py.",
            ]
        ),
    }
    places = warehouse_places()
    names = [e.name for g in places for e in g.entries]
    landmarks = warehouse_landmarks()
    for n in (2, 4, 8):
        robots = [robot(f"r{i + 1}", x, y, th, w) for i, (w, x, y, th) in enumerate(WAREHOUSE_STARTS[:n])]
        spec = Spec(
            header=warehouse_header(n, len(names), sum(len(g.entries) for g in landmarks)),
            name=f"warehouse-{n}robots",
            description=f"Logistics floor from a ROS map: {len(names)} goal places (docks, staging lanes, aisles, "
            f"pick and charging stations), {n} robots",
            map_lines=["  ros: warehouse/map.yaml"],
            rooms=places,
            doors=[],
            landmarks=landmarks,
            robots=[Group("", robots)],
            roadmap=roadmap_lines("warehouse"),
            goals=spread(names, 20),
            goals_comment="default task: 20 places spread over the floor (`tmpnav bench` draws its own)",
            models=LIDAR,
        )
        files[f"warehouse-{n}robots.yaml"] = scenario_text(spec).encode()
    return files


def warehouse_header(robots: int, places: int, landmarks: int) -> list[str]:
    return [
        f"A warehouse from a ROS map_server map (warehouse/map.yaml + map.pgm), {places} goal places,",
        f"{robots} robots. The goal places are the scenario's rooms: polygons in metres of the map frame.",
        "",
        "Layout of the 64 m x 40 m hall (map frame, y up): eight loading docks along the south",
        "wall (dock1..dock8, bumpers either side of each door) and six staging lanes in front of",
        "them (stage1..stage6, y 5.8..9); the rack area (x 4..52.6, y 11.5..34) with nine 3 m",
        "aisles between double racks, cut in two by a 3 m cross aisle (y 21.5..24.5): a1s..a9s",
        "south of it, a1n..a9n north of it; six pick stations along a conveyor on the north wall",
        "(pick1..pick6); four charging stations on the west wall (charge1..charge4); an office and",
        "a quality-control room (walled, doors facing west) and a returns area on the east side.",
        "Main aisles run along the racks' south (y 9..11.5) and north (y 34..36.6) ends.",
        "",
        f"{landmarks} landmarks: rack ends (a sign on the end face), six building pillars, two pick",
        "terminals, two chargers and a sign. From the middle of an aisle none is in sight within",
        "5 m (the default landmark sensor): the racks hide the pillars. The robots carry a 2D",
        "lidar (models.range_sensor) and localise against the racks and walls.",
        "Robots start in the main aisles, the cross aisle and the open floor east of the staging",
        "lanes; warehouse-2robots, -4robots and -8robots share the map and each team is the first",
        "robots of the larger one (`tmpnav bench --scenario configs/warehouse-{robots}robots.yaml`).",
        "Default task (goals, at the end): visit 20 places spread evenly over the floor (tmpnav",
        "plans it with the anytime search); the bench draws its own places.",
        "",
        "Written by benchmarks/scenarios/generate.py (edit that script, not this file).",
        "Units: metres, radians.",
    ]


# ------------------------------------------------------ the landmark-sparse hall (ROS)

SPARSE_HALL = 50.0
PILLAR_X = (7.0, 21.0, 30.0, 43.0)  # spacings 14, 9, 13 m
PILLAR_Y = (6.0, 20.0, 28.0, 42.0)  # spacings 14, 8, 14 m
SPARSE_PLACES = (
    ("P1", 14.0, 13.0),
    ("P2", 36.5, 13.0),
    ("P3", 14.0, 35.0),
    ("P4", 36.5, 35.0),
    ("P5", 25.5, 46.5),
    ("P6", 47.5, 24.0),
    ("P7", 3.5, 13.0),
    ("P8", 25.5, 24.0),
)


def sparse_raster() -> Raster:
    r = Raster((-1.0, -1.0), (SPARSE_HALL + 2, SPARSE_HALL + 2))
    r.fill(-0.3, -0.3, SPARSE_HALL + 0.3, SPARSE_HALL + 0.3, OCCUPIED)
    r.fill(0, 0, SPARSE_HALL, SPARSE_HALL, FREE)
    for x in PILLAR_X:
        for y in PILLAR_Y:
            r.fill(x - 0.25, y - 0.25, x + 0.25, y + 0.25, OCCUPIED)
    r.fill(0, 23.9, 12, 24.1, OCCUPIED)  # partition wall from the west wall
    r.fill(9, 45, 9.2, 50, OCCUPIED)  # office in the north-west corner, door on its south side
    r.fill(0, 45, 9.2, 45.2, OCCUPIED)
    r.fill(3, 45, 4.5, 45.2, FREE)
    r.fill(33, 44, 47, 45.2, OCCUPIED)  # two rack rows in the north-east, a 1.8 m aisle between
    r.fill(33, 47, 47, 48.2, OCCUPIED)
    r.fill(40, 9.9, 50, 10.1, OCCUPIED)  # a fence from the east wall
    return r


def sparse_warehouse() -> dict[str, bytes]:
    raster = sparse_raster()
    pillars = [(x, y) for y in PILLAR_Y for x in PILLAR_X]
    centre = (SPARSE_HALL / 2, SPARSE_HALL / 2)
    # only the pillars along the south wall and the west and east columns carry a tag: the
    # middle and the north of the hall have no landmark at all
    tagged = [(k, (x, y)) for k, (x, y) in enumerate(pillars) if y == PILLAR_Y[0] or x in (PILLAR_X[0], PILLAR_X[-1])]
    tagged = [(k, xy) for k, xy in tagged if xy[1] != PILLAR_Y[-1]]
    marks = [
        landmark(f"pillar{k + 1}", "pillar", pillar_landmark(x, y, 0.25, centre), f"pillar at {pt((x, y))}")
        for k, (x, y) in tagged
    ]
    tags = [pillar_landmark(x, y, 0.25, centre) for _, (x, y) in tagged]
    places, gaps = [], []
    for name, x, y in SPARSE_PLACES:
        gaps.append(min(math.hypot(x - tx, y - ty) for tx, ty in tags))
        places.append(room(name, box(x - 1.5, y - 1.5, x + 1.5, y + 1.5), f"centre {gaps[-1]:.1f} m from a landmark"))
    spec = Spec(
        header=[
            "A landmark-sparse warehouse from a ROS map_server map (sparse-warehouse/map.yaml +",
            "map.pgm): a 50 m x 50 m hall of open floor with 16 pillars (0.5 m square) on an",
            "irregular grid, 7 to 15 m apart (x 7, 21, 30, 43; y 6, 20, 28, 42). Only 8 of them carry",
            "a landmark tag: the four along the south wall (y 6) and two each in the west and east",
            "columns (x 7 and 43, y 20 and 28). The middle and the north of the hall have none, so",
            "the belief a robot carries into a place depends on the way it came: canonical start",
            "states (--costs table) misjudge the plans there, the beliefs carried step to step",
            "(--costs carried) do not. The robots have no range sensor: this is the paper's model,",
            "which this hall is built to starve (a lidar would see the pillars and pin the beliefs).",
            "A few walls and racks: a partition from the west wall (y 24, x 0..12), an office in the",
            "north-west corner (door on its south side), two rack rows in the north-east",
            "(x 33..47) and a fence from the east wall (y 10, x 40..50).",
            "",
            "The eight places to visit (3 m x 3 m, P1..P8) sit in the middle of the widest gaps",
            f"between pillars, their centres {min(gaps):.1f} to {max(gaps):.1f} m from the nearest landmark: with the",
            "default 5 m landmark sensor a robot sees none there, and routes between places cross long",
            "stretches without one. Each landmark is a tag 5 cm off the pillar corner that faces",
            "the middle of the hall (tmpnav hides a landmark behind any occupied cell, so a point",
            "inside the pillar would never be seen). Three robots start along the south wall.",
            "",
            "Written by benchmarks/scenarios/generate.py (edit that script, not this file).",
            "Units: metres, radians.",
        ],
        name="sparse-warehouse",
        description="Open 50 m x 50 m hall from a ROS map, landmarks on 8 pillars along its south, west and east "
        "sides only, 3 robots, 8 places",
        map_lines=["  ros: sparse-warehouse/map.yaml"],
        rooms=[Group("places to visit, in the gaps between pillars", places)],
        doors=[],
        landmarks=[Group("tagged pillars, south to north, west to east", marks)],
        robots=[
            Group(
                "along the south wall, facing north",
                [robot("r1", 10, 2, 1.5708), robot("r2", 25.5, 2, 1.5708), robot("r3", 40, 2, 1.5708)],
            )
        ],
        models=["models: {}  # the paper's models: landmarks only, no range sensor (a lidar would see the pillars)"],
        roadmap=roadmap_lines("sparse-warehouse"),
        goals=[p[0] for p in SPARSE_PLACES],
        goals_comment="visit every place",
    )
    return {
        "sparse-warehouse/map.pgm": raster.pgm(
            "tmpnav sparse warehouse, 0.05 m/pixel, benchmarks/scenarios/generate.py"
        ),
        "sparse-warehouse/map.yaml": raster.map_yaml(
            [
                "ROS map_server map (nav2 layout) of an open 50 m x 50 m hall for tmpnav: 0.3 m outer",
                "walls, 1 m of unknown space around them, 16 pillars. Pixels: 254 free, 0 occupied,",
                "205 unknown; free_thresh 0.196 keeps the unknown grey unknown (0.196 < 205's 0.1961).",
                "Written by benchmarks/scenarios/generate.py.",
            ]
        ),
        "sparse-warehouse.yaml": scenario_text(spec).encode(),
    }


# ------------------------------------------------------------------------- main


def all_files() -> dict[str, bytes]:
    """Every generated file, by its path relative to configs/."""
    return {**building_20(), **office_building(), **warehouse(), **sparse_warehouse()}


def main(argv: list[str] | None = None) -> int:
    """Write (or with ``--check`` compare) every generated file; returns the exit code."""
    parser = argparse.ArgumentParser(description="Write tmpnav's scenarios of real size into configs/.")
    parser.add_argument("--out", type=Path, default=ROOT / "configs", help="folder to write (default: configs/)")
    parser.add_argument("--check", action="store_true", help="compare with the files in --out, write nothing")
    args = parser.parse_args(argv)
    stale = []
    for rel, data in all_files().items():
        path = args.out / rel
        if args.check:
            if not path.is_file() or path.read_bytes() != data:
                stale.append(rel)
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.is_file() or path.read_bytes() != data:
            path.write_bytes(data)
            print(f"wrote {path}")
    if stale:
        print("out of date, rerun benchmarks/scenarios/generate.py: " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
