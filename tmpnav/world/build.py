"""Stage 2: a scenario -> the :class:`World` (occupancy grid, clearance, rooms, landmarks)."""

from __future__ import annotations

import hashlib
import itertools
from dataclasses import dataclass, field

import numpy as np

from tmpnav.types import Landmark, PolygonMap, RangeSensor, Room, Scenario
from tmpnav.world.geometry import points_in_polygon
from tmpnav.world.grid import (
    OccupancyGrid,
    clearance,
    fill_polygon,
    fill_segment,
    footprint_margins,
    line_of_sight,
    line_of_sight_traced,
)
from tmpnav.world.lidar import signed_distance
from tmpnav.world.reach import SectorReach
from tmpnav.world.rosmap import load_ros_map
from tmpnav.world.scan_information import ScanInformation


@dataclass(frozen=True)
class Learned:
    """Cells a copy of a :class:`World` computed: each reach table's sub-cells and their reach
    (as codes, :class:`~tmpnav.world.reach.SectorReach`), each scan table's keys and factors
    (:meth:`World.take_new`)."""

    reach: dict[float, tuple[np.ndarray, np.ndarray]]
    scans: dict[RangeSensor, tuple[np.ndarray, np.ndarray]]

    def __bool__(self) -> bool:
        """Whether any cell is in it."""
        return any(keys.size for keys, _ in (*self.reach.values(), *self.scans.values()))


@dataclass(frozen=True, eq=False)
class World:
    """Everything geometric the later stages need, as plain arrays."""

    grid: OccupancyGrid
    clearance: np.ndarray  # (rows, cols) m
    rooms: tuple[Room, ...]
    landmarks: tuple[Landmark, ...]
    landmark_xy: np.ndarray  # (L, 2)
    fingerprint: str  # content hash of the grid, rooms and landmarks
    _reach: dict[float, SectorReach] = field(default_factory=dict, repr=False)  # radius -> its cells' reach
    _scans: dict[RangeSensor, ScanInformation] = field(default_factory=dict, repr=False)  # sensor -> its scans
    _sdf: list[np.ndarray] = field(default_factory=list, repr=False)  # the signed distance field, once computed
    _components: dict[float, np.ndarray] = field(default_factory=dict, repr=False)  # radius -> free-space labels
    _polygons: list[tuple[str, np.ndarray, np.ndarray]] = field(default_factory=list, repr=False)  # name, vertices, box
    _free_cells: dict[tuple[str, float], np.ndarray] = field(default_factory=dict, repr=False)  # by room, radius
    _recording: list[bool] = field(default_factory=list, repr=False)  # [True] once take_new was called

    def is_free(self, points: np.ndarray, radius: float) -> np.ndarray:
        """Whether a disc of ``radius`` centred at each point (..., 2) is collision-free."""
        i, j, inside = self.grid.cells(points)
        return inside & (self.clearance[i, j] >= radius + self.grid.resolution)

    def margins(self, points: np.ndarray, radius: float) -> np.ndarray:
        """The free margin of a disc of ``radius`` at each point (tmpnav.world.grid.footprint_margins)."""
        return footprint_margins(self.grid, self.clearance, points, radius)

    def reach(self, radius: float) -> SectorReach:
        """The sector reach of a disc of ``radius`` (tmpnav.world.reach), its cells computed
        when first asked for and remembered for the world's lifetime."""
        if radius not in self._reach:
            self._reach[radius] = SectorReach(self.grid, self.clearance, radius)
            if self._recording:
                self._reach[radius].take_new()
        return self._reach[radius]

    def free_components(self, radius: float) -> np.ndarray:
        """The connected components of the free space of a disc of ``radius`` (the cells
        :meth:`is_free` accepts, 8-connected): a label per cell, 0 where it does not fit;
        computed when first asked for and remembered for the world's lifetime."""
        if radius not in self._components:
            from scipy import ndimage

            free = self.clearance >= radius + self.grid.resolution
            self._components[radius] = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))[0]
        return self._components[radius]

    @property
    def signed_distance(self) -> np.ndarray:
        """The signed distance field of the walls (tmpnav.world.lidar), computed when first asked for."""
        if not self._sdf:
            self._sdf.append(signed_distance(self.grid))
        return self._sdf[0]

    def scans(self, sensor: RangeSensor) -> ScanInformation:
        """The scan information of ``sensor`` (tmpnav.world.scan_information), its cells computed
        when first asked for and remembered for the world's lifetime."""
        if sensor not in self._scans:
            self._scans[sensor] = ScanInformation(self.grid, self.signed_distance, sensor)
            if self._recording:
                self._scans[sensor].take_new()
        return self._scans[sensor]

    def take_new(self) -> Learned:
        """What the reach and scan tables computed since the last call (their ``take_new``):
        a worker process's copy of the world hands it to the parent's (:meth:`learn`), so that
        the parent does not compute again the cells its workers did. The first call starts the
        record (a worker's, when it starts) and returns none: the planning process keeps none."""
        self._recording[:] = [True]
        reach = {radius: table.take_new() for radius, table in self._reach.items()}
        scans = {sensor: table.take_new() for sensor, table in self._scans.items()}
        return Learned(reach, scans)

    def learn(self, new: Learned) -> Learned:
        """Take what another copy of this world computed (:meth:`take_new`); what of it this
        copy did not know yet."""
        reach = {r: self.reach(r).learn(keys, codes) for r, (keys, codes) in new.reach.items() if keys.size}
        scans = {s: self.scans(s).learn(keys, values) for s, (keys, values) in new.scans.items() if keys.size}
        return Learned(
            {r: fresh for r, fresh in reach.items() if fresh[0].size},
            {s: fresh for s, fresh in scans.items() if fresh[0].size},
        )

    def line_of_sight(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether segments a[k]-b[k] cross no occupied cell (sphere tracing)."""
        return line_of_sight_traced(self.grid, self.clearance, a, b)

    def line_of_sight_sampled(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """The same test by sampling every half cell (the reference for tests)."""
        return line_of_sight(self.grid, a, b)

    def room_polygon(self, name: str) -> np.ndarray:
        return np.array(next(r.polygon for r in self.rooms if r.name == name), dtype=float)

    def room_of(self, point: np.ndarray) -> str | None:
        """The name of the first room containing ``point`` (2,), or None; a room or place, never a
        station (which shares its place's polygon: :meth:`place_of`)."""
        if not self._polygons:
            for room in (r for r in self.rooms if r.place is None):
                vertices = np.array(room.polygon, dtype=float)
                self._polygons.append((room.name, vertices, np.r_[vertices.min(axis=0), vertices.max(axis=0)]))
        p = np.atleast_2d(np.asarray(point, dtype=float))
        x, y = float(p[0, 0]), float(p[0, 1])
        for name, vertices, box in self._polygons:
            if box[0] <= x <= box[2] and box[1] <= y <= box[3] and points_in_polygon(p, vertices)[0]:
                return name
        return None

    def place_of(self, name: str) -> str:
        """The room or place a goal lies in: a station's place, else the room ``name`` itself (what
        :meth:`room_of` gives for a point at the goal)."""
        return next((r.place for r in self.rooms if r.name == name and r.place is not None), name)

    def free_cells_in_room(self, name: str, radius: float) -> np.ndarray:
        """Centres (m, 2) of the cells of a room where a robot of ``radius`` fits (kept: a
        replan asks for every goal room again)."""
        if (name, radius) not in self._free_cells:
            cells = self._free_cells_in_room(name, radius)
            cells.setflags(write=False)
            self._free_cells[(name, radius)] = cells
        return self._free_cells[(name, radius)]

    def _free_cells_in_room(self, name: str, radius: float) -> np.ndarray:
        polygon = self.room_polygon(name)
        xs, ys = self.grid.cell_centers()
        cols = np.nonzero((xs >= polygon[:, 0].min()) & (xs <= polygon[:, 0].max()))[0]
        rows = np.nonzero((ys >= polygon[:, 1].min()) & (ys <= polygon[:, 1].max()))[0]
        gx, gy = np.meshgrid(xs[cols], ys[rows])
        pts = np.column_stack([gx.ravel(), gy.ravel()])
        keep = points_in_polygon(pts, polygon)
        pts = pts[keep]
        return pts[self.is_free(pts, radius)]


def rasterize(spec: PolygonMap) -> OccupancyGrid:
    """A polygonal map as a grid: walls (thick polylines) and obstacles are occupied."""
    xmin, ymin, xmax, ymax = spec.bounds
    r = spec.resolution
    # the tolerance keeps a rounding error ((0.2 - -2.7) / 0.1 = 29.000000000000004) from adding a cell
    cols, rows = int(np.ceil((xmax - xmin) / r - 1e-9)), int(np.ceil((ymax - ymin) / r - 1e-9))
    grid = OccupancyGrid(np.zeros((rows, cols), dtype=bool), (xmin, ymin), r)
    xs, ys = grid.cell_centers()
    for wall in spec.walls:
        pts = np.array(wall, dtype=float)
        for a, b in itertools.pairwise(pts):
            fill_segment(grid.occupied, xs, ys, a, b, spec.wall_thickness, True)
    for obstacle in spec.obstacles:
        fill_polygon(grid.occupied, xs, ys, np.array(obstacle, dtype=float), True)
    return grid


def build(scenario: Scenario) -> World:
    """Build the world of a scenario; ROS map images are read here (may raise MapImageError)."""
    grid = rasterize(scenario.map) if isinstance(scenario.map, PolygonMap) else load_ros_map(scenario.map)
    xs, ys = grid.cell_centers()
    for door in scenario.doors:
        a, b = (np.array(p, dtype=float) for p in door.segment)
        # an open door is carved through whatever the map drew, exactly as wide as declared
        # (flat caps); a closed one is a wall joining the wall ends (round caps)
        thickness = door.thickness + (2 * grid.resolution if door.open else 0.0)
        fill_segment(grid.occupied, xs, ys, a, b, thickness, not door.open, flat_caps=door.open)
    landmark_xy = np.array([lm.position for lm in scenario.landmarks], dtype=float).reshape(-1, 2)
    h = hashlib.sha256()
    h.update(np.packbits(grid.occupied).tobytes())
    h.update(repr((grid.shape, grid.origin, grid.resolution)).encode())
    h.update(repr([(r.name, r.polygon) for r in scenario.rooms]).encode())
    h.update(landmark_xy.tobytes())
    return World(
        grid=grid,
        clearance=clearance(grid),
        rooms=scenario.rooms,
        landmarks=scenario.landmarks,
        landmark_xy=landmark_xy,
        fingerprint=h.hexdigest(),
    )
