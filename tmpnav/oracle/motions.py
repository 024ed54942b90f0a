"""Nominal motions made and kept: what a robot does and sees when it drives a roadmap path.

A :class:`~tmpnav.oracle.nominal.NominalMotion` drives the shortest roadmap path from a start
node to a goal node, turn-then-drive or as nav2's RPP drives it. Motions depend only on the
robot's build, its start (node, heading) and the goal node, so the :class:`MotionLibrary`
computes each once and shares it between the single-robot and joint evaluations that need it.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from tmpnav.belief.controls import PathControls, path_controls, turn_to
from tmpnav.belief.pursuit import RppParams, pursuit_along
from tmpnav.belief.pursuit_path import Rounding, rounded_path
from tmpnav.belief.sequences import NoiseStreams
from tmpnav.oracle.nominal import NominalMotion, footprint, stable_seed
from tmpnav.roadmap import RoadmapGraph
from tmpnav.roadmap.graph import safe_weights
from tmpnav.roadmap.shortcut import least_clearance, required_clearance, shortcut
from tmpnav.types import Roadmap, RobotSpec, Scenario
from tmpnav.world import World
from tmpnav.world.reach import encoded
from tmpnav.world.scan_information import ScanInformation
from tmpnav.world.visibility import LandmarkVisibility

#: the landmarks' visibility of the last worlds, by world and sensor range: a replan's library
#: (a new context on the same world) takes it as it is
_VISIBILITY: dict[tuple[str, float], LandmarkVisibility] = {}


#: what a motion set keeps whatever its start belief: its goals in its order, its prefix matrix,
#: steps, c_u and final positions (tmpnav.oracle.motionsets.MotionSet)
SetLayout = tuple[tuple[int, ...], np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _scan_keys(m: NominalMotion) -> np.ndarray:
    """The motion's scan keys; -1 (no scan) at every pose of a motion without them."""
    return m.scan_keys if m.scan_keys is not None else np.full(m.poses.shape[0], -1, dtype=np.int64)


def visibility_of(world: World, sensor_range: float) -> LandmarkVisibility:
    """The landmarks' visibility polygons of ``world`` for a sensor of ``sensor_range``."""
    key = (world.fingerprint, sensor_range)
    if key not in _VISIBILITY:
        _VISIBILITY[key] = LandmarkVisibility(world, sensor_range)
        while len(_VISIBILITY) > 2:
            _VISIBILITY.pop(next(iter(_VISIBILITY)))
    return _VISIBILITY[key]


def _specs(scenario: Scenario) -> tuple[tuple[str, float, float, float], ...]:
    """What a nominal motion takes of the robots: not where they start."""
    return tuple((r.name, r.radius, r.speed, r.turn_rate) for r in scenario.robots)


def _model(robot: RobotSpec) -> tuple[float, float, float]:
    """What a robot's nominal motions take of it, besides its name (and the noise stream named after it)."""
    return (robot.radius, robot.speed, robot.turn_rate)


#: the parameters of nav2's RPP the planner's motions are driven with (models.controller: rpp)
RPP = RppParams()

#: nominal motions kept in memory (least recently used dropped first): a motion of a few
#: hundred steps with its landmark visibility takes 10-20 kB, and a building of 60 rooms and
#: 8 robots asks for over 100,000 of them
MAX_MOTIONS = 8192
#: and the bytes their arrays may take (:func:`footprint`): a fleet's motions are long, 8192 of
#: them took 230 MB of each oracle worker at 100 rooms and 16 robots, where none was asked for
#: again past the last 1024; a 24-room office's 8192 take about half of this
MAX_MOTION_BYTES = 96 * 2**20
#: routes kept (:class:`Route`, least recently used dropped first): a node's motions to a goal
#: at each heading robots arrive there with drive one route; a fleet's oracle worker drove
#: 36,000 motions along 10,000 routes at 100 rooms and 16 robots, most of them again within the
#: 4096 routes asked for last (a route takes about 5 kB at 100 rooms)
MAX_ROUTES = 4096
_MISSING = object()
#: the landmarks a motion sees where no belief fuses them: none (broadcast to its poses and landmarks)
_UNSEEN = np.zeros((1, 1), dtype=bool)


class Route:
    """A roadmap path as RPP drives it from whatever heading (:meth:`MotionLibrary._driven`): the
    node paths its rollouts try in turn (the shortened path, then the path itself), the clearance
    a rollout must keep to be taken, and each try's polyline with its corners rounded, made when
    first driven (tmpnav.belief.pursuit_path.rounded_path)."""

    __slots__ = ("_rounded", "keep", "path", "tries")

    def __init__(self, path: tuple[int, ...], keep: float, tries: tuple[tuple[int, ...], ...]):
        self.path, self.keep, self.tries = path, keep, tries
        self._rounded: list[tuple[np.ndarray, np.ndarray] | None] = [None] * len(tries)

    def rounded(self, k: int, lib: MotionLibrary, robot: str) -> tuple[np.ndarray, np.ndarray]:
        """Try k's polyline with its corners rounded for ``robot`` (of the radius the route is
        kept for), and the index in it of each of the try's nodes."""
        found = self._rounded[k]
        if found is None:
            rounding = Rounding(lib.required(robot), lib.world.clearance, lib.origin, lib.resolution)
            found = self._rounded[k] = rounded_path(lib.graph.points(self.tries[k]), rounding)
        return found


class MotionLibrary:
    """Memoised nominal motions of one scenario, world and roadmap."""

    def __init__(self, scenario: Scenario, world: World, roadmap: Roadmap):
        self.scenario = scenario
        self.world = world
        self.roadmap = roadmap
        radius = max(r.radius for r in scenario.robots)
        clearance = scenario.roadmap.clearance or 0.0  # 0: the paper's shortest paths
        self.graph = RoadmapGraph(roadmap, safe_weights(roadmap, world, radius, clearance) if clearance > 0 else None)
        self.visibility = visibility_of(world, scenario.models.landmark_sensor.range)
        #: the map's clearance grid as RPP's motions read it: its origin (m) and cell size (m)
        self.origin = (float(world.grid.origin[0]), float(world.grid.origin[1]))
        self.resolution = float(world.grid.resolution)
        sensor = scenario.models.range_sensor
        # a range scan's information per cell and heading (tmpnav.world.scan_information)
        self.scans: ScanInformation | None = world.scans(sensor) if sensor is not None else None
        self.noise = NoiseStreams()  # the simulated observations' draws, by stream
        self._motions: OrderedDict[tuple[str, int, float, int], NominalMotion | None] = OrderedDict()
        self._motion_bytes = 0  # their footprint (MAX_MOTION_BYTES)
        #: the heading a motion ends at, at the node of a job's goal pose (goals.jobs)
        self.goal_headings: dict[int, float] = {
            roadmap.instantiations[j.room][0]: j.pose[2]
            for j in scenario.goals.jobs
            if j.pose is not None and roadmap.instantiations.get(j.room)
        }
        self._along: dict[tuple[str, tuple[int, ...], float], NominalMotion] = {}
        self._seeds: dict[tuple[str, int], int] = {}  # the landmark-noise streams (_noise_seed)
        #: the other robots of each robot's radius, speed and turn rate, whose motions are its own (_alike)
        self._twins = {
            r.name: tuple(o.name for o in scenario.robots if o.name != r.name and _model(o) == _model(r))
            for r in scenario.robots
        }
        self._unseen_rows: dict[int, np.ndarray] = {}  # no landmark seen, by poses (_unseen)
        #: the routes from a node to another by the robots' radius (None: not connected)
        self._routes: OrderedDict[tuple[int, int, float], Route | None] = OrderedDict()
        #: the order and arrays of the motion sets built from a robot's node and heading to a set
        #: of goals, whatever the belief there (tmpnav.oracle.motionsets.motion_sets)
        self.sets: OrderedDict[tuple[str, int, float, frozenset[int]], SetLayout] = OrderedDict()

    def inherit(self, other: MotionLibrary) -> None:
        """Take what ``other`` computed that holds here too, when it is the library of the same
        world, models and robots on the same roadmap with other sources (a replan's starts,
        Roadmap.sources; tmpnav.roadmap.with_starts): the shortest-path trees from the nodes
        both share and the nominal motions from them (no path between those nodes passes
        through a source). A planning service revising a plan again and again then computes
        only what its new starts change."""
        models, its = self.scenario.models, other.scenario.models
        same = (
            self.world.fingerprint == other.world.fingerprint
            and self.roadmap.grown == other.roadmap.grown
            and repr(models) == repr(its)
            and _specs(self.scenario) == _specs(other.scenario)
            and self.goal_headings == other.goal_headings
        )
        if not same:
            return
        self.graph.inherit(other.graph)
        shared = self.roadmap.base_nodes
        for key, motion in other._motions.items():
            if key[1] < shared and key not in self._motions:
                self._keep(key, motion)
        for key2, along in other._along.items():
            if max(key2[1]) < shared:
                self._along.setdefault(key2, along)

    def motion(self, robot: str, start: int, heading: float, goal: int) -> NominalMotion | None:
        """The nominal motion start -> goal, or None if the roadmap does not connect them."""
        key = (robot, start, heading, goal)
        found = self._motions.get(key, _MISSING)
        if found is _MISSING:
            found = self._alike(robot, start, heading, goal)
            if found is _MISSING:
                found = self._compute(robot, start, heading, goal)
            self._keep(key, found)  # type: ignore[arg-type]
        else:
            self._motions.move_to_end(key)
        return found  # type: ignore[return-value]

    def _alike(self, robot: str, start: int, heading: float, goal: int) -> NominalMotion | object | None:
        """The motion start -> goal of another robot of the same radius, speed and turn rate from
        the same node and heading, as ``robot``'s (its arrays, and the rows kept for them, are the
        same: a fleet's robots share a model, and drove one motion in fourteen twice); _MISSING
        where no such robot's is kept."""
        for other in self._twins.get(robot, ()):
            found = self._motions.get((other, start, heading, goal), _MISSING)
            if found is None:
                return None
            if found is not _MISSING:
                return replace(found, robot=robot, noise_seed=self._noise_seed(robot, start))  # type: ignore[type-var]
        return _MISSING

    def _keep(self, key: tuple[str, int, float, int], motion: NominalMotion | None) -> None:
        """Remember ``motion``, dropping the least recently used past :data:`MAX_MOTIONS` or
        :data:`MAX_MOTION_BYTES`."""
        self._motions[key] = motion
        self._motion_bytes += footprint(motion)
        while len(self._motions) > 1 and (len(self._motions) > MAX_MOTIONS or self._motion_bytes > MAX_MOTION_BYTES):
            _, dropped = self._motions.popitem(last=False)
            self._motion_bytes -= footprint(dropped)

    def reach(self, motion: NominalMotion, rows: np.ndarray | slice = slice(None)) -> np.ndarray:
        """The sector reach (T+1, K) m of ``motion``'s footprint at its poses (``rows`` of them),
        through the rows the motion keeps (:meth:`_rows`)."""
        table = self.world.reach(self.scenario.robot(motion.robot).radius)
        found = self._rows([motion], table, lambda m: m.cells, table.rows_of)
        return table.values[table.codes[found[rows]]]

    def reach_layout(self, motions: list[NominalMotion]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sector reach of every pose of ``motions`` laid end to end, as a table of codes
        (R, K), the reaches they stand for (V,) m, and the row of the table of each pose
        (sum (T+1),): the pose's reach is ``values[codes[rows[k]]]``.

        With one robot radius the table is that radius' :class:`~tmpnav.world.reach.SectorReach`
        table and each motion's rows are found once and kept with it (:meth:`_rows`): an
        evaluation lays out hundreds of motions, most of them laid out before, and finding
        their cells' rows and copying 64 sectors per pose took a fifth of a sub-problem's
        oracle time. With several radii, the reach itself, one row per pose."""
        radii = {self.scenario.robot(m.robot).radius for m in motions}
        if len(radii) > 1:
            codes, values = encoded(np.concatenate([self.reach(m) for m in motions]))
            return codes, values, np.arange(codes.shape[0], dtype=np.int64)
        reach = self.world.reach(radii.pop() if radii else 0.0)
        rows = self._rows(motions, reach, lambda m: m.cells, reach.rows_of)
        return reach.codes, reach.values, rows  # the table after the rows were added to it

    def scan_rows_all(self, motions: list[NominalMotion]) -> np.ndarray:
        """The rows of :attr:`scans`' table of every pose's scan of ``motions``, laid end to end
        (0: no scan), each motion's found once and kept with it."""
        scans = self.scans
        assert scans is not None
        return self._rows(motions, scans, _scan_keys, scans.rows)

    @staticmethod
    def _rows(
        motions: list[NominalMotion],
        table: object,
        keys: Callable[[NominalMotion], np.ndarray],
        find: Callable[[np.ndarray], np.ndarray],
    ) -> np.ndarray:
        """``find`` applied to the ``keys`` of the poses of the motions laid end to end. Each
        motion keeps its rows by the ``table`` they index (the object itself: a table's rows stay
        where they are as it grows, and no other table, a copy of it included, shares the key);
        those of the motions without them are found at once."""
        new = [m for m in dict.fromkeys(motions) if table not in m.rows]
        if new:
            found = [keys(m) for m in new]
            split = np.split(find(np.concatenate(found)), np.cumsum([k.shape[0] for k in found])[:-1])
            for m, rows in zip(new, split, strict=True):
                m.rows[table] = rows
        if not motions:
            return np.zeros(0, dtype=np.int64)
        return np.concatenate([m.rows[table] for m in motions])

    def prepare(self, starts: list[int]) -> None:
        """Run Dijkstra from many start nodes at once."""
        self.graph.prepare(starts)

    def along(self, robot: str, path: tuple[int, ...], heading: float) -> NominalMotion:
        """The nominal motion along the roadmap nodes ``path`` (a detour, tmpnav.attachment.detours),
        with the noise stream of the move from ``path[0]`` as every motion from there has."""
        key = (robot, path, heading)
        found = self._along.get(key)
        if found is None:
            found = self._along[key] = self._driven(robot, path, heading, shorten=False)
            if len(self._along) > MAX_MOTIONS:
                self._along.pop(next(iter(self._along)))
        return found

    def _compute(self, robot: str, start: int, heading: float, goal: int) -> NominalMotion | None:
        if self.scenario.models.driving != "rpp":
            path = self.graph.path(start, goal)
            return None if path is None else self._motion(robot, path, heading, pursue=False)
        key = (start, goal, self.scenario.robot(robot).radius)
        route = self._routes.get(key, _MISSING)
        if route is _MISSING:
            path = self.graph.path(start, goal)
            route = None if path is None else self._route(robot, path, shorten=True)
            self._routes[key] = route
            if len(self._routes) > MAX_ROUTES:
                self._routes.popitem(last=False)
        else:
            self._routes.move_to_end(key)
        return None if route is None else self._pursued(robot, route, heading)  # type: ignore[arg-type]

    def _driven(self, robot: str, path: tuple[int, ...], heading: float, shorten: bool) -> NominalMotion:
        """The motion along the roadmap ``path`` by the scenario's controller (models.controller).
        With RPP: along the path shortened (``shorten``; nav2's global plans are smoothed), else
        along the path itself, whichever RPP drives first keeping half the margin the roadmap path
        keeps at its tightest (or half the shortcut's margin, where the path keeps more), to a grid
        cell (the clearance's own resolution), and never nearer to an obstacle than the path where
        the path's footprint has no margin (a door as wide as the robot); else
        turn-then-drive along the path, which keeps the path's own margin. RPP cuts corners: at a
        door the cut may take it near the frame, and the margin is the robot's footprint's free
        distance, its clearance less its radius and a grid cell's diagonal."""
        if self.scenario.models.driving != "rpp":
            return self._motion(robot, path, heading, pursue=False)
        return self._pursued(robot, self._route(robot, path, shorten), heading)

    def _route(self, robot: str, path: tuple[int, ...], shorten: bool) -> Route:
        """The :class:`Route` RPP drives ``robot`` along ``path`` by (:meth:`_driven` states the rule)."""
        origin, res = self.origin, self.resolution
        own = self.scenario.robot(robot).radius + float(np.sqrt(2.0)) * res  # a margin's zero
        tightest = least_clearance(self.graph.points(path), self.world.clearance, origin, res)
        keep = min(own + 0.5 * max(min(self.required(robot), tightest) - own, 0.0), tightest)
        # to a grid cell, but never nearer than the roadmap path where it leaves the footprint no room
        keep = max(keep - res, min(own, tightest))
        candidates = (self.shortened(robot, path), path) if shorten and len(path) > 2 else (path,)
        return Route(path, keep, tuple(dict.fromkeys(candidates)))

    def _pursued(self, robot: str, route: Route, heading: float) -> NominalMotion:
        """The first of ``route``'s tries RPP drives from ``heading`` keeping its clearance, else
        turn-then-drive along its path."""
        for k, candidate in enumerate(route.tries):
            motion = self._motion(robot, candidate, heading, pursue=True, rounded=route.rounded(k, self, robot))
            if least_clearance(motion.poses, self.world.clearance, self.origin, self.resolution, polyline=False) >= (
                route.keep
            ):
                return motion
        return self._motion(robot, route.path, heading, pursue=False)

    def required(self, robot: str) -> float:
        """The clearance (m, from the robot's centre to the nearest occupied cell's centre) a
        shortened path keeps: the robot's radius, the roadmap's clearance and a cell's diagonal."""
        return required_clearance(self.scenario.robot(robot).radius, self.scenario.roadmap, self.resolution)

    def shortened(self, robot: str, path: tuple[int, ...]) -> tuple[int, ...]:
        """The nodes of ``path`` that :func:`tmpnav.roadmap.shortcut.shortcut` keeps for ``robot``:
        the straight lines between them keep :meth:`required` (or, where the path came nearer to
        an obstacle, that path's own clearance)."""
        keep = shortcut(
            self.graph.points(path), self.required(robot), self.world.clearance, self.origin, self.resolution
        )
        return tuple(path[int(k)] for k in keep)

    def controls(
        self,
        robot: str,
        points: np.ndarray,
        heading: float,
        pursue: bool,
        goal_heading: float | None = None,
        rounded: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> PathControls:
        """The controls and nominal poses of ``robot`` driving the polyline ``points`` from heading
        ``heading``: by nav2's Regulated Pure Pursuit when ``pursue`` (tmpnav.belief.pursuit), or
        by the paper's turn on the spot then drive straight (tmpnav.belief.controls), which is
        also what a path RPP cannot finish is driven by. ``rounded``: the polyline with its
        corners rounded for the robot, when known (:class:`Route`)."""
        spec = self.scenario.robot(robot)
        dt = self.scenario.models.dt
        if pursue:
            clear, origin, res = self.world.clearance, self.origin, self.resolution
            if rounded is None:
                rounding = Rounding(self.required(robot), clear, origin, res)
                rounded = rounded_path(points, rounding)
            pc = pursuit_along(
                *rounded, len(points), heading, spec.speed, spec.turn_rate, dt, RPP, clear, origin, res, goal_heading
            )
            if pc is not None:
                return pc
        return path_controls(points, heading, spec.speed, spec.turn_rate, dt)

    def _motion(
        self,
        robot: str,
        path: tuple[int, ...],
        heading: float,
        pursue: bool,
        rounded: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> NominalMotion:
        start = path[0]
        spec = self.scenario.robot(robot)
        models = self.scenario.models
        final = self.goal_headings.get(path[-1]) if len(path) > 1 else None
        pc = self.controls(robot, self.graph.points(path), heading, pursue, final, rounded)
        controls, poses = pc.controls, pc.poses
        pursued = pursue and pc.pursued
        if final is not None and not pursued:  # a job's goal pose: on it, then turned to its heading
            controls, poses = turn_to(controls, poses, final, spec.turn_rate, models.dt)
        if models.others_fused:
            lm_visible = self.visibility.visible(poses, models.landmark_sensor.fov, min_range=spec.radius)
        else:  # no belief takes them in (the EKF reads them only where it fuses them): none seen,
            # one row of False seen at every pose (a read-only view: a fleet's thousands of
            # motions kept 100 MB of False a process at 100 rooms)
            lm_visible = self._unseen(poses.shape[0])
        return NominalMotion(
            robot=robot,
            path=path,
            controls=controls,
            poses=poses,
            node_steps=pc.node_steps,
            lm_visible=lm_visible,
            cells=self.world.reach(spec.radius).cells(poses[:, :2]),
            scan_keys=self.scans.keys(poses) if self.scans is not None else None,
            noise_seed=self._noise_seed(robot, start),
            controller="rpp" if pursued else "turn-then-drive",
        )

    def _noise_seed(self, robot: str, start: int) -> int:
        """The landmark-noise stream of ``robot``'s motions from node ``start``: one stream per
        robot and start node, drawn step by step, so a robot sees the same simulated
        observations at step k alone or in a pair, whatever its goal, factorised pairs are
        exact and motions with a common prefix share it."""
        key = (robot, start)
        found = self._seeds.get(key)
        if found is None:
            found = self._seeds[key] = stable_seed(self.scenario.models.seed, "landmarks", robot, start)
        return found

    def _unseen(self, rows: int) -> np.ndarray:
        """No landmark seen at ``rows`` poses: one row of False broadcast (read-only), the same
        view for every motion of as many poses."""
        found = self._unseen_rows.get(rows)
        if found is None:
            found = self._unseen_rows[rows] = np.broadcast_to(_UNSEEN, (rows, self.world.landmark_xy.shape[0]))
        return found
