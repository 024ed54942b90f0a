"""The scenario format: every key, its type, unit, default and meaning.

This tree is the single source of truth: the loader validates against it and
``tmpnav reference`` / docs/scenario.md print it as the reference table.

Longer than 400 lines on purpose: it is one declarative table of every key of the format,
section after section, and splitting it would scatter the one place the format is defined.
"""

from __future__ import annotations

import math
from typing import Any

from tmpnav.choices import COSTS, ENCODINGS, OBJECTIVES, SEARCHES
from tmpnav.scenario.limits import MAP_CELLS, grid_cells
from tmpnav.scenario.schema import (
    Choice,
    Covariance,
    Ctx,
    Field,
    Flag,
    ListOf,
    Name,
    NamedList,
    NameList,
    NameMap,
    Number,
    PointList,
    Section,
    Text,
    Vector,
)
from tmpnav.types import NAV2_AMCL, ScanModelKind

DEG = math.pi / 180.0

#: the task stage's choices (tmpnav.choices)
ENCODING_CHOICES = tuple(ENCODINGS)
SEARCH_CHOICES = SEARCHES
COSTS_CHOICES = COSTS
OBJECTIVE_CHOICES = OBJECTIVES

#: points of a room outline: rooms are tested for self-intersection pair by pair
MAX_ROOM_POINTS = 1000

#: coordinates farther from the origin are beyond any map on Earth (UTM northings reach 1e7 m)
MAX_COORDINATE = 1e7

#: seeds are 32-bit (OMPL and numpy take them; larger ones are typos)
MAX_SEED = 2**32 - 1

#: a planner time limit beyond 11 days is a typo
MAX_TIMEOUT = 1e6

HALF_TURN = "a spread beyond a half turn says nothing about the bearing"

#: sensor noise below a micrometre (microradian) drives the EKF's covariance below float
#: precision: costs turned NaN or astronomically negative at 1e-30 and below (measured)
MIN_SIGMA = 1e-6
PRECISE = "a sensor more precise than 1e-6 drives the filter below float precision"
NOISE = "beyond 1 the noise's standard deviation exceeds the command itself"

#: cost weights are relative; at 1e6 to 1 the smaller term is already below the cost's
#: resolution (thousandths), and larger weights let costs overflow
WEIGHT = Number(None, minimum=0.0, maximum=1e6, reason="weights are relative, 1e6 to 1 hides the smaller term")


def polygonal_cells(bounds: tuple[float, ...], resolution: float) -> float:
    """How many cells the occupancy grid of a polygonal map has (world.build.rasterize)."""
    return grid_cells(bounds[2] - bounds[0], bounds[3] - bounds[1], resolution)


def _one_map_kind(section: dict[str, Any], ctx: Ctx, path: str, raw: tuple[Any, ...]) -> None:
    has_ros, has_bounds = section.get("ros") is not None, section.get("bounds") is not None
    if has_ros == has_bounds:
        ctx.add(path, raw, "must have exactly one of 'ros' (a ROS map_server YAML file) or 'bounds' (a polygonal map)")
    if has_ros and (section.get("walls") or section.get("obstacles")):
        ctx.add(path, raw, "'walls' and 'obstacles' belong to polygonal maps; a ROS map takes its walls from the image")
    if has_bounds and section.get("despeckle"):
        ctx.add(
            f"{path}.despeckle", (*raw, "despeckle"), "belongs to ROS maps (map.ros); a polygonal map has no specks"
        )
    bounds = section.get("bounds")
    if bounds is not None and (bounds[2] <= bounds[0] or bounds[3] <= bounds[1]):
        ctx.add(
            f"{path}.bounds",
            (*raw, "bounds"),
            f"{list(bounds)} is empty; expected [xmin, ymin, xmax, ymax] with xmin < xmax and ymin < ymax",
        )
    elif bounds is not None:
        # a typo (bounds in mm, resolution in m) would otherwise exhaust memory: refuse it here
        cells = polygonal_cells(bounds, section["resolution"])
        if cells > MAP_CELLS.value():
            ctx.add(
                f"{path}.resolution",
                (*raw, "resolution"),
                f"{section['resolution']:g} m over bounds {list(bounds)} makes "
                + MAP_CELLS.refusal(cells, "a coarser resolution or smaller bounds"),
            )


def _some_goal(section: dict[str, Any], ctx: Ctx, path: str, raw: tuple[Any, ...]) -> None:
    if not section.get("visit") and not any(section.get("robots", {}).values()) and not section.get("ends"):
        ctx.add(path, raw, "names no room to visit; expected rooms in goals.visit, goals.robots or goals.ends")


MAP = Section(
    fields={
        "ros": Field(
            Text(),
            "ROS map_server YAML file (image, resolution, origin, negate, occupied_thresh, free_thresh, mode), relative to the scenario file",
        ),
        "despeckle": Field(
            Number("length", minimum=0.0, maximum=1.0, reason="past 1 m a speck may be a pillar or a rack"),
            "ROS map: specks of occupied cells no wider than this, free all around, are map noise (a reflection, "
            "a person mapped in passing) and are cleared, for planning and simulation alike (`tmpnav rooms` writes "
            "0.1 where the map has such specks); 0: every occupied cell is an obstacle",
            default=0.0,
        ),
        "bounds": Field(
            Vector(dimensions=("length",) * 4, names="xmin, ymin, xmax, ymax", max_abs=MAX_COORDINATE),
            "polygonal map: the bounded plane; outside is occupied",
        ),
        "resolution": Field(
            Number("length", minimum=0.0, exclusive_minimum=True, maximum=1.0),
            "polygonal map: grid cell size for collision and line-of-sight checks",
            default=0.05,
        ),
        "wall_thickness": Field(
            Number("length", minimum=0.0, exclusive_minimum=True),
            "polygonal map: thickness of wall polylines and closed doors",
            default=0.15,
        ),
        "walls": Field(
            ListOf(PointList(min_points=2, what="polyline", max_abs=MAX_COORDINATE), what="polylines"),
            "polygonal map: wall polylines",
            default=(),
        ),
        "obstacles": Field(
            ListOf(PointList(min_points=3, what="polygon", max_abs=MAX_COORDINATE), what="polygons"),
            "polygonal map: filled obstacle polygons",
            default=(),
        ),
    },
    post=_one_map_kind,
)

ROOM = Section(
    fields={
        "name": Field(Name(), "room name (a PDDL object: unique among rooms and robots)", required=True),
        "polygon": Field(
            PointList(min_points=3, max_points=MAX_ROOM_POINTS, what="polygon", max_abs=MAX_COORDINATE),
            "room outline: a simple polygon of at most 1000 points; pose instantiations are sampled inside it",
            required=True,
        ),
    }
)

DOOR = Section(
    fields={
        "name": Field(Name(), "door name", required=True),
        "segment": Field(
            PointList(min_points=2, max_points=2, what="segment", max_abs=MAX_COORDINATE),
            "the door leaf across a wall gap",
            required=True,
        ),
        "state": Field(
            Choice(choices=("open", "closed")), "open doors are carved free, closed doors are walls", default="open"
        ),
        "thickness": Field(
            Number("length", minimum=0.0, exclusive_minimum=True),
            "thickness of the door (defaults to map.wall_thickness, 0.15 m for ROS maps)",
        ),
    }
)

LANDMARK = Section(
    fields={
        "name": Field(Name(), "landmark name", required=True),
        "position": Field(
            Vector(dimensions=("length", "length"), names="x, y", max_abs=MAX_COORDINATE),
            "landmark position",
            required=True,
        ),
        "kind": Field(Text(), "what it is (printer, trash can, ...); used for the legend of plots", default="landmark"),
    }
)

ROBOT = Section(
    fields={
        "name": Field(Name(), "robot name (a PDDL object: unique among rooms and robots)", required=True),
        "pose": Field(
            Vector(dimensions=("length", "length", "angle"), names="x, y, theta", max_abs=MAX_COORDINATE),
            "mean of the initial pose belief",
            required=True,
        ),
        "covariance": Field(
            Covariance(),
            "covariance of the initial pose belief",
            default=((0.01, 0.0, 0.0), (0.0, 0.01, 0.0), (0.0, 0.0, 0.003)),
        ),
        "radius": Field(
            Number("length", minimum=0.0, exclusive_minimum=True), "radius of the robot's disc footprint", default=0.25
        ),
        "speed": Field(
            Number("speed", minimum=0.0, exclusive_minimum=True), "driving speed along roadmap edges", default=0.5
        ),
        "turn_rate": Field(
            Number("angular_speed", minimum=0.0, exclusive_minimum=True),
            "turning speed when aligning with the next edge",
            default=1.0,
        ),
    }
)


def _noise_within_range(section: dict[str, Any], ctx: Ctx, path: str, raw: tuple[Any, ...]) -> None:
    if section["sigma_range"] > section["range"]:
        ctx.add(
            f"{path}.sigma_range",
            (*raw, "sigma_range"),
            f"{section['sigma_range']:g} m is larger than the sensor's range {section['range']:g} m; expected a noise "
            "standard deviation below the range (a larger one says nothing about the distance)",
        )


def _some_weight(section: dict[str, Any], ctx: Ctx, path: str, raw: tuple[Any, ...]) -> None:
    if not any(v for k, v in section.items() if k != "M_T"):
        ctx.add(path, raw, "weights M_u, M_G and M_Sigma are all 0, so every plan would cost 0; expected one above 0")


def _sensor(range_: float, fov: float, doc: str) -> Section:
    return Section(
        fields={
            "range": Field(
                Number("length", minimum=0.0, exclusive_minimum=True), f"{doc}: maximum detection range", default=range_
            ),
            "fov": Field(
                Number("angle", minimum=0.0, exclusive_minimum=True, maximum=2 * math.pi + 1e-9),
                f"{doc}: field of view, centred on the heading",
                default=fov,
            ),
            "sigma_range": Field(
                Number("length", minimum=MIN_SIGMA, reason=PRECISE),  # at most the range: see _noise_within_range
                f"{doc}: range noise standard deviation",
                default=0.1,
            ),
            "sigma_bearing": Field(
                Number("angle", minimum=MIN_SIGMA, maximum=math.pi, reason=f"{PRECISE}; {HALF_TURN}"),
                f"{doc}: bearing noise standard deviation",
                default=3 * DEG,
            ),
        },
        post=_noise_within_range,
    )


def _range_sensor_reach(section: dict[str, Any], ctx: Ctx, path: str, raw: tuple[Any, ...]) -> None:
    _noise_within_range(section, ctx, path, raw)
    if section["min_range"] >= section["range"]:
        ctx.add(
            f"{path}.min_range",
            (*raw, "min_range"),
            f"{section['min_range']:g} m is not below the sensor's range {section['range']:g} m; expected a blind "
            "zone shorter than the range (no beam could return)",
        )
    localiser = section.get("localiser")
    if isinstance(localiser, dict) and localiser.get("model") == ScanModelKind.AMCL.value:
        weighed = min(localiser["max_beams"], section["beams"])
        if localiser["floor_beams"] >= weighed:
            ctx.add(
                f"{path}.localiser.floor_beams",
                (*raw, "localiser", "floor_beams"),
                f"{localiser['floor_beams']:g} is not below the {weighed} beams the localiser weighs "
                "(localiser.max_beams, at most the sensor's beams); expected fewer: a scan would inform "
                "no direction of the belief",
            )


#: beams of one scan: past this the per-step cost grows for information the filter would
#: over-trust anyway (beams of one scan are correlated through the map; docs/models.md)
MAX_BEAMS = 2000

_NAV2 = NAV2_AMCL
LOCALISER = Section(
    fields={
        "model": Field(
            Choice(choices=tuple(k.value for k in ScanModelKind)),
            "amcl: nav2's AMCL (likelihood field), the information a particle filter takes from a scan; "
            "beams: every beam an independent measurement of the sensor's own noise (the sensor's bound, "
            "which no localiser reaches)",
            default=ScanModelKind.AMCL.value,
        ),
        "sigma_hit": Field(
            Number("length", minimum=MIN_SIGMA, maximum=5.0, reason=PRECISE),
            "amcl: noise of a beam endpoint's distance to the nearest wall (nav2's sigma_hit)",
            default=_NAV2.sigma_hit,
        ),
        "z_hit": Field(
            Number(None, minimum=0.0, maximum=1.0, exclusive_minimum=True, reason="a share of the beams"),
            "amcl: share of beams that hit the mapped walls (nav2's z_hit)",
            default=_NAV2.z_hit,
        ),
        "z_rand": Field(
            Number(None, minimum=0.0, maximum=1.0, reason="a share of the beams"),
            "amcl: share of random returns (nav2's z_rand)",
            default=_NAV2.z_rand,
        ),
        "max_beams": Field(
            Number(None, minimum=1, maximum=MAX_BEAMS, integer=True, reason="AMCL weighs at least one beam"),
            "amcl: beams of a scan the localiser weighs, evenly spaced (nav2's max_beams)",
            default=_NAV2.max_beams,
        ),
        "update_min_d": Field(
            Number("length", minimum=0.0, exclusive_minimum=True, maximum=10.0),
            "amcl: distance driven before the localiser updates with a scan (nav2's update_min_d)",
            default=_NAV2.update_min_d,
        ),
        "update_min_a": Field(
            Number("angle", minimum=0.0, exclusive_minimum=True, maximum=2 * math.pi),
            "amcl: turn before the localiser updates with a scan (nav2's update_min_a)",
            default=_NAV2.update_min_a,
        ),
        "information": Field(
            Number(None, minimum=0.0, exclusive_minimum=True, maximum=1000.0),
            "amcl: the share of the likelihood field's information that the localiser's estimate "
            "realises, fitted by tmpnav calibrate (beams correlated through the map, AMCL's particles)",
            default=_NAV2.information,
        ),
        "lidar_only": Field(
            Flag(),
            "amcl: the robots' beliefs fuse the lidar alone, as nav2's AMCL does (the landmarks and the partners "
            "a robot sees do not update it); false: they do too",
            default=_NAV2.lidar_only,
        ),
        "walls": Field(
            Choice(choices=("local", "map")),
            "amcl: what the collision bound prices. local: the position relative to the walls the lidar sees "
            "(nav2's costmaps place obstacles from the live scans), an error of local_std; map: the belief "
            "against the map, as if the robot steered on its global estimate alone",
            default=_NAV2.walls,
        ),
        "local_std": Field(
            Number("length", minimum=MIN_SIGMA, maximum=1.0, reason=PRECISE),
            "amcl, walls local: std of the position relative to the walls the lidar sees (a costmap cell, the "
            "map's walls a few centimetres off, the controller's tracking)",
            default=_NAV2.local_std,
        ),
        "local_time": Field(
            Number("time", minimum=0.0, exclusive_minimum=True, maximum=600.0),
            "amcl, walls local: correlation time of that error (how long the controller takes to correct it)",
            default=_NAV2.local_time,
        ),
        "failure_rate": Field(
            Number(None, minimum=0.0, maximum=1.0, reason="a rate per metre driven"),
            "amcl: wall hits per metre driven that the Gaussian error does not explain (AMCL off the robot's "
            "pose, a recovery backing it off its path), added along each move's path to its collision bound; "
            "fitted by tmpnav calibrate (the upper 95% limit of the rate it counts); 0: the Gaussian error alone",
            default=_NAV2.failure_rate,
        ),
        "heading_blur": Field(
            Number("angle", minimum=0.0, maximum=1.0, reason="a particle cloud's heading spread of a few degrees"),
            "amcl: the heading spread of AMCL's particle cloud, which spreads a beam's endpoint across the particles "
            "by its range times it, so that far returns tell the localiser less than near ones (docs/models.md); "
            "0: none",
            default=_NAV2.heading_blur,
        ),
        "floor_beams": Field(
            Number(None, minimum=0.0, maximum=MAX_BEAMS, reason="a number of AMCL's beams"),
            "amcl: a direction of a scan informs the localiser only by what it has beyond the information of this "
            "many head-on beams (AMCL's weights add the beams' cubed likelihoods, so a direction few beams see, "
            "along a corridor, barely moves them; docs/models.md); 0: by all it has",
            default=_NAV2.floor_beams,
        ),
        "prediction_noise": Field(
            Section(
                fields={
                    f"alpha{k}": Field(
                        Number(None, minimum=0.0, maximum=1.0, reason=NOISE),
                        f"nav2's alpha{k}: {what}",
                        default=0.2,
                    )
                    for k, what in (
                        (1, "rotation noise from rotation"),
                        (2, "rotation noise from translation"),
                        (3, "translation noise from translation"),
                        (4, "translation noise from rotation"),
                    )
                },
                absent_is_none=True,
            ),
            "amcl: the motion noise the planned beliefs predict with in place of the robots' own motion_noise, "
            "as nav2's alpha1-4 (odom_model_type diff): how fast AMCL's estimate drifts where the scans say "
            "little; absent: 0.03 each, fitted to nav2's AMCL on six sites (docs/models.md); {}: nav2's defaults "
            "(0.2 each), the rate AMCL's particle cloud spreads at; to predict with the robots' own noise, give "
            "their alphas here",
        ),
    }
)

RANGE_SENSOR = Section(
    fields={
        "range": Field(
            Number("length", minimum=0.0, exclusive_minimum=True),
            "range sensor: longest range that returns (a typical 2D lidar: 8-30 m)",
            default=12.0,
        ),
        "fov": Field(
            Number("angle", minimum=0.0, exclusive_minimum=True, maximum=2 * math.pi + 1e-9),
            "range sensor: field of view, centred on the heading",
            default=2 * math.pi,
        ),
        "beams": Field(
            Number(None, minimum=1, maximum=MAX_BEAMS, integer=True, reason="a scan needs at least one beam"),
            "range sensor: beams per scan, spread evenly over the field of view; the effective count of "
            "independent beams (nav2's AMCL uses 60 of a scan)",
            default=60,
        ),
        "sigma_range": Field(
            Number("length", minimum=MIN_SIGMA, reason=PRECISE),
            "range sensor: range noise standard deviation of one beam",
            default=0.03,
        ),
        "min_range": Field(
            Number("length", minimum=0.0),
            "range sensor: blind zone; nearer surfaces return nothing",
            default=0.1,
        ),
        "divergence": Field(
            Number("angle", minimum=0.0, maximum=0.1, reason="a spot wider than 0.1 rad per metre is no beam"),
            "range sensor: how fast a beam's spot widens (rad, metres per metre of range); a surface met at "
            "incidence beta spreads a return over r divergence tan(beta), which adds to the range noise "
            "(a typical 2D lidar: 3-15 mrad)",
            default=0.01,
        ),
        "max_incidence": Field(
            Number(
                "angle",
                minimum=0.0,
                exclusive_minimum=True,
                maximum=89 * DEG,
                reason="a beam along a wall returns nothing",
            ),
            "range sensor: a beam that meets a surface farther than this from head-on returns nothing",
            default=75 * DEG,
        ),
        "localiser": Field(
            LOCALISER,
            'what the robots\' localiser makes of a scan (docs/models.md, "What a localiser achieves"); '
            "omitted: nav2's AMCL at its defaults, calibrated (model amcl); model beams: the sensor's own bound, "
            "which no localiser reaches",
        ),
    },
    post=_range_sensor_reach,
    absent_is_none=True,
)

MODELS = Section(
    fields={
        "dt": Field(
            Number("time", minimum=0.0, exclusive_minimum=True, maximum=10.0), "control time step", default=0.5
        ),
        "motion_noise": Field(
            Section(
                fields={
                    "alpha1": Field(
                        Number(None, minimum=0.0, maximum=1.0, reason=NOISE),
                        "speed noise variance per v² (W = diag(a1 v² + a2 w², a3 v² + a4 w²))",
                        default=0.01,
                    ),
                    "alpha2": Field(
                        Number(None, minimum=0.0, maximum=1.0, reason=NOISE),
                        "speed noise variance per w² (m²/rad²)",
                        default=0.0,
                    ),
                    "alpha3": Field(
                        Number(None, minimum=0.0, maximum=1.0, reason=NOISE),
                        "turn-rate noise variance per v² (rad²/m²)",
                        default=0.02,
                    ),
                    "alpha4": Field(
                        Number(None, minimum=0.0, maximum=1.0, reason=NOISE),
                        "turn-rate noise variance per w²",
                        default=0.01,
                    ),
                }
            ),
            "motion noise W(u) of the unicycle model (paper eq. (4))",
        ),
        "landmark_sensor": Field(
            _sensor(5.0, 2 * math.pi, "landmark sensor"), "range-bearing landmark sensor (paper eq. (5))"
        ),
        "mutual_sensor": Field(
            _sensor(4.0, 2 * math.pi, "mutual sensor"), "range-bearing sensor of other robots (paper eq. (14))"
        ),
        "range_sensor": Field(
            RANGE_SENSOR,
            "2D range finder (lidar) against the map's walls, in every robot's EKF; absent: the paper's model "
            "(landmarks and partners only); {} for a typical lidar",
        ),
        "mutual_observations": Field(
            Flag(), "use mutual observations between robots (false: the paper's config 2)", default=True
        ),
        "observations": Field(
            Choice(choices=("noisy", "max-likelihood")),
            "simulated future observations: nominal + seeded noise (paper) or maximum likelihood (BRM)",
            default="noisy",
        ),
        "seed": Field(
            Number(None, minimum=0, maximum=MAX_SEED, integer=True),
            "seed of the simulated observation noise",
            default=0,
        ),
        "controller": Field(
            Choice(choices=("auto", "turn-then-drive", "rpp")),
            "how a robot drives a roadmap path: turn on the spot at every node, then straight (the paper), or "
            "as nav2's Regulated Pure Pursuit drives the path shortened within its clearance (docs/models.md, "
            "Controllers); auto: rpp when the robots carry a range sensor (models.range_sensor), else the paper's",
            default="auto",
        ),
    }
)

COST = Section(
    fields={
        "M_u": Field(WEIGHT, "weight of the control usage c_u", default=1.0),
        "M_G": Field(WEIGHT, "weight of the distance to goal c_G", default=1.0),
        "M_Sigma": Field(WEIGHT, "weight of the uncertainty c_Sigma (time integral of trace(Sigma))", default=1.0),
        "M_T": Field(
            WEIGHT,
            "cost of one second of the team's makespan in the weighted objective (planner.objective)",
            default=1.0,
        ),
    },
    post=_some_weight,
)

ROADMAP = Section(
    fields={
        "samples": Field(
            Number(None, minimum=10, maximum=200000, integer=True),
            "PRM milestones grown by OMPL; a roadmap that does not then reach every room grows on, doubling each round up to 32 times as many milestones, half of each round on PRM's bounce walks from the milestones that failed to connect (a narrow door)",
            default=1500,
        ),
        "instantiations": Field(
            Number(None, minimum=1, maximum=50, integer=True), "pose instantiations sampled in each room", default=4
        ),
        "seed": Field(
            Number(None, minimum=0, maximum=MAX_SEED, integer=True),
            "seed of the roadmap (OMPL) and of the instantiations",
            default=1,
        ),
        "neighbors": Field(
            Number(None, minimum=2, maximum=100, integer=True),
            "k of the PRM's k-nearest connection strategy",
            default=10,
        ),
        "clearance": Field(
            Number("length", minimum=0.0, maximum=5.0, reason="beyond 5 m no corridor has a middle"),
            "the margin from the walls (beyond the robot's radius) that paths prefer, as nav2's inflation "
            "does (an edge weighs more as its margin falls below it), and that goal poses keep where the room "
            "allows; the roadmap then also gets milestones through the middle of every passage narrower than "
            "it (doors); 0: the paper's shortest paths (default: 0.5 m when the robots carry a range sensor, "
            "models.range_sensor, or plan within a threshold, planner.max_risk; else 0)",
        ),
    }
)

#: the longest time at a station (s): a day
MAX_SERVICE = 86_400.0


def _window_in_order(section: dict[str, Any], ctx: Ctx, path: str, raw: tuple[Any, ...]) -> None:
    window = section.get("window")
    if window is not None and not 0.0 <= window[0] <= window[1]:
        ctx.add(
            f"{path}.window",
            (*raw, "window"),
            f"[{window[0]:g}, {window[1]:g}] s is no window; expected [earliest, latest] with 0 <= earliest <= latest",
        )


JOB = Section(
    fields={
        "name": Field(
            Name(),
            "the goal room (or place) of the job, or, with place, the name of a station: a goal of its own; "
            "named in goals.visit, goals.robots or goals.ends",
            required=True,
        ),
        "place": Field(
            Name(),
            "makes the job a station: a named goal pose (pose, required) inside this room or place, which may "
            "hold several; its name, unique among rooms, robots and stations, is then a goal as a room's is (the "
            "roadmap holds its pose as a node; plans, schedules, plan.json, figures and nav2 files name it); "
            "naming the place itself in the goals still means any pose in it",
        ),
        "service": Field(
            Number("time", minimum=0.0, maximum=MAX_SERVICE),
            "time the robot that visits the room stands there after it arrives (time at a station): on the "
            "team's clock, in the makespan and in the schedule",
            default=0.0,
        ),
        "robots": Field(
            NameList(), "the robots that may do the job (capabilities); no other robot enters the room", default=()
        ),
        "pose": Field(
            Vector(dimensions=("length", "length", "angle"), names="x, y, theta", max_abs=MAX_COORDINATE),
            "the goal pose inside the room (or the station's place): the robot ends its move there, turned to "
            "theta; without it, the room's sampled pose instantiations",
        ),
        "penalty": Field(
            Number(None, minimum=0.0, maximum=1e9),
            "makes the goal optional: a plan may leave it undone when the team cannot do it for less, and pays "
            "this much in the objective's units (a higher penalty: a higher priority); only for a room of "
            "goals.visit; omitted: the goal must be done",
        ),
        "window": Field(
            Vector(dimensions=("time", "time"), names="earliest, latest"),
            "when the robot may arrive, on the team's clock (s from the plan's start): one that arrives "
            "earlier waits in the room until the earliest, then serves; no plan arrives later than the latest",
        ),
    },
    post=_window_in_order,
)

GOALS = Section(
    fields={
        "visit": Field(NameList(), "rooms that some robot must visit", default=()),
        "robots": Field(NameMap(), "rooms that a given robot must visit: {robot: [rooms]}", default={}),
        "ends": Field(
            NameMap(value=Name()),
            "where a robot must finish (its dock, a charger): {robot: room}; its last move enters that room, "
            "also when it starts there (a goals.jobs entry for the room gives the pose)",
            default={},
        ),
        "jobs": Field(
            NamedList(item=JOB, what="job"),
            "what a goal room asks of its visit: time at the station, the robots that may do it; a job with a "
            "place is a station of that place",
            default=[],
        ),
    },
    post=_some_goal,
)

PLANNER = Section(
    fields={
        "name": Field(
            Text(),
            "unified-planning engine: enhsp-blind (optimal; default), enhsp-opt (optimal, hrmax), enhsp, enhsp-any, "
            "or any installed engine that supports the problem",
            default="enhsp-blind",
        ),
        "encoding": Field(
            Choice(choices=ENCODING_CHOICES),
            "task encoding: the paper's pair action, single-robot actions, or both",
            default="mixed",
        ),
        "timeout": Field(
            Number("time", minimum=0.0, exclusive_minimum=True, maximum=MAX_TIMEOUT),
            "planner time limit",
            default=300.0,
        ),
        "pair_min_gain": Field(
            Number(None, minimum=0.0, maximum=1.0),
            "mixed encoding: a paired move is offered to the planner only if it saves at least this fraction of its two single moves; the plan costs at most 1/(1 - pair_min_gain) times the optimum over all pairs (0: every saving pair, exact)",
            default=0.05,
        ),
        "search": Field(
            Choice(choices=SEARCH_CHOICES),
            "task-level search: exact (one optimal ENHSP search over the whole cost table), anytime (large-neighbourhood search with ENHSP on sub-problems and a certified lower bound), or auto (exact where it finishes quickly; a replan: anytime)",
            default="auto",
        ),
        "work_budget": Field(
            Number(None, minimum=1, maximum=10**6, integer=True),
            "anytime search: its budget in work, the ENHSP sub-problems it may solve; it stops earlier when the plan is proved optimal or no neighbourhood improves it, and gives the same plan on any machine (default: 2 per goal room and robot, from 50 to 1000; a replan has a tenth of it, at least 10)",
            default=None,
        ),
        "routing_time": Field(
            Number("time", minimum=0.0, exclusive_minimum=True, maximum=MAX_TIMEOUT),
            "anytime search: OR-Tools' time limit on its first routes, which its count of solutions (500) should end; where the limit ends them (200 places and 32 robots take about 2 minutes for 500) the plan is the machine's and plan.json says so (default: a quarter of the search's time cap, at most 30 s)",
            default=None,
        ),
        "time_budget": Field(
            Number("time", minimum=0.0, exclusive_minimum=True, maximum=MAX_TIMEOUT),
            "anytime search: a time cap for the whole run; past it the search returns its best plan and says that the time cap ended it (a plan of the machine's speed; default: none, the work budget bounds the search)",
            default=None,
        ),
        "time_limit": Field(
            Number("time", minimum=0.0, exclusive_minimum=True, maximum=MAX_TIMEOUT),
            "seconds a whole plan, replan, simulate or export-pddl may take: past it the best plan found so far (simulate: the executions done so far), else exit code 5 naming the stage that took the time (default: none)",
            default=None,
        ),
        "objective": Field(
            Choice(choices=OBJECTIVE_CHOICES),
            "what the plan minimises: weighted (the sum of action costs plus cost.M_T per second of makespan), cost (the paper's sum of action costs) or makespan (the team's time first, then the sum); omitted: makespan for a team on a shift (two robots or more, and goals.ends or a job with a service time) and for a fleet of 9 robots or more, else weighted",
            default=None,
        ),
        "max_risk": Field(
            Number(None, minimum=0.0, exclusive_minimum=True, maximum=1.0),
            "the chance constraint: the largest probability of collision a move may have (each robot's bound on touching a wall along the move, from its covariance at every step and the map's clearance; also the margin robots keep from each other); moves over it are not offered to the planner, and robots in each other's way are kept apart (keep_apart) where that keeps every move within it; omitted: 0.05 when the robots carry a range sensor (models.range_sensor), else none (the paper's model)",
            default=None,
        ),
        "keep_apart": Field(
            Flag(),
            "robots in each other's way on the team's clock (closer than their radii plus a margin for their uncertainty) are kept apart, every plan the anytime search would take priced so (an exact plan that keeping apart makes dearer is searched on so): a move held back (a wait), driven along another roadmap path around the other robot (a detour) or made through a room no goal names (a sidestep), if that raises the plan's objective by at most half (under max_risk: if every move stays within it); false: the plan as planned, its conflicts reported (the paper's model)",
            default=True,
        ),
        "clock_drift": Field(
            Number(None, minimum=0.0, maximum=1.0),
            "robots kept apart (keep_apart) allow for running late on the plan's clock: each may fall behind by this many seconds per second it drives (a planned wait absorbs it; partners of a paired move start it together), and two robots are in each other's way when they come within their separation within that much time of each other; 0: at the same planned instant only (the paper's model); omitted: 0.1 where models.range_sensor.localiser is amcl (nav2 executes the plan), else 0 (docs/models.md, \"Two robots off the plan's clock\")",
            default=None,
        ),
        "min_rooms": Field(
            Number(None, minimum=0, maximum=10**4, integer=True),
            "the goal rooms (goals.visit and the robots' own targets, not their ends) each robot visits at least, so that no robot stands idle while others work; lowered to the goal rooms' share per robot where there are fewer; a plan that cannot keep to it is ranked below every plan that does and its report names the robots short of it; the anytime search keeps it (search auto plans so; exact and the paper's encoding do not take it); 0: no minimum; omitted: 3 for a fleet of 9 robots or more (set aside by search exact or the paper's encoding), else 0",
            default=None,
        ),
        "costs": Field(
            Choice(choices=COSTS_CHOICES),
            "what an action costs the planner: carried (from the beliefs the robots carry at that point of the plan, as executed) or table (every move from a canonical start state: faster, far off where landmarks are sparse)",
            default="carried",
        ),
    }
)

SCENARIO = Section(
    fields={
        "name": Field(Name(), "scenario name (defaults to the file name)"),
        "description": Field(Text(), "free text", default=""),
        "map": Field(MAP, "the building: a polygonal map or a ROS map_server map", required=True),
        "rooms": Field(NamedList(item=ROOM, what="room", min_items=1), "rooms that robots can visit", required=True),
        "doors": Field(NamedList(item=DOOR, what="door"), "doors (optional)", default=[]),
        "landmarks": Field(NamedList(item=LANDMARK, what="landmark"), "known landmarks the robots observe", default=[]),
        "robots": Field(NamedList(item=ROBOT, what="robot", min_items=1), "the robot team", required=True),
        "models": Field(MODELS, "motion and sensing models"),
        "cost": Field(COST, "cost weights of c = M_u c_u + M_G c_G + M_Sigma c_Sigma"),
        "roadmap": Field(ROADMAP, "probabilistic roadmap"),
        "goals": Field(GOALS, "what the team must achieve", required=True),
        "planner": Field(PLANNER, "task planner options"),
    }
)

#: The keys of a ROS map_server YAML file (ROS wiki, map_server).
ROS_MAP = Section(
    fields={
        "image": Field(Text(), "image file (PGM, PNG, ...) relative to the map YAML", required=True),
        "resolution": Field(
            Number("length", minimum=0.0, exclusive_minimum=True, maximum=1.0), "metres per pixel", required=True
        ),
        "origin": Field(
            Vector(dimensions=("length", "length", "angle"), names="x, y, yaw", max_abs=MAX_COORDINATE),
            "pose of the lower-left pixel; yaw must be 0",
            required=True,
        ),
        "negate": Field(Number(None, minimum=0, maximum=1, integer=True), "1 swaps white/black", default=0),
        "occupied_thresh": Field(
            Number(None, minimum=0.0, maximum=1.0), "occupancy probability above which a cell is occupied", default=0.65
        ),
        "free_thresh": Field(
            Number(None, minimum=0.0, maximum=1.0), "occupancy probability below which a cell is free", default=0.196
        ),
        "mode": Field(Choice(choices=("trinary", "scale", "raw")), "interpretation of pixel values", default="trinary"),
    }
)
