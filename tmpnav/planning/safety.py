"""Is a plan safe to hand to the robots? Its robots in each other's way, and what would help a move
over the chance constraint.

:func:`conflicts_left` runs the independent checker (tmpnav.belief.conflicts) over a plan's
re-simulated trajectories; :func:`riskiest_point` finds where a move's collision bound is made
(the control step whose own bound is largest) and :func:`what_would_help` turns it into advice
for the one line of an error: the door or room it is in, how uncertain the robot is there
against the room the walls leave it, and what would change that.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tmpnav.attachment.drift import clock_drift, trajectory_windows
from tmpnav.belief.conflicts import DEFAULT_DELTA, Conflict, find_conflicts, seen_std
from tmpnav.belief.risk import local_errors, position_std, step_bound, step_lengths
from tmpnav.belief.sequences import hazard, local_walls
from tmpnav.numbers import length, probability
from tmpnav.results import PlanReport

#: a door within this of the riskiest point (m) is named as the place
DOOR_NEAR = 1.5


def conflicts_left(report: PlanReport, drift: float | None = None) -> list[Conflict]:
    """Robots closer than their radii plus the margin of their uncertainty, by the independent
    checker over the re-simulated trajectories (the margin's threshold is planner.max_risk, else
    0.05), within the pairs' time windows of ``drift`` (tmpnav.attachment.drift; the
    scenario's by default, 0: at the same planned instant only)."""
    radii = {r.name: r.radius for r in report.scenario.robots}
    delta = report.scenario.planner.max_risk or DEFAULT_DELTA
    rate = clock_drift(report.scenario) if drift is None else drift
    windows = trajectory_windows(report.trajectories, report.schedule, rate)
    return find_conflicts(report.trajectories, radii, delta, windows, seen_std(report.scenario.models))


@dataclass(frozen=True)
class RiskyPoint:
    """Where a move's collision bound is made: the robot's mean there (m), its position std (m,
    along its most uncertain direction), the free margin its footprint has (m), that step's own
    bound, the door near it or the room it is in."""

    robot: str
    origin: str
    target: str
    bound: float  # the move's
    xy: tuple[float, float]
    std: float
    margin: float
    step_bound: float
    door: str | None
    room: str | None
    failures: float = 0.0  # the part of the move's bound that is the localiser's failures along its path


def riskiest_point(report: PlanReport) -> RiskyPoint | None:
    """The riskiest move's riskiest control step (None for a plan without moves)."""
    moves = [(p, m, a.index - 1) for a in report.actions for p, m in zip(a.risk, a.moves, strict=False)]
    if not moves:
        return None
    bound, (robot, origin, target), index = max(moves, key=lambda x: x[0])
    timed = next((t for t in report.schedule.moves if t.step == index and t.robot == robot), None)
    steps = report.trajectories.get(robot, [])
    window = [s for s in steps if timed is None or timed.start - 1e-9 <= s.t <= timed.end + 1e-9] or steps
    if not window:
        return None
    means = np.array([s.mean for s in window], dtype=float)
    covs = np.array([s.cov for s in window], dtype=float)[:, :2, :2]
    var, rho = local_walls(report.scenario.models)
    if var > 0.0:  # the bound prices the error relative to the walls the robot sees
        covs = local_errors(len(window), var, rho)[0]
    spec = report.scenario.robot(robot)
    world = report.world
    reach = world.reach(spec.radius).at(means[:, :2])
    per_step = step_bound(covs, reach)
    k = int(np.argmax(per_step))
    xy = (float(means[k, 0]), float(means[k, 1]))
    margin = float(world.margins(means[k : k + 1, :2], spec.radius)[0])
    return RiskyPoint(
        robot,
        origin,
        target,
        float(bound),
        xy,
        float(position_std(covs[k : k + 1])[0]),
        margin,
        float(per_step[k]),
        _door_near(report, np.array(xy)),
        world.room_of(np.array(xy)),
        hazard(report.scenario.models) * float(step_lengths(means).sum()),
    )


def _door_near(report: PlanReport, xy: NDArray[np.float64]) -> str | None:
    best, name = DOOR_NEAR, None
    for door in report.scenario.doors:
        a, b = (np.array(p, dtype=float) for p in door.segment)
        t = np.clip(np.dot(xy - a, b - a) / max(float(np.dot(b - a, b - a)), 1e-12), 0.0, 1.0)
        d = float(np.hypot(*(xy - (a + t * (b - a)))))
        if d < best:
            best, name = d, door.name
    return name


def what_would_help(report: PlanReport, point: RiskyPoint) -> str:
    """The riskiest point in words, and what would bring its bound down there."""
    x, y = point.xy
    where = f"({x:.1f}, {y:.1f})" + (f", by {point.door}" if point.door else f", in {point.room}" if point.room else "")
    said = (
        f"{point.robot}'s move {point.origin} -> {point.target} is at {probability(min(1.0, point.bound))}, made at "
        f"{where}, where its position std is {length(point.std)} and its footprint {length(max(point.margin, 0.0))} "
        "from the walls"
    )
    helps = []
    sensor = report.scenario.models.range_sensor
    if point.std > max(point.margin, 0.0) / 3.0:  # too uncertain for the room there
        if sensor is not None and sensor.localiser.local_walls:  # the error relative to the walls it sees
            helps.append("a smaller models.range_sensor.localiser.local_std (finer costmaps, tighter tracking)")
        elif sensor is None or sensor.localiser.fuses_others:  # AMCL alone sees neither
            helps.append(f"a landmark or a partner near ({x:.1f}, {y:.1f})")
        else:
            helps.append("a localiser that takes more from the lidar (models.range_sensor.localiser)")
        if sensor is None:
            helps.append("a range sensor (models.range_sensor)")
        helps.append("less motion noise (models.motion_noise)")
    if point.margin < 0.3:  # the walls leave little room
        helps.append(f"a wider {point.door}" if point.door else "more room there (a path clear of the walls)")
    if point.failures >= 0.5 * point.bound:  # most of it is the localiser's failures along the path
        said += f"; {probability(point.failures)} of it the localiser's failures along its path"
        helps.append(
            "shorter moves, or a localiser that fails less often (models.range_sensor.localiser.failure_rate, "
            "counted by tmpnav calibrate)"
        )
    return f"{said}; what would help there: {', '.join(helps)}"


def speck_hint(report: PlanReport) -> str:
    """What the error of a plan over the chance constraint adds where the map's specks are kept as
    obstacles (tmpnav.world.rosmap.specks): on a map made by SLAM most are noise, and paths must
    pass them close enough for a robot's local error to reach them; "" where there are none."""
    from tmpnav.types import RosMap
    from tmpnav.world.rosmap import SPECK_WIDTH, speck_count

    spec = report.scenario.map
    if not isinstance(spec, RosMap) or spec.despeckle > 0:
        return ""
    n = speck_count(report.world.grid.occupied, SPECK_WIDTH, report.world.grid.resolution)
    if not n:
        return ""
    return (
        f"; the map has {n} speck{'s' * (n > 1)} of occupied cells up to {SPECK_WIDTH:g} m wide alone in free "
        f"space, obstacles the paths pass: if they are map noise, map.despeckle: {SPECK_WIDTH:g} clears them"
    )
