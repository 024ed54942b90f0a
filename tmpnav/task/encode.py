"""Stage 6a: a cost table and goals -> a unified-planning problem, in one of three encodings.

``paper``  the paper's pair action: every action moves two robots (pddl/paper.pddl);
``single`` one action per robot, single-robot costs (pddl/single.pddl);
``mixed``  single moves plus grounded cooperative pair moves (pddl/mixed.pddl).

In ``single`` and ``mixed`` a robot only enters a room nobody has visited, or one of its
own target rooms (goals.robots) it has not visited itself. So every room of goals.visit
that is nobody's target and nobody's start is entered exactly once in every plan, and the
search can be informed by cost reshaping: with h_x no more than the cheapest way into
room x (a pair move counts half for each of its rooms), every move into x costs c - h_x.
All plans then cost sum(h_x) less, the same for all, so the optimal plans are unchanged;
but the planner's uniform-cost search now behaves as A* with the admissible heuristic
"cheapest way into each room still to visit" (potential-based reshaping). The reported
plan cost is always the table's own.

Costs are written as integers in thousandths (``COST_SCALE``): unified-planning warns on
every float constant it cannot represent exactly, and ENHSP reads integers as exactly.

The domains say, like the paper, ``(increase (act-cost) <cost>)``. unified-planning
classifies an increase by a (static) function as general numeric planning, which
``enhsp-opt`` declares it cannot do; :func:`act_cost_to_action_costs` therefore turns
those increases into action costs (``MinimizeActionCosts``), the standard PDDL
``:action-costs`` form that ENHSP and Fast Downward read. The plans are the same.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.resources import files
from typing import Any

from tmpnav.types import CostTable, Goals, MoveKey

COST_SCALE = 1000


@dataclass(frozen=True)
class Encoding:
    """How an encoding uses the cost table; the pipeline asks the oracle for exactly this."""

    name: str
    domain_file: str
    pairs: bool  # whether joint costs of two robots moving together are needed
    destinations: str  # goals | all-rooms: where a robot may move to
    reshape: bool  # whether every reshaped room is entered exactly once (see above)
    doc: str


ENCODINGS: dict[str, Encoding] = {
    "paper": Encoding(
        "paper",
        "paper.pddl",
        True,
        "all-rooms",
        False,
        "the paper's goto_room for a pair of robots, both move in every action",
    ),
    "single": Encoding(
        "single", "single.pddl", False, "goals", True, "one goto_room per robot, no mutual-observation credit"
    ),
    "mixed": Encoding(
        "mixed",
        "mixed.pddl",
        True,
        "goals",
        True,
        "single moves plus paired moves where mutual observations lower the joint cost",
    ),
}


@dataclass
class EncodedProblem:
    """The UP problem and what decoding its plan needs."""

    problem: Any  # unified_planning.model.Problem
    encoding: Encoding
    pair_actions: dict[str, tuple[MoveKey, MoveKey]] = field(default_factory=dict)
    potentials: dict[str, int] = field(default_factory=dict)  # room -> h_x (scaled)

    @property
    def n_actions(self) -> int:
        return len(self.problem.actions)


def pair_filter(encoding: str, goals: Goals, start_location: dict[str, str]) -> Callable[[MoveKey, MoveKey], bool]:
    """Which pairs of moves can ever be applied together in ``encoding``.

    The oracle computes joint costs only for these. In ``mixed`` a room is entered only
    when unvisited or as its robot's own target, so two robots are never in the same room
    (unless they start there or it is a target) and never both enter one room.
    """
    if encoding == "paper":
        return lambda m1, m2: m1[0] != m2[0]
    targets = {(r, room) for r, rooms in goals.per_robot for room in rooms}
    starts = set(start_location.values())

    def enter_occupied(robot: str, room: str) -> bool:
        return (robot, room) in targets

    def possible(m1: MoveKey, m2: MoveKey) -> bool:
        (r1, o1, t1), (r2, o2, t2) = m1, m2
        if r1 == r2:
            return False
        if t1 == t2 and not (enter_occupied(r1, t1) or enter_occupied(r2, t2)):
            return False
        if o1 == o2 and o1 not in starts and not (enter_occupied(r1, o1) or enter_occupied(r2, o2)):
            return False
        if t1 == o2 and not enter_occupied(r1, t1):
            return False
        return not (t2 == o1 and not enter_occupied(r2, t2))

    return possible


def domain_text(encoding: str) -> str:
    return files("tmpnav.pddl").joinpath(ENCODINGS[encoding].domain_file).read_text(encoding="utf-8")


def scaled(cost: float) -> int:
    return round(cost * COST_SCALE)


def encode(
    table: CostTable, goals: Goals, encoding: str, name: str = "tmpnav", min_gain: float = 0.0
) -> EncodedProblem:
    """Build the UP problem for ``encoding`` from the cost table and the goals.

    ``min_gain`` (mixed): a pair move enters the encoding only if it saves at least this
    fraction of its two single moves (0: any saving). Leaving out pairs that save less
    than a fraction g costs at most that fraction of those moves: the plan is within a
    factor 1 / (1 - g) of the optimum over every pair.
    """
    from unified_planning.io import PDDLReader

    enc = ENCODINGS[encoding]
    problem = PDDLReader().parse_problem_string(domain_text(encoding))
    problem.name = name
    robot_t, loc_t = problem.user_type("robot"), problem.user_type("location")
    robots = {r: upm_object(r, robot_t) for r in table.robots}
    locs = {loc: upm_object(loc, loc_t) for loc in table.locations}
    problem.add_objects([*robots.values(), *locs.values()])
    robot_in, can_move, target = problem.fluent("robot_in"), problem.fluent("can_move"), problem.fluent("target")
    visited, visited_by = problem.fluent("visited"), problem.fluent("visited_by")

    targets = {(r, room) for r, rooms in goals.per_robot for room in rooms}
    problem.set_initial_value(problem.fluent("act-cost")(), 0)
    for r, loc in table.start_location.items():
        problem.set_initial_value(robot_in(robots[r], locs[loc]), True)
        problem.set_initial_value(visited(locs[loc]), True)
        if (r, loc) in targets:
            problem.set_initial_value(visited_by(robots[r], locs[loc]), True)
    for r, room in targets:
        problem.set_initial_value(target(robots[r], locs[room]), True)
    for r, origin, dest in table.single:
        problem.set_initial_value(can_move(robots[r], locs[origin], locs[dest]), True)

    encoded = EncodedProblem(problem, enc)
    if encoding == "paper":
        _paper_costs(problem, table, robots, locs)
    else:
        pairs = _useful_pairs(table, min_gain) if enc.pairs else {}
        encoded.potentials = potentials(table, goals, pairs) if enc.reshape else {}
        h = encoded.potentials
        move_cost = problem.fluent("move-cost")
        for r, origin, dest in itertools.product(robots, locs, locs):  # every grounding defined
            cost = table.single.get((r, origin, dest))
            value = 0 if cost is None else scaled(cost) - h.get(dest, 0)
            problem.set_initial_value(move_cost(robots[r], locs[origin], locs[dest]), value)
        for (m1, m2), cost in pairs.items():
            _add_pair_action(encoded, m1, m2, scaled(cost) - h.get(m1[2], 0) - h.get(m2[2], 0), targets, robots, locs)

    for room in goals.visit:
        problem.add_goal(visited(locs[room]))
    for r, room in sorted(targets):
        problem.add_goal(visited_by(robots[r], locs[room]))
    act_cost_to_action_costs(problem)
    return encoded


def upm_object(name: str, kind: Any) -> Any:
    import unified_planning.model as upm

    return upm.Object(name, kind)


def _useful_pairs(table: CostTable, min_gain: float = 0.0) -> dict[tuple[MoveKey, MoveKey], float]:
    """Pairs cheaper than their two single moves by more than ``min_gain`` of them (pairs
    that save nothing are dominated by two single moves and never needed)."""
    out = {}
    for (m1, m2), cost in table.pair.items():
        alone = scaled(table.single[m1]) + scaled(table.single[m2])
        if scaled(cost) < alone and scaled(cost) <= (1.0 - min_gain) * alone:
            out[(m1, m2)] = cost
    return out


def potentials(table: CostTable, goals: Goals, pairs: dict[tuple[MoveKey, MoveKey], float]) -> dict[str, int]:
    """h_x for each room entered exactly once: the cheapest move into it, pairs halved."""
    targeted = {room for _, rooms in goals.per_robot for room in rooms}
    starts = set(table.start_location.values())
    rooms = {x for x in goals.visit if x not in targeted and x not in starts}
    h: dict[str, int] = {}
    for (_, _, dest), cost in table.single.items():
        if dest in rooms:
            h[dest] = min(h.get(dest, scaled(cost)), scaled(cost))
    for (m1, m2), cost in pairs.items():
        half = scaled(cost) // 2
        for dest in (m1[2], m2[2]):
            if dest in rooms:
                h[dest] = min(h.get(dest, half), half)
    return {x: max(v, 0) for x, v in h.items()}


def act_cost_to_action_costs(problem: Any) -> None:
    """Replace each action's ``(increase (act-cost) c)`` by the action cost c."""
    import unified_planning.model as upm

    act_cost = problem.fluent("act-cost")
    costs = {}
    for action in problem.actions:
        kept, cost = [], None
        for effect in action.effects:
            if effect.fluent.is_fluent_exp() and effect.fluent.fluent() == act_cost:
                cost = effect.value
            else:
                kept.append(effect)
        action.clear_effects()
        for effect in kept:
            action._add_effect_instance(effect)
        costs[action] = cost if cost is not None else problem.environment.expression_manager.Int(0)
    problem.add_quality_metric(upm.metrics.MinimizeActionCosts(costs))


def _paper_costs(problem: Any, table: CostTable, robots: dict[str, Any], locs: dict[str, Any]) -> None:
    """pair-cost for every ordered pair of moves of two different robots (both orders).

    Like the paper's encoding, the 6-ary function is defined for every combination of its
    arguments (0 where the moves do not exist; can_move keeps those actions out): this is
    the size that makes the paper's encoding slow with many robots.
    """
    pair_cost = problem.fluent("pair-cost")
    values = {}
    for (m1, m2), cost in table.pair.items():
        values[(*m1, *m2)] = values[(*m2, *m1)] = scaled(cost)
    for r1, f1, t1, r2, f2, t2 in itertools.product(robots, locs, locs, robots, locs, locs):
        args = (robots[r1], locs[f1], locs[t1], robots[r2], locs[f2], locs[t2])
        problem.set_initial_value(pair_cost(*args), values.get((r1, f1, t1, r2, f2, t2), 0))


def pair_action_name(m1: MoveKey, m2: MoveKey) -> str:
    return "goto_room_pair__" + "__".join((*m1, *m2))


def _add_pair_action(
    encoded: EncodedProblem,
    m1: MoveKey,
    m2: MoveKey,
    cost: int,
    targets: set[tuple[str, str]],
    robots: dict[str, Any],
    locs: dict[str, Any],
) -> None:
    """One grounded action moving two robots together, with goto_room's entry rules."""
    import unified_planning.model as upm
    from unified_planning.shortcuts import Not, Or

    problem = encoded.problem
    robot_in, visited, visited_by = problem.fluent("robot_in"), problem.fluent("visited"), problem.fluent("visited_by")
    name = pair_action_name(m1, m2)
    action = upm.InstantaneousAction(name)
    for r, origin, dest in (m1, m2):
        action.add_precondition(robot_in(robots[r], locs[origin]))
        if (r, dest) in targets:
            action.add_precondition(Or(Not(visited(locs[dest])), Not(visited_by(robots[r], locs[dest]))))
        else:
            action.add_precondition(Not(visited(locs[dest])))
    for r, origin, _ in (m1, m2):
        action.add_effect(robot_in(robots[r], locs[origin]), False)
    for r, _, dest in (m1, m2):
        action.add_effect(robot_in(robots[r], locs[dest]), True)
        action.add_effect(visited(locs[dest]), True)
        if (r, dest) in targets:
            action.add_effect(visited_by(robots[r], locs[dest]), True)
    action.add_increase_effect(problem.fluent("act-cost")(), cost)  # an action cost, see above
    problem.add_action(action)
    encoded.pair_actions[name] = (m1, m2)
