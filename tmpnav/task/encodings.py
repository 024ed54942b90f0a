"""The task encodings, as objects: what each needs from the oracle, and how it encodes.

``paper``  the paper's pair action: every action moves two robots (pddl/paper.pddl);
``single`` one action per robot, single-robot costs (pddl/single.pddl);
``mixed``  single moves plus grounded cooperative pair moves (pddl/mixed.pddl).

:data:`ENCODINGS` is the registry: the pipeline asks an encoding for its
:class:`TableRequest` (which moves and pairs the oracle must cost), :func:`tmpnav.task.encode.encode`
lets it write its costs into the problem. Its names, one-line docs and destinations are those
of :data:`tmpnav.choices.ENCODINGS`, where the command line and the scenario format read
them. A new encoding is a name there and a subclass registered here, with its domain file in
pddl/.

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
every float constant it cannot represent exactly, and ENHSP reads integers exactly.

This module imports no planning library.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib.resources import files
from typing import Protocol

from tmpnav.choices import ENCODINGS as SPECS
from tmpnav.choices import Destinations
from tmpnav.types import CostTable, Goals, MoveKey

COST_SCALE = 1000

PairFilter = Callable[[MoveKey, MoveKey], bool]


def scaled(cost: float) -> int:
    """A cost as the integer the PDDL problem holds (thousandths)."""
    return round(cost * COST_SCALE)


class CostSink(Protocol):
    """Where an encoding writes its costs: the unified-planning problem being built
    (:class:`tmpnav.task.encode.ProblemBuilder`) or its PDDL text
    (:class:`tmpnav.task.pddl_text.TextBuilder`)."""

    potentials: dict[str, int]  # room -> h_x (scaled), filled in by the encoding

    def set_move_costs(self, cost: Callable[[MoveKey], int]) -> None: ...

    def set_pair_costs(self, values: dict[tuple[str, ...], int]) -> None: ...

    def add_pair_action(self, m1: MoveKey, m2: MoveKey, cost: int) -> None: ...


@dataclass(frozen=True)
class TableRequest:
    """What an encoding needs the oracle to cost (the arguments of ``oracle.table.build_table``)."""

    destinations: Destinations
    pair_filter: PairFilter | None  # pairs of moves worth a joint cost; None: no pairs at all
    filter_key: str  # names the filter in the cost table's cache key
    pair_min_gain: float | None  # pairs proved unable to save this fraction are not simulated


@dataclass(frozen=True)
class Encoding:
    """One way of writing the task problem; subclasses say which pairs and costs it uses."""

    name: str
    domain_file: str  # in pddl/
    doc: str  # one line, for --help and the reference
    destinations: Destinations

    def domain_text(self) -> str:
        """The PDDL domain this encoding's problems are written against."""
        return files("tmpnav.pddl").joinpath(self.domain_file).read_text(encoding="utf-8")

    def pair_filter(self, goals: Goals, start_location: dict[str, str]) -> PairFilter | None:
        """Which pairs of moves can ever be applied together; None when the encoding has none."""
        return None

    def prune_bound(self, pair_min_gain: float) -> float | None:
        """The saving below which the oracle may leave a pair out unsimulated (None: keep all)."""
        return None

    def table_request(self, goals: Goals, start_location: dict[str, str], pair_min_gain: float) -> TableRequest:
        """What the oracle must cost for this encoding, these goals and robot starts."""
        return TableRequest(
            destinations=self.destinations,
            pair_filter=self.pair_filter(goals, start_location),
            filter_key=repr((self.name, goals)),
            pair_min_gain=self.prune_bound(pair_min_gain),
        )

    def add_costs(self, problem: CostSink, table: CostTable, goals: Goals, min_gain: float) -> None:
        """Write the table's costs into ``problem`` (fluent values, grounded actions)."""
        raise NotImplementedError


@dataclass(frozen=True)
class PaperEncoding(Encoding):
    """The paper's ``goto_room`` for a pair of robots: both move in every action."""

    def pair_filter(self, goals: Goals, start_location: dict[str, str]) -> PairFilter | None:
        return lambda m1, m2: m1[0] != m2[0]

    def add_costs(self, problem: CostSink, table: CostTable, goals: Goals, min_gain: float) -> None:
        """pair-cost for every ordered pair of moves of two different robots (both orders)."""
        values: dict[tuple[str, ...], int] = {}
        for (m1, m2), cost in table.pair.items():
            values[(*m1, *m2)] = values[(*m2, *m1)] = scaled(cost)
        problem.set_pair_costs(values)


@dataclass(frozen=True)
class SingleEncoding(Encoding):
    """One ``goto_room`` per robot with single-robot costs, reshaped by room potentials."""

    def offered_pairs(self, table: CostTable, min_gain: float) -> dict[tuple[MoveKey, MoveKey], float]:
        """The paired moves the problem offers the planner (none here)."""
        return {}

    def add_costs(self, problem: CostSink, table: CostTable, goals: Goals, min_gain: float) -> None:
        pairs = self.offered_pairs(table, min_gain)
        h = potentials(table, goals, pairs)
        problem.potentials.update(h)

        def move_cost(move: MoveKey) -> int:
            cost = table.single.get(move)
            return 0 if cost is None else scaled(cost) - h.get(move[2], 0)

        problem.set_move_costs(move_cost)
        for (m1, m2), cost in pairs.items():
            problem.add_pair_action(m1, m2, scaled(cost) - h.get(m1[2], 0) - h.get(m2[2], 0))


@dataclass(frozen=True)
class MixedEncoding(SingleEncoding):
    """Single moves plus the paired moves that save at least ``pair_min_gain``."""

    def pair_filter(self, goals: Goals, start_location: dict[str, str]) -> PairFilter | None:
        return occupancy_filter(goals, start_location)

    def prune_bound(self, pair_min_gain: float) -> float | None:
        return pair_min_gain if pair_min_gain > 0 else None

    def offered_pairs(self, table: CostTable, min_gain: float) -> dict[tuple[MoveKey, MoveKey], float]:
        return offered_pairs(table, min_gain)


def offered_pairs(table: CostTable, min_gain: float) -> dict[tuple[MoveKey, MoveKey], float]:
    """The mixed encoding's paired moves: those cheaper than their two single moves by at least
    ``min_gain`` of them (a pair that saves nothing is dominated by two single moves and never
    needed). Leaving out pairs that save less than g keeps the plan within 1 / (1 - g) of the
    optimum."""
    out = {}
    for (m1, m2), cost in table.pair.items():
        alone = scaled(table.single[m1]) + scaled(table.single[m2])
        if scaled(cost) < alone and scaled(cost) <= (1.0 - min_gain) * alone:
            out[(m1, m2)] = cost
    return out


def strongest_pairs(table: CostTable, min_gain: float, most: int) -> CostTable:
    """The table with only the ``most`` paired moves the mixed encoding would offer (those that
    save ``min_gain``) that save the largest share of their two single moves (ties: by the moves'
    names). A sub-problem of the anytime search offers ENHSP these alone: ENHSP parses and
    grounds every paired move it is offered, four actions each where time is priced, and on
    sub-problems that hold both robots of a pair-rich team that text is most of a search's time,
    while the paired moves that improve a plan are among the few that save most (tmpnav.task.subproblems)."""
    offered = offered_pairs(table, min_gain)
    if len(offered) <= most:
        return table

    def share_kept(p: tuple[MoveKey, MoveKey]) -> float:  # the pair's cost over its moves alone
        return scaled(offered[p]) / (scaled(table.single[p[0]]) + scaled(table.single[p[1]]))

    order = sorted(offered, key=lambda p: (share_kept(p), p))
    kept = set(order[:most])
    return replace(
        table,
        pair={p: c for p, c in table.pair.items() if p in kept},
        pair_duration={p: d for p, d in table.pair_duration.items() if p in kept},
    )


def _registered(cls: type[Encoding], name: str, domain_file: str) -> Encoding:
    """The encoding ``name`` of :data:`tmpnav.choices.ENCODINGS` (its doc and destinations)."""
    spec = SPECS[name]
    return cls(name, domain_file, spec.doc, spec.destinations)


#: the registry: one entry per name of :data:`tmpnav.choices.ENCODINGS`, in its order
ENCODINGS: dict[str, Encoding] = {
    e.name: e
    for e in (
        _registered(PaperEncoding, "paper", "paper.pddl"),
        _registered(SingleEncoding, "single", "single.pddl"),
        _registered(MixedEncoding, "mixed", "mixed.pddl"),
    )
}


def occupancy_filter(goals: Goals, start_location: dict[str, str]) -> PairFilter:
    """Pairs of moves that ``single``/``mixed``'s entry rule lets happen together: a room is
    entered only when unvisited or as its robot's own target, so two robots are never in the
    same room (unless they start there or it is a target) and never both enter one room."""
    targets = goals.entries  # a robot's targets and its end
    starts = set(start_location.values())

    def own_target(robot: str, room: str) -> bool:
        return (robot, room) in targets

    def possible(m1: MoveKey, m2: MoveKey) -> bool:
        (r1, o1, t1), (r2, o2, t2) = m1, m2
        if r1 == r2:
            return False
        if t1 == t2 and not (own_target(r1, t1) or own_target(r2, t2)):
            return False
        if o1 == o2 and o1 not in starts and not (own_target(r1, o1) or own_target(r2, o2)):
            return False
        if t1 == o2 and not own_target(r1, t1):
            return False
        return not (t2 == o1 and not own_target(r2, t2))

    return possible


def potentials(table: CostTable, goals: Goals, pairs: dict[tuple[MoveKey, MoveKey], float]) -> dict[str, int]:
    """h_x for each room entered exactly once: the cheapest move into it, pairs halved (an
    optional goal, which a plan may leave undone, has none)."""
    targeted = {room for _, rooms in goals.per_robot for room in rooms}
    starts = set(table.start_location.values())
    rooms = {x for x in goals.required if x not in targeted and x not in starts}
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
