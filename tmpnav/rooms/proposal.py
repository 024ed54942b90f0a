"""A ROS map -> a proposed scenario: named rooms, doors, landmark candidates, a robot and goals.

Everything here is plain data; :mod:`tmpnav.rooms.skeleton` writes it as a scenario YAML file
and :mod:`tmpnav.report.rooms_plot` draws it over the map.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import ndimage

from tmpnav.errors import Problem, ScenarioError
from tmpnav.rooms.doors import DoorCandidate, find_doors
from tmpnav.rooms.landmarks import LandmarkCandidate, find_landmarks
from tmpnav.rooms.polygon import outline
from tmpnav.rooms.segment import EIGHT, Segmentation, SegmentParams, segment
from tmpnav.types import RosMap
from tmpnav.world.grid import OccupancyGrid, clearance, fill_polygon, fill_segment

ROBOT_RADIUS = 0.25  # m: the scenario format's default robot radius, which the placeholder robot gets
DOOR_THICKNESS = 0.15  # m: the scenario format's default door thickness on a ROS map
DEEP_DOOR = 1.2  # m: a door carved this deep also clears noise just before and after the doorway
#: m: a passage counts when a robot this much wider fits through: validate accepts a path one cell
#: wide between specks of noise, but the roadmap's random samples would hardly ever find it
LEEWAY = 0.05
SAMPLES_PER_M2 = 6.0  # PRM milestones per m² of free space a robot can reach ...
SAMPLES_RANGE = (1000, 6000)  # ... within these bounds


@dataclass(frozen=True, eq=False)
class RoomProposal:
    name: str  # R1, R2, ... in reading order
    label: int  # its label in the segmentation
    polygon: np.ndarray  # (k, 2) m, counter-clockwise
    area: float  # m² of free space
    width: float  # m: twice the largest clearance inside it (the widest disc that fits)
    spot: tuple[float, float]  # the point of largest clearance, m
    reachable: bool  # whether the placeholder robot can drive there from its start


@dataclass(frozen=True, eq=False)
class Proposal:
    """What ``tmpnav rooms`` found in a map, ready to be written as a scenario."""

    map: RosMap
    grid: OccupancyGrid
    segmentation: Segmentation
    rooms: tuple[RoomProposal, ...]
    doors: dict[str, DoorCandidate]  # D1, D2, ... -> door
    deep_doors: frozenset[str]  # doors to carve DEEP_DOOR deep (noise at the doorway blocks them)
    landmarks: dict[str, LandmarkCandidate]  # name -> candidate
    robot_pose: tuple[float, float, float]  # the placeholder robot r1, m, m, rad
    robot_room: str
    goals: tuple[str, ...]  # pre-filled goals: rooms near the robot
    samples: int  # PRM milestones suggested for this map

    def room(self, label: int) -> RoomProposal:
        return next(r for r in self.rooms if r.label == label)

    @property
    def usable_rooms(self) -> tuple[RoomProposal, ...]:
        return tuple(r for r in self.rooms if r.reachable)


def read_map(path: Path) -> tuple[RosMap, OccupancyGrid]:
    """A ROS map_server map (YAML + image) and its occupancy grid; ScenarioError if unusable."""
    from tmpnav.scenario.load import read_ros_map
    from tmpnav.world.rosmap import MapImageError, load_ros_map

    spec, problems = read_ros_map(Path(path).resolve())
    if spec is None or problems:
        raise ScenarioError(problems)
    try:
        return spec, load_ros_map(spec)
    except MapImageError as err:
        raise ScenarioError([err.problem]) from None


def propose(spec: RosMap, grid: OccupancyGrid, params: SegmentParams | None = None) -> Proposal:
    """Segment the map and propose the scenario's parts (see the module docstring)."""
    seg = segment(grid, params)
    if seg.n_rooms == 0:
        where = str(spec.yaml_path)
        raise ScenarioError([Problem(where, "", "no free area large enough for a room (see --min-area) in this map")])
    clear = clearance(grid)
    rooms = _rooms(seg, clear)
    door_list = find_doors(seg)
    doors = {f"D{i}": d for i, d in enumerate(door_list, start=1)}
    hub = _hub(rooms, door_list)
    i, j = np.unravel_index(np.argmax(np.where(seg.mask(hub.label), clear, -1.0)), clear.shape)
    if clear[i, j] < ROBOT_RADIUS + grid.resolution:
        message = f"no room is wide enough for a robot of radius {ROBOT_RADIUS:g} m (widest: {2 * clear[i, j]:.2f} m)"
        raise ScenarioError([Problem(str(spec.yaml_path), "", message)])
    x0, y0 = grid.origin
    start = (float(x0 + (j + 0.5) * grid.resolution), float(y0 + (i + 0.5) * grid.resolution))
    reach, deep = _reachability(seg, rooms, doors, (int(i), int(j)))
    reach.add(hub.label)  # the robot starts there, however cluttered it is
    rooms = tuple(RoomProposal(r.name, r.label, r.polygon, r.area, r.width, r.spot, r.label in reach) for r in rooms)
    outlines = {r.label: r.polygon for r in rooms}
    landmarks = _name_landmarks(find_landmarks(seg, doors, outlines))
    usable = [r for r in rooms if r.reachable]
    others = sorted((r for r in usable if r.label != hub.label), key=lambda r: np.hypot(*np.subtract(r.spot, start)))
    goals = tuple(r.name for r in others[:2]) or (hub.name,)
    free_area = sum(r.area for r in usable)
    lo, hi = SAMPLES_RANGE
    samples = int(min(hi, max(lo, round(SAMPLES_PER_M2 * free_area, -2))))
    return Proposal(spec, grid, seg, rooms, doors, frozenset(deep), landmarks, (*start, 0.0), hub.name, goals, samples)


def _rooms(seg: Segmentation, clear: np.ndarray) -> tuple[RoomProposal, ...]:
    grid = seg.grid
    x0, y0 = grid.origin
    out = []
    for k in range(1, seg.n_rooms + 1):
        mask = seg.mask(k)
        i, j = np.unravel_index(np.argmax(np.where(mask, clear, -1.0)), mask.shape)
        spot = (float(x0 + (j + 0.5) * grid.resolution), float(y0 + (i + 0.5) * grid.resolution))
        area = float(mask.sum()) * grid.resolution**2
        width = 2.0 * float(seg.clearance[mask].max())  # furniture and speckles left out
        out.append(RoomProposal(f"R{k}", k, outline(mask, grid), area, width, spot, True))
    return tuple(out)


def _hub(rooms: tuple[RoomProposal, ...], doors: list[DoorCandidate]) -> RoomProposal:
    """The room with the most doors (a corridor, a hall), the larger one on a tie."""
    count = {r.label: 0 for r in rooms}
    for d in doors:
        for label in d.rooms:
            count[label] += 1
    return max(rooms, key=lambda r: (count[r.label], r.area))


def _reachability(
    seg: Segmentation, rooms: tuple[RoomProposal, ...], doors: dict[str, DoorCandidate], start: tuple[int, int]
) -> tuple[set[int], set[str]]:
    """The rooms a robot of the default radius reaches from ``start``, and the doors that must be
    carved ``DEEP_DOOR`` deep for that.

    Free space is what ``tmpnav validate`` tests on the world the scenario builds (doors carved
    free, clearance at least radius plus one cell, 8-connected), with ``LEEWAY`` to spare. Validate is content with one
    reachable cell inside a room's polygon; here at least half of the room's free cells must be
    reachable (a doorway's share of a room is not the room). A speck of noise just before a
    doorway can block it for the robot; a door carved deeper clears it, and is used only where
    that makes a room reachable that was not.
    """
    grid = seg.grid
    xs, ys = grid.cell_centers()
    inside = {}
    for room in rooms:
        inside[room.label] = np.zeros(grid.shape, dtype=bool)
        fill_polygon(inside[room.label], xs, ys, room.polygon, True)

    def reachable(deep: set[str]) -> set[int]:
        free, component = _free_from(seg.grid, doors, deep, start)
        out = set()
        for label, cells in inside.items():
            room_free = np.count_nonzero(cells & free)
            if room_free and np.count_nonzero(cells & component) >= 0.5 * room_free:
                out.add(label)
        return out

    usual = reachable(set())
    deep = {name for name, d in doors.items() if not set(d.rooms) <= usual}
    found = reachable(deep)
    deep = {name for name in deep if not set(doors[name].rooms) <= usual and set(doors[name].rooms) <= found}
    return reachable(deep), deep


def _free_from(
    grid: OccupancyGrid, doors: dict[str, DoorCandidate], deep: set[str], start: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """Cells where a robot of the default radius fits with ``LEEWAY`` to spare, and those of them
    it reaches from ``start``, with the doors carved as world.build carves them."""
    occupied = grid.occupied.copy()
    xs, ys = grid.cell_centers()
    for name, door in doors.items():
        thickness = (DEEP_DOOR if name in deep else DOOR_THICKNESS) + 2 * grid.resolution  # as world.build carves
        a, b = (np.array(p) for p in door.segment)
        fill_segment(occupied, xs, ys, a, b, thickness, False, flat_caps=True)
    clear = clearance(OccupancyGrid(occupied, grid.origin, grid.resolution))
    free = clear >= ROBOT_RADIUS + grid.resolution + LEEWAY
    comp, _ = ndimage.label(free, structure=EIGHT)
    return free, (comp == comp[start] if comp[start] > 0 else np.zeros(grid.shape, dtype=bool))


def _name_landmarks(found: list[LandmarkCandidate]) -> dict[str, LandmarkCandidate]:
    """Names like pillar1, door-frame2, corner1: one counter per kind."""
    counts: dict[str, int] = {}
    named = {}
    for lm in found:
        counts[lm.kind] = counts.get(lm.kind, 0) + 1
        named[f"{lm.kind}{counts[lm.kind]}"] = lm
    return named
