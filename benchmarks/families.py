"""Generated families of buildings: the instances tmpnav is measured on, not tuned on.

    .venv/bin/python benchmarks/families.py office --rooms 40 --robots 4 --seed 3 -o office.yaml
    .venv/bin/python benchmarks/families.py warehouse --rooms 30 --robots 4 --seed 1 -o hall.yaml
    .venv/bin/python benchmarks/families.py warehouse --rooms 10 --stations 40 --robots 4 -o stations.yaml

Two kinds, each a scenario file that ``tmpnav plan`` takes as it is (default roadmap settings):

* ``office``: one to three east-west corridors (2.5-3 m wide), each with rooms on both sides
  (4-10 m wide, 5-7 m deep, seeded), doors 1.0-1.4 m wide at random places along each room's
  corridor wall, the corridors joined at their west end by a north-south corridor; a landmark
  every ``landmark_spacing`` m along each corridor, on alternating sides; robots at the ends
  of the corridors.
* ``warehouse``: a hall with rows of double racks (2.4 m deep, with gaps), aisles of 2.6-3.4 m
  between them, a main aisle along the south and north walls, docks along the south wall;
  the goal places are stretches of aisle and the docks; landmarks on rack ends. With
  ``--stations N``, N stations spread over the places (pick faces along the racks, charging
  spots in the docks) are the goals instead.

Both carry the shipped scenarios' lidar unless ``--no-lidar``; the goals are every room or
place. :func:`office` and :func:`warehouse` return the scenario as a dict (benchmarks/bench_families.py
writes them).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml

LIDAR = {"range": 12, "fov": "360 deg", "beams": 60, "sigma_range": 0.03, "divergence": 0.01}
WALL = 0.15  # m, wall thickness


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [
        [round(x0, 3), round(y0, 3)],
        [round(x1, 3), round(y0, 3)],
        [round(x1, 3), round(y1, 3)],
        [round(x0, 3), round(y1, 3)],
    ]


#: m: the spacing of robots queued at one corridor end, and the least x a queued robot stands at
QUEUE_SPACING, QUEUE_WEST = 1.5, 0.6


def _queued_x(x: float, k: int) -> float:
    """The x of the k-th robot queued at a corridor end whose first robot stands at ``x``: every
    1.5 m westwards while inside the map (x at least 0.6 m: the west corridor), then eastwards
    from beyond the first (a fleet of 32 robots on 2 corridors queues 8 at each end)."""
    west = int((x - QUEUE_WEST) // QUEUE_SPACING) + 1  # robots that fit westwards, the first included
    return x - QUEUE_SPACING * k if k < west else x + QUEUE_SPACING * (k - west + 1)


def _widths(rng: np.random.Generator, n: int) -> list[float]:
    return [float(round(rng.uniform(4.0, 10.0) * 2) / 2) for _ in range(n)]


def office(
    rooms: int, robots: int, seed: int, corridors: int | None = None, landmark_spacing: float = 12.0, lidar: bool = True
) -> dict[str, Any]:
    """An office of ``rooms`` rooms on one to three corridors (module docstring)."""
    rng = np.random.default_rng(seed)
    corridors = corridors or (1 if rooms <= 24 else 2 if rooms <= 50 else 3)
    per_row = [rooms // (2 * corridors) + (1 if k < rooms % (2 * corridors) else 0) for k in range(2 * corridors)]
    rows = [_widths(rng, n) for n in per_row]
    length = max(sum(w) for w in rows)
    west = 3.0  # the north-south corridor joining the corridors
    x_end = west + length
    walls: list[list[list[float]]] = []
    room_list, doors, landmarks, starts = [], [], [], []
    y = 0.0
    for c in range(corridors):
        depth_s, depth_n, width = (
            float(round(v * 2) / 2) for v in (rng.uniform(5, 7), rng.uniform(5, 7), rng.uniform(2.5, 3.0))
        )
        y_s, y_c0, y_c1, y_n = y, y + depth_s, y + depth_s + width, y + depth_s + width + depth_n
        if c > 0:  # back to back with the rooms of the corridor below
            walls.append([[west, y_s], [x_end, y_s]])
        for side, (widths, door_y, back_y) in enumerate(((rows[2 * c], y_c0, y_s), (rows[2 * c + 1], y_c1, y_n))):
            x = west
            wall_x = west
            for k, w in enumerate(widths):
                name = f"{'SN'[side]}{c + 1}-{k + 1}"
                door_w = float(rng.uniform(1.0, 1.4))
                a = float(rng.uniform(x + 0.4, x + w - 0.4 - door_w))
                walls.append([[wall_x, door_y], [a, door_y]])
                doors.append(
                    {
                        "name": f"door-{name}",
                        "segment": [[round(a, 3), door_y], [round(a + door_w, 3), door_y]],
                        "state": "open",
                    }
                )
                wall_x = a + door_w
                lo, hi = min(door_y, back_y), max(door_y, back_y)
                room_list.append({"name": name, "polygon": _box(x + 0.1, lo + 0.1, x + w - 0.1, hi - 0.1)})
                walls.append([[x + w, door_y], [x + w, back_y]])
                x += w
            walls.append([[wall_x, door_y], [x_end, door_y]])
            walls.append([[west, door_y], [west, back_y]])
        for k, lx in enumerate(np.arange(west + landmark_spacing / 2, x_end, landmark_spacing)):
            ly = y_c0 + 0.3 if k % 2 == 0 else y_c1 - 0.3
            landmarks.append(
                {"name": f"mark-{c + 1}-{k + 1}", "kind": "sign", "position": [round(float(lx), 3), round(ly, 3)]}
            )
        starts.append((x_end - 1.0, (y_c0 + y_c1) / 2, math.pi))
        starts.append((west + 1.2, (y_c0 + y_c1) / 2, 0.0))
        y = y_n
    height = y
    walls.append([[0.0, 0.0], [x_end, 0.0], [x_end, height], [0.0, height], [0.0, 0.0]])
    # the west corridor's wall, open towards every corridor
    if corridors > 1:
        for c in range(corridors):
            landmarks.append(
                {"name": f"west-{c + 1}", "kind": "sign", "position": [0.3, round(height * (c + 0.5) / corridors, 3)]}
            )
    robot_list = [
        {
            "name": f"r{i + 1}",
            "pose": [
                round(_queued_x(starts[i % len(starts)][0], i // len(starts)), 3),
                round(starts[i % len(starts)][1], 3),
                round(starts[i % len(starts)][2], 4),
            ],
        }
        for i in range(robots)
    ]
    doc: dict[str, Any] = {
        "name": f"office-{rooms}rooms-{robots}robots-seed{seed}",
        "description": f"Generated office: {rooms} rooms on {corridors} corridor(s), {robots} robots, seed {seed}",
        "map": {
            "bounds": [0, 0, round(x_end, 3), round(height, 3)],
            "resolution": 0.05,
            "wall_thickness": WALL,
            "walls": walls,
        },
        "rooms": room_list,
        "doors": doors,
        "landmarks": landmarks,
        "robots": robot_list,
        "goals": {"visit": [r["name"] for r in room_list]},
    }
    if lidar:
        doc["models"] = {"range_sensor": dict(LIDAR)}
    return doc


def stations_in(place: dict[str, Any], k: int) -> list[dict[str, Any]]:
    """``k`` stations (``goals.jobs`` with a place) evenly along the long axis of a box-shaped
    place, alternately against either long side (0.6 m in, facing it: the rack's pick faces
    of an aisle, a dock's charging spots), named ``<place>-<i>``."""
    (x0, y0), _, (x1, y1), _ = place["polygon"]
    along_x = x1 - x0 >= y1 - y0
    length, across = (x1 - x0, y1 - y0) if along_x else (y1 - y0, x1 - x0)
    offset = max(0.0, across / 2 - 0.6)
    out = []
    for i in range(k):
        t = (i + 0.5) / k * length
        side = 1 if i % 2 == 0 else -1
        if along_x:
            x, y, heading = x0 + t, (y0 + y1) / 2 + side * offset, 90 * side
        else:
            x, y, heading = (x0 + x1) / 2 + side * offset, y0 + t, 0 if side > 0 else 180
        pose = [round(x, 3), round(y, 3), f"{heading} deg"]
        out.append({"name": f"{place['name']}-{i + 1}", "place": place["name"], "pose": pose})
    return out


def warehouse(rooms: int, robots: int, seed: int, lidar: bool = True, stations: int = 0) -> dict[str, Any]:
    """A rack hall with ``rooms`` goal places: stretches of aisle and docks (module docstring);
    with ``stations``, that many stations spread over the places (:func:`stations_in`) are the
    goals instead of the places."""
    rng = np.random.default_rng(seed)
    docks = max(2, rooms // 5)
    per_aisle = 2
    aisles = max(2, math.ceil((rooms - docks) / per_aisle))
    aisle_w = [float(round(rng.uniform(2.6, 3.4), 1)) for _ in range(aisles)]
    rack = 2.4
    x0, main = 3.0, 3.5  # west margin, main aisles' width
    rack_len = float(round(rng.uniform(14, 22)))
    width = x0 + sum(aisle_w) + rack * (aisles + 1) + 3.0
    height = main + 4.0 + rack_len + main
    obstacles, places, landmarks = [], [], []
    x = x0
    ys, yn = main + 4.0, main + 4.0 + rack_len
    for a in range(aisles + 1):
        gap = float(rng.uniform(ys + 4, yn - 6))  # a gap through each rack row
        obstacles.append(_box(x, ys, x + rack, gap))
        obstacles.append(_box(x, gap + 1.6, x + rack, yn))
        landmarks.append(
            {"name": f"rack-{a + 1}", "kind": "rack end", "position": [round(x + rack / 2, 3), round(ys - 0.1, 3)]}
        )
        x += rack
        if a < aisles:
            w = aisle_w[a]
            half = ys + rack_len / 2
            places.append({"name": f"a{a + 1}s", "polygon": _box(x + 0.2, ys + 0.5, x + w - 0.2, half - 0.3)})
            places.append({"name": f"a{a + 1}n", "polygon": _box(x + 0.2, half + 0.3, x + w - 0.2, yn - 0.5)})
            x += w
    for d in range(docks):
        cx = x0 + (d + 0.5) * (width - 2 * x0) / docks
        places.append({"name": f"dock{d + 1}", "polygon": _box(cx - 1.2, 0.4, cx + 1.2, 2.8)})
    places = places[:rooms] if len(places) > rooms else places
    walls = [[[0.0, 0.0], [width, 0.0], [width, height], [0.0, height], [0.0, 0.0]]]
    robot_list = [
        {
            "name": f"r{i + 1}",
            "pose": [round(x0 + 1.5 + i * (width - 2 * x0 - 3) / max(robots - 1, 1), 3), round(main + 1.8, 3), 0.0],
        }
        for i in range(robots)
    ]
    doc: dict[str, Any] = {
        "name": f"warehouse-{len(places)}places-{robots}robots-seed{seed}",
        "description": f"Generated rack hall: {len(places)} places, {robots} robots, seed {seed}",
        "map": {
            "bounds": [0, 0, round(width, 3), round(height, 3)],
            "resolution": 0.05,
            "wall_thickness": 0.3,
            "walls": walls,
            "obstacles": obstacles,
        },
        "rooms": places,
        "landmarks": landmarks,
        "robots": robot_list,
        "goals": {"visit": [p["name"] for p in places]},
    }
    if stations:
        jobs = [j for i, p in enumerate(places) for j in stations_in(p, _share(stations, len(places), i))]
        doc["name"] = f"warehouse-{len(jobs)}stations-{len(places)}places-{robots}robots-seed{seed}"
        doc["description"] = (
            f"Generated rack hall: {len(jobs)} stations in {len(places)} places, {robots} robots, seed {seed}"
        )
        doc["goals"] = {"visit": [j["name"] for j in jobs], "jobs": jobs}
    if lidar:
        doc["models"] = {"range_sensor": dict(LIDAR)}
    return doc


def _share(total: int, parts: int, i: int) -> int:
    """Part ``i`` of ``total`` split as evenly as it goes into ``parts``."""
    return total // parts + (1 if i < total % parts else 0)


KINDS = {"office": office, "warehouse": warehouse}


def write(doc: dict[str, Any], path: Path) -> Path:
    path.write_text(yaml.safe_dump(doc, sort_keys=False, width=140))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("kind", choices=tuple(KINDS))
    parser.add_argument("--rooms", type=int, default=20)
    parser.add_argument("--robots", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-lidar", action="store_true")
    parser.add_argument("--stations", type=int, default=0, help="warehouse: stations over the places, the goals")
    parser.add_argument("-o", "--output", type=Path, required=True)
    args = parser.parse_args()
    extra = {"stations": args.stations} if args.stations else {}
    doc = KINDS[args.kind](args.rooms, args.robots, args.seed, lidar=not args.no_lidar, **extra)
    print(f"wrote {write(doc, args.output)}")


if __name__ == "__main__":
    main()
