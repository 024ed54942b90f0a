"""Rooms and halls together: the regions a scenario names, their doors and landmark candidates.

The segmentation finds rooms (:mod:`tmpnav.rooms.segment`); a room larger than ``max_area`` is
a hall, split into places (:mod:`tmpnav.rooms.places`). What the scenario calls rooms are the
rooms that are no hall, ``R1..Rn`` in reading order, and the places of the halls, ``P1..Pm``,
hall by hall (``H1, H2, ...``), each hall's in reading order.

Doors are of two kinds. A *door* joins two rooms (or a room and the place of a hall it opens
onto), found on the rooms exactly as without halls. A *connection* joins two places of one
hall across open floor, kept off pillars and racks. Landmark candidates are found on the rooms
(a hall keeps the share of pillars it had as one room) and given to the place they are in.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from tmpnav.rooms.doors import DoorCandidate, find_doors
from tmpnav.rooms.landmarks import LandmarkCandidate
from tmpnav.rooms.places import PlaceParams, split_halls
from tmpnav.rooms.segment import Segmentation, reading_order, speckle_cells, speckles


@dataclass(frozen=True, eq=False)
class Layout:
    """Rooms and places: the two segmentations and how their labels relate."""

    rooms: Segmentation  # the rooms, halls whole
    segmentation: Segmentation  # the regions of the scenario: rooms that are no hall, then places
    names: dict[int, str]  # label in ``segmentation`` -> R1.. or P1..
    hall_of: dict[int, int]  # label of a place in ``segmentation`` -> label of its hall in ``rooms``
    hall_names: dict[int, str]  # label of a hall in ``rooms`` -> H1..
    room_label: np.ndarray  # label in ``rooms`` -> label in ``segmentation`` (0 for a hall)

    def region_of(self, room: int, xy: tuple[float, float]) -> int:
        """The label (in ``segmentation``) of the region of room ``room`` (a label in ``rooms``)
        at ``xy`` or nearest to it: the room itself, or the place of a hall."""
        if room not in self.hall_names:
            return int(self.room_label[room])
        grid = self.rooms.grid
        i, j, _ = grid.cells(np.array(xy))
        for reach in (4, 16, 64, max(grid.shape)):
            top, left = max(int(i) - reach, 0), max(int(j) - reach, 0)
            box = slice(top, int(i) + reach + 1), slice(left, int(j) + reach + 1)
            cells = np.argwhere(self.rooms.labels[box] == room) + np.array([top, left])
            if cells.size:
                a, b = cells[int(np.argmin(((cells - np.array([i, j])) ** 2).sum(axis=1)))]
                return int(self.segmentation.labels[a, b])
        raise ValueError(f"room {room} has no cells")


def lay_out(rooms: Segmentation, params: PlaceParams) -> Layout:
    """Split the halls among ``rooms`` into places and number everything (module docstring)."""
    places = split_halls(rooms, params)
    room_of = _room_of(rooms.labels, places)
    halls = [k for k in range(1, rooms.n_rooms + 1) if np.count_nonzero(room_of == k) >= 2]
    plain = [k for k in range(1, rooms.n_rooms + 1) if k not in halls]
    room_label = np.zeros(rooms.n_rooms + 1, dtype=np.int32)
    room_label[plain] = np.arange(1, len(plain) + 1)
    labels = room_label[rooms.labels]
    in_hall = np.isin(rooms.labels, halls)
    rank = reading_order(np.where(in_hall, places, 0))  # places 1..m in reading order, over all halls
    rank_hall = _room_of(rooms.labels, rank)
    order = sorted(range(1, len(rank_hall)), key=lambda p: (halls.index(int(rank_hall[p])), p))
    lookup = np.zeros(len(rank_hall), dtype=np.int32)
    lookup[order] = np.arange(len(plain) + 1, len(plain) + len(order) + 1)
    labels[in_hall] = lookup[rank[in_hall]]
    names = {k: f"R{k}" for k in range(1, len(plain) + 1)}
    names.update({len(plain) + n: f"P{n}" for n in range(1, len(order) + 1)})
    hall_of = {int(lookup[p]): int(rank_hall[p]) for p in order}
    segmentation = Segmentation(rooms.grid, labels, rooms.clearance, rooms.filled)
    hall_names = {k: f"H{n}" for n, k in enumerate(halls, start=1)}
    return Layout(rooms, segmentation, names, hall_of, hall_names, room_label)


def _room_of(rooms: np.ndarray, regions: np.ndarray) -> np.ndarray:
    """For each label 0..n of ``regions``, the label in ``rooms`` of its cells (0 for label 0);
    every region lies in one room."""
    out = np.zeros(int(regions.max()) + 1, dtype=np.int64)
    out[regions.ravel()] = rooms.ravel()
    out[0] = 0
    return out


def named_doors(layout: Layout) -> tuple[dict[str, DoorCandidate], dict[str, DoorCandidate], frozenset[str]]:
    """Doors and connections named D1.. (by the regions they join, then position): as the
    scenario has them (labels of ``layout.segmentation``), the doors as found between rooms
    (labels of ``layout.rooms``, for the landmark candidates at their jambs), and which names
    are connections between the places of a hall."""
    found = find_doors(layout.rooms)
    moved = [
        replace(d, rooms=tuple(sorted(layout.region_of(k, d.centre) for k in d.rooms)))  # type: ignore[arg-type]
        for d in found
    ]
    grid = layout.rooms.grid
    solid = grid.occupied & ~speckles(grid.occupied, speckle_cells(grid.resolution))
    hall_of = layout.hall_of
    links = find_doors(
        layout.segmentation, solid=solid, pairs=lambda p: p[0] in hall_of and hall_of[p[0]] == hall_of.get(p[1])
    )
    tagged = [(d, f) for d, f in zip(moved, found, strict=True)] + [(d, None) for d in links]
    tagged.sort(key=lambda t: (t[0].rooms, t[0].centre[1], t[0].centre[0]))
    doors, as_found, connections = {}, {}, set()
    for n, (door, original) in enumerate(tagged, start=1):
        doors[f"D{n}"] = door
        if original is None:
            connections.add(f"D{n}")
        else:
            as_found[f"D{n}"] = original
    return doors, as_found, frozenset(connections)


def place_landmarks(layout: Layout, found: list[LandmarkCandidate]) -> list[LandmarkCandidate]:
    """Landmark candidates found on the rooms, each given to the region it lies in."""
    return [replace(lm, room=layout.region_of(lm.room, lm.position)) for lm in found]
