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

With a price on time (``span_weight`` > 0: the objectives of :mod:`tmpnav.task.objectives`)
the problem also holds the team's clock: a fluent ``(clock ?r)`` per robot, the time its
last move ends, and ``(span)``, the latest of them, the makespan so far. A move of robot r
from o to x takes ``(duration r o x)``; a paired move starts when both of its robots are
free, so it sets both clocks from the later one. Each move is written as two actions, one
that ends within the span and one that extends it, the second paying ``span_weight`` per
second it adds (a paired move: four, by which robot is free later). The plan's total cost
is then its action costs plus ``span_weight`` times its makespan, the team moving at once
(tmpnav.task.timing), and ENHSP's uniform-cost search finds its minimum: every action's
cost is non-negative, however it depends on the clocks.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from tmpnav.errors import PlannerCrashError
from tmpnav.task.encodings import COST_SCALE, ENCODINGS, Encoding, scaled, strongest_pairs
from tmpnav.task.names import PddlNames
from tmpnav.task.solve import SolveResult, solve_text
from tmpnav.types import CostTable, Goals, MoveKey

#: the encodings this module writes
TEXT_ENCODINGS = ("single", "mixed")
#: the name of the actions that leave an optional goal undone (``drop_goal_1``, ...)
DROP_PREFIX = "drop_goal_"

_DOMAIN_HEAD = """(define (domain {name})
 (:requirements :strips :typing :negative-preconditions :disjunctive-preconditions :conditional-effects
   :action-costs{numeric})
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
   (total-cost){clock_functions}
 )
"""

_MOVE = """ (:action {name}
  :parameters (?r - robot ?from - location ?to - location)
  :precondition (and (robot_in ?r ?from) (can_move ?r ?from ?to){when}
                     (or (not (visited ?to)) (and (target ?r ?to) (not (visited_by ?r ?to)))))
  :effect (and (not (robot_in ?r ?from)) (robot_in ?r ?to) (visited ?to)
               (when (target ?r ?to) (visited_by ?r ?to)){clock}
               (increase (total-cost) {cost})))
"""

_CLOCK_FUNCTIONS = """
   (clock ?r - robot)
   (span)
   (duration ?r - robot ?from - location ?to - location)"""
_END = "(+ (clock ?r) (duration ?r ?from ?to))"


def _move_actions(span_weight: float, timed: bool | None = None) -> str:
    """``goto_room`` (and, with a price on time or jobs' windows (``timed``), ``goto_room_late``:
    the move that ends after the span)."""
    if not (span_weight if timed is None else timed):
        return _MOVE.format(name="goto_room", when="", clock="", cost="(move-cost ?r ?from ?to)")
    clock = "\n               (increase (clock ?r) (duration ?r ?from ?to))"
    within = _MOVE.format(
        name="goto_room",
        when=f"\n                     (<= {_END} (span))",
        clock=clock,
        cost="(move-cost ?r ?from ?to)",
    )
    late = _MOVE.format(
        name="goto_room_late",
        when=f"\n                     (>= {_END} (span))",
        clock=clock + f"\n               (assign (span) {_END})",
        cost=f"(+ (move-cost ?r ?from ?to) (* {_number(span_weight)} (- {_END} (span))))",
    )
    return within + late


def _number(x: float) -> str:
    """A PDDL number: no exponent, no needless digits."""
    text = f"{x:.6f}".rstrip("0").rstrip(".")
    return text if text not in ("", "-0") else "0"


@dataclass
class PddlTask:
    """A task problem as PDDL text, with what decoding its plans needs."""

    domain: str
    problem: str
    names: PddlNames
    pair_actions: dict[str, tuple[MoveKey, MoveKey]] = field(default_factory=dict)
    potentials: dict[str, int] = field(default_factory=dict)  # room -> h_x (scaled)
    n_actions: int = 0  # goto_room groundings (moves) plus paired actions
    #: grounded single moves into rooms with a job's window: action name -> the move
    window_actions: dict[str, MoveKey] = field(default_factory=dict)

    def solve(self, planner: str, timeout: float) -> SolveResult:
        """Run the ENHSP engine ``planner`` on this text (see :func:`tmpnav.task.solve.solve_text`)."""
        return solve_text(self.domain, self.problem, planner, timeout)

    def decode(self, result: SolveResult) -> list[tuple[MoveKey, ...]]:
        """The plan's actions, each as the moves of the robots it moves (1 or 2); an optional goal
        left undone is no step."""
        steps = []
        for name, params in result.actions:
            if name.lower().startswith(DROP_PREFIX):
                continue
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
        if name in self.window_actions:
            return (self.window_actions[name],)
        if name in ("goto_room", "goto_room_late") and len(params) == 3:
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

    def __init__(self, encoding: Encoding, table: CostTable, goals: Goals, span_weight: float = 0.0):
        if encoding.name not in TEXT_ENCODINGS:
            raise ValueError(f"the {encoding.name!r} encoding is written through unified-planning")
        self.table, self.goals = table, goals
        self.span_weight = span_weight * COST_SCALE  # in the problem's cost units, per second
        self.names = PddlNames.of(table.robots, table.locations)
        self.targets = goals.entries  # a robot's targets and its end: rooms it may enter after others
        self.potentials: dict[str, int] = {}
        self.move_cost: Callable[[MoveKey], int] = lambda move: 0
        self.pair_texts: list[str] = []
        self.pair_actions: dict[str, tuple[MoveKey, MoveKey]] = {}
        self.pairs_written = 0  # paired moves written (each is up to four actions)
        self.windows = goals.windows  # room -> (earliest, latest) arrival, s on the problem's clock
        # clocks when time has a price, and when a job's window bounds an arrival
        self.timed = bool(self.span_weight) or bool(self.windows)
        self.window_actions: dict[str, MoveKey] = {}

    def set_move_costs(self, cost: Callable[[MoveKey], int]) -> None:
        self.move_cost = cost

    def set_pair_costs(self, values: dict[tuple[str, ...], int]) -> None:
        raise NotImplementedError("a six-argument pair cost is written through unified-planning")

    def add_pair_action(self, m1: MoveKey, m2: MoveKey, cost: int) -> None:
        rob, loc = self.names.robot, self.names.location
        self.pairs_written += 1
        name = f"goto_room_pair_{self.pairs_written}"
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
        if not self.timed:
            self._pair_text(name, (m1, m2), pre, [*dels, *adds], str(cost))
            return
        d1, d2 = self._pair_durations(m1, m2)
        for later, (ra, da), (rb, db) in (("a", (m1[0], d1), (m2[0], d2)), ("b", (m2[0], d2), (m1[0], d1))):
            ca, cb, end = f"(clock {rob[ra]})", f"(clock {rob[rb]})", f"(+ (clock {rob[ra]}) {_number(max(d1, d2))})"
            clocks = [f"(>= {ca} {cb})"]
            # a job's window at a robot's target: the pair arrives within it (a paired move is
            # not offered to arrive early and wait there: such a plan has single moves)
            for (_, _, dest), d in ((m1, d1), (m2, d2)):
                if dest in self.windows:
                    earliest, latest = self.windows[dest]
                    arrive = f"(+ {ca} {_number(d - self.goals.service(dest))})"
                    clocks += [f"(>= {arrive} {_number(earliest)})", f"(<= {arrive} {_number(latest)})"]
            moved = [*dels, *adds, f"(increase {ca} {_number(da)})", f"(assign {cb} (+ {ca} {_number(db)}))"]
            self._pair_text(f"{name}_{later}", (m1, m2), [*pre, *clocks, f"(<= {end} (span))"], moved, str(cost))
            late = f"(+ {cost} (* {_number(self.span_weight)} (- {end} (span))))"
            extend = [*moved, f"(assign (span) {end})"]
            self._pair_text(f"{name}_{later}_late", (m1, m2), [*pre, *clocks, f"(>= {end} (span))"], extend, late)

    def _pair_text(self, name: str, pair: tuple[MoveKey, MoveKey], pre: list[str], eff: list[str], cost: str) -> None:
        self.pair_texts.append(
            f" (:action {name}\n  :parameters ()\n  :precondition (and {' '.join(pre)})\n"
            f"  :effect (and {' '.join(eff)} (increase (total-cost) {cost})))\n"
        )
        self.pair_actions[name] = pair

    def _pair_durations(self, m1: MoveKey, m2: MoveKey) -> tuple[float, float]:
        t = self.table
        if (m1, m2) in t.pair_duration:
            return t.pair_duration[(m1, m2)]
        d2, d1 = t.pair_duration.get((m2, m1), (0.0, 0.0))
        return d1, d2

    def domain_text(self, name: str) -> str:
        timed = self.timed
        head = _DOMAIN_HEAD.format(
            name=f"{name}-domain",
            numeric=" :numeric-fluents" if timed else "",
            robots=" ".join(self.names.robot.values()),
            locations=" ".join(self.names.location.values()),
            clock_functions=_CLOCK_FUNCTIONS if timed else "",
        )
        moves = _move_actions(self.span_weight, self.timed)
        if self.windows:  # the lifted move only into rooms without a window; grounded moves into the others
            head = head.replace(
                "(visited_by ?r - robot ?l - location)\n",
                "(visited_by ?r - robot ?l - location)\n   (windowed ?l - location)\n",
            )
            moves = moves.replace("(can_move ?r ?from ?to)", "(can_move ?r ?from ?to) (not (windowed ?to))")
        return head + moves + "".join(self.pair_texts) + self._window_texts() + self._drop_texts() + ")\n"

    def _window_texts(self) -> str:
        """The single moves into rooms with a job's window, grounded (their numbers constants):
        the robot arrives at clock + drive (its move's duration less the room's service) no later
        than the latest; on time it is free at clock + duration, early (``_early``) it waits
        there and is free at earliest + service; each within the span and extending it
        (``_late``, at ``span_weight`` per s), as :func:`_move_actions`."""
        if not self.windows:
            return ""
        rob, loc, out = self.names.robot, self.names.location, []
        w = _number(self.span_weight)
        for k, move in enumerate(m for m in self.table.single if m[2] in self.windows):
            r, origin, dest = move
            earliest, latest = self.windows[dest]
            service, d = self.goals.service(dest), self.table.duration.get(move, 0.0)
            clock = f"(clock {rob[r]})"
            arrive = f"(+ {clock} {_number(d - service)})"
            pre = [f"(robot_in {rob[r]} {loc[origin]})"]
            if (r, dest) in self.targets:
                pre.append(f"(or (not (visited {loc[dest]})) (not (visited_by {rob[r]} {loc[dest]})))")
            else:
                pre.append(f"(not (visited {loc[dest]}))")
            eff = [f"(not (robot_in {rob[r]} {loc[origin]}))", f"(robot_in {rob[r]} {loc[dest]}) (visited {loc[dest]})"]
            if (r, dest) in self.targets:
                eff.append(f"(visited_by {rob[r]} {loc[dest]})")
            cost = self.move_cost(move)
            for kind, when, free, clock_effect in (
                ("", f"(>= {arrive} {_number(earliest)})", f"(+ {clock} {_number(d)})",
                 f"(increase {clock} {_number(d)})"),
                ("_early", f"(<= {arrive} {_number(earliest)})", _number(earliest + service),
                 f"(assign {clock} {_number(earliest + service)})"),
            ):  # fmt: skip
                bounds = [when, f"(<= {arrive} {_number(latest)})"]
                for late in ("", "_late"):
                    name = f"goto_room_window_{k + 1}{kind}{late}"
                    if late:
                        cond, more = f"(>= {free} (span))", [f"(assign (span) {free})"]
                        price = f"(+ {cost} (* {w} (- {free} (span))))"
                    else:
                        cond, more, price = f"(<= {free} (span))", [], str(cost)
                    out.append(
                        f" (:action {name}\n  :parameters ()\n  :precondition (and {' '.join([*pre, *bounds, cond])})\n"
                        f"  :effect (and {' '.join([*eff, clock_effect, *more])} (increase (total-cost) {price})))\n"
                    )
                    self.window_actions[name] = move
        return "".join(out)

    def _drop_texts(self) -> str:
        """One action per optional goal of the problem: leave it undone, at its penalty (it then
        counts as visited, so nobody enters it)."""
        loc, out = self.names.location, []
        for k, (room, penalty) in enumerate(sorted(self.goals.optional.items())):
            if room in self.goals.visit and room in loc:
                out.append(
                    f" (:action {DROP_PREFIX}{k + 1}\n  :parameters ()\n  :precondition (not (visited {loc[room]}))\n"
                    f"  :effect (and (visited {loc[room]}) (increase (total-cost) {scaled(penalty)})))\n"
                )
        return "".join(out)

    def problem_text(self, name: str, ends: dict[str, str] | None = None, clocks: Clocks | None = None) -> str:
        rob, loc = self.names.robot, self.names.location
        table, init = self.table, []
        if self.timed:
            init += self._clock_facts(clocks or Clocks(dict(self.goals.held)))
        init.extend(f"(windowed {loc[x]})" for x in sorted(self.windows) if x in loc)
        for r, where in table.start_location.items():
            init.append(f"(robot_in {rob[r]} {loc[where]}) (visited {loc[where]})")
            if (r, where) in self.goals.marked_at_start(table.start_location):
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
        return self._problem(name, init, goal, ends)

    def _clock_facts(self, clocks: Clocks) -> list[str]:
        """The clocks at the start (each robot's, and the span) and the duration of every move."""
        rob, loc, t = self.names.robot, self.names.location, self.table
        facts = [f"(= (clock {rob[r]}) {_number(clocks.start.get(r, 0.0))})" for r in t.robots]
        facts.append(f"(= (span) {_number(clocks.span)})")
        for r in t.robots:
            for origin in t.locations:
                for dest in t.locations:
                    d = t.duration.get((r, origin, dest), 0.0)
                    facts.append(f"(= (duration {rob[r]} {loc[origin]} {loc[dest]}) {_number(d)})")
        return facts

    def _problem(self, name: str, init: list[str], goal: list[str], ends: dict[str, str] | None) -> str:
        rob, loc = self.names.robot, self.names.location
        goal += [f"(visited_by {rob[r]} {loc[room]})" for r, room in sorted(self.goals.targets)]
        # where a robot must be at the end: its end (goals.ends), or where a sub-problem's plan goes on
        ends = {**dict(self.goals.ends), **(ends or {})}
        goal += [f"(robot_in {rob[r]} {loc[where]})" for r, where in sorted(ends.items())]
        return (
            f"(define (problem {name})\n (:domain {name}-domain)\n (:init\n  (= (total-cost) 0)\n  "
            + "\n  ".join(init)
            + "\n )\n (:goal (and\n  "
            + "\n  ".join(goal)
            + "\n ))\n (:metric minimize (total-cost))\n)\n"
        )


@dataclass(frozen=True)
class Clocks:
    """The team's clock where a problem starts: when each robot is free, and the span so far
    (a sub-problem of the anytime search starts where the plan before it left the team)."""

    start: dict[str, float] = field(default_factory=dict)
    span: float = 0.0


def write_task(
    table: CostTable,
    goals: Goals,
    encoding: Encoding | str,
    name: str = "tmpnav",
    min_gain: float = 0.0,
    ends: dict[str, str] | None = None,
    span_weight: float = 0.0,
    clocks: Clocks | None = None,
    most_pairs: int | None = None,
) -> PddlTask:
    """The PDDL text of ``encoding`` (``single`` or ``mixed``) for the cost table and the goals.

    ``min_gain`` (mixed): a pair move enters the problem only if it saves at least this
    fraction of its two single moves (0: any saving), as in :func:`tmpnav.task.encode.encode`.
    ``ends`` (a sub-problem of the anytime search): robot -> the location it must end in.
    ``span_weight``: the objective's price of a second of makespan (0: none, no clocks);
    ``clocks``: where the team's clock starts (default: every robot free at 0).
    ``most_pairs`` (mixed): at most this many paired moves, those that save most
    (:func:`tmpnav.task.encodings.strongest_pairs`; None: every one that saves ``min_gain``).
    """
    enc = ENCODINGS[encoding] if isinstance(encoding, str) else encoding
    if most_pairs is not None and table.pair:
        table = strongest_pairs(table, min_gain, most_pairs)
    builder = TextBuilder(enc, table, goals, span_weight)
    enc.add_costs(builder, table, goals, min_gain)
    pname = _problem_name(name)
    return PddlTask(
        domain=builder.domain_text(pname),
        problem=builder.problem_text(pname, ends, clocks),
        names=builder.names,
        pair_actions=builder.pair_actions,
        window_actions=builder.window_actions,
        potentials=builder.potentials,
        n_actions=len(table.single) + len(set(builder.pair_actions.values())),
    )


def _problem_name(name: str) -> str:
    """A PDDL identifier for the problem (the scenario's name may hold any characters)."""
    slug = "".join(c if c.isalnum() or c == "-" else "-" for c in name.lower()).strip("-")
    return f"tmpnav-{slug}" if slug else "tmpnav"


def sample_task(encoding: Encoding | str, span_weight: float = 0.0, min_gain: float = 0.0) -> PddlTask:
    """A small problem of the kind the anytime search gives ENHSP, to warm a search before the
    run's first (:func:`tmpnav.task.solve.warm_up`): two robots at the ends of a row of four
    rooms, costs and durations growing with the distance, one paired move that saves, and the
    team's clock where ``span_weight`` prices time. Its plan is of no use."""
    where = {"a-start": 0, "w": 1, "x": 2, "y": 3, "z": 4, "b-start": 5}
    start = {"a": "a-start", "b": "b-start"}
    rooms = ("w", "x", "y", "z")
    single = {(r, o, t): 1.0 + 2.0 * abs(where[o] - where[t]) for r in start for o in (start[r], *rooms) for t in rooms}
    duration = {m: 5.0 * abs(where[m[1]] - where[m[2]]) for m in single}
    single = {m: c for m, c in single.items() if m[1] != m[2]}
    duration = {m: d for m, d in duration.items() if m in single}
    pair_moves = (("a", "a-start", "w"), ("b", "b-start", "z"))
    pair = {pair_moves: 0.8 * (single[pair_moves[0]] + single[pair_moves[1]])}
    pair_duration = {pair_moves: (duration[pair_moves[0]], duration[pair_moves[1]])}
    table = CostTable(("a", "b"), rooms, (*rooms, *start.values()), start, single, pair, duration, pair_duration)
    return write_task(table, Goals(rooms, ()), encoding, "warm-up", min_gain, None, span_weight)
