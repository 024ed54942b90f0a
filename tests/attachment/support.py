"""Small carried-belief problems on the shipped worlds, and an independent enumeration of their plans."""

from __future__ import annotations

import math
from dataclasses import replace

from tmpnav.attachment.canonical import CanonicalCosts
from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.team import Team
from tmpnav.oracle.executors import OracleContext
from tmpnav.oracle.oracle import Oracle
from tmpnav.pipeline import load_world
from tmpnav.roadmap import build_roadmap
from tmpnav.shipped import configs_dir
from tmpnav.task.encodings import ENCODINGS, scaled
from tmpnav.task.plans import Plan, PlanError, Rules, State
from tmpnav.types import Goals, Scenario
from tmpnav.world import World


def carried_problem(config: str, rooms: tuple[str, ...], robots: int) -> tuple[Scenario, World, CarriedCosts]:
    """A shipped world with the first ``robots`` robots that must visit ``rooms``, costed with
    carried beliefs (no disk cache, serial oracle)."""
    scenario, world = load_world(configs_dir() / config)
    scenario = replace(scenario, robots=scenario.robots[:robots], goals=Goals(rooms, ()))
    roadmap = build_roadmap(world, scenario.robots, scenario.roadmap)
    oracle = Oracle(OracleContext(scenario, world, roadmap))
    canonical = CanonicalCosts(oracle, world, scenario.planner.pair_min_gain)
    return scenario, world, CarriedCosts(oracle, canonical)


def cheapest_plan_by_enumeration(carried: CarriedCosts, goals: Goals, min_gain: float) -> tuple[float, Plan, int]:
    """Every plan of single moves and paired moves that save ``min_gain`` over the same two
    moves made alone from the same beliefs, run step by step with carried beliefs: the
    cheapest one, its cost, and how many complete plans there were."""
    rules = Rules(carried.start_location, goals)
    keep = ENCODINGS["mixed"].pair_filter(goals, carried.start_location)
    assert keep is not None
    rooms = tuple(dict.fromkeys(goals.all_rooms))
    best: list[tuple[float, Plan]] = [(math.inf, ())]
    count = [0]

    def visit(team: Team, state: State, cost: float, prefix: Plan) -> None:
        if rules.done(state):
            count[0] += 1
            if cost < best[0][0]:
                best[0] = (cost, prefix)
            return
        singles = [
            ((r, state.at[r], x),)
            for r in carried.robots
            for x in rooms
            if x != state.at[r] and rules.may_enter(state, r, x)
        ]
        alone = {}
        for step in singles:
            outcome = carried.advance(team, step)
            alone[step[0]] = outcome.cost
            visit(outcome.team, rules.apply(state, step), cost + outcome.cost, (*prefix, step))
        for i, a in enumerate(singles):
            for b in singles[i + 1 :]:
                pair = (a[0], b[0])
                if a[0][0] == b[0][0] or not keep(*pair):
                    continue
                try:
                    after = rules.apply(state, pair)
                except PlanError:
                    continue
                outcome = carried.advance(team, pair)
                s = scaled(alone[a[0]]) + scaled(alone[b[0]])
                if scaled(outcome.cost) < s and scaled(outcome.cost) <= (1 - min_gain) * s:
                    visit(outcome.team, after, cost + outcome.cost, (*prefix, pair))

    visit(carried.start, rules.start(), 0.0, ())
    return best[0][0], best[0][1], count[0]
