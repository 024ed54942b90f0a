"""Checks that need the size of the map: model values that stop being meaningful beyond
it, and the resource caps estimated from it (tmpnav.scenario.limits).

The world stage runs them once the grid's extent is known (tmpnav.world.checks), before
the roadmap or the oracle start. Each returns ``(key path, message)`` pairs; a message
says what is wrong, the accepted range, and for a cap the estimate and how to lift it.
"""

from __future__ import annotations

import math

from tmpnav.choices import choose
from tmpnav.scenario.limits import (
    GOAL_ASSIGNMENTS,
    MOVE_STEPS,
    TABLE_ENTRIES,
    encoding_table,
    move_steps,
    table_entries,
)
from tmpnav.types import Scenario

#: a sensor range below this is never refused, however small the map
MIN_RANGE_CAP = 10.0

Finding = tuple[str, str]


def model_ranges(scenario: Scenario, width: float, height: float) -> list[Finding]:
    """Covariances larger than the map, control steps that jump across it, sensor
    ranges far beyond it."""
    diagonal = math.hypot(width, height)
    dt = scenario.models.dt
    found: list[Finding] = []
    for robot in scenario.robots:
        found += _covariance(robot.name, robot.covariance, diagonal)
        step = robot.speed * dt
        if step > diagonal:
            found.append(
                (
                    f"robots.{robot.name}.speed",
                    f"{robot.speed:g} m/s covers {step:.3g} m in one control step (models.dt {dt:g} s), more than "
                    f"the map's diagonal {diagonal:.3g} m; expected at most {diagonal / dt:.3g} m/s, or a shorter "
                    "models.dt",
                )
            )
    longest = max(diagonal, MIN_RANGE_CAP)
    sensors = {"landmark_sensor": scenario.models.landmark_sensor, "mutual_sensor": scenario.models.mutual_sensor}
    for key, sensor in sensors.items():
        if sensor.range > longest:
            found.append(
                (
                    f"models.{key}.range",
                    f"{sensor.range:g} m is longer than the map's diagonal {diagonal:.3g} m; expected at most "
                    f"{longest:.3g} m (a longer range sees nothing more, and costs memory in proportion)",
                )
            )
    return found


def _covariance(robot: str, cov: tuple[tuple[float, ...], ...], diagonal: float) -> list[Finding]:
    """A start belief wider than the map, or a heading spread beyond a half turn, means
    the robot's position is unknown: the EKF's linearisation says nothing there."""
    limit = diagonal**2
    position = max(cov[0][0], cov[1][1])
    path = f"robots.{robot}.covariance"
    if position > limit:
        return [
            (
                path,
                f"position variance {position:.3g} m² (standard deviation {math.sqrt(position):.3g} m) is wider than "
                f"the map (diagonal {diagonal:.3g} m); expected at most {limit:.3g} m² on x and y",
            )
        ]
    if cov[2][2] > math.pi**2:
        return [
            (
                path,
                f"heading variance {cov[2][2]:.3g} rad² (standard deviation {math.degrees(math.sqrt(cov[2][2])):.3g} "
                f"deg) is beyond a half turn; expected at most {math.pi**2:.3g} rad² (180 deg standard deviation)",
            )
        ]
    return []


def move_sizes(scenario: Scenario, width: float, height: float) -> list[Finding]:
    """Control steps of a long move for each robot, against the ``move_steps`` cap.

    When every robot is over the cap, the time step is the cause: one line for models.dt.
    """
    cap = MOVE_STEPS.value()
    dt = scenario.models.dt
    over = []
    for robot in scenario.robots:
        drive, turn = move_steps(width, height, robot.speed, robot.turn_rate, dt)
        if drive + turn > cap:
            over.append((robot, drive, turn))
    if not over:
        return []
    if len(over) == len(scenario.robots) and len(over) > 1:
        robot, drive, turn = max(over, key=lambda o: o[1] + o[2])
        return [
            (
                "models.dt",
                f"{dt:g} s makes robot {robot.name} take about "
                + MOVE_STEPS.refusal(drive + turn, "a longer dt, or faster robots"),
            )
        ]
    found = []
    for robot, drive, turn in over:
        key, value = ("speed", f"{robot.speed:g} m/s") if drive >= turn else ("turn_rate", f"{robot.turn_rate:g} rad/s")
        found.append(
            (
                f"robots.{robot.name}.{key}",
                f"{value} with models.dt {dt:g} s makes about "
                + MOVE_STEPS.refusal(drive + turn, f"a higher {key.replace('_', ' ')} or a longer models.dt"),
            )
        )
    return found


def plan_sizes(scenario: Scenario) -> list[Finding]:
    """Goal rooms x robots and the estimated cost-table entries, against their caps.

    Depends on the encoding and the goals, so the load stage checks the scenario in force,
    the command line's overrides applied (``plan --encoding``, the bench's goal draws):
    :func:`tmpnav.pipeline.load_world`.
    """
    goal_rooms = set(scenario.goals.visit)
    for _, rooms in scenario.goals.per_robot:
        goal_rooms.update(rooms)
    robots = len(scenario.robots)
    assignments = len(goal_rooms) * robots
    if assignments > GOAL_ASSIGNMENTS.value():
        return [
            (
                "goals",
                f"names {len(goal_rooms)} goal rooms for {robots} robots: "
                + GOAL_ASSIGNMENTS.refusal(assignments, "fewer goal rooms or robots"),
            )
        ]
    encoding = scenario.planner.encoding
    where, _ = encoding_table(encoding)
    if where == "all-rooms":
        counts = [len(scenario.rooms)] * robots
    else:
        counts = [len(set(scenario.goals.visit) | set(scenario.goals.for_robot(r.name))) for r in scenario.robots]
    if not _lists_the_whole_table(scenario, len(goal_rooms)):
        encoding = "single"  # the other searches cost paired moves only as they need them
    entries = table_entries(counts, encoding)
    if entries > TABLE_ENTRIES.value():
        return [
            (
                "goals",
                f"with the {encoding} encoding and the exact search needs about "
                + TABLE_ENTRIES.refusal(
                    entries, "--search anytime, fewer goal rooms or robots, or the single encoding"
                ),
            )
        ]
    return []


def _lists_the_whole_table(scenario: Scenario, rooms: int) -> bool:
    """Does the search in force cost every paired move first (:func:`tmpnav.choices.choose`)?"""
    sp = scenario.planner
    return choose(sp.encoding, sp.search, sp.costs, rooms, len(scenario.robots), sp.min_rooms).lists_whole_table
