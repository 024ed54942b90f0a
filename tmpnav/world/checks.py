"""Geometric checks of a scenario against its world, each problem naming its key path.

Run by ``tmpnav validate`` and before every plan: things outside the map, robots starting
in collision or on top of each other, rooms that are degenerate, self-intersecting, too
cramped for a robot, or unreachable; model values that stop being meaningful at the
map's size, and the control steps of a move estimated from it (tmpnav.scenario.extent).
The caps on the plan's size, which depend on the command line's overrides, are checked
with them by the load stage (:func:`tmpnav.pipeline.load_world`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tmpnav.errors import Problem
from tmpnav.scenario import display_path
from tmpnav.scenario.extent import model_ranges, move_sizes
from tmpnav.types import RobotSpec, Scenario
from tmpnav.world.build import World
from tmpnav.world.geometry import polygon_area


def check(scenario: Scenario, world: World) -> list[Problem]:
    """Every geometric problem of the scenario in this world (empty when all is well)."""
    file = display_path(scenario.source)

    def problem(path: str, message: str) -> Problem:
        return Problem(file, path, message, scenario.line_of(path))

    xmin, ymin, xmax, ymax = world.grid.extent
    extent = f"[{xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}]"

    def inside(p: tuple[float, float]) -> bool:
        return xmin <= p[0] <= xmax and ymin <= p[1] <= ymax

    width, height = xmax - xmin, ymax - ymin
    problems = [
        problem(path, message)
        for path, message in model_ranges(scenario, width, height) + move_sizes(scenario, width, height)
    ]
    problems += _room_outlines(scenario, world, inside, extent, problem)
    for lm in scenario.landmarks:
        if not inside(lm.position):
            problems.append(
                problem(
                    f"landmarks.{lm.name}.position",
                    f"{list(lm.position)} is outside the map {extent}; expected a point inside the map",
                )
            )
    for door in scenario.doors:
        for p in door.segment:
            if not inside(p):
                problems.append(
                    problem(
                        f"doors.{door.name}.segment",
                        f"point {list(p)} is outside the map {extent}; expected a door inside the map",
                    )
                )
                break
    start_problems, starts_ok = _starts(scenario, world, inside, extent, problem)
    problems += start_problems
    problems += _range_sensor(scenario, world, problem)
    problems += _overlapping(scenario, problem)
    if any(p.path.startswith("rooms.") for p in problems):
        return problems
    problems += _reachability(scenario, world, starts_ok, problem)
    problems += _jobs(scenario, world, problem)
    return problems


def _jobs(scenario: Scenario, world: World, problem: Callable[[str, str], Problem]) -> list[Problem]:
    """A job's goal pose lies in its room where the robots that may do it fit; a job's room is
    done by a robot that enters it, so no robot starts inside (it would count as having done
    it at time 0: a visit's rule is that where a robot starts is visited)."""
    out = _stations_apart(scenario, problem)
    place = {r.name: r.place for r in scenario.stations}
    for job in scenario.goals.jobs:
        if job.pose is not None:
            x, y, _ = job.pose
            robots = [r for r in scenario.robots if not job.robots or r.name in job.robots]
            radius = max((r.radius for r in robots), default=0.0)
            room = place.get(job.room) or job.room
            if world.room_of([x, y]) != room:  # type: ignore[arg-type]
                whose = "the job's room" if room == job.room else f"the station's place {room!r}"
                out.append(
                    problem(
                        f"goals.jobs.{job.room}.pose",
                        f"[{x:g}, {y:g}] is not inside room {room!r}; expected a goal pose inside {whose}",
                    )
                )
            elif not world.is_free(np.array([[x, y]]), radius)[0]:
                out.append(
                    problem(
                        f"goals.jobs.{job.room}.pose",
                        f"a robot of radius {radius:g} m at [{x:g}, {y:g}] touches a wall or an obstacle; "
                        "expected a goal pose with room for the robot",
                    )
                )
        for robot in scenario.robots:
            if scenario.goals.end_of(robot.name) == job.room or job.room in place:
                # a robot that starts at its end comes back to it: its job is done then; a robot in
                # a station's place is not at the station until it drives there
                continue
            if world.room_of([robot.pose.x, robot.pose.y]) == job.room:  # type: ignore[arg-type]
                out.append(
                    problem(
                        f"goals.jobs.{job.room}",
                        f"robot {robot.name} starts in {job.room!r}, so the job would count as done at 0 s; "
                        "expected a job only at a room no robot starts in (start the robot outside it, "
                        "or drop the job)",
                    )
                )
    return out


def _stations_apart(scenario: Scenario, problem: Callable[[str, str], Problem]) -> list[Problem]:
    """Two stations at one point: the roadmap holds one node per station pose, and a robot at
    one would count as at both."""
    out: list[Problem] = []
    seen: dict[tuple[float, float], str] = {}
    for job in scenario.goals.jobs:
        if job.pose is None or job.room not in {r.name for r in scenario.stations}:
            continue
        xy = (round(job.pose[0], 6), round(job.pose[1], 6))
        if xy in seen:
            out.append(
                problem(
                    f"goals.jobs.{job.room}.pose",
                    f"[{xy[0]:g}, {xy[1]:g}] is station {seen[xy]!r}'s pose too; expected one station per pose",
                )
            )
        seen.setdefault(xy, job.room)
    return out


def _range_sensor(scenario: Scenario, world: World, problem: Callable[[str, str], Problem]) -> list[Problem]:
    """A range sensor that reaches no wall from anywhere the robots must be (their starts, the
    rooms): it would never return a beam, and the map has no walls for it to see."""
    sensor = scenario.models.range_sensor
    if sensor is None:
        return []
    points = [np.array([[r.pose.x, r.pose.y] for r in scenario.robots], dtype=float).reshape(-1, 2)]
    points += [
        np.asarray(world.free_cells_in_room(room.name, 0.0), dtype=float).reshape(-1, 2) for room in scenario.places
    ]
    xy = np.concatenate(points)  # (a scenario without robots, already refused, still gets this check)
    i, j, inside = world.grid.cells(xy)
    if not inside.any():
        return []
    nearest = float(world.clearance[i[inside], j[inside]].min())
    if nearest <= sensor.range:
        return []
    return [
        problem(
            "models.range_sensor.range",
            f"{sensor.range:g} m reaches no wall from any robot's start or room (the nearest wall is {nearest:.3g} m "
            "away); expected a range that reaches the map's walls, or no range_sensor (landmarks and partners only)",
        )
    ]


def _room_outlines(
    scenario: Scenario,
    world: World,
    inside: Callable[[tuple[float, float]], bool],
    extent: str,
    problem: Callable[[str, str], Problem],
) -> list[Problem]:
    """Room polygons outside the map, crossing themselves, or of (almost) zero area."""
    problems = []
    for room in scenario.places:  # a station has its place's outline
        path = f"rooms.{room.name}.polygon"
        outside = [p for p in room.polygon if not inside(p)]
        crossing = _self_intersection(np.array(room.polygon, dtype=float))
        if outside:
            problems.append(
                problem(path, f"point {list(outside[0])} is outside the map {extent}; expected a room inside the map")
            )
        elif crossing is not None:
            i, j = crossing
            problems.append(
                problem(
                    path,
                    f"edge {i} (point {i} to {(i + 1) % len(room.polygon)}) crosses edge {j} (point {j} to "
                    f"{(j + 1) % len(room.polygon)}); expected a simple polygon, an outline that does not cross itself",
                )
            )
        elif abs(polygon_area(np.array(room.polygon))) < world.grid.resolution**2:
            problems.append(problem(path, "has (almost) zero area; expected a polygon enclosing a region"))
    return problems


def _starts(
    scenario: Scenario,
    world: World,
    inside: Callable[[tuple[float, float]], bool],
    extent: str,
    problem: Callable[[str, str], Problem],
) -> tuple[list[Problem], list[RobotSpec]]:
    """Start poses outside the map or in collision, and the robots whose start is fine."""
    problems = []
    starts_ok = []
    for robot in scenario.robots:
        path = f"robots.{robot.name}.pose"
        xy = np.array([robot.pose.x, robot.pose.y])
        if not inside((robot.pose.x, robot.pose.y)):
            problems.append(
                problem(
                    path, f"{[robot.pose.x, robot.pose.y]} is outside the map {extent}; expected a start inside the map"
                )
            )
        elif not world.is_free(xy[None, :], robot.radius)[0]:
            problems.append(
                problem(
                    path,
                    f"{[robot.pose.x, robot.pose.y]} is in collision (a disc of radius {robot.radius:g} m overlaps "
                    "a wall or obstacle); expected a free start",
                )
            )
        else:
            starts_ok.append(robot)
    return problems, starts_ok


def _overlapping(scenario: Scenario, problem: Callable[[str, str], Problem]) -> list[Problem]:
    """Robots whose discs overlap at the start: two robots cannot stand on one spot."""
    problems = []
    robots = scenario.robots
    for k, robot in enumerate(robots):
        for other in robots[:k]:
            distance = float(np.hypot(robot.pose.x - other.pose.x, robot.pose.y - other.pose.y))
            if distance < robot.radius + other.radius:
                problems.append(
                    problem(
                        f"robots.{robot.name}.pose",
                        f"{[robot.pose.x, robot.pose.y]} is {distance:.3g} m from robot {other.name}'s start, closer "
                        f"than their radii {robot.radius:g} + {other.radius:g} m; expected robots that do not overlap",
                    )
                )
                break
    return problems


def _self_intersection(polygon: np.ndarray) -> tuple[int, int] | None:
    """The first pair (i, j), i < j, of non-adjacent edges of a closed polygon (k, 2)
    that cross each other, or None. Edge i joins point i to point i + 1 (the last edge
    closes the outline).

    Room outlines are short (the format allows at most ``MAX_ROOM_POINTS``), so all
    pairs are tested at once with the orientation test.
    """
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    k = len(a)
    if k < 4:
        return None

    def orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
        """Sign of the turn p -> q -> r: 1 counter-clockwise, -1 clockwise, 0 collinear."""
        pq, pr = q - p, r - p
        return np.sign(pq[..., 0] * pr[..., 1] - pq[..., 1] * pr[..., 0])

    A, B = a[:, None, :], b[:, None, :]
    C, D = a[None, :, :], b[None, :, :]
    o1, o2, o3, o4 = orient(A, B, C), orient(A, B, D), orient(C, D, A), orient(C, D, B)
    proper = (o1 * o2 < 0) & (o3 * o4 < 0)
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    adjacent = (np.abs(i - j) <= 1) | (np.abs(i - j) == k - 1)
    hits = np.argwhere(proper & ~adjacent & (i < j))
    if hits.size == 0:
        return None
    first = hits[0]
    return int(first[0]), int(first[1])


def _reachability(scenario: Scenario, world: World, robots: list, problem) -> list[Problem]:
    """Rooms no robot can reach.

    A room some robot reaches but not the robot that goals.robots sends there is left to
    the planner, which proves the task unsolvable (exit code 6).

    Free space for a robot of radius rho is the set of cells with clearance >= rho + r;
    its 8-connected components are what a robot can drive through.
    """
    problems: list[Problem] = []
    places = scenario.places  # a station's pose is checked with its job, and reached as the roadmap is built
    reach: dict[str, set[str]] = {room.name: set() for room in places}
    cramped: dict[str, list[str]] = {room.name: [] for room in places}
    by_radius: dict[float, list] = {}
    for robot in robots:
        by_radius.setdefault(robot.radius, []).append(robot)
    for radius, group in by_radius.items():
        labels = world.free_components(radius)
        for room in places:
            cells = world.free_cells_in_room(room.name, radius)
            if cells.shape[0] == 0:
                cramped[room.name] += [r.name for r in group]
                continue
            i, j, _ = world.grid.cells(cells)
            room_labels = set(np.unique(labels[i, j]).tolist()) - {0}
            for robot in group:
                si, sj, _ = world.grid.cells(np.array([[robot.pose.x, robot.pose.y]]))
                if int(labels[si[0], sj[0]]) in room_labels:
                    reach[room.name].add(robot.name)
    if not robots:
        return problems
    for room in places:
        if reach[room.name]:
            continue
        if len(cramped[room.name]) == len(robots):
            problems.append(
                problem(
                    f"rooms.{room.name}",
                    "has no free space large enough for any robot; expected a room a robot fits in",
                )
            )
        else:
            problems.append(
                problem(
                    f"rooms.{room.name}",
                    "no robot can reach this room through free space (closed door or too narrow passage?); "
                    "expected a room connected to some robot's start",
                )
            )
    return problems


#: a start whose footprint is nearer the map's walls than this many standard deviations of the
#: robot's initial position gets a warning (:func:`start_advice`): a disc drawn from that belief
#: touches them about one time in six. At 2 the generated families' starts (0.15 m from the
#: walls with a std of 0.1 m) and depot-jobs' docks would all be warned of
START_SIGMAS = 1.0


def start_advice(scenario: Scenario, world: World) -> list[str]:
    """One line per robot whose footprint starts nearer the map's walls than :data:`START_SIGMAS`
    standard deviation of its initial position (its covariance's widest axis): every move
    from there has that little margin under its collision bound. office-ros' r1 and r2 stood
    5-7 cm from clutter in the corridor, and under the AMCL model any move of r2 had a bound
    of 0.21: the plan left it idle in r1's way."""
    file = display_path(scenario.source)
    out = []
    for robot in scenario.robots:
        i, j, inside = world.grid.cells(np.array([[robot.pose.x, robot.pose.y]]))
        if not inside[0]:
            continue  # an error of its own (check)
        margin = float(world.clearance[i[0], j[0]]) - robot.radius
        std = float(np.sqrt(np.linalg.eigvalsh(np.asarray(robot.cov, dtype=float)[:2, :2]).max()))
        need = START_SIGMAS * std
        if margin < need:
            path = f"robots.{robot.name}.pose"
            line = scenario.line_of(path)
            out.append(
                f"{file}{f':{line}' if line else ''}: {path}: {robot.name} starts {margin:.2f} m from the map's "
                f"walls, less than {START_SIGMAS:g} std of its initial position ({need:.2f} m): its moves from "
                f"there are priced with that margin; expected a start at least {need - margin:.2f} m further clear"
            )
    return out
