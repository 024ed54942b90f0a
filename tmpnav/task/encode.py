"""Stage 6a: a cost table and goals -> a unified-planning problem, in one of the encodings.

This is the general path: any engine unified-planning can run, and the paper's encoding.
For ENHSP and the ``single``/``mixed`` encodings, :mod:`tmpnav.task.pddl_text` writes the
same problem as text, far faster; :func:`encode_task` picks the path.

:func:`encode` writes what every encoding shares (robots, locations, where each robot
starts, which moves exist, the goals) and lets the :class:`~tmpnav.task.encodings.Encoding`
write its costs through a :class:`ProblemBuilder`, the thin adapter over unified-planning
(see tmpnav/task/encodings.py for the encodings themselves).

The domains say, like the paper, ``(increase (act-cost) <cost>)``. unified-planning
classifies an increase by a (static) function as general numeric planning, which
``enhsp-opt`` declares it cannot do; :func:`act_cost_to_action_costs` therefore turns
those increases into action costs (``MinimizeActionCosts``), the standard PDDL
``:action-costs`` form that ENHSP and Fast Downward read. The plans are the same.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from tmpnav.errors import InputError, PlannerCrashError
from tmpnav.task.encodings import ENCODINGS, Encoding, scaled
from tmpnav.task.names import PddlNames
from tmpnav.task.pddl_text import TEXT_ENCODINGS, PddlTask, write_task
from tmpnav.task.solve import SolveResult, reads_pddl_text, solve
from tmpnav.types import CostTable, Goals, MoveKey

if TYPE_CHECKING:
    from unified_planning.model import Fluent, Object, Problem

Step = tuple[MoveKey, ...]


class EncodedTask(Protocol):
    """A task problem ready for a planner, by either path: solve it, decode its plans, print it."""

    pair_actions: dict[str, tuple[MoveKey, MoveKey]]  # grounded pair actions
    potentials: dict[str, int]  # room -> h_x (scaled)

    @property
    def n_actions(self) -> int: ...

    def solve(self, planner: str, timeout: float) -> SolveResult: ...

    def decode(self, result: SolveResult) -> list[Step]: ...

    def texts(self) -> tuple[str, str]: ...


@dataclass
class EncodedProblem:
    """The unified-planning problem and what decoding its plan needs."""

    problem: Problem
    encoding: Encoding
    names: PddlNames
    pair_actions: dict[str, tuple[MoveKey, MoveKey]] = field(default_factory=dict)  # grounded pair actions
    potentials: dict[str, int] = field(default_factory=dict)  # room -> h_x (scaled)

    @property
    def n_actions(self) -> int:
        return len(self.problem.actions)

    def solve(self, planner: str, timeout: float) -> SolveResult:
        return solve(self.problem, planner, timeout)

    def decode(self, result: SolveResult) -> list[Step]:
        """The plan's actions, each as the moves of the robots it moves (1 or 2)."""
        from tmpnav.task.pddl_text import DROP_PREFIX

        steps: list[Step] = []
        for name, params in result.actions:
            if name.lower().startswith(DROP_PREFIX):
                continue  # an optional goal left undone: no step
            try:
                step = self._step(name, params)
            except KeyError:
                step = None
            if step is None:
                raise PlannerCrashError(f"the planner returned an action tmpnav does not know: {name}{params}")
            steps.append(step)
        return steps

    def _step(self, name: str, params: tuple[str, ...]) -> Step | None:
        rob, loc = self.names.robot_named, self.names.location_named
        if name in self.pair_actions:
            return self.pair_actions[name]
        if name == "goto_room" and len(params) == 3:
            return ((rob(params[0]), loc(params[1]), loc(params[2])),)
        if name == "goto_room" and len(params) == 6:
            return (
                (rob(params[0]), loc(params[1]), loc(params[2])),
                (rob(params[3]), loc(params[4]), loc(params[5])),
            )
        return None

    def texts(self) -> tuple[str, str]:
        """(domain, problem) as unified-planning writes them for ENHSP."""
        from unified_planning.io import PDDLWriter

        writer = PDDLWriter(self.problem)
        return str(writer.get_domain()), str(writer.get_problem())


def encode_task(
    table: CostTable,
    goals: Goals,
    encoding: str,
    planner: str,
    name: str = "tmpnav",
    min_gain: float = 0.0,
    span_weight: float = 0.0,
) -> EncodedTask:
    """The task problem for ``planner``: PDDL text written by tmpnav when the planner is an
    ENHSP engine and the encoding is ``single`` or ``mixed``, else a unified-planning problem.
    A price on time (``span_weight``, tmpnav.task.objectives) needs the text: the robots'
    clocks are numeric fluents that only tmpnav's writer adds."""
    if encoding in TEXT_ENCODINGS and reads_pddl_text(planner):
        return write_task(table, goals, encoding, name, min_gain, span_weight=span_weight)
    if span_weight:
        raise InputError(
            f"the objective prices the team's time, which only tmpnav's PDDL text for ENHSP holds: use an ENHSP "
            f"planner with the single or mixed encoding (not {planner!r} with {encoding!r}), or --objective cost"
        )
    return encode(table, goals, encoding, name, min_gain)


def _text_task_interface(task: PddlTask) -> EncodedTask:  # mypy checks that PddlTask fits EncodedTask
    return task


class ProblemBuilder:
    """A problem being written: the domain's objects and fluents, and the calls that add costs."""

    def __init__(self, encoding: Encoding, table: CostTable, goals: Goals, name: str):
        from unified_planning.io import PDDLReader
        from unified_planning.model import Object

        problem = PDDLReader().parse_problem_string(encoding.domain_text())
        problem.name = name
        robot_t, loc_t = problem.user_type("robot"), problem.user_type("location")
        names = PddlNames.of(table.robots, table.locations)
        self.robots: dict[str, Object] = {r: Object(names.robot[r], robot_t) for r in table.robots}
        self.locs: dict[str, Object] = {loc: Object(names.location[loc], loc_t) for loc in table.locations}
        problem.add_objects([*self.robots.values(), *self.locs.values()])
        em = problem.environment.expression_manager
        self._exp = {o: em.ObjectExp(o) for o in (*self.robots.values(), *self.locs.values())}
        self.problem = problem
        self.targets = goals.entries  # a robot's targets and its end: rooms it may enter after others
        self.encoded = EncodedProblem(problem, encoding, names)
        self.potentials = self.encoded.potentials

    def _set(self, fluent: Fluent, args: Sequence[Object], value: int) -> None:
        """One initial value, its arguments and value built as expressions once: unified-planning
        promotes each argument of ``fluent(*args)`` again on every call (the paper's encoding sets
        82,944 pair costs on the 10-room corridor: 5.8 s that way, 2.2 s this way)."""
        em = self.problem.environment.expression_manager
        self.problem.set_initial_value(em.FluentExp(fluent, [self._exp[a] for a in args]), em.Int(value))

    def set_move_costs(self, cost: Callable[[MoveKey], int]) -> None:
        """``move-cost`` of every robot, origin and target (every grounding, 0 where no move exists)."""
        move_cost = self.problem.fluent("move-cost")
        for r, origin, dest in itertools.product(self.robots, self.locs, self.locs):
            self._set(move_cost, (self.robots[r], self.locs[origin], self.locs[dest]), cost((r, origin, dest)))

    def set_pair_costs(self, values: dict[tuple[str, ...], int]) -> None:
        """``pair-cost`` for every combination of its six arguments: the pair's cost, or
        where the oracle has none (both robots would end on one pose) a cost above every plan
        that avoids it, so the optimal search never takes it. This full grounding is the
        size that makes the paper's encoding slow with many robots (a static predicate
        naming the pairs that exist would be exact, but ENHSP's grounder runs out of memory
        on a six-argument predicate)."""
        pair_cost = self.problem.fluent("pair-cost")
        robots, locs = self.robots, self.locs
        never = sum(values.values()) + 1
        for r1, f1, t1, r2, f2, t2 in itertools.product(robots, locs, locs, robots, locs, locs):
            args = (robots[r1], locs[f1], locs[t1], robots[r2], locs[f2], locs[t2])
            self._set(pair_cost, args, values.get((r1, f1, t1, r2, f2, t2), never))

    def add_pair_action(self, m1: MoveKey, m2: MoveKey, cost: int) -> None:
        """One grounded action moving two robots together, with goto_room's entry rules."""
        from unified_planning.model import InstantaneousAction
        from unified_planning.shortcuts import Not, Or

        problem, robots, locs = self.problem, self.robots, self.locs
        robot_in, visited, visited_by = (
            problem.fluent("robot_in"),
            problem.fluent("visited"),
            problem.fluent("visited_by"),
        )
        name = f"goto_room_pair_{len(self.encoded.pair_actions) + 1}"
        action = InstantaneousAction(name)
        for r, origin, dest in (m1, m2):
            action.add_precondition(robot_in(robots[r], locs[origin]))
            if (r, dest) in self.targets:
                action.add_precondition(Or(Not(visited(locs[dest])), Not(visited_by(robots[r], locs[dest]))))
            else:
                action.add_precondition(Not(visited(locs[dest])))
        for r, origin, _ in (m1, m2):
            action.add_effect(robot_in(robots[r], locs[origin]), False)
        for r, _, dest in (m1, m2):
            action.add_effect(robot_in(robots[r], locs[dest]), True)
            action.add_effect(visited(locs[dest]), True)
            if (r, dest) in self.targets:
                action.add_effect(visited_by(robots[r], locs[dest]), True)
        action.add_increase_effect(problem.fluent("act-cost")(), cost)  # an action cost, see the module doc
        problem.add_action(action)
        self.encoded.pair_actions[name] = (m1, m2)


def encode(
    table: CostTable, goals: Goals, encoding: Encoding | str, name: str = "tmpnav", min_gain: float = 0.0
) -> EncodedProblem:
    """The unified-planning problem of ``encoding`` for the cost table and the goals.

    ``min_gain`` (mixed): a pair move enters the problem only if it saves at least this
    fraction of its two single moves (0: any saving).
    """
    enc = ENCODINGS[encoding] if isinstance(encoding, str) else encoding
    builder = ProblemBuilder(enc, table, goals, name)
    problem, robots, locs = builder.problem, builder.robots, builder.locs
    robot_in, can_move, target = problem.fluent("robot_in"), problem.fluent("can_move"), problem.fluent("target")
    visited, visited_by = problem.fluent("visited"), problem.fluent("visited_by")
    problem.set_initial_value(problem.fluent("act-cost")(), 0)
    for r, loc in table.start_location.items():
        problem.set_initial_value(robot_in(robots[r], locs[loc]), True)
        problem.set_initial_value(visited(locs[loc]), True)
        if (r, loc) in goals.marked_at_start(table.start_location):
            problem.set_initial_value(visited_by(robots[r], locs[loc]), True)
    for r, room in builder.targets:
        problem.set_initial_value(target(robots[r], locs[room]), True)
    for r, origin, dest in table.single:
        problem.set_initial_value(can_move(robots[r], locs[origin], locs[dest]), True)
    enc.add_costs(builder, table, goals, min_gain)
    for room in goals.visit:
        problem.add_goal(visited(locs[room]))
    for r, room in sorted(goals.targets):
        problem.add_goal(visited_by(robots[r], locs[room]))
    for r, room in goals.ends:
        problem.add_goal(robot_in(robots[r], locs[room]))
    _add_drops(problem, goals, locs)
    act_cost_to_action_costs(problem)
    return builder.encoded


def act_cost_to_action_costs(problem: Problem) -> None:
    """Replace each action's ``(increase (act-cost) c)`` by the action cost c."""
    from unified_planning.model.metrics import MinimizeActionCosts

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
    problem.add_quality_metric(MinimizeActionCosts(costs))


def _add_drops(problem: Problem, goals: Goals, locs: dict[str, Object]) -> None:
    """One action per optional goal: leave it undone at its penalty (it then counts as visited)."""
    from unified_planning.model import InstantaneousAction
    from unified_planning.shortcuts import Not

    from tmpnav.task.pddl_text import DROP_PREFIX

    visited = problem.fluent("visited")
    for k, (room, penalty) in enumerate(sorted(goals.optional.items())):
        if room not in locs or room not in goals.visit:
            continue
        action = InstantaneousAction(f"{DROP_PREFIX}{k + 1}")
        action.add_precondition(Not(visited(locs[room])))
        action.add_effect(visited(locs[room]), True)
        action.add_increase_effect(problem.fluent("act-cost")(), scaled(penalty))
        problem.add_action(action)
