"""The task problem's single moves as a vehicle routing problem, solved by OR-Tools.

A thin adapter (the only module of tmpnav that imports ``ortools``): it gives plain data
in and plain data out, and is meant for an initial assignment of rooms to robots, a good
plan where the exact planner cannot go (20 rooms and more), and a yardstick for the lower
bound of :mod:`tmpnav.task.bound`.

The model. Vehicles are the robots, each starting at its start location, with open
routes (each vehicle ends at a dummy node that every node reaches at cost 0), or, for a robot
with an end (``goals.ends``), a route that ends in that room, its last move priced as any. The nodes
to visit are the rows of :func:`tmpnav.task.bound.required_entries`: every goal room that
is nobody's start and nobody's target (any robot with a move into it may take it), and
every target room of a robot that does not start there (only that robot may take it), so
a robot's start room that is a goal counts as visited. Rooms that are nobody's goal, start
or target are optional waypoints (a detour through one may be cheaper than the direct
move). Arc costs depend on the vehicle: the table's single-move cost in thousandths
(``COST_SCALE``); a move that is not in the table is forbidden, never merely expensive.
Pairs are not modelled: the routes are plans of single moves, and the table cost
reported is theirs.

Executed robot after robot, the routes are a plan of the ``mixed`` (and ``single``)
encoding: each room is entered once, or once by each robot that targets it.

Routes are a subset of the plans: a plan may also pass through a room that is another
robot's target before that robot gets there, which can be cheaper when the table's costs
break the triangle inequality, or necessary when a move is missing. So the best
routes may cost more than the best single-move plan; on tables whose costs obey the
triangle inequality they cost the same (tests/task/test_routing.py).

Time. With ``span_weight`` > 0 (an objective that prices the team's time,
tmpnav.task.objectives) the model also has a time dimension: each arc takes the move's
duration (the table's ``duration``, in centiseconds), every route starts at 0 (a robot's
hold, ``goals.held``, later), and the
global span cost prices the latest end, the makespan of the routes run at once, at
``span_weight`` per second (OR-Tools' min-max routing when the arc costs are left out:
``arc_costs=False``). A job's window (``goals.jobs``) bounds the time its room is reached:
the arc into it takes the move's travel time, the room's node waits (slack) until the window
opens, and the service follows (arc out of it); the time dimension is added for windows
whatever the objective.

Work rooms. With ``min_rooms`` (planner.min_rooms, tmpnav.task.minimum) a dimension counts the
work rooms each route enters, and each route's end has a soft lower bound there: a room short
of it costs :func:`tmpnav.task.objectives.strict_price`.

Search: a first solution (``PATH_CHEAPEST_ARC`` by default), then guided local search
until the time limit (or ``solution_limit`` solutions). OR-Tools' local search is
single-threaded and deterministic up to its stopping point: with a ``solution_limit``
that stops the search first, the routes are the same on every run; with a time limit
they depend on how far the search got, so on the machine's speed and load. Guided local
search never proves optimality. ``proved`` is "optimal" or "infeasible" when OR-Tools
reports that status (it does on very small models): a statement about routes, not about
every plan. One proof holds for every plan: "infeasible" with
status ``NO_ROBOT_CAN_ENTER``, when a goal room has no move of an allowed robot into it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tmpnav.task.bound import required_entries
from tmpnav.task.encodings import COST_SCALE
from tmpnav.task.minimum import work_rooms
from tmpnav.task.objectives import strict_price
from tmpnav.types import CostTable, Goals, MoveKey

#: OR-Tools' time unit: a hundredth of a second
TIME_UNIT = 0.01
#: the status of routes that cannot exist: a goal room no allowed robot has a move into
NO_ROBOT_CAN_ENTER = "NO_ROBOT_CAN_ENTER"
#: OR-Tools' statuses that end a search it did not cut short by its time limit
_NOT_TIMED = ("ROUTING_OPTIMAL", "ROUTING_INFEASIBLE", "ROUTING_INVALID", "ROUTING_FAIL")
#: OR-Tools' first-solution strategies that tmpnav offers (names of its enum)
FIRST_SOLUTION = ("PATH_CHEAPEST_ARC", "PARALLEL_CHEAPEST_INSERTION", "SAVINGS", "GLOBAL_CHEAPEST_ARC")


@dataclass(frozen=True)
class Routes:
    """Per robot, the rooms it enters in order (its start not included); the table cost
    of those single moves (inf when no routes were found); OR-Tools' status name; and
    what was proved: "optimal", "infeasible" or "nothing"."""

    rooms: dict[str, tuple[str, ...]]
    cost: float
    status: str
    proved: str
    #: the solutions OR-Tools found, at which of them its objective last improved, and the most
    #: in a row that did not improve it before one that did
    solutions: int = 0
    last_improvement: int = 0
    plateau: int = 0
    #: OR-Tools' time limit ended its search (not a count of solutions, nor nothing left to try):
    #: the routes depend on the machine's speed
    timed_out: bool = False
    detail: str = ""  # why there are no routes, in words (the rooms no robot can enter)
    by: str = "OR-Tools routing"  # what found them (tmpnav.task.insertion when OR-Tools found none)

    @property
    def found(self) -> bool:
        return math.isfinite(self.cost)

    @property
    def method(self) -> str:
        """How the routes were found, with OR-Tools' status: ``OR-Tools routing (ROUTING_SUCCESS)``."""
        return f"{self.by} ({self.status})"

    def moves(self, table: CostTable) -> list[MoveKey]:
        """The routes as single moves, robot after robot (a valid plan in this order)."""
        out: list[MoveKey] = []
        for r in table.robots:
            here = table.start_location[r]
            for room in self.rooms.get(r, ()):
                out.append((r, here, room))
                here = room
        return out


def solve_routes(
    table: CostTable,
    goals: Goals,
    time_limit: float,
    solution_limit: int | None = None,
    first_solution: str = "PATH_CHEAPEST_ARC",
    span_weight: float = 0.0,
    arc_costs: bool = True,
    initial: dict[str, tuple[str, ...]] | None = None,
    stagnation: int | None = None,
    min_rooms: int = 0,
) -> Routes:
    """Routes for the robots that visit every goal, by OR-Tools within ``time_limit`` s.

    ``solution_limit`` stops the search after that many solutions (reproducible runs), and
    ``stagnation`` after that many solutions in a row that did not improve its objective;
    ``first_solution`` is one of ``FIRST_SOLUTION``; ``span_weight`` prices a second of the
    routes' makespan, ``arc_costs=False`` leaves the moves' costs out (min-max routing).
    ``initial`` (each robot's rooms in order: a replan's plan under way) is the solution the
    local search starts from instead of a first solution of its own, when the model accepts it.
    ``min_rooms``: each route should enter that many work rooms (tmpnav.task.minimum), a room
    it lacks priced at :func:`tmpnav.task.objectives.strict_price`.
    See the module docstring for the model.
    """
    if first_solution not in FIRST_SOLUTION:
        raise ValueError(f"first_solution {first_solution!r} is not one of {', '.join(FIRST_SOLUTION)}")
    if time_limit <= 0:
        raise ValueError(f"time_limit must be positive, got {time_limit}")
    ends = set(goals.ends)
    tasks = [row for row in required_entries(table, goals) if row not in ends]  # an end is its route's end node
    starts = set(table.start_location.values())
    optional = [(None, x) for x in goals.optional if x not in starts]  # visited, or left undone at their penalty
    tasks += optional
    robots = table.robots
    if not tasks and not goals.ends:
        return Routes({r: () for r in robots}, 0.0, "NOTHING_TO_VISIT", "optimal")
    allowed = [_allowed(table, robot, room) for robot, room in tasks]
    if not all(allowed):
        closed = ", ".join(dict.fromkeys(room for (_, room), able in zip(tasks, allowed, strict=True) if not able))
        return Routes({}, math.inf, NO_ROBOT_CAN_ENTER, "infeasible", detail=closed)
    waypoints: list[tuple[str | None, str]] = [(None, x) for x in _waypoints(table, goals)]
    model = _Model(
        table, tasks + waypoints, allowed + [_allowed(table, None, x) for _, x in waypoints], arc_costs, goals
    )
    for node in range(model.first_task + len(tasks), len(model.location)):
        model.routing.AddDisjunction([model.manager.NodeToIndex(node)], 0)  # optional, free to skip
    for k, (_, x) in enumerate(optional):  # an optional goal: skipped at its penalty (in the arc costs' units)
        node = model.first_task + len(tasks) - len(optional) + k
        model.routing.AddDisjunction([model.manager.NodeToIndex(node)], round(goals.optional[x] * COST_SCALE))
    if (span_weight > 0 or goals.windows or goals.held) and table.duration:
        model.add_time(span_weight, goals)
    if min_rooms > 0:
        model.add_minimum(min_rooms, work_rooms(goals), span_weight)
    return model.solve(time_limit, solution_limit, first_solution, initial, stagnation)


#: OR-Tools' search ends when it has failed this many times since its last solution: its local
#: search has nothing left to try. On a problem of two rooms it finds one solution and would fail
#: on until its time limit (about 24,000 failures a second); on 10-60 rooms and 2-8 robots at
#: most 5 failures came between two solutions (benchmarks/routing/first_routes.txt).
IDLE_FAILURES = 1000


#: OR-Tools asks its limit whether to stop at every node of its search (about 145,000 times a
#: second); the failures are read from the solver every this many asks only. Reading them on
#: every ask took a third of OR-Tools' time (40 rooms and 4 robots: 6.4-9.6 s, 4.8-5.8 s so)
FAILURE_CHECK = 64


class _Trace:
    """OR-Tools' solutions counted as it finds them, and the last that improved its objective;
    the search's limit once ``stagnation`` solutions in a row did not improve it (where given),
    or it failed :data:`IDLE_FAILURES` times since its last solution (seen within
    :data:`FAILURE_CHECK` asks)."""

    def __init__(self, routing: object, stagnation: int | None):
        self.routing, self.stagnation = routing, stagnation
        self.solver = routing.solver()  # type: ignore[attr-defined]
        self.solutions, self.last_improvement, self.plateau, self.best = 0, 0, 0, math.inf
        self.failures = 0  # the solver's failures at the last solution
        self.stale = False  # ``stagnation`` solutions in a row without improvement
        self.idle = False  # IDLE_FAILURES failures since the last solution
        self.asked = 0

    def at_solution(self) -> None:
        self.solutions += 1
        self.failures = self.solver.Failures()
        value = self.routing.CostVar().Value()  # type: ignore[attr-defined]
        if value < self.best:
            self.plateau = max(self.plateau, self.solutions - self.last_improvement - 1)
            self.best, self.last_improvement = value, self.solutions
        self.stale = self.stagnation is not None and self.solutions - self.last_improvement >= self.stagnation

    def counts(self) -> tuple[int, int, int]:
        return self.solutions, self.last_improvement, self.plateau

    def stagnated(self) -> bool:
        if self.stale:
            return True
        self.asked += 1
        if self.asked % FAILURE_CHECK:
            return False
        self.idle = self.solutions > 0 and self.solver.Failures() - self.failures >= IDLE_FAILURES
        return self.idle


def _waypoints(table: CostTable, goals: Goals) -> list[str]:
    """Rooms no plan has to enter and nobody else can enter after a robot passes through:
    not a goal, nobody's start, nobody's target. A route may pass through them when that
    is cheaper than the direct move (the table's costs need not obey the triangle inequality)."""
    taken = set(goals.all_rooms) | set(table.start_location.values())
    entered = {x for _, _, x in table.single}
    return [x for x in table.locations if x not in taken and x in entered]


def _allowed(table: CostTable, robot: str | None, room: str) -> list[int]:
    """Indices of the robots that may take a task: those with a move into its room."""
    candidates = table.robots if robot is None else (robot,)
    entering = {r for r, _, x in table.single if x == room}
    return [table.robots.index(r) for r in candidates if r in entering]


class _Model:
    """The OR-Tools routing model of one task problem (nodes: starts, ends, tasks)."""

    def __init__(
        self,
        table: CostTable,
        tasks: list[tuple[str | None, str]],
        allowed: list[list[int]],
        arc_costs: bool = True,
        goals: Goals | None = None,
    ):
        from ortools.constraint_solver import pywrapcp

        self.table, self.tasks = table, tasks
        n_v = len(table.robots)
        ends = [(goals.end_of(r) if goals else None) or "" for r in table.robots]
        # nodes: 0..n_v-1 the robots' starts, n_v..2n_v-1 their ends (dummy: ""), then the tasks
        self.location = [table.start_location[r] for r in table.robots] + ends + [x for _, x in tasks]
        self.n_v = n_v
        self.first_task = 2 * n_v
        self.vehicles = [[v] for v in range(n_v)] * 2 + allowed
        starts, end_nodes = list(range(n_v)), list(range(n_v, 2 * n_v))
        self.manager = pywrapcp.RoutingIndexManager(len(self.location), n_v, starts, end_nodes)
        self.routing = pywrapcp.RoutingModel(self.manager)
        for v, r in enumerate(table.robots):
            callback = self.routing.RegisterTransitMatrix(self._matrix(r) if arc_costs else self._zeros())
            self.routing.SetArcCostEvaluatorOfVehicle(callback, v)
        for node in range(self.first_task, len(self.location)):
            # VehicleVar's domain, not SetAllowedVehiclesForIndex: that binding rejects Python lists
            self.routing.VehicleVar(self.manager.NodeToIndex(node)).SetValues([-1, *self.vehicles[node]])
        self._forbid_missing_moves()

    def _matrix(self, robot: str) -> list[list[int]]:
        """Arc costs of one robot in thousandths; a missing move gets a cost that no
        solution pays (it is also forbidden by a constraint)."""
        n = len(self.location)
        worst = max((c for (r, _, _), c in self.table.single.items() if r == robot), default=0.0)
        missing = (n + 1) * round(worst * COST_SCALE + 1)
        rows = []
        for i in range(n):
            row = [0] * n
            for j in self._entered():
                cost = self._move(robot, i, j, self.table.single)
                row[j] = missing if cost is None else round(cost * COST_SCALE)
            rows.append(row)
        return rows

    def _entered(self) -> list[int]:
        """The nodes an arc's cost depends on: the tasks and the real ends."""
        ends = [self.n_v + v for v in range(self.n_v) if self.location[self.n_v + v]]
        return [*ends, *range(self.first_task, len(self.location))]

    def _move(self, robot: str, i: int, j: int, values: dict[MoveKey, float]) -> float | None:
        """The table's value of the move i -> j (0 for a robot that ends where it already is)."""
        a, b = self.location[i], self.location[j]
        if a == b and j < self.first_task:
            return 0.0
        return values.get((robot, a, b))

    def _zeros(self) -> list[list[int]]:
        n = len(self.location)
        return [[0] * n for _ in range(n)]

    def add_time(self, span_weight: float, goals: Goals) -> None:
        """A time dimension (each arc: its move's duration) whose global span costs
        ``span_weight`` per second, in the arc costs' units (thousandths). With windows, an arc
        into a room takes the travel, the room waits until its window opens, and the arc out
        of it takes the room's service first (the table's durations end after the service)."""
        n, callbacks, longest = len(self.location), [], 1
        service = [goals.service(x) if x else 0.0 for x in self.location]
        for r in self.table.robots:
            rows = []
            for i in range(n):
                row = [0] * n
                for j in self._entered():
                    d = self._move(r, i, j, self.table.duration)
                    row[j] = 0 if d is None else max(0, round((d - service[j] + service[i]) / TIME_UNIT))
                for j in range(self.n_v, 2 * self.n_v):
                    if not self.location[j]:  # a dummy end: the last room's service ends the route
                        row[j] = round(service[i] / TIME_UNIT)
                rows.append(row)
                longest += max(row)
            callbacks.append(self.routing.RegisterTransitMatrix(rows))
        windows = goals.windows
        longest += round(max((w[1] for w in windows.values()), default=0.0) / TIME_UNIT)
        held = [round(goals.held_for(r) / TIME_UNIT) for r in self.table.robots]
        longest += max(held, default=0)
        # a route starts at 0, or after its robot's hold (Goals.held: the rest of a service under way)
        self.routing.AddDimensionWithVehicleTransits(
            callbacks, longest if windows else 0, longest, not any(held), "time"
        )
        time = self.routing.GetDimensionOrDie("time")
        for v, h in enumerate(held):
            if any(held):
                time.CumulVar(self.routing.Start(v)).SetRange(h, h)
        if span_weight > 0:
            per_unit = span_weight * COST_SCALE * TIME_UNIT
            time.SetGlobalSpanCostCoefficient(max(1, round(per_unit)))
        for node in range(self.first_task, n):
            window = windows.get(self.location[node])
            if window is not None:
                earliest, latest = (round(w / TIME_UNIT) for w in window)
                time.CumulVar(self.manager.NodeToIndex(node)).SetRange(earliest, latest)

    def add_minimum(self, least: int, work: frozenset[str], span_weight: float) -> None:
        """A dimension that counts the work rooms a route enters, with a soft lower bound of
        ``least`` at every route's end: each room short of it costs the search's
        :func:`tmpnav.task.objectives.strict_price` under ``span_weight`` (in the arc costs' units)."""
        n = len(self.location)
        ones = [1 if i >= self.first_task and self.location[i] in work else 0 for i in range(n)]
        callback = self.routing.RegisterUnaryTransitVector(ones)
        self.routing.AddDimension(callback, 0, sum(ones), True, "work rooms")
        rooms = self.routing.GetDimensionOrDie("work rooms")
        for v in range(self.n_v):
            rooms.SetCumulVarSoftLowerBound(self.routing.End(v), least, round(strict_price(span_weight) * COST_SCALE))
            # an empty route's costs count only for a vehicle "used when empty" (else an idle robot pays nothing)
            self.routing.SetVehicleUsedWhenEmpty(True, v)

    def _forbid_missing_moves(self) -> None:
        """Remove each arc i -> j from every vehicle whose table has no such move."""
        solver, n = self.routing.solver(), len(self.location)
        from_nodes = [*range(len(self.table.robots)), *range(self.first_task, n)]
        for i in from_nodes:
            next_i = self.routing.NextVar(self.manager.NodeToIndex(i))
            for v, r in enumerate(self.table.robots):  # a robot's end: only by a move into it
                if self.location[self.n_v + v] and self._move(r, i, self.n_v + v, self.table.single) is None:
                    next_i.RemoveValue(self.routing.End(v))
            for j in range(self.first_task, n):
                common = sorted(set(self.vehicles[i]) & set(self.vehicles[j]))
                able = [v for v in common if self._has_move(v, i, j)]
                index_j = self.manager.NodeToIndex(j)
                if i == j or not able:
                    if i != j:
                        next_i.RemoveValue(index_j)
                    continue
                vehicle_i = self.routing.VehicleVar(self.manager.NodeToIndex(i))
                for v in set(common) - set(able):
                    solver.Add(solver.IsEqualCstVar(next_i, index_j) + solver.IsEqualCstVar(vehicle_i, v) <= 1)

    def _has_move(self, v: int, i: int, j: int) -> bool:
        return (self.table.robots[v], self.location[i], self.location[j]) in self.table.single

    def solve(
        self,
        time_limit: float,
        solution_limit: int | None,
        first_solution: str,
        initial: dict[str, tuple[str, ...]] | None = None,
        stagnation: int | None = None,
    ) -> Routes:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2

        params = pywrapcp.DefaultRoutingSearchParameters()
        params.first_solution_strategy = getattr(routing_enums_pb2.FirstSolutionStrategy, first_solution)
        params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
        params.time_limit.FromMilliseconds(max(1, round(time_limit * 1000)))
        if solution_limit is not None:
            params.solution_limit = solution_limit
        trace = _Trace(self.routing, stagnation)
        self.routing.AddAtSolutionCallback(trace.at_solution)
        self.routing.AddSearchMonitor(self.routing.solver().CustomLimit(trace.stagnated))
        start = self._initial(initial, params) if initial else None
        if start is not None:
            solution = self.routing.SolveFromAssignmentWithParameters(start, params)
        else:
            solution = self.routing.SolveWithParameters(params)
        status = routing_enums_pb2.RoutingSearchStatus.Value.Name(self.routing.status())
        proved = {"ROUTING_OPTIMAL": "optimal", "ROUTING_INFEASIBLE": "infeasible"}.get(status, "nothing")
        counted = solution_limit is not None and trace.solutions >= solution_limit
        timed_out = status not in _NOT_TIMED and not (counted or trace.stale or trace.idle)
        if solution is None:
            why = "OR-Tools found no routes within its time limit" if timed_out else "OR-Tools found no routes"
            return Routes({}, math.inf, status, proved, *trace.counts(), timed_out=timed_out, detail=why)
        rooms = {r: self._route(solution, v) for v, r in enumerate(self.table.robots)}
        cost = 0.0
        for r, here, room in Routes(rooms, 0.0, status, proved).moves(self.table):
            cost += self.table.single[(r, here, room)]
        return Routes(rooms, cost, status, proved, *trace.counts(), timed_out=timed_out)

    def _initial(self, routes: dict[str, tuple[str, ...]], params: object) -> object | None:
        """The assignment of ``routes`` (each robot's rooms in order, its end left out: the end
        node is its route's end), or None when a room is no task of the robot or the model
        refuses the routes."""
        nodes: list[list[int]] = []
        free = {j: self.location[j] for j in range(self.first_task, len(self.location))}
        for v, r in enumerate(self.table.robots):
            end = self.location[self.n_v + v]
            rooms = list(routes.get(r, ()))
            if end and rooms and rooms[-1] == end:
                rooms.pop()
            route = []
            for room in rooms:
                node = next((j for j, x in free.items() if x == room and v in self.vehicles[j]), None)
                if node is None:
                    return None
                route.append(self.manager.NodeToIndex(node))
                del free[node]
            nodes.append(route)
        self.routing.CloseModelWithParameters(params)
        return self.routing.ReadAssignmentFromRoutes(nodes, True)

    def _route(self, solution: object, v: int) -> tuple[str, ...]:
        index, out = self.routing.Start(v), list[str]()
        end = self.location[self.n_v + v]
        while True:
            index = solution.Value(self.routing.NextVar(index))  # type: ignore[attr-defined]
            if self.routing.IsEnd(index):
                if end and end != (out[-1] if out else self.location[v]):
                    out.append(end)  # the move into its end
                return tuple(out)
            out.append(self.location[self.manager.IndexToNode(index)])
