"""A certified lower bound on the cost of every plan of the ``mixed`` encoding.

The task problem (tmpnav/task/encode.py): robot r starts at s_r; a plan is a sequence of
steps, each a single move m = (r, o, t) at cost c(m) or an offered pair of moves (m1, m2)
of two robots at cost p(m1, m2) (offered: it saves at least ``min_gain`` of c(m1) + c(m2),
as ``offered_pairs`` decides). A robot enters a room only if nobody has visited it, or if
the room is one of its own target rooms that it has not visited itself (for a pair, both
moves are checked against the state before the step). We assume, and check, that all
costs are non-negative and that no pair moves two robots into one room that neither of
them targets (tmpnav's ``pair_filter`` never asks the oracle for one). We write S for the
start locations, T_r for robot r's target rooms, and

    U = goals.visit minus S minus (every T_r)      the rooms entered exactly once,
    E = {(r, x) : x in T_r, x != s_r}              the target entries a plan must make.

**Facts about every plan.** (F1) No robot enters a location twice, and no robot re-enters
its start: entering a location marks it visited, and a target room also visited-by-r,
which closes both ways in (a start is visited from the outset, and visited-by-r when it
is r's target). So each robot's moves form a simple path from s_r. (F2) A room of U is
not visited at the start and is nobody's target, so it is entered exactly once (it is a
goal), and left at most once (one robot was ever in it). (F3) For (r, x) in E the plan
contains exactly one move of r into x (F1). These moves and the moves into the rooms of
U are pairwise different moves: they differ in their target room or their robot.

**Move prices.** Give each move of a pair a share of the pair's cost, in proportion to
the two single costs (the shares are non-negative and sum to p). A plan's cost is then
the sum over its moves of their prices (c(m) for a single step, the share for a pair
step), and a move's price is at least w(m) = min(c(m), its share in every offered pair
that contains it). By (F3) a plan costs at least the sum of w over its moves into U and
its moves of E, since every other move has a non-negative price.

**(a) Potentials.** Each of those moves costs at least the cheapest w of any move with
the same target room (and, for E, the same robot): the sum of these minima is a bound.
It is the relaxation behind the encoding's cost reshaping (``encode.potentials``, which
halves pairs instead of splitting them in proportion).

**(b) Assignment.** Give each row -- a room x of U, or an entry (r, x) of E -- the
origin of the plan's move that makes it. The origin is (i) s_r, when the move is r's
first; (ii) a room of U that the robot entered earlier; or (iii) another location o that
the robot entered earlier, which is possible only if r has a move into o in the table,
o != s_r, and o is not a start or is r's own target (call such r able to enter o). Each
robot has one first move, and a room of U is left at most once (F2), so the rows use
every column of kind (i) and (ii) at most once; kind (iii) may be used by any number of
rows and is represented by a private column per row holding the row's cheapest such
origin. The plan's moves thus define a feasible assignment of rows to columns whose cost
(the arc costs below) is at most their summed prices. Arc costs: for a row x of U, the
minimum of w(r, o, x) over the robots r that can make that move (for (i), r itself; for
(ii) and (iii), every r able to enter o); for a row (r, x) of E, w(r, o, x) with r fixed.
The cheapest assignment (scipy's ``min_weight_full_bipartite_matching``, exact) is a
lower bound on every plan, and at least (a), because every arc cost is at least its row's
minimum in (a). If no assignment exists, no plan exists, and the bound is infinite.

**(c) Flow.** The assignment permits closed loops among rooms of U that no robot can
reach, takes each arc's cheapest robot independently of the robot that arrived, and
fixes the pairs' split in advance. :mod:`tmpnav.task.bound_lp` writes the plans as an
integer program with exact costs (one 0/1 column per single move and per offered pair),
one flow of moves per robot from its start, and connectivity cuts, relaxes it to a linear
program, and bounds that from below through weak duality with the solver's duals, so an
inexact solver makes the bound weaker but never wrong. Its feasible set holds the plans'
assignments of (b) with every split of the pairs, so (c) >= (b) up to the LP's tolerance.

The value reported is the largest of the three, rounded down by a relative 1e-9 so that
the floating point of these sums never lifts it above a plan's cost. It bounds plans of
the ``mixed`` encoding with the given ``min_gain``; the ``single`` encoding is the case
without pairs. tests/task/test_bound.py checks it against exhaustive search and records
how close it comes. On the corridor configurations (2-4 robots, up to 10 rooms) it equals
ENHSP's optimum; on a 60-room building table with 8 robots and 20,000 pairs it takes about
10 s (2 cores), without pairs 4 s, and then proves OR-Tools' routes within 0.3% of optimal.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from tmpnav.task.encodings import offered_pairs as _useful_pairs
from tmpnav.types import CostTable, Goals, MoveKey

#: relative slack that covers floating-point error in the sums (see the module docstring)
ROUNDING = 1e-9
#: the relative gap below which a plan's cost counts as proved optimal
OPTIMAL_GAP = 1e-6
#: rounds of connectivity cuts in relaxation (c): the 200-room, 2-robot office converges in 18; a
#: 100-room, 16-robot office gains 1% of its bound from round 25 to its convergence at 40-44,
#: at 2.5 times the LPs' time
CUT_ROUNDS = 25
#: choices of n + 1 rooms (n robots) the makespan's pair bound tries at most (20 rooms, 4 robots: 15,504)
MAX_PAIR_SUBSETS = 20_000

Row = tuple[str | None, str]  # (robot, room): robot None for a room of U, else an entry of E


@dataclass(frozen=True)
class Bound:
    """A lower bound on the cost of every plan: its value, the relaxation that gave it,
    the value of each part (``potentials``, ``assignment``, ``flow``; the first two also
    split into the rooms entered once, ``*.rooms``, and the robots' target entries,
    ``*.targets``), and how the linear program of ``flow`` went."""

    value: float
    relaxation: str  # flow | assignment | potentials | none (nothing to visit) | infeasible
    parts: dict[str, float] = field(default_factory=dict)
    rounds: int = 0  # LPs solved by (c)
    cuts: int = 0  # connectivity cuts (c) added
    converged: bool = False  # (c) stopped because no cut was violated (not on its round limit)
    stopped: bool = False  # (c) cut short by the ``stop`` of :func:`lower_bound`

    def gap(self, cost: float) -> float:
        """(cost - bound) / cost: how far a plan of this cost may be from the optimum."""
        if cost <= 0.0:
            return 0.0
        return max(0.0, (cost - self.value) / cost)

    def proves_optimal(self, cost: float) -> bool:
        """Whether the bound proves a plan of this cost optimal (relative gap <= 1e-6)."""
        return self.gap(cost) <= OPTIMAL_GAP


def lower_bound(
    table: CostTable,
    goals: Goals,
    min_gain: float = 0.0,
    cut_rounds: int = CUT_ROUNDS,
    stop: Callable[[], bool] | None = None,
) -> Bound:
    """A lower bound on the cost of every plan of the ``mixed`` encoding on ``table``.

    ``min_gain`` is the encoding's ``pair_min_gain``: only the pairs it offers take part.
    ``cut_rounds`` bounds the rounds of cuts of (c) (0: the plain LP), and ``stop``, asked
    after each of its LPs, may end them sooner (a time share: the bound then depends on the
    machine's speed, and says so in ``stopped``). The proof is the
    module's docstring. Raises ValueError on a negative cost or on a pair that moves two
    robots into one room that neither targets (tmpnav's ``pair_filter`` never asks for one).
    """
    from tmpnav.task.bound_lp import flow_bound

    price = move_prices(table, min_gain)
    _check_pairs(table, goals, min_gain)
    rows = required_entries(table, goals)
    if not rows:
        return Bound(0.0, "none", {"potentials": 0.0, "assignment": 0.0, "flow": 0.0})
    parts = {**_potentials(price, rows), **_assignment(table, goals, price, rows)}
    if math.isinf(parts["assignment"]):
        return Bound(math.inf, "infeasible", parts)
    flow = flow_bound(table, goals, min_gain, rows, _able_to_enter(table, goals), cut_rounds, stop)
    if flow is not None:
        parts["flow"] = flow.value
    best = max(("flow", "assignment", "potentials"), key=lambda name: parts.get(name, -math.inf))
    value = parts[best] - ROUNDING * max(1.0, abs(parts[best]))
    if flow is None:
        return Bound(value, best, parts)
    return Bound(value, best, parts, flow.rounds, flow.cuts, flow.converged, flow.stopped)


def _check_pairs(table: CostTable, goals: Goals, min_gain: float) -> None:
    targets = goals.entries  # rooms a robot may enter after others: its targets and its end
    for (r1, _, t1), (r2, _, t2) in _useful_pairs(table, min_gain):
        if t1 == t2 and (r1, t1) not in targets and (r2, t2) not in targets:
            raise ValueError(f"the pair of moves of {r1} and {r2} into {t1} enters one room twice at once")


def move_prices(table: CostTable, min_gain: float = 0.0) -> dict[MoveKey, float]:
    """w(m): the least a plan pays for move m, alone or as its share of an offered pair."""
    bad = [m for m, c in table.single.items() if c < 0] + [k for k, c in table.pair.items() if c < 0]
    if bad:
        raise ValueError(f"the lower bound needs non-negative costs; {bad[0]} costs less than 0")
    price = dict(table.single)
    for (m1, m2), cost in _useful_pairs(table, min_gain).items():
        c1, c2 = table.single[m1], table.single[m2]
        share1 = cost * c1 / (c1 + c2) if c1 + c2 > 0 else cost / 2
        price[m1] = min(price[m1], share1)
        price[m2] = min(price[m2], cost - share1)
    return price


def required_entries(table: CostTable, goals: Goals) -> list[Row]:
    """The entries every plan makes: (None, x) for each room x entered exactly once (a goal
    that is nobody's start, nobody's target and not optional), then (r, x) for each target room x of a
    robot r that does not start in it, and for each robot's end that it does not start in."""
    starts = set(table.start_location.values())
    targeted = {room for _, rooms in goals.per_robot for room in rooms}
    once: list[Row] = [(None, x) for x in dict.fromkeys(goals.required) if x not in starts and x not in targeted]
    entries: list[Row] = [
        (r, x) for r, rooms in goals.per_robot for x in dict.fromkeys(rooms) if table.start_location.get(r) != x
    ]
    entries += [(r, x) for r, x in goals.ends if table.start_location.get(r) != x]  # its last move
    return once + entries


def _potentials(price: dict[MoveKey, float], rows: list[Row]) -> dict[str, float]:
    """(a): every row pays at least its cheapest way in."""
    cheapest: dict[Row, float] = {}
    for (r, _, x), w in price.items():
        for row in ((None, x), (r, x)):
            cheapest[row] = min(cheapest.get(row, math.inf), w)
    rooms = sum(cheapest.get(row, math.inf) for row in rows if row[0] is None)
    targets = sum(cheapest.get(row, math.inf) for row in rows if row[0] is not None)
    return {"potentials": rooms + targets, "potentials.rooms": rooms, "potentials.targets": targets}


def _assignment(table: CostTable, goals: Goals, price: dict[MoveKey, float], rows: list[Row]) -> dict[str, float]:
    """(b): the cheapest assignment of rows to origins, each origin left at most once."""
    from scipy.sparse import csr_array
    from scipy.sparse.csgraph import min_weight_full_bipartite_matching

    cost = _assignment_matrix(table, goals, price, rows)
    finite = np.isfinite(cost)
    i, j = np.nonzero(finite)
    # the allowed arcs only, each weighing 1 more than it costs: a sparse matrix has no
    # explicit zero weights, and every row is assigned, so the shift does not change the choice
    arcs = csr_array((cost[i, j] + 1.0, (i, j)), shape=cost.shape)
    try:
        row_ind, col_ind = min_weight_full_bipartite_matching(arcs)
    except ValueError:  # no assignment of every row to a column of its own
        return {"assignment": math.inf, "assignment.rooms": math.inf, "assignment.targets": math.inf}
    chosen = cost[row_ind, col_ind]
    rooms = float(sum(c for i, c in zip(row_ind, chosen, strict=True) if rows[i][0] is None))
    targets = float(sum(c for i, c in zip(row_ind, chosen, strict=True) if rows[i][0] is not None))
    return {"assignment": rooms + targets, "assignment.rooms": rooms, "assignment.targets": targets}


def _assignment_matrix(
    table: CostTable, goals: Goals, price: dict[MoveKey, float], rows: list[Row]
) -> NDArray[np.float64]:
    """Rows x columns [robot starts | rooms of U | one private column per row], inf = forbidden."""
    robots = table.robots
    once = [x for r, x in rows if r is None]
    enter = _able_to_enter(table, goals)
    by_dest: dict[str, list[tuple[str, str, float]]] = {}
    for (r, o, x), w in price.items():
        by_dest.setdefault(x, []).append((r, o, w))
    n_cols = len(robots) + len(once) + len(rows)
    cost = np.full((len(rows), n_cols), np.inf)
    start_col = {r: i for i, r in enumerate(robots)}
    once_col = {x: len(robots) + i for i, x in enumerate(once)}
    for i, (robot, x) in enumerate(rows):
        private = len(robots) + len(once) + i
        for r, o, w in by_dest.get(x, ()):
            if (robot is not None and r != robot) or o == x:
                continue
            if table.start_location.get(r) == o:
                col = start_col[r]
            elif r in enter.get(o, ()):
                col = once_col.get(o, private)
            else:
                continue  # r can never be at o when it makes this move
            cost[i, col] = min(cost[i, col], w)
    return cost


def _able_to_enter(table: CostTable, goals: Goals) -> dict[str, set[str]]:
    """Location -> the robots that can ever enter it (they may later leave it)."""
    starts = set(table.start_location.values())
    targets = goals.entries  # rooms a robot may enter after others: its targets and its end
    out: dict[str, set[str]] = {}
    for r, _, o in table.single:
        if o == table.start_location.get(r):
            continue
        if o not in starts or (r, o) in targets:
            out.setdefault(o, set()).add(r)
    return out


def makespan_bound(table: CostTable, goals: Goals) -> float:
    """A lower bound on the makespan of every schedule whose moves take at least
    ``table.duration`` (time floors, tmpnav.attachment.floors, each ending after the service at
    its target: :meth:`CostTable.with_service`), the robots moving at once, each waiting at a
    job's room for its window to open.

    Every required entry (:func:`required_entries`) is made by some robot, one that may do the
    room's job. (1) That robot finishes there at the earliest after driving there directly from
    its start, waiting for the window and serving (shortest times obey the triangle inequality;
    waiting only adds), then, if it has an end elsewhere, driving on to its end and serving
    there (:func:`round_trip`): the makespan is at least the largest, over the entries, of the
    least such round trip of a robot that may make it. (2) Every entry takes at least the
    quickest move into its room from anywhere; the robots share that work, so the makespan is
    at least its sum divided by the number of robots. (3) Among any n + 1 of the rooms entered
    exactly once (n robots), some robot serves two: the makespan is at least the least round
    trip of a robot through two of them, for the n + 1 rooms where that is largest
    (:func:`_pair_bound`). 0 without durations."""
    rows = required_entries(table, goals)
    if not rows or not table.duration:
        return 0.0
    into: dict[Row, float] = {}
    for (r, _, x), d in table.duration.items():
        for row in ((None, x), (r, x)):
            into[row] = min(into.get(row, math.inf), d)
    trips = [_least_trip(table, goals, row) for row in rows]
    work = sum(into.get(row, 0.0) for row in rows) / max(1, len(table.robots))
    return max(max(trips, default=0.0), work, _pair_bound(table, goals, rows))


def _pair_bound(table: CostTable, goals: Goals, rows: list[Row]) -> float:
    """(3) of :func:`makespan_bound`: the largest, over every n + 1 rooms entered exactly once,
    of the least round trip through two of them (in either order) of a robot that may serve
    both; 0 where there are no more such rooms than robots or more than
    :data:`MAX_PAIR_SUBSETS` choices of n + 1 of them."""
    once = [x for r, x in rows if r is None]
    n = len(table.robots)
    if len(once) <= n or math.comb(len(once), n + 1) > MAX_PAIR_SUBSETS:
        return 0.0
    pair: dict[tuple[str, str], float] = {}
    for x, y in itertools.combinations(once, 2):
        both = [r for r in table.robots if goals.may_visit(r, x) and goals.may_visit(r, y)]
        pair[(x, y)] = min((_through(table, goals, r, p) for r in both for p in ((x, y), (y, x))), default=math.inf)
    best = 0.0
    for rooms in itertools.combinations(once, n + 1):
        least = min(pair[p] for p in itertools.combinations(rooms, 2))
        if math.isfinite(least):  # infinite: no robot may serve two of them, and no plan exists
            best = max(best, least)
    return best


def _least_trip(table: CostTable, goals: Goals, row: Row) -> float:
    """The least :func:`round_trip` through ``row``'s room of a robot that may make the entry
    (0 when the table has none: no bound from it)."""
    robot, x = row
    robots = (robot,) if robot is not None else tuple(r for r in table.robots if goals.may_visit(r, x))
    trips = [round_trip(table, goals, r, x) for r in robots]
    finite = [t for t in trips if math.isfinite(t)]
    return min(finite, default=0.0)


def round_trip(table: CostTable, goals: Goals, robot: str, room: str) -> float:
    """The earliest ``robot`` can be done if it serves ``room``: its quickest move there from its
    start, a wait for the room's window, the service, then its quickest move on to its end (and
    the end's window and service), when it has an end elsewhere. ``table.duration`` ends each
    move after its target's service; inf when the table has no move of the robot there."""
    return _through(table, goals, robot, (room,))


def _through(table: CostTable, goals: Goals, robot: str, rooms: tuple[str, ...]) -> float:
    """:func:`round_trip` through ``rooms`` in their order (inf without a move of the table)."""
    done, at = 0.0, table.start_location[robot]
    for room in rooms:
        done = _served(goals, room, done, table.duration.get((robot, at, room), math.inf))
        at = room
    end = goals.end_of(robot)
    if end is None or end == at or not math.isfinite(done):
        return done
    back = table.duration.get((robot, at, end))
    # without the move in the table (a floor of no path), the way on is not counted
    return done if back is None else _served(goals, end, done, back)


def _served(goals: Goals, room: str, leave: float, move: float) -> float:
    """When a robot that leaves at ``leave`` on a move of ``move`` s into ``room`` (service
    included) is done there: the service starts at its arrival, or when the window opens."""
    service = goals.service(room)
    arrival = leave + move - service
    return arrival + goals.opens(room, arrival) + service
