"""A ROS map -> a proposed scenario: named rooms and places, doors, landmark candidates, robots
and goals.

Everything here is plain data; :mod:`tmpnav.rooms.skeleton` writes it as a scenario YAML file
and :mod:`tmpnav.report.rooms_plot` draws it over the map. A map with halls (rooms larger than
``max_area``, split into places: :mod:`tmpnav.rooms.halls`) gets two placeholder robots and a
handful of goal places, as a robot team works there; a map of rooms gets one robot and two goal
rooms.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy import ndimage

from tmpnav.errors import Problem, ScenarioError
from tmpnav.rooms.doors import DoorCandidate
from tmpnav.rooms.halls import Layout, lay_out, named_doors, place_landmarks
from tmpnav.rooms.landmarks import LandmarkCandidate, find_landmarks
from tmpnav.rooms.places import PlaceParams
from tmpnav.rooms.polygon import outline
from tmpnav.rooms.reach import DEEP_DOOR, reachable_rooms
from tmpnav.rooms.segment import Segmentation, SegmentParams, segment
from tmpnav.types import RosMap
from tmpnav.world.grid import OccupancyGrid, clearance

__all__ = ["DEEP_DOOR", "ROBOT_RADIUS", "Proposal", "RoomProposal", "propose", "read_map"]

ROBOT_RADIUS = 0.25  # m: the scenario format's default robot radius, which the placeholder robots get
SAMPLES_PER_M2 = 6.0  # PRM milestones per m² of free space a robot can reach ...
SAMPLES_RANGE = (1000, 6000)  # ... within these bounds
ROOM_GOALS = 2  # goals pre-filled on a map of rooms (one robot) ...
HALL_GOALS = 4  # ... and on a map with halls (two robots)
APART = 2.0  # m: the second robot starts at least this far from the first
#: a map of more cells is segmented on cells a few times larger, down to this many: the rooms of a
#: 2000 x 2000 map of 5 cm cells on 10 cm cells (the scenario's check, its roadmap, runs on the map)
LARGE_MAP = 1_000_000
MARGIN = 10  # cells kept around the free space of a map
ROOMY = 0.7  # a place's spot: near its centre, where the clearance is at least this share of its largest


@dataclass(frozen=True, eq=False)
class RoomProposal:
    name: str  # R1, R2, ... in reading order; P1, P2, ... for the places of halls
    label: int  # its label in the segmentation
    polygon: np.ndarray  # (k, 2) m, counter-clockwise
    area: float  # m² of free space
    width: float  # m: twice the largest clearance inside it (the widest disc that fits)
    spot: tuple[float, float]  # the point of largest clearance, m
    reachable: bool  # whether the placeholder robot can drive there from its start
    hall: str | None = None  # H1, H2, ...: the hall it is a place of (None: a room)


@dataclass(frozen=True, eq=False)
class HallProposal:
    """A room larger than ``max_area``, written as its places."""

    name: str  # H1, H2, ... in reading order
    polygon: np.ndarray  # (k, 2) m, counter-clockwise: the hall's outline
    area: float  # m²
    places: tuple[str, ...]


@dataclass(frozen=True)
class PlacedRobot:
    name: str  # r1, r2
    pose: tuple[float, float, float]  # x, y (m), heading (rad)
    room: str  # the room or place it starts in


@dataclass(frozen=True, eq=False)
class Proposal:
    """What ``tmpnav rooms`` found in a map, ready to be written as a scenario."""

    map: RosMap
    grid: OccupancyGrid  # the map as read
    segmentation: Segmentation  # rooms and places, as the scenario names them (on working_grid(grid))
    rooms: tuple[RoomProposal, ...]  # rooms, then the places of halls
    doors: dict[str, DoorCandidate]  # D1, D2, ... -> door or connection
    deep_doors: frozenset[str]  # doors to carve DEEP_DOOR deep (noise at the doorway blocks them)
    landmarks: dict[str, LandmarkCandidate]  # name -> candidate
    robots: tuple[PlacedRobot, ...]  # placeholders: r1 (and r2 on a map with halls)
    goals: tuple[str, ...]  # pre-filled goals: rooms near the robots
    samples: int  # PRM milestones suggested for this map
    halls: tuple[HallProposal, ...] = ()
    connections: frozenset[str] = field(default_factory=frozenset)  # doors between places of one hall
    max_area: float = SegmentParams.max_area  # m²: rooms larger than this were split

    def room(self, label: int) -> RoomProposal:
        return next(r for r in self.rooms if r.label == label)

    @property
    def usable_rooms(self) -> tuple[RoomProposal, ...]:
        return tuple(r for r in self.rooms if r.reachable)

    @property
    def places(self) -> tuple[RoomProposal, ...]:
        """The places of halls (usable or not)."""
        return tuple(r for r in self.rooms if r.hall is not None)

    @property
    def robot_pose(self) -> tuple[float, float, float]:
        """r1's start pose."""
        return self.robots[0].pose

    @property
    def robot_room(self) -> str:
        """The room r1 starts in."""
        return self.robots[0].room


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
    """Segment the map, split its halls and propose the scenario's parts (module docstring)."""
    params = params or SegmentParams()
    work = working_grid(grid)
    found = segment(work, params)
    if found.n_rooms == 0:
        where = str(spec.yaml_path)
        raise ScenarioError([Problem(where, "", "no free area large enough for a room (see --min-area) in this map")])
    # --max-rooms asks for so many rooms: a room it made by joining others is not split again
    max_area = params.max_area if params.max_rooms is None else math.inf
    layout = lay_out(found, PlaceParams(max_area, params.min_area, ROBOT_RADIUS))
    clear = clearance(work)
    rooms = _rooms(layout, clear)
    doors, as_found, connections = named_doors(layout)
    hub = _hub(rooms, list(doors.values()))
    start = _start(spec, work, clear, hub)
    reach, deep, component = reachable_rooms(work, {r.label: r.polygon for r in rooms}, doors, start, ROBOT_RADIUS)
    reach.add(hub.label)  # the robot starts there, however cluttered it is
    rooms = tuple(replace(r, reachable=r.label in reach) for r in rooms)
    halls = _halls(layout, rooms)
    outlines = {k: rooms[label - 1].polygon for k, label in enumerate(layout.room_label.tolist()) if label}
    outlines.update({k: h.polygon for k, h in zip(layout.hall_names, halls, strict=True)})
    landmarks = _name_landmarks(place_landmarks(layout, find_landmarks(found, as_found, outlines)))
    robots = _robots(rooms, hub, doors, component, work, two=bool(halls))
    goals = _goals(rooms, robots, HALL_GOALS if halls else ROOM_GOALS)
    free_area = sum(r.area for r in rooms if r.reachable)
    lo, hi = SAMPLES_RANGE
    samples = int(min(hi, max(lo, round(SAMPLES_PER_M2 * free_area, -2))))
    return Proposal(
        spec,
        grid,
        layout.segmentation,
        rooms,
        doors,
        frozenset(deep),
        landmarks,
        robots,
        goals,
        samples,
        halls,
        connections,
        params.max_area,
    )


def working_grid(grid: OccupancyGrid) -> OccupancyGrid:
    """The part of ``grid`` the rooms are found on: the box around its free cells (with
    ``MARGIN`` cells of what surrounds them; the rest, unknown or occupied, changes nothing),
    and for more than ``LARGE_MAP`` cells, the grid of blocks of f x f cells (f as small as brings
    it below ``LARGE_MAP``), a block occupied where any of its cells is."""
    free = ~grid.occupied
    rows, cols = np.nonzero(free.any(axis=1))[0], np.nonzero(free.any(axis=0))[0]
    if rows.size == 0:
        return grid
    top, left = max(int(rows[0]) - MARGIN, 0), max(int(cols[0]) - MARGIN, 0)
    box = slice(top, int(rows[-1]) + MARGIN + 1), slice(left, int(cols[-1]) + MARGIN + 1)
    x0, y0 = grid.origin
    r = grid.resolution
    occupied = grid.occupied[box]
    f = math.ceil(math.sqrt(occupied.size / LARGE_MAP))
    if f >= 2:
        rows_, cols_ = occupied.shape
        padded = np.pad(occupied, ((0, -rows_ % f), (0, -cols_ % f)), constant_values=True)
        occupied = np.asarray(padded.reshape(padded.shape[0] // f, f, padded.shape[1] // f, f).any(axis=(1, 3)))
    return OccupancyGrid(np.ascontiguousarray(occupied), (x0 + left * r, y0 + top * r), r * max(f, 1))


def _rooms(layout: Layout, clear: np.ndarray) -> tuple[RoomProposal, ...]:
    """A proposal for every region of the layout (rooms and places), with its outline."""
    seg = layout.segmentation
    grid = seg.grid
    out = []
    for k, box in enumerate(ndimage.find_objects(seg.labels), start=1):
        if box is None:
            continue
        mask = seg.labels[box] == k
        hall = layout.hall_names.get(layout.hall_of.get(k, 0))
        i, j = _roomiest(mask, clear[box], central=hall is not None)
        spot = _centre(grid, box[0].start + i, box[1].start + j)
        area = float(mask.sum()) * grid.resolution**2
        width = 2.0 * float(seg.clearance[box][mask].max())  # furniture and speckles left out
        out.append(RoomProposal(layout.names[k], k, outline(mask, _sub(grid, box)), area, width, spot, True, hall))
    return tuple(out)


def _roomiest(mask: np.ndarray, clear: np.ndarray, central: bool) -> tuple[int, int]:
    """The cell of ``mask`` with the largest clearance; with ``central``, of the cells with at
    least ``ROOMY`` of it, the one nearest to the centroid (an aisle's clearance is the same all
    along it, and the first such cell would be at one end)."""
    room = np.where(mask, clear, -1.0)
    if not central:
        i, j = np.unravel_index(np.argmax(room), mask.shape)
        return int(i), int(j)
    cells = np.argwhere(room >= ROOMY * room.max())
    centroid = np.argwhere(mask).mean(axis=0)
    i, j = cells[int(np.argmin(((cells - centroid) ** 2).sum(axis=1)))]
    return int(i), int(j)


def _halls(layout: Layout, rooms: tuple[RoomProposal, ...]) -> tuple[HallProposal, ...]:
    """The halls, with their outlines and the places they were split into."""
    grid = layout.rooms.grid
    boxes = ndimage.find_objects(layout.rooms.labels)
    out = []
    for k, name in layout.hall_names.items():
        box = boxes[k - 1]
        mask = layout.rooms.labels[box] == k
        places = tuple(r.name for r in rooms if r.hall == name)
        out.append(HallProposal(name, outline(mask, _sub(grid, box)), float(mask.sum()) * grid.resolution**2, places))
    return tuple(out)


def _sub(grid: OccupancyGrid, box: tuple[slice, slice]) -> OccupancyGrid:
    """The part ``box`` of ``grid``, at its place in the map."""
    x0, y0 = grid.origin
    origin = (x0 + box[1].start * grid.resolution, y0 + box[0].start * grid.resolution)
    return OccupancyGrid(grid.occupied[box], origin, grid.resolution)


def _centre(grid: OccupancyGrid, i: int, j: int) -> tuple[float, float]:
    x0, y0 = grid.origin
    return float(x0 + (j + 0.5) * grid.resolution), float(y0 + (i + 0.5) * grid.resolution)


def _hub(rooms: tuple[RoomProposal, ...], doors: list[DoorCandidate]) -> RoomProposal:
    """The room with the most doors (a corridor, a hall's crossing), the larger one on a tie."""
    count = {r.label: 0 for r in rooms}
    for d in doors:
        for label in d.rooms:
            count[label] += 1
    return max(rooms, key=lambda r: (count[r.label], r.area))


def _start(spec: RosMap, grid: OccupancyGrid, clear: np.ndarray, hub: RoomProposal) -> tuple[int, int]:
    """The cell of r1's start: the roomiest spot of ``hub``; ScenarioError if no robot fits there."""
    i, j, _ = grid.cells(np.array(hub.spot))
    if clear[i, j] < ROBOT_RADIUS + grid.resolution:
        message = f"no room is wide enough for a robot of radius {ROBOT_RADIUS:g} m (widest: {2 * clear[i, j]:.2f} m)"
        raise ScenarioError([Problem(str(spec.yaml_path), "", message)])
    return int(i), int(j)


def _robots(
    rooms: tuple[RoomProposal, ...],
    hub: RoomProposal,
    doors: dict[str, DoorCandidate],
    component: np.ndarray,
    grid: OccupancyGrid,
    two: bool,
) -> tuple[PlacedRobot, ...]:
    """r1 at the roomiest spot of ``hub``; with ``two``, r2 at the roomiest spot of the
    best-connected other place (or room) it reaches (``component``), at least ``APART`` away."""
    first = PlacedRobot("r1", (*hub.spot, 0.0), hub.name)
    if not two:
        return (first,)
    count = {r.label: sum(r.label in d.rooms for d in doors.values()) for r in rooms}

    def fits(r: RoomProposal) -> bool:
        i, j, _ = grid.cells(np.array(r.spot))
        return bool(component[i, j]) and float(np.hypot(*np.subtract(r.spot, hub.spot))) >= APART

    others = [r for r in rooms if r.reachable and r.label != hub.label and fits(r)]
    if not others:
        return (first,)
    second = max(others, key=lambda r: (r.hall is not None, count[r.label], r.area))  # a place, if any
    return first, PlacedRobot("r2", (*second.spot, 0.0), second.name)


def _goals(rooms: tuple[RoomProposal, ...], robots: tuple[PlacedRobot, ...], n: int) -> tuple[str, ...]:
    """The ``n`` reachable rooms nearest to a robot, other than those the robots start in."""
    taken = {r.room for r in robots}
    others = [r for r in rooms if r.reachable and r.name not in taken]
    near = sorted(others, key=lambda r: min(float(np.hypot(*np.subtract(r.spot, b.pose[:2]))) for b in robots))
    return tuple(r.name for r in near[:n]) or (robots[0].room,)


def _name_landmarks(found: list[LandmarkCandidate]) -> dict[str, LandmarkCandidate]:
    """Names like pillar1, door-frame2, corner1: one counter per kind."""
    counts: dict[str, int] = {}
    named = {}
    for lm in found:
        counts[lm.kind] = counts.get(lm.kind, 0) + 1
        named[f"{lm.kind}{counts[lm.kind]}"] = lm
    return named
