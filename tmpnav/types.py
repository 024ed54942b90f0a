"""Plain values shared by the pipeline's stages.

Every stage takes and returns these frozen dataclasses (or numpy arrays), never objects of a
third-party library, so each stage can be tested without the others' dependencies.
Units are SI throughout: metres, radians, seconds.
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TypeVar

import numpy as np

from tmpnav.choices import Costs, Objective, Search

Point = tuple[float, float]
Polygon = tuple[Point, ...]


Vec3 = tuple[float, float, float]
Cov3 = tuple[Vec3, Vec3, Vec3]


def vec3(a: np.ndarray) -> Vec3:
    """Three numbers (a pose, a mean) as a plain tuple of floats."""
    return (float(a[0]), float(a[1]), float(a[2]))


def cov3(m: np.ndarray) -> Cov3:
    """A 3x3 matrix (a pose covariance) as plain tuples of floats."""
    return (vec3(m[0]), vec3(m[1]), vec3(m[2]))


# --------------------------------------------------------------------------- scenario


@dataclass(frozen=True)
class Pose:
    """Robot pose x = (x, y, theta): metres, metres, radians."""

    x: float
    y: float
    theta: float

    def as_array(self) -> np.ndarray:
        return np.array([self.x, self.y, self.theta], dtype=float)


@dataclass(frozen=True)
class PolygonMap:
    """A bounded plane with polygonal obstacles and thick wall polylines."""

    bounds: tuple[float, float, float, float]  # xmin, ymin, xmax, ymax
    resolution: float  # grid cell size used for collision checks (m)
    wall_thickness: float  # m
    walls: tuple[tuple[Point, ...], ...]  # polylines
    obstacles: tuple[Polygon, ...]  # filled polygons


@dataclass(frozen=True)
class RosMap:
    """A ROS map_server map: YAML metadata plus an image (PGM/PNG)."""

    yaml_path: Path
    image_path: Path
    resolution: float
    origin: tuple[float, float, float]
    negate: bool
    occupied_thresh: float
    free_thresh: float
    mode: str  # trinary | scale | raw
    #: occupied specks no wider than this (m), free all around, are cleared as map noise (0: none)
    despeckle: float = 0.0


MapSpec = PolygonMap | RosMap


@dataclass(frozen=True)
class Room:
    """A room or place of the map; or, with ``place``, a station: a goal of its own at one pose
    inside the room ``place`` (a job's ``place`` and ``pose``, ``goals.jobs``), whose polygon is
    its place's and whose one pose instantiation is its job's pose."""

    name: str
    polygon: Polygon
    place: str | None = None  # a station: the room or place it stands in


@dataclass(frozen=True)
class Door:
    """A door across a wall gap; a closed door is a wall, an open one is free space."""

    name: str
    segment: tuple[Point, Point]
    open: bool
    thickness: float  # m


@dataclass(frozen=True)
class Landmark:
    name: str
    position: Point
    kind: str = "landmark"


@dataclass(frozen=True)
class RobotSpec:
    name: str
    pose: Pose
    covariance: tuple[tuple[float, float, float], ...]  # 3x3, (m², m², rad²)
    radius: float  # m
    speed: float  # m/s, driving speed along roadmap edges
    turn_rate: float  # rad/s, turning speed when aligning with the next edge

    @property
    def cov(self) -> np.ndarray:
        return np.array(self.covariance, dtype=float)


@dataclass(frozen=True)
class RangeBearingSensor:
    """Range-bearing sensor: detection range (m), field of view (rad), noise std devs."""

    range: float
    fov: float
    sigma_range: float  # m
    sigma_bearing: float  # rad

    @property
    def Q(self) -> np.ndarray:
        return np.diag([self.sigma_range**2, self.sigma_bearing**2])


class ScanModelKind(enum.StrEnum):
    """How a robot's localiser turns a scan into information about its pose."""

    BEAMS = "beams"  # every beam an independent range measurement of the sensor's own noise (Censi)
    AMCL = "amcl"  # nav2's AMCL: a particle filter with the likelihood-field model, calibrated


@dataclass(frozen=True)
class ScanModel:
    """What one scan tells the robot's localiser (docs/models.md, "What a localiser achieves").

    ``beams``: Censi's bound, each beam of the sensor an independent range measurement with
    the sensor's noise; the information the sensor could give, far more than a localiser
    takes from it. ``amcl``: nav2's AMCL with the likelihood-field model. A beam's endpoint is
    scored by its distance to the nearest wall with noise ``sigma_hit`` (m) against a share
    ``z_hit`` of hits and ``z_rand`` of random returns; AMCL weighs ``max_beams`` beams of a
    scan and updates only after the robot has moved ``update_min_d`` (m) or turned
    ``update_min_a`` (rad). What the derivation cannot give (beams correlated through the map's
    errors, AMCL's sum of cubed beam likelihoods in place of their product, its particles) is
    one factor, ``information``: the share of the likelihood field's information that AMCL's
    estimate realises, fitted by ``tmpnav calibrate`` against nav2's AMCL. AMCL fuses the lidar
    alone (``lidar_only``): the landmarks and the partners a robot sees are then not in its belief."""

    kind: ScanModelKind = ScanModelKind.BEAMS
    sigma_hit: float = 0.2  # m
    z_hit: float = 0.5
    z_rand: float = 0.5
    max_beams: int = 60
    update_min_d: float = 0.25  # m
    update_min_a: float = 0.2  # rad
    information: float = 1.0
    #: ``amcl``: the robot's belief fuses its lidar alone, as nav2's AMCL does (no landmarks, no
    #: partners seen); False: the landmarks and mutual observations update it too
    lidar_only: bool = True
    #: ``amcl``: what the collision bound prices. ``local``: the robot's position relative to the
    #: walls its lidar sees, as nav2's costmaps place them from the live scans (a stationary
    #: Gauss-Markov error of std ``local_std`` and correlation time ``local_time``); ``map``: its
    #: belief against the map, as if it steered on its global estimate alone
    walls: str = "local"
    local_std: float = 0.05  # m
    local_time: float = 2.0  # s
    #: ``amcl``: wall hits per metre driven that the Gaussian error does not explain (AMCL converging
    #: off the robot's pose, a recovery behaviour backing it off its path), a Poisson rate along the
    #: path that the collision bound adds (docs/models.md, "Localisation failures"); fitted by
    #: ``tmpnav calibrate`` as the upper 95% limit of the rate it counts; 0: the Gaussian error alone
    failure_rate: float = 0.0  # 1/m
    #: ``amcl``: nav2's alpha1..alpha4 (odom_model_type diff) of the rate AMCL's estimate drifts at where
    #: the scans say little; the planned belief predicts with it (:meth:`belief_noise`) instead of the
    #: robot's own motion noise (nav2's defaults, 0.2 each, are the rate its particle cloud spreads
    #: at). None: the robot's own (models.motion_noise)
    prediction_noise: tuple[float, float, float, float] | None = None
    #: ``amcl``: the heading spread (rad) of AMCL's particle cloud, which spreads a beam's endpoint
    #: across the particles by its range times it: the likelihood field's endpoint variance becomes
    #: sigma_lf² + (r heading_blur)², and far returns tell less than near ones; 0: none
    heading_blur: float = 0.0
    #: ``amcl``: the information of this many head-on beams, below which a direction of a scan does not
    #: separate AMCL's particles (its weights add the beams' cubed likelihoods, so a direction few beams
    #: see hardly changes them): each direction of a scan informs the belief by its excess over it alone
    #: (docs/models.md, "Directions AMCL does not resolve"); 0: every direction by all it has
    floor_beams: float = 0.0

    def belief_noise(self, own: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
        """alpha1..alpha4 of W(u) (docs/models.md, "Motion noise") that the planned belief of a robot
        localised this way predicts with: ``own``, the robot's, unless an ``amcl`` localiser names its
        ``prediction_noise``. nav2's odometry model draws a step's translation with variance alpha3
        d_trans² + alpha4 d_rot² and its rotation with alpha1 d_rot² + alpha2 d_trans², so per
        control step (d_trans = v dt, d_rot = omega dt) W(u) = diag(alpha3 v² + alpha4 omega², alpha2
        v² + alpha1 omega²)."""
        if self.kind is not ScanModelKind.AMCL or self.prediction_noise is None:
            return own
        a1, a2, a3, a4 = self.prediction_noise
        return (a3, a4, a2, a1)

    @property
    def hazard(self) -> float:
        """Wall hits per metre driven that the collision bound adds to the Gaussian error's (0 for ``beams``)."""
        return self.failure_rate if self.kind is ScanModelKind.AMCL else 0.0

    @property
    def local_walls(self) -> bool:
        """The collision bound prices the error relative to the walls the robot sees (``amcl``, ``walls: local``)."""
        return self.kind is ScanModelKind.AMCL and self.walls == "local"

    @property
    def fuses_others(self) -> bool:
        """Landmarks and mutual observations update the robot's belief (all but AMCL alone)."""
        return self.kind is ScanModelKind.BEAMS or not self.lidar_only

    def update_rate(self, v: float, omega: float, dt: float) -> float:
        """The share of control steps at which the localiser updates with a scan, driving at (v, omega)
        for dt: 1 for ``beams`` (every step, standing or not); for ``amcl`` the distance or turn of
        the step over AMCL's thresholds, at most 1, 0 standing (AMCL does not update a robot that
        stands)."""
        if self.kind is ScanModelKind.BEAMS:
            return 1.0
        return min(1.0, max(abs(v) * dt / self.update_min_d, abs(omega) * dt / self.update_min_a))

    def mixture_factor(self, range_max: float) -> float:
        """eta in (0, 1]: the Fisher information about a beam endpoint's distance to the wall under
        the likelihood-field mixture z_hit N(0, sigma_hit²) + z_rand / range_max, over that of the
        Gaussian alone (docs/models.md); 1 for ``beams``."""
        if self.kind is ScanModelKind.BEAMS:
            return 1.0
        s = self.sigma_hit
        d = np.linspace(-8.0 * s, 8.0 * s, 4001)
        phi = np.exp(-0.5 * (d / s) ** 2) / (s * math.sqrt(2.0 * math.pi))
        dphi = -d / s**2 * phi
        c = self.z_rand / max(range_max, 1e-9) / max(self.z_hit, 1e-12)
        return float(s**2 * np.sum(dphi**2 / (phi + c)) * (d[1] - d[0]))


#: nav2's AMCL at its default parameters (docs/amcl.md), with the information share, the floor
#: and the prediction noise fitted together against nav2's AMCL on six sites (docs/models.md,
#: benchmarks/amcl/tradeoff/) and the failure rate counted in 248 executions of building-4robots
#: under AMCL (4 moves with a wall hit in 74.9 km driven, the rate's upper 95% limit;
#: benchmarks/amcl/failures/): the model the shipped lidar configs and ``tmpnav rooms`` skeletons
#: plan with when they name no other
NAV2_AMCL = ScanModel(
    ScanModelKind.AMCL,
    information=0.16,
    failure_rate=0.000122,
    prediction_noise=(0.03, 0.03, 0.03, 0.03),
    heading_blur=0.05,
    floor_beams=15.0,
)


@dataclass(frozen=True)
class RangeSensor:
    """A 2D range finder (lidar) that measures, per beam, the range to the map's walls.

    ``beams`` rays spread evenly over the field of view ``fov`` (rad) centred on the heading,
    each with independent Gaussian range noise. ``beams`` is the effective number of
    independent beams per scan (a lidar's returns are correlated through the map's errors;
    nav2's AMCL uses 60 of them). A beam's range has the variance sigma_range² + (r divergence
    tan beta)²: the noise of its range ``sigma_range`` (m), and the spread of its spot, which
    widens by ``divergence`` (rad) per metre of range r, along a surface met at incidence beta.
    A beam returns nothing beyond ``range`` or before ``min_range`` (m), nor where it meets a
    surface more than ``max_incidence`` (rad) from head-on. docs/models.md, "Range sensor"."""

    range: float  # m
    fov: float  # rad
    beams: int
    sigma_range: float  # m
    min_range: float  # m
    max_incidence: float  # rad
    divergence: float = 0.0  # rad
    localiser: ScanModel = ScanModel()  # what the robot's localiser makes of a scan

    def beam_angles(self) -> np.ndarray:
        """(beams,) rad: each beam's direction relative to the heading, evenly over the field of view."""
        return -0.5 * self.fov + (np.arange(self.beams) + 0.5) * (self.fov / self.beams)


class ObservationMode(enum.StrEnum):
    """How future observations are simulated while planning."""

    NOISY = "noisy"  # the paper: nominal observation corrupted by seeded noise
    MAX_LIKELIHOOD = "max-likelihood"  # BRM: the observation equals its prediction


@dataclass(frozen=True)
class Models:
    """Motion and sensing models of the EKF (see docs/models.md)."""

    dt: float  # s, control time step
    motion_noise: tuple[float, float, float, float]  # alpha1..alpha4 of W(u)
    landmark_sensor: RangeBearingSensor
    mutual_sensor: RangeBearingSensor
    mutual_observations: bool
    observations: ObservationMode
    seed: int  # seed of the simulated observation noise
    range_sensor: RangeSensor | None = None  # a lidar against the map; None: landmarks and partners only
    #: how a robot drives a path: "turn-then-drive" (the paper: on the spot at every node, then
    #: straight), "rpp" (nav2's Regulated Pure Pursuit on the shortened path, tmpnav.belief.pursuit)
    #: or "auto" (rpp for robots with a range sensor, nav2's robots; else the paper's): :attr:`driving`
    controller: str = "auto"

    @property
    def driving(self) -> str:
        """The controller in force: ``rpp`` or ``turn-then-drive`` (``auto`` resolved)."""
        if self.controller == "auto":
            return "rpp" if self.range_sensor is not None else "turn-then-drive"
        return self.controller

    @property
    def midpoint(self) -> bool:
        """Each control step translates along the heading at its middle (a second-order step of
        the unicycle, tmpnav.belief.models.motion): RPP turns while it drives, and its 0.5 s steps
        then stay on the arcs nav2's 20 Hz commands drive. The paper's turn-then-drive steps
        either turn or drive and keep the Euler step of eq. (4)."""
        return self.driving == "rpp"

    @property
    def belief_noise(self) -> tuple[float, float, float, float]:
        """alpha1..alpha4 of W(u) that the planned beliefs predict with: the robots' own
        ``motion_noise``, or the motion model of the localiser that keeps them
        (ScanModel.belief_noise). Simulated robots move with ``motion_noise`` either way."""
        sensor = self.range_sensor
        return self.motion_noise if sensor is None else sensor.localiser.belief_noise(self.motion_noise)

    @property
    def others_fused(self) -> bool:
        """Whether the robots' beliefs take in anything besides their own range scans (landmarks,
        partners): not where nav2's AMCL fuses its lidar alone (ScanModel.fuses_others)."""
        sensor = self.range_sensor
        return sensor is None or sensor.localiser.fuses_others

    @property
    def partners_fused(self) -> bool:
        """Whether the robots' beliefs take in their mutual observations: switched on, and not
        nav2's AMCL fusing its lidar alone (ScanModel.fuses_others). Without them a paired move
        costs exactly its two single moves."""
        return self.mutual_observations and self.others_fused


CostValue = TypeVar("CostValue", float, np.ndarray)

#: the chance constraint in force when a scenario whose robots carry a range sensor names none
#: (planner.max_risk): every move's collision bound at most 5% (docs/planning.md)
DEFAULT_MAX_RISK = 0.05
DEFAULT_RISK_SOURCE = "the default for robots with a range sensor"
#: PlannerOptions.min_rooms_from of a fleet's default minimum (tmpnav.choices.default_min_rooms)
FLEET_DEFAULT = "the default for a fleet of 9 robots or more"
#: m: the margin from the walls paths prefer and goal poses keep when the robots carry a range
#: sensor or plan within a threshold, and the scenario names none (roadmap.clearance;
#: tmpnav.roadmap.graph.safe_weights)
SAFE_MARGIN = 0.5


#: what a move costs per unit of probability by which its collision bound exceeds the chance
#: constraint (planner.max_risk): so much that a plan with a move over the threshold costs more
#: than any plan within it (the planner keeps within it when it can, and otherwise finds the
#: plan of least excess, which names the threshold it does meet)
RISK_PENALTY = 1e12
#: a cost at least this large holds a move over the chance constraint: a collision bound a
#: millionth over it adds this, more than any sum of action costs tmpnav meets
PENALISED = RISK_PENALTY * 1e-6


def risk_penalty(risk: float, max_risk: float | None) -> float:
    """The cost added to a move whose collision bound ``risk`` exceeds ``max_risk``."""
    if max_risk is None or risk <= max_risk:
        return 0.0
    return RISK_PENALTY * (risk - max_risk)


@dataclass(frozen=True)
class CostWeights:
    """c = M_u*c_u + M_G*c_G + M_Sigma*c_Sigma (paper, section Approach); M_T weighs the
    team's time, a second of makespan, in the ``weighted`` objective (tmpnav.task.objectives)."""

    M_u: float
    M_G: float
    M_Sigma: float
    M_T: float = 1.0

    def combine(self, c_u: CostValue, c_G: CostValue | float, c_Sigma: CostValue) -> CostValue:
        """The weighted cost M_u c_u + M_G c_G + M_Sigma c_Sigma: the one place it is written.

        Works on floats and, element by element, on numpy arrays of terms; always in this
        order of operations, so every caller gets the same bits for the same terms.
        """
        return self.M_u * c_u + self.M_G * c_G + self.M_Sigma * c_Sigma


@dataclass(frozen=True)
class RoadmapParams:
    samples: int  # PRM milestones grown by OMPL (excluding instantiations and starts)
    instantiations: int  # pose instantiations sampled per room
    seed: int
    neighbors: int  # k of the k-nearest connection strategy
    #: m: the margin from the walls paths prefer and goal poses keep where a room allows it
    #: (0: the paper's shortest paths; None until the chance constraint in force decides it)
    clearance: float | None = None
    #: rooms whose one pose instantiation is given (a job's goal pose, ``goals.jobs``): (room, x, y)
    poses: tuple[tuple[str, float, float], ...] = ()


#: seconds by which an arrival may pass a window's latest and still count as within it (rounding)
WINDOW_TOL = 1e-6


@dataclass(frozen=True)
class Job:
    """What a goal room asks of the robot that visits it (``goals.jobs``): ``service`` seconds
    standing there after it arrives (time at a station), the ``robots`` that may do it (every
    robot when empty), and the ``pose`` it ends at (x, y in m, heading in rad; None: the room's
    sampled pose instantiations, as any goal room), and the ``window`` [earliest, latest] of its
    arrival on the team's clock (s from the plan's start; None: any time): a robot that arrives
    earlier waits there until the earliest, one that would arrive later may not take the job."""

    room: str
    service: float = 0.0  # s
    robots: tuple[str, ...] = ()
    pose: tuple[float, float, float] | None = None
    window: tuple[float, float] | None = None  # s on the team's clock
    #: an optional goal: the plan may leave it undone at this price, in the objective's units
    #: (a higher penalty: a higher priority); None: it must be done
    penalty: float | None = None


@dataclass(frozen=True)
class Goals:
    visit: tuple[str, ...]  # rooms that some robot must visit
    per_robot: tuple[tuple[str, tuple[str, ...]], ...]  # (robot, rooms it must visit)
    jobs: tuple[Job, ...] = ()
    #: (robot, room) where a robot must finish (its dock, a charger): its last move enters it
    ends: tuple[tuple[str, str], ...] = ()
    #: (robot, s): a robot that stands where it is for that long before its first move, on the
    #: team's clock (a replan: the rest of the service it is doing when the team replans)
    held: tuple[tuple[str, float], ...] = ()

    def held_for(self, robot: str) -> float:
        """Seconds ``robot`` stands where it starts before it may move (0: it may at once)."""
        return dict(self.held).get(robot, 0.0)

    def for_robot(self, robot: str) -> tuple[str, ...]:
        """The rooms ``robot`` must enter: its targets, then its end."""
        end = self.end_of(robot)
        return dict(self.per_robot).get(robot, ()) + (() if end is None else (end,))

    def end_of(self, robot: str) -> str | None:
        """Where ``robot`` must finish (None: anywhere)."""
        return dict(self.ends).get(robot)

    @property
    def targets(self) -> frozenset[tuple[str, str]]:
        """(robot, room): a room a given robot must visit (goals.robots); a robot's end is not one."""
        return frozenset((r, x) for r, rooms in self.per_robot for x in rooms)

    @property
    def entries(self) -> frozenset[tuple[str, str]]:
        """(robot, room): a room a given robot may enter though others entered it (its targets and
        its end), once, recorded as ``visited_by``."""
        return self.targets | frozenset(self.ends)

    def marked_at_start(self, start_location: dict[str, str]) -> frozenset[tuple[str, str]]:
        """The targets its robot visits by starting there; a robot that starts at its end must
        still come back to it."""
        return frozenset((r, x) for r, x in start_location.items() if (r, x) in self.targets)

    def ended(self, at: dict[str, str]) -> bool:
        """Whether every robot with an end is there."""
        return all(at.get(r) == x for r, x in self.ends)

    def window(self, room: str) -> tuple[float, float] | None:
        """The window of arrival at ``room`` (s on the team's clock), if its job gives one."""
        job = self.job(room)
        return None if job is None else job.window

    @property
    def windows(self) -> dict[str, tuple[float, float]]:
        return {j.room: j.window for j in self.jobs if j.window is not None}

    @property
    def optional(self) -> dict[str, float]:
        """Room -> the penalty of leaving it undone, for the optional goals (``goals.jobs``)."""
        return {j.room: j.penalty for j in self.jobs if j.penalty is not None}

    @property
    def required(self) -> tuple[str, ...]:
        """The rooms of ``visit`` that every plan must visit (the others are optional)."""
        optional = self.optional
        return tuple(x for x in self.visit if x not in optional)

    def dropped(self, entered: Iterable[str]) -> tuple[str, ...]:
        """The optional goals a plan that enters ``entered`` (and the robots' starts) leaves undone."""
        seen = set(entered)
        return tuple(x for x in self.optional if x not in seen)

    def drop_penalty(self, entered: Iterable[str]) -> float:
        """The objective's price of the optional goals left undone."""
        optional = self.optional
        return float(sum(optional[x] for x in self.dropped(entered)))

    def opens(self, room: str, arrival: float) -> float:
        """Seconds a robot that arrives at ``room`` at ``arrival`` (team's clock) waits for its
        window to open (0 without one)."""
        window = self.window(room)
        return 0.0 if window is None else max(0.0, window[0] - arrival)

    def too_late(self, room: str, arrival: float) -> bool:
        """Whether an arrival at ``room`` at ``arrival`` s is after its window closes."""
        window = self.window(room)
        return window is not None and arrival > window[1] + WINDOW_TOL

    def job(self, room: str) -> Job | None:
        """The job at ``room``, if the goals give one."""
        return self._job_at.get(room)

    @functools.cached_property
    def _job_at(self) -> dict[str, Job]:
        """Room -> its job (the first of the goals' at it), for :meth:`job`: the route edits ask
        millions of times at fleet size."""
        found: dict[str, Job] = {}
        for j in self.jobs:
            found.setdefault(j.room, j)
        return found

    def may_visit(self, robot: str, room: str) -> bool:
        """Whether ``robot`` may enter ``room``: every robot may, unless the room's job names
        the robots that may."""
        job = self.job(room)
        return job is None or not job.robots or robot in job.robots

    def service(self, room: str) -> float:
        """Seconds a robot stands at ``room`` after it arrives, for the room's job (0 without)."""
        job = self.job(room)
        return 0.0 if job is None else job.service

    def service_steps(self, room: str, dt: float) -> int:
        """:meth:`service` in control steps of ``dt`` s, rounded up: how long the team's clock
        and the simulator keep the robot standing there."""
        service = self.service(room)
        return math.ceil(service / dt - 1e-9) if service > 0 else 0

    def opens_steps(self, room: str, arrive: int, dt: float) -> int:
        """Control steps of ``dt`` s a robot that arrives at ``room`` at step ``arrive`` waits
        there for the job's window to open (0 without one): for the team's clock and the simulator."""
        window = self.window(room)
        return 0 if window is None else max(0, math.ceil(window[0] / dt - 1e-9) - arrive)

    @property
    def all_rooms(self) -> tuple[str, ...]:
        """Every room a plan enters: the rooms to visit, the robots' targets and ends."""
        rooms = list(self.visit)
        for _, targets in self.per_robot:
            rooms.extend(t for t in targets if t not in rooms)
        rooms.extend(x for _, x in self.ends)
        return tuple(dict.fromkeys(rooms))


@dataclass(frozen=True)
class PlannerOptions:
    name: str  # a unified-planning engine name
    encoding: str  # paper | single | mixed
    timeout: float  # s
    pair_min_gain: float = 0.05  # mixed: minimum relative saving of a paired move
    search: Search = "auto"  # exact | anytime | auto (tmpnav.choices)
    time_budget: float | None = None  # s, the anytime search's time cap for the run; None: no cap
    work_budget: int | None = None  # ENHSP sub-problems the anytime search may solve; None: by size
    #: s, OR-Tools' time limit on the anytime search's first routes; None: a quarter of the
    #: search's time cap, at most 30 s (tmpnav.task.first_routes)
    routing_time: float | None = None
    time_limit: float | None = None  # s, the whole run (plan, replan, simulate); None: unbounded
    costs: Costs = "carried"  # carried (the beliefs the robots carry; default) | table (canonical start states)
    objective: Objective = "weighted"  # weighted | cost | makespan (tmpnav.choices)
    #: the chance constraint: each move's bound on the probability of touching an obstacle,
    #: and of two robots touching, at most this (None: unconstrained; docs/models.md)
    max_risk: float | None = None
    #: where max_risk comes from, in words for the reports: "planner.max_risk", "--max-risk",
    #: DEFAULT_RISK_SOURCE (a team with a range sensor), or "" (none is in force)
    max_risk_from: str = ""
    #: robots in each other's way on the clock kept apart after planning, by waits and detours
    #: (and sidesteps under max_risk; tmpnav.attachment.apart.keep_apart)
    keep_apart: bool = True
    #: seconds a robot may fall behind the plan's clock per second it drives, which robots kept
    #: apart allow for (None: by the localiser; tmpnav.attachment.drift.clock_drift)
    clock_drift: float | None = None
    #: work rooms each robot visits at least, where the goals allow (0: no minimum; tmpnav.task.minimum)
    min_rooms: int = 0
    #: where min_rooms comes from, in words for the reports: "planner.min_rooms", "--min-rooms",
    #: FLEET_DEFAULT (a fleet's default, tmpnav.choices.default_min_rooms) or "" (none in force)
    min_rooms_from: str = ""


@dataclass(frozen=True)
class Scenario:
    name: str
    source: Path  # the YAML file; relative paths inside it are relative to its folder
    map: MapSpec
    rooms: tuple[Room, ...]
    doors: tuple[Door, ...]
    landmarks: tuple[Landmark, ...]
    robots: tuple[RobotSpec, ...]
    models: Models
    cost: CostWeights
    roadmap: RoadmapParams
    goals: Goals
    planner: PlannerOptions
    description: str = ""
    #: display key path -> line in the YAML file, for messages of later checks
    key_lines: dict[str, int] = field(default_factory=dict, compare=False, repr=False)

    def line_of(self, path: str) -> int | None:
        """The YAML line of a key path, or of its nearest ancestor."""
        while path:
            if path in self.key_lines:
                return self.key_lines[path]
            path = path.rpartition(".")[0]
        return None

    def robot(self, name: str) -> RobotSpec:
        return self._robots_by_name[name]

    @functools.cached_property
    def _robots_by_name(self) -> dict[str, RobotSpec]:
        """Each robot by its name: the oracle asks for a robot's spec on every motion it lays out."""
        return {r.name: r for r in self.robots}

    def room(self, name: str) -> Room:
        return next(r for r in self.rooms if r.name == name)

    @property
    def places(self) -> tuple[Room, ...]:
        """The rooms and places of the map, without the stations (what the map is cut into)."""
        return tuple(r for r in self.rooms if r.place is None)

    @property
    def stations(self) -> tuple[Room, ...]:
        """The stations: goals at one pose each inside a place (``goals.jobs`` with ``place``)."""
        return tuple(r for r in self.rooms if r.place is not None)


# --------------------------------------------------------------------------- roadmap


@dataclass(frozen=True, eq=False)
class Roadmap:
    """A probabilistic roadmap as plain arrays (nothing downstream imports OMPL).

    ``nodes`` (N, 2) are positions in metres; ``edges`` (E, 2) index pairs of an
    undirected graph with Euclidean ``weights`` (E,); ``instantiations`` maps a room to
    the node indices of its pose instantiations; ``starts`` maps a robot to its start node.

    ``sources`` are nodes added to a grown roadmap (``base`` its fingerprint) at the starts of
    a replan (tmpnav.roadmap.prm.with_starts): their edges lead out only, so no path between
    the grown roadmap's nodes passes through them, and every motion from those nodes is the
    one the grown roadmap gives.
    """

    nodes: np.ndarray
    edges: np.ndarray
    weights: np.ndarray
    instantiations: dict[str, tuple[int, ...]]
    starts: dict[str, int]
    fingerprint: str = ""  # content hash: equal fingerprints, identical roadmaps
    sources: tuple[int, ...] = ()
    base: str = ""  # with sources: the fingerprint of the roadmap they were added to

    @property
    def grown(self) -> str:
        """The fingerprint of the roadmap without its sources: what decides every path that
        does not start at a source."""
        return self.base or self.fingerprint

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def base_nodes(self) -> int:
        """How many nodes are the roadmap's without its sources (they are numbered after them)."""
        return self.n_nodes - len(self.sources)


# --------------------------------------------------------------------------- belief


@dataclass(frozen=True, eq=False)
class Belief:
    """A Gaussian belief b[x] ~ N(mean, cov) over one robot (3) or several (3n)."""

    mean: np.ndarray
    cov: np.ndarray

    @property
    def dim(self) -> int:
        return int(self.mean.shape[0])

    def marginal(self, i: int) -> Belief:
        """The belief of the i-th robot of a joint belief."""
        s = slice(3 * i, 3 * i + 3)
        return Belief(self.mean[s].copy(), self.cov[s, s].copy())


@dataclass(frozen=True)
class CostTerms:
    """The three terms of one robot's motion cost, before weighting."""

    c_u: float
    c_G: float
    c_Sigma: float

    def total(self, w: CostWeights) -> float:
        """This robot's weighted cost under ``w`` (:meth:`CostWeights.combine`)."""
        return w.combine(self.c_u, self.c_G, self.c_Sigma)


# --------------------------------------------------------------------------- oracle / task


@dataclass(frozen=True)
class MotionResult:
    """The oracle's answer for one action: min cost over goal instantiations.

    ``goal_nodes`` and ``paths`` are per robot of the action (roadmap node indices);
    ``terms`` per robot; ``final`` is the belief of the robots of the action at the end
    (joint when two robots moved together). For a factorised pair (the robots never saw
    each other) it is block-diagonal, each block the robot's belief at its own arrival.
    """

    cost: float
    robots: tuple[str, ...]
    goal_nodes: tuple[int, ...]
    paths: tuple[tuple[int, ...], ...]
    terms: tuple[CostTerms, ...]
    final_mean: tuple[float, ...]
    final_cov: tuple[tuple[float, ...], ...]
    mutual_steps: int = 0  # steps with at least one mutual observation
    final_headings: tuple[float, ...] = ()  # nominal heading of each robot at its goal
    pruned: bool = False  # a pair proved unable to save min_gain: cost is a lower bound only
    steps: tuple[int, ...] = ()  # control steps of each robot's motion (its duration is steps x dt)
    #: each robot's bound on the probability that its footprint touches an obstacle during the
    #: move (docs/models.md, "Collision bound"; at most 1); empty when the request had no
    #: threshold on it (``max_risk``): the oracle then does not compute it
    risk: tuple[float, ...] = ()

    @property
    def final(self) -> Belief:
        return Belief(np.array(self.final_mean), np.array(self.final_cov))


MoveKey = tuple[str, str, str]  # (robot, origin location, target room)


@dataclass(frozen=True, eq=False)
class CostTable:
    """The action costs the task planner sees, computed by the oracle before planning.

    ``single[(r, origin, target)]`` is the cost of robot r moving alone;
    ``pair[(m1, m2)]`` the joint cost of two moves done together (m1's robot comes first
    in the scenario's robot order); ``duration`` and ``pair_duration`` how long they take.
    Locations are rooms plus ``<robot>-start`` for a robot that does not start inside a room.
    """

    robots: tuple[str, ...]
    rooms: tuple[str, ...]
    locations: tuple[str, ...]
    start_location: dict[str, str]
    single: dict[MoveKey, float]
    pair: dict[tuple[MoveKey, MoveKey], float]
    #: seconds each move takes (its motion's control steps x dt); a paired move's two robots
    #: start together and each ends with its own motion: ``pair_duration[(m1, m2)]`` = (d1, d2)
    duration: dict[MoveKey, float] = field(default_factory=dict)
    pair_duration: dict[tuple[MoveKey, MoveKey], tuple[float, float]] = field(default_factory=dict)

    def with_service(self, goals: Goals) -> CostTable:
        """The same table with each move's duration ending after the service its target's job
        asks (``goals.jobs``): the time until its robot is free again, as schedules count it."""
        if not any(j.service for j in goals.jobs):
            return self
        s = goals.service
        duration = {m: d + s(m[2]) for m, d in self.duration.items()}
        pair_duration = {(m1, m2): (d1 + s(m1[2]), d2 + s(m2[2])) for (m1, m2), (d1, d2) in self.pair_duration.items()}
        return replace(self, duration=duration, pair_duration=pair_duration)


class PlanStatus(enum.StrEnum):
    SOLVED_OPTIMALLY = "solved-optimally"
    SOLVED_SATISFICING = "solved-satisficing"


@dataclass(frozen=True)
class TrajectoryStep:
    """One control step of a robot in the re-simulated plan."""

    t: float
    mean: tuple[float, float, float]
    cov: tuple[tuple[float, float, float], ...]
    node: int | None = None  # roadmap node reached at this step, if any


@dataclass(frozen=True)
class PlannedAction:
    """A step of the task-motion plan: the action and each robot's optimal path."""

    index: int
    name: str  # the PDDL action name
    moves: tuple[MoveKey, ...]  # (robot, from, to) of each robot that moves
    planner_cost: float  # from the cost table, as the planner saw it
    resimulated_cost: float  # with beliefs carried over from the previous actions
    goal_nodes: tuple[int, ...]
    paths: tuple[tuple[int, ...], ...]
    goal_poses: tuple[tuple[float, float, float], ...]
    #: each move's bound on the probability that its robot touches an obstacle (docs/models.md)
    risk: tuple[float, ...] = ()
    #: how each robot drives its path: "rpp" or "turn-then-drive" (models.controller; empty: all
    #: turn-then-drive, as plans made before the controller was recorded)
    controllers: tuple[str, ...] = ()
