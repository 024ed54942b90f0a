"""Precompute every action cost the task encoding needs, before the planner runs.

ENHSP cannot call back into tmpnav during its search, so the semantic attachment is
evaluated up front for every move the encoding may use. Which start belief does a table
entry use? The paper makes the pose instantiation chosen by a robot's previous move the
start of its next one, which depends on the path the search took. The table fixes one
canonical start per robot and location:

* the robot's own start location: its initial pose and initial belief;
* any other room A: the state in which the robot arrives in A when it drives there
  directly from its start (the chosen instantiation, the arrival heading, the belief at
  arrival).

A replan's table (:mod:`tmpnav.replan`) costs the moves from the robots' new starts, but
reaches the other rooms' canonical states from where the revised plan's robots started (its
:class:`Origin`): the moves between rooms are that plan's, read from the cache, instead of
a table of its own from every new start.

Pairs start from the two robots' canonical states with uncorrelated beliefs. The
re-simulation of the final plan (:mod:`tmpnav.resimulate`) carries the true beliefs,
cross-correlations included, from action to action and reports how far its cost is from
the table's.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.requests import Request, StartState
from tmpnav.types import CostTable, MotionResult, MoveKey, Roadmap, RobotSpec, Scenario, cov3, vec3
from tmpnav.world import World


@dataclass(frozen=True)
class Origin:
    """Where a robot's canonical states at rooms are reached from: its start location (a room,
    or ``<robot>-start``) and its state there. A table's robots start at their origins unless
    a replan gives them others (:func:`origins`)."""

    location: str
    state: StartState


def origins(robots: tuple[RobotSpec, ...], world: World, base: Roadmap) -> dict[str, Origin]:
    """The origins of a replan's table: the robots as the plan being revised had them at its
    start, on the roadmap ``base`` that plan was made on (a replan's roadmap keeps its nodes)."""
    return {r.name: Origin(start_location(r, world), start_state(r, base.starts[r.name])) for r in robots}


def start_locations(scenario: Scenario, world: World) -> dict[str, str]:
    """Each robot's start location: the room its start pose lies in, else ``<robot>-start``."""
    return {r.name: start_location(r, world) for r in scenario.robots}


def start_location(robot: RobotSpec, world: World) -> str:
    """The room the robot's start pose lies in, else ``<robot>-start``."""
    room = world.room_of([robot.pose.x, robot.pose.y])  # type: ignore[arg-type]
    return room if room is not None else f"{robot.name}-start"


def destinations(scenario: Scenario, mode: str) -> dict[str, tuple[str, ...]]:
    """Rooms each robot may move to: the goal rooms it may serve (those whose job allows it),
    or every room."""
    if mode == "all-rooms":
        rooms = tuple(r.name for r in scenario.rooms)
        return {r.name: rooms for r in scenario.robots}
    goals = scenario.goals
    return {
        r.name: tuple(x for x in dict.fromkeys((*goals.visit, *goals.for_robot(r.name))) if goals.may_visit(r.name, x))
        for r in scenario.robots
    }


def initial_state(scenario: Scenario, roadmap_start: int, robot: str) -> StartState:
    return start_state(scenario.robot(robot), roadmap_start)


def start_state(robot: RobotSpec, node: int) -> StartState:
    """The robot at its start pose, with its initial belief, at roadmap node ``node``."""
    pose = robot.pose
    return StartState(node, pose.theta, (pose.x, pose.y, pose.theta), robot.covariance)


def arrival_state(result: MotionResult, i: int = 0) -> StartState:
    """The state in which robot i of an action ends it: its canonical start for the next."""
    belief = result.final.marginal(i)
    return StartState(result.goal_nodes[i], result.final_headings[i], vec3(belief.mean), cov3(belief.cov))


def build_table(
    oracle: Oracle,
    world: World,
    dest_mode: str,
    pair_filter: Callable[[MoveKey, MoveKey], bool] | None = None,
    filter_key: str = "",
    pair_min_gain: float | None = None,
    origin: Mapping[str, Origin] | None = None,
) -> CostTable:
    """The cost table: single moves for every robot, and the pairs ``pair_filter`` admits
    (none without a filter). The filter comes from the task encoding: only pairs that can
    ever apply together are worth simulating; ``filter_key`` names it for the cache. With
    ``pair_min_gain``, pairs proved unable to save that fraction are left out unsimulated.
    ``origin`` (a replan's, :func:`origins`): where each robot named reaches its canonical
    states at the rooms from, instead of its start.

    The whole table is also cached as one entry, so a warm run reads one record instead
    of one per action; its key covers the oracle's context (code, world, roadmap, models,
    weights), the robots, the destinations, the pair filter and the origins.
    """
    scenario = oracle.ctx.scenario
    starts = start_locations(scenario, world)
    dests = destinations(scenario, dest_mode)
    origin = dict(origin or {})
    named = f"{filter_key}|{pair_min_gain!r}|{sorted(origin.items())!r}"
    key = table_key(oracle, starts, dests, pair_filter is not None, named)
    found = oracle.cache.get_many([key]).get(key)
    if found is not None:
        oracle.stats.table_hit = True
        return _table_from_json(found).with_service(scenario.goals)
    table = _compute_table(oracle, starts, dests, pair_filter, pair_min_gain, origin)
    oracle.cache.put_many({key: _table_to_json(table)})  # the motions' own times: service added on reading
    return table.with_service(scenario.goals)


def table_key(
    oracle: Oracle, starts: dict[str, str], dests: dict[str, tuple[str, ...]], pairs: bool, filter_key: str
) -> str:
    specs = [(r.name, r.pose, r.covariance, r.radius, r.speed, r.turn_rate) for r in oracle.ctx.scenario.robots]
    parts = ("table/2", oracle.context, specs, sorted(starts.items()), sorted(dests.items()), pairs, filter_key)
    return hashlib.sha256(repr(parts).encode()).hexdigest()


def _compute_table(
    oracle: Oracle,
    starts: dict[str, str],
    dests: dict[str, tuple[str, ...]],
    pair_filter: Callable[[MoveKey, MoveKey], bool] | None,
    pair_min_gain: float | None = None,
    origin: dict[str, Origin] | None = None,
) -> CostTable:
    scenario, roadmap = oracle.ctx.scenario, oracle.ctx.roadmap
    origin = origin or {}
    dt = scenario.models.dt
    duration: dict[MoveKey, float] = {}
    canonical: dict[tuple[str, str], StartState] = {}
    for r in scenario.robots:
        canonical[(r.name, starts[r.name])] = initial_state(scenario, roadmap.starts[r.name], r.name)

    # wave 1: from each robot's start to every destination; fixes the canonical starts (a
    # robot with an origin: from there, the origin's room its own state)
    first = [(r, starts[r], d) for r in dests for d in dests[r] if d != starts[r]]
    reached = [(r, d) for r in dests if r in origin for d in dests[r] if d not in (starts[r], origin[r].location)]
    requests = [_single(canonical, k) for k in first]
    requests += [Request((r,), (origin[r].state,), (d,)) for r, d in reached]
    results = oracle.evaluate(requests)
    singles: dict[MoveKey, float] = {}
    for key, res in zip(first, results[: len(first)], strict=True):
        if res is not None:
            singles[key] = res.cost
            duration[key] = res.steps[0] * dt
            if key[0] not in origin:
                canonical[(key[0], key[2])] = arrival_state(res)
    for (name, d), res in zip(reached, results[len(first) :], strict=True):
        if res is not None:
            canonical[(name, d)] = arrival_state(res)
    for name, o in origin.items():
        if name in dests and o.location in dests[name] and o.location != starts[name]:
            canonical[(name, o.location)] = o.state
    # wave 2: between destinations, from their canonical starts
    second = [
        (r, a, b)
        for r in dests
        for a in dests[r]
        for b in dests[r]
        if a != b and a != starts[r] and (r, a) in canonical
    ]
    for key, res in zip(second, oracle.evaluate([_single(canonical, k) for k in second]), strict=True):
        if res is not None:
            singles[key] = res.cost
            duration[key] = res.steps[0] * dt

    pairs: dict[tuple[MoveKey, MoveKey], float] = {}
    pair_duration: dict[tuple[MoveKey, MoveKey], tuple[float, float]] = {}
    if pair_filter is not None:
        names = [r.name for r in scenario.robots]
        wanted = [
            (m1, m2)
            for i, r1 in enumerate(names)
            for r2 in names[i + 1 :]
            for m1 in singles
            if m1[0] == r1
            for m2 in singles
            if m2[0] == r2 and pair_filter(m1, m2)
        ]
        requests = [
            Request(
                (m1[0], m2[0]),
                (canonical[(m1[0], m1[1])], canonical[(m2[0], m2[1])]),
                (m1[2], m2[2]),
                min_gain=pair_min_gain,
            )
            for m1, m2 in wanted
        ]
        for pair, res in zip(wanted, oracle.evaluate(requests), strict=True):
            if res is not None and not res.pruned:
                pairs[pair] = res.cost
                pair_duration[pair] = (res.steps[0] * dt, res.steps[1] * dt)

    return CostTable(
        robots=tuple(r.name for r in scenario.robots),
        rooms=tuple(room.name for room in scenario.rooms),
        locations=tuple(dict.fromkeys([*(room.name for room in scenario.rooms), *starts.values()])),
        start_location=starts,
        single=singles,
        pair=pairs,
        duration=duration,
        pair_duration=pair_duration,
    )


def _table_to_json(table: CostTable) -> dict:
    return {
        "robots": list(table.robots),
        "rooms": list(table.rooms),
        "locations": list(table.locations),
        "start_location": table.start_location,
        "single": [[*k, v, table.duration[k]] for k, v in table.single.items()],
        "pair": [[*m1, *m2, v, *table.pair_duration[(m1, m2)]] for (m1, m2), v in table.pair.items()],
    }


def _table_from_json(d: dict) -> CostTable:
    return CostTable(
        robots=tuple(d["robots"]),
        rooms=tuple(d["rooms"]),
        locations=tuple(d["locations"]),
        start_location=dict(d["start_location"]),
        single={(r, o, t): float(v) for r, o, t, v, _ in d["single"]},
        pair={((a, b, c), (e, f, g)): float(v) for a, b, c, e, f, g, v, _, _ in d["pair"]},
        duration={(r, o, t): float(s) for r, o, t, _, s in d["single"]},
        pair_duration={((a, b, c), (e, f, g)): (float(s1), float(s2)) for a, b, c, e, f, g, _, s1, s2 in d["pair"]},
    )


def _single(canonical: dict[tuple[str, str], StartState], move: MoveKey) -> Request:
    robot, origin, target = move
    return Request((robot,), (canonical[(robot, origin)],), (target,))
