"""Small carried-belief problems on the shipped worlds, and an independent enumeration of their plans."""

from __future__ import annotations

from dataclasses import replace

from tmpnav.attachment.canonical import CanonicalCosts
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.oracle.executors import OracleContext
from tmpnav.oracle.oracle import Oracle
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap
from tmpnav.shipped import configs_dir
from tmpnav.task.encodings import ENCODINGS
from tmpnav.task.plans import Plan, PlanError, Rules, State, Step
from tmpnav.types import Goals, ScanModelKind, Scenario
from tmpnav.world import World


def carried_problem(
    config: str, rooms: tuple[str, ...], robots: int, controller: str | None = None, beams: bool = False
) -> tuple[Scenario, World, CarriedCosts]:
    """A shipped world with the first ``robots`` robots that must visit ``rooms``, costed with
    carried beliefs (no disk cache, serial oracle); driven by ``controller`` (models.controller)
    when given; ``beams``: its range sensor's localiser is the sensor's bound (every beam
    independent, the landmarks and partners fused too) instead of the shipped nav2 AMCL."""
    scenario, world = load_world(configs_dir() / config)
    scenario = replace(scenario, robots=scenario.robots[:robots], goals=Goals(rooms, ()))
    if controller is not None:
        scenario = replace(scenario, models=replace(scenario.models, controller=controller))
    sensor = scenario.models.range_sensor
    if beams and sensor is not None:
        sensor = replace(sensor, localiser=replace(sensor.localiser, kind=ScanModelKind.BEAMS))
        scenario = replace(scenario, models=replace(scenario.models, range_sensor=sensor))
    roadmap = build_roadmap(world, scenario.robots, scenario.roadmap)
    oracle = Oracle(OracleContext(scenario, world, roadmap))
    canonical = CanonicalCosts(oracle, world, scenario.planner.pair_min_gain)
    return scenario, world, CarriedCosts(oracle, canonical)


def every_plan(carried: CarriedCosts, goals: Goals) -> list[Plan]:
    """Every plan of single moves and of paired moves the encoding's filter allows (every
    order of the steps of different robots too: several orders are one schedule), by the
    entry rules alone, knowing nothing of the clock or of the unfolded search."""
    rules = Rules(carried.start_location, goals)
    keep = ENCODINGS["mixed"].pair_filter(goals, carried.start_location)
    assert keep is not None
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    plans: list[Plan] = []

    def visit(state: State, prefix: Plan) -> None:
        if rules.done(state):
            plans.append(prefix)
            return
        singles = [
            ((r, state.at[r], x),)
            for r in carried.robots
            for x in rooms
            if x != state.at[r] and rules.may_enter(state, r, x)
        ]
        steps: list[Step] = list(singles)
        steps += [
            (a[0], b[0])
            for i, a in enumerate(singles)
            for b in singles[i + 1 :]
            if a[0][0] != b[0][0] and keep(a[0], b[0])
        ]
        for step in steps:
            try:
                after = rules.apply(state, step)
            except PlanError:
                continue
            visit(after, (*prefix, step))

    visit(rules.start(), ())
    return plans


def objective(carried: CarriedCosts, plan: Plan, span_weight: float) -> float:
    """The plan's objective as the team's clock runs it."""
    return carried.plan_cost(plan).value(span_weight)
