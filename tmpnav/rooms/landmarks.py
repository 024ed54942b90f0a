"""Landmark candidates: things a robot's range-bearing sensor can pick out and that stay put.

- *pillars and obstacles*: isolated obstacles (touching no wall, larger than a speckle of noise
  and no piece of wall), at their centre; a few per room (more in a large one), the largest first;
- *door frames*: one jamb of every door, where a wall ends;
- *corners*: for a room with none of the above inside it, one corner of its outline (a
  vertex with an interior angle near 90 degrees), the one farthest from its doors.

They are candidates: the user keeps those the robots can really recognise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from tmpnav.rooms.doors import DoorCandidate
from tmpnav.rooms.segment import EIGHT, Segmentation, removable, speckle_cells, speckles
from tmpnav.world.geometry import distance_to_segment, points_in_polygon

PER_ROOM = 2  # isolated obstacles proposed per room ...
AREA_PER_LANDMARK = 25.0  # m²: ... or one per this much floor, if more (an open hall gets more)
MAX_OBSTACLE_AREA = 4.0  # m²: larger isolated obstacles are not proposed (a block of shelves is no landmark)
PILLAR_AREA = 0.25  # m²: an isolated obstacle up to this size is a pillar (a post, a column)
NEAR = 0.3  # m: a landmark this close to a room's outline counts as the room's


@dataclass(frozen=True)
class LandmarkCandidate:
    position: tuple[float, float]  # m
    kind: str  # pillar | obstacle | door-frame | corner
    room: int  # label of the room it belongs to (1-based)
    note: str  # what it is, for the scenario's comments


def find_landmarks(
    seg: Segmentation, doors: dict[str, DoorCandidate], outlines: dict[int, np.ndarray]
) -> list[LandmarkCandidate]:
    """Candidates in the order obstacles, door frames, corners (see the module docstring);
    ``doors`` by name, ``outlines`` by room label."""
    found = obstacles(seg) + [
        LandmarkCandidate(d.segment[0], "door-frame", d.rooms[0], f"a jamb of door {name}") for name, d in doors.items()
    ]
    for label, polygon in outlines.items():
        if not any(_belongs(lm.position, polygon) for lm in found):
            corner = room_corner(polygon, [d for d in doors.values() if label in d.rooms])
            if corner is not None:
                found.append(LandmarkCandidate(corner, "corner", label, "a corner of the room"))
    return found


def obstacles(seg: Segmentation) -> list[LandmarkCandidate]:
    """Isolated obstacles up to ``MAX_OBSTACLE_AREA`` (pillars, tables, machines), the largest
    first, at most ``PER_ROOM`` per room or one per ``AREA_PER_LANDMARK`` of its floor."""
    r = seg.grid.resolution
    isolated = removable(seg.grid, MAX_OBSTACLE_AREA) & ~speckles(seg.grid.occupied, speckle_cells(r))
    comp, n = ndimage.label(isolated, structure=EIGHT)
    area = np.bincount(comp.ravel(), minlength=n + 1)[1:] * r**2
    boxes = ndimage.find_objects(comp, n)
    centres = ndimage.center_of_mass(isolated, comp, np.arange(1, n + 1))
    floor = np.bincount(seg.labels.ravel()) * r**2
    cap = np.maximum(PER_ROOM, (floor / AREA_PER_LANDMARK).astype(int))
    per_room: dict[int, int] = {}
    out = []
    for k in np.argsort(-area, kind="stable"):
        box = boxes[k]
        around = tuple(slice(max(b.start - 3, 0), b.stop + 3) for b in box)  # the room lies around it
        labels = seg.labels[around][seg.labels[around] > 0]
        room = int(np.bincount(labels).argmax()) if labels.size else 0
        if room == 0 or per_room.get(room, 0) >= cap[room]:
            continue
        per_room[room] = per_room.get(room, 0) + 1
        i, j = centres[k]
        x0, y0 = seg.grid.origin
        xy = (float(x0 + (j + 0.5) * r), float(y0 + (i + 0.5) * r))
        kind = "pillar" if area[k] <= PILLAR_AREA else "obstacle"
        out.append(LandmarkCandidate(xy, kind, room, f"an isolated {kind} of {area[k]:.2f} m²"))
    return out


def room_corner(polygon: np.ndarray, doors: list[DoorCandidate]) -> tuple[float, float] | None:
    """The vertex of ``polygon`` (counter-clockwise) with an interior angle of 60-120 degrees that
    lies farthest from the room's doors (any such vertex when it has none), or None."""
    prev, nxt = np.roll(polygon, 1, axis=0), np.roll(polygon, -1, axis=0)
    a, b = prev - polygon, nxt - polygon
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-12)
    convex = (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) < 0  # a left turn when walking counter-clockwise
    ok = np.nonzero(convex & (np.abs(cos) <= 0.5))[0]
    if ok.size == 0:
        return None
    if doors:
        gap = np.min(
            [distance_to_segment(polygon[ok], np.array(d.segment[0]), np.array(d.segment[1])) for d in doors], axis=0
        )
        best = ok[int(np.argmax(gap))]
    else:
        best = ok[0]
    return float(polygon[best, 0]), float(polygon[best, 1])


def _belongs(point: tuple[float, float], polygon: np.ndarray) -> bool:
    """Whether ``point`` lies in the room's polygon or within ``NEAR`` of its outline."""
    p = np.array([point], dtype=float)
    if points_in_polygon(p, polygon)[0]:
        return True
    ends = np.roll(polygon, -1, axis=0)
    return any(distance_to_segment(p, a, b)[0] <= NEAR for a, b in zip(polygon, ends, strict=True))
