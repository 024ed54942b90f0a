"""Stage 6a, fast path: the ``single`` and ``mixed`` problems written straight to PDDL text.

unified-planning's writer enumerates every grounding of every fluent and builds an object
per grounded action, about a millisecond per paired move (16.6 s for 16,000 of them on a
20-room building). ENHSP only needs the text, so for the encodings ENHSP runs, tmpnav writes
it itself: the lifted ``goto_room`` of pddl/single.pddl and pddl/mixed.pddl with its cost as
an action cost (``(increase (total-cost) (move-cost ?r ?from ?to))``, the form
:func:`tmpnav.task.encode.act_cost_to_action_costs` gives the unified-planning problem), the
static facts and costs of the moves that exist, and one parameterless action per offered
paired move, with exactly the preconditions and effects
:meth:`tmpnav.task.encode.ProblemBuilder.add_pair_action` gives it. The encodings write their
costs through the same calls (:class:`tmpnav.task.encodings.CostSink`), so both paths hold
the same numbers; tests/task/test_pddl_text.py reads this text back with unified-planning's
parser and checks that the two problems have the same plans and costs.

Object names come from :mod:`tmpnav.task.names`, so no user name can collide with the
domain's identifiers. The paper's encoding needs a six-argument cost function over every
combination of its arguments and stays on the unified-planning path.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from tmpnav.errors import PlannerCrashError
from tmpnav.task.encodings import ENCODINGS, Encoding
from tmpnav.task.names import PddlNames
from tmpnav.task.solve import SolveResult, solve_text
from tmpnav.types import CostTable, Goals, MoveKey

#: the encodings this module writes
TEXT_ENCODINGS = ("single", "mixed")

_DOMAIN_HEAD = """(define (domain {name})
 (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions :conditional-effects :action-costs)
 (:types robot location)
 (:constants
   {robots} - robot
   {locations} - location
 )
 (:predicates
   (robot_in ?r - robot ?l - location)
   (can_move ?r - robot ?from - location ?to - location)
   (target ?r - robot ?l - location)
   (visited ?l - location)
   (visited_by ?r - robot ?l - location)
 )
 (:functions
   (move-cost ?r - robot ?from - location ?to - location)
   (total-cost)
 )
 (:action goto_room
  :parameters (?r - robot ?from - location ?to - location)
  :precondition (and (robot_in ?r ?from) (can_move ?r ?from ?to)
                     (or (not (visited ?to)) (and (target ?r ?to) (not (visited_by ?r ?to)))))
  :effect (and (not (robot_in ?r ?from)) (robot_in ?r ?to) (visited ?to)
               (when (target ?r ?to) (visited_by ?r ?to))
               (increase (total-cost) (move-cost ?r ?from ?to))))
"""


@dataclass
class PddlTask:
    """A task problem as PDDL text, with what decoding its plans needs."""

    domain: str
    problem: str
    names: PddlNames
    pair_actions: dict[str, tuple[MoveKey, MoveKey]] = field(default_factory=dict)
    potentials: dict[str, int] = field(default_factory=dict)  # room -> h_x (scaled)
    n_actions: int = 0  # goto_room groundings (moves) plus paired actions

    def solve(self, planner: str, timeout: float) -> SolveResult:
        """Run the ENHSP engine ``planner`` on this text (see :func:`tmpnav.task.solve.solve_text`)."""
        return solve_text(self.domain, self.problem, planner, timeout)

    def decode(self, result: SolveResult) -> list[tuple[MoveKey, ...]]:
        """The plan's actions, each as the moves of the robots it moves (1 or 2)."""
        steps = []
        for name, params in result.actions:
            step = self.decode_action(name, params)
            if step is None:
                raise PlannerCrashError(f"the planner returned an action tmpnav does not know: {name}{params}")
            steps.append(step)
        return steps

    def decode_action(self, name: str, params: tuple[str, ...]) -> tuple[MoveKey, ...] | None:
        """The moves of one plan action (ENHSP's names, any case); None if it is not ours."""
        name = name.lower()
        if name in self.pair_actions:
            return self.pair_actions[name]
        if name == "goto_room" and len(params) == 3:
            try:
                robot = self.names.robot_named(params[0])
                return ((robot, self.names.location_named(params[1]), self.names.location_named(params[2])),)
            except KeyError:
                return None
        return None

    def texts(self) -> tuple[str, str]:
        return self.domain, self.problem


class TextBuilder:
    """A problem being written as text: the calls of :class:`~tmpnav.task.encodings.CostSink`."""

    def __init__(self, encoding: Encoding, table: CostTable, goals: Goals):
        if encoding.name not in TEXT_ENCODINGS:
            raise ValueError(f"the {encoding.name!r} encoding is written through unified-planning")
        self.table, self.goals = table, goals
        self.names = PddlNames.of(table.robots, table.locations)
        self.targets = {(r, room) for r, rooms in goals.per_robot for room in rooms}
        self.potentials: dict[str, int] = {}
        self.move_cost: Callable[[MoveKey], int] = lambda move: 0
        self.pair_texts: list[str] = []
        self.pair_actions: dict[str, tuple[MoveKey, MoveKey]] = {}

    def set_move_costs(self, cost: Callable[[MoveKey], int]) -> None:
        self.move_cost = cost

    def set_pair_costs(self, values: dict[tuple[str, ...], int]) -> None:
        raise NotImplementedError("a six-argument pair cost is written through unified-planning")

    def add_pair_action(self, m1: MoveKey, m2: MoveKey, cost: int) -> None:
        rob, loc = self.names.robot, self.names.location
        name = f"goto_room_pair_{len(self.pair_actions) + 1}"
        pre, dels, adds = [], [], []
        for r, origin, dest in (m1, m2):
            pre.append(f"(robot_in {rob[r]} {loc[origin]})")
            if (r, dest) in self.targets:
                pre.append(f"(or (not (visited {loc[dest]})) (not (visited_by {rob[r]} {loc[dest]})))")
            else:
                pre.append(f"(not (visited {loc[dest]}))")
            dels.append(f"(not (robot_in {rob[r]} {loc[origin]}))")
        for r, _, dest in (m1, m2):
            adds.append(f"(robot_in {rob[r]} {loc[dest]}) (visited {loc[dest]})")
            if (r, dest) in self.targets:
                adds.append(f"(visited_by {rob[r]} {loc[dest]})")
        self.pair_texts.append(
            f" (:action {name}\n  :parameters ()\n  :precondition (and {' '.join(pre)})\n"
            f"  :effect (and {' '.join(dels)} {' '.join(adds)} (increase (total-cost) {cost})))\n"
        )
        self.pair_actions[name] = (m1, m2)

    def domain_text(self, name: str) -> str:
        head = _DOMAIN_HEAD.format(
            name=f"{name}-domain",
            robots=" ".join(self.names.robot.values()),
            locations=" ".join(self.names.location.values()),
        )
        return head + "".join(self.pair_texts) + ")\n"

    def problem_text(self, name: str, ends: dict[str, str] | None = None) -> str:
        rob, loc = self.names.robot, self.names.location
        table, init = self.table, []
        for r, where in table.start_location.items():
            init.append(f"(robot_in {rob[r]} {loc[where]}) (visited {loc[where]})")
            if (r, where) in self.targets:
                init.append(f"(visited_by {rob[r]} {loc[where]})")
        init.extend(f"(target {rob[r]} {loc[room]})" for r, room in sorted(self.targets))
        init.extend(f"(can_move {rob[r]} {loc[origin]} {loc[dest]})" for r, origin, dest in table.single)
        # every grounding gets a cost (0 where there is no move) so that no numeric value is undefined
        for r in table.robots:
            for origin in table.locations:
                for dest in table.locations:
                    cost = self.move_cost((r, origin, dest)) if (r, origin, dest) in table.single else 0
                    init.append(f"(= (move-cost {rob[r]} {loc[origin]} {loc[dest]}) {cost})")
        goal = [f"(visited {loc[room]})" for room in self.goals.visit]
        goal += [f"(visited_by {rob[r]} {loc[room]})" for r, room in sorted(self.targets)]
        goal += [f"(robot_in {rob[r]} {loc[where]})" for r, where in sorted((ends or {}).items())]
        return (
            f"(define (problem {name})\n (:domain {name}-domain)\n (:init\n  (= (total-cost) 0)\n  "
            + "\n  ".join(init)
            + "\n )\n (:goal (and\n  "
            + "\n  ".join(goal)
            + "\n ))\n (:metric minimize (total-cost))\n)\n"
        )


def write_task(
    table: CostTable,
    goals: Goals,
    encoding: Encoding | str,
    name: str = "tmpnav",
    min_gain: float = 0.0,
    ends: dict[str, str] | None = None,
) -> PddlTask:
    """The PDDL text of ``encoding`` (``single`` or ``mixed``) for the cost table and the goals.

    ``min_gain`` (mixed): a pair move enters the problem only if it saves at least this
    fraction of its two single moves (0: any saving), as in :func:`tmpnav.task.encode.encode`.
    ``ends`` (a sub-problem of the anytime search): robot -> the location it must end in.
    """
    enc = ENCODINGS[encoding] if isinstance(encoding, str) else encoding
    builder = TextBuilder(enc, table, goals)
    enc.add_costs(builder, table, goals, min_gain)
    pname = _problem_name(name)
    return PddlTask(
        domain=builder.domain_text(pname),
        problem=builder.problem_text(pname, ends),
        names=builder.names,
        pair_actions=builder.pair_actions,
        potentials=builder.potentials,
        n_actions=len(table.single) + len(builder.pair_actions),
    )


def _problem_name(name: str) -> str:
    """A PDDL identifier for the problem (the scenario's name may hold any characters)."""
    slug = "".join(c if c.isalnum() or c == "-" else "-" for c in name.lower()).strip("-")
    return f"tmpnav-{slug}" if slug else "tmpnav"
