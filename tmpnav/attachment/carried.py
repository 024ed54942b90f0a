"""Costs from the beliefs the robots carry: the paper's semantic attachment, on the team's clock.

The paper's module evaluates an action from the belief the search has reached: the pose
instantiation and the belief in which the robot's previous move ended start its next move.
:class:`CarriedCosts` does exactly that for whole plans, with the team moving at once: a
plan runs on the team's clock (:mod:`tmpnav.attachment.clock`), each move starting when its
robot (and, for a paired move, its partner) is free, every robot in one joint EKF, mutual
observations whenever two robots see each other. A step's cost is the weighted cost of its
robots' moves; the plan also has its schedule and makespan.

This is also what the re-simulation of the final plan does (:mod:`tmpnav.resimulate` calls
:meth:`CarriedCosts.replay`, the same run recording every control step), so with ``--costs
carried`` the cost the planner minimises is the executed cost, number for number.

A plan's run is remembered (the search costs the same plans again when it revisits them).

For the search's sub-problems (:meth:`CarriedCosts.subtable`), the first move of each robot
is costed from its actual belief after the steps before the sub-problem (the team's state
when all of them have ended); a later move between two of the sub-problem's rooms from the
state in which the robot arrives in the first room driving there directly from where it
is (the table's canonical rule, applied at that point of the plan). Each plan the search
keeps is then run in full, as above.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping, Sequence
from functools import cached_property

from tmpnav.attachment.canonical import CanonicalCosts, _offered, _ordered
from tmpnav.attachment.clock import TeamClock
from tmpnav.attachment.clock_state import ClockRun, Unreachable
from tmpnav.attachment.floors import motion_floors
from tmpnav.attachment.team import Team, paired_moves
from tmpnav.choices import Costs
from tmpnav.oracle.bounds import cannot_save
from tmpnav.oracle.executors import library
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.oracle import Oracle
from tmpnav.oracle.requests import Request, StartState
from tmpnav.oracle.table import arrival_state
from tmpnav.task.model import PlanCost, entered, robot_ends, sub_moves
from tmpnav.task.plans import Plan
from tmpnav.types import CostTable, Goals, MotionResult, MoveKey, Scenario

#: plan runs remembered (the least recently used dropped first)
MAX_RUNS = 4096


class CarriedCosts:
    """Plan costs with carried-over beliefs (the module docstring); a :class:`~tmpnav.task.model.CostModel`."""

    costs: Costs = "carried"

    def __init__(self, oracle: Oracle, canonical: CanonicalCosts):
        self.oracle = oracle
        self.canonical = canonical
        self.scenario = oracle.ctx.scenario
        self.lib = library(oracle.ctx)
        self.robots = canonical.robots
        self.start_location = canonical.start_location
        self.min_gain = canonical.min_gain
        self.start = Team.at_start(self.lib, self.scenario)
        self.clock = TeamClock(oracle, self.lib, self.start)
        self.controls = canonical.controls  # (the same library: one memory of least efforts)
        self._runs: OrderedDict[Plan, ClockRun | None] = OrderedDict()  # None: a step cannot be made
        self.plans_run = 0

    # ------------------------------------------------------------------ CostModel

    def singles(self, goals: Goals) -> CostTable:
        """The single moves from canonical states: the search's first plan is routed on them."""
        return self.canonical.singles(goals)

    def plan_cost(self, plan: Plan) -> PlanCost:
        run = self.run(plan)
        if run is None or run.end.late:  # it cannot be made, or arrives after a job's window closes
            return PlanCost.impossible(len(plan))
        costs = run.step_costs(len(plan), self.scenario.cost, self.scenario.planner.max_risk)
        dropped = self.scenario.goals.drop_penalty(entered(plan, self.start_location))
        return PlanCost(float(sum(costs)), tuple(costs), run.schedule, dropped)

    def ends(self, head: Plan) -> dict[str, float]:
        run = self.run(head)
        return robot_ends(run.schedule if run is not None else None, self.robots)

    def run(self, plan: Plan) -> ClockRun | None:
        """The plan run on the team's clock (remembered); None when a step cannot be made."""
        plan = tuple(plan)
        if plan in self._runs:
            self._runs.move_to_end(plan)
            return self._runs[plan]
        try:
            found: ClockRun | None = self.clock.run(plan)
        except Unreachable:
            found = None
        self.plans_run += 1
        self._runs[plan] = found
        if len(self._runs) > MAX_RUNS:
            self._runs.popitem(last=False)
        return found

    def replay(
        self,
        plan: Plan,
        delays: Mapping[int, float] | None = None,
        detours: Mapping[tuple[int, str], tuple[int, ...]] | None = None,
    ) -> ClockRun:
        """The plan run as :meth:`plan_cost` runs it, recording each robot's belief at every
        control step. Raises TmpnavError when a step's robots cannot reach their rooms."""
        return self.clock.run(tuple(plan), delays, record=True, detours=detours)

    def state_after(self, head: Plan) -> Team:
        """The team when every step of ``head`` has ended."""
        run = self.run(head)
        if run is None:
            raise Unreachable("a step of the plan's head cannot be made")
        return run.end.team

    def subtable(self, head: Plan, robots: Sequence[str], rooms: Sequence[str], goals: Goals) -> CostTable:
        team = self.state_after(head)
        idx = {r: team.names.index(r) for r in robots}
        at = {r: _location(self.start_location[r], head, r) for r in robots}
        first = [(r, at[r], t) for r in robots for t in rooms if t != at[r]]
        results = self.oracle.evaluate([team.request([r], [t]) for r, _, t in first])
        single: dict[MoveKey, float] = {}
        duration: dict[MoveKey, float] = {}
        arrived: dict[tuple[str, str], StartState] = {}
        for move, res in zip(first, results, strict=True):
            if res is not None:
                single[move], duration[move] = res.cost, self._seconds(res)[0]
                arrived[(move[0], move[2])] = arrival_state(res)
        later = [m for m in sub_moves(at, rooms) if m[1] != at[m[0]] and (m[0], m[1]) in arrived]
        results = self.oracle.evaluate([Request((r,), (arrived[(r, o)],), (t,)) for r, o, t in later])
        for m, res in zip(later, results, strict=True):
            if res is not None:
                single[m], duration[m] = res.cost, self._seconds(res)[0]
        pair, pair_duration = self._pairs(team, idx, at, arrived, single, goals)
        locations = tuple(dict.fromkeys([*rooms, *at.values()]))
        table = CostTable(tuple(robots), tuple(rooms), locations, at, single, pair, duration, pair_duration)
        return table.with_service(self.scenario.goals)  # a move's time until its robot is free

    def _seconds(self, result: MotionResult) -> tuple[float, ...]:
        return tuple(n * self.scenario.models.dt for n in result.steps)

    def _pairs(
        self,
        team: Team,
        idx: dict[str, int],
        at: dict[str, str],
        arrived: dict[tuple[str, str], StartState],
        single: dict[MoveKey, float],
        goals: Goals,
    ) -> tuple[dict[tuple[MoveKey, MoveKey], float], dict[tuple[MoveKey, MoveKey], tuple[float, float]]]:
        """Paired moves of the sub-problem that save at least ``min_gain``, and their durations:
        from the robots' actual joint belief when both make their first move, else from their
        arrival states."""
        keep = paired_moves(self.scenario, goals, at)
        moves = list(single)
        floor = {m: self._floor(m) for m in moves}
        wanted = [
            _ordered(m1, m2, self.robots)
            for i, m1 in enumerate(moves)
            for m2 in moves[i + 1 :]
            if m1[0] != m2[0] and keep(m1, m2) and not self._hopeless(m1, m2, single, floor)
        ]
        asked, requests = [], []
        for m1, m2 in wanted:
            if m1[1] == at[m1[0]] and m2[1] == at[m2[0]]:
                req = team.request([m1[0], m2[0]], [m1[2], m2[2]])
            else:
                s1 = team.start_state(idx[m1[0]]) if m1[1] == at[m1[0]] else arrived[(m1[0], m1[1])]
                s2 = team.start_state(idx[m2[0]]) if m2[1] == at[m2[0]] else arrived[(m2[0], m2[1])]
                req = Request((m1[0], m2[0]), (s1, s2), (m1[2], m2[2]))
            if self.controls.cannot_pair(req, single[m1] + single[m2], self.min_gain):
                continue  # (tmpnav.oracle.bounds.ControlFloors)
            gain = self.min_gain if self.min_gain > 0 and req.joint_cov is None else None
            asked.append((m1, m2))
            requests.append(Request(req.robots, req.starts, req.rooms, req.joint_cov, min_gain=gain))
        out, times = {}, {}
        for p, res in zip(asked, self.oracle.evaluate(requests), strict=True):
            if res is not None and not res.pruned and _offered(res.cost, single[p[0]] + single[p[1]], self.min_gain):
                out[p] = res.cost
                d1, d2 = self._seconds(res)
                times[p] = (d1, d2)
        return out, times

    def _hopeless(
        self, m1: MoveKey, m2: MoveKey, single: Mapping[MoveKey, float], floor: Mapping[MoveKey, float]
    ) -> bool:
        """Whether the pair of ``m1`` and ``m2`` cannot save ``min_gain`` of their single moves'
        costs whatever its robots' beliefs: each robot of a pair drives its own path, so the pair
        costs at least the two moves' motion floors (:mod:`tmpnav.attachment.floors`). Such a
        pair is never offered (the oracle would prune it, or simulate it and find it dearer),
        so it is not asked for (on a generated 40-room office with a lidar, 4,011 of the 26,694
        pairs the oracle pruned). ``floor``: each move's :meth:`_floor`."""
        return cannot_save(floor[m1] + floor[m2], single[m1] + single[m2], self.min_gain)

    def _floor(self, move: MoveKey) -> float:
        """The least ``move`` costs from wherever its robot stands at its origin: a room's pose
        instantiations, and the robot's start pose where the origin is where it started (0
        where the floors do not know the move)."""
        r, origin, target = move
        found = [self._floors.get(move)] if origin in self.lib.roadmap.instantiations else []
        if origin == self.start_location[r]:
            found.append(self._floors.get((r, _START.format(r), target)))
        known = [f for f in found if f is not None]
        return min(known) if known and len(known) == len(found) else 0.0

    @cached_property
    def _floors(self) -> dict[MoveKey, float]:
        """The motion floor of every single move between the rooms a plan of this scenario can
        move between (its goal rooms and the rooms its robots start in), from any heading (a
        robot may stand on a room's node turned to a job's heading), and from each robot's start
        pose (origin ``<robot>@start``; a robot that starts in a room and comes back stands on
        one of its instantiations). A move outside them has no floor here (:meth:`_floor`)."""
        instantiated = self.lib.roadmap.instantiations
        starts = (x for x in self.start_location.values() if x in instantiated)
        return room_floors(self.scenario, self.lib, self.robots, (*self.scenario.goals.all_rooms, *starts))


#: the origin of a robot's moves from its start pose in :func:`room_floors`
_START = "{}@start"


def room_floors(
    scenario: Scenario, lib: MotionLibrary, robots: Sequence[str], among: Sequence[str] | None = None
) -> dict[MoveKey, float]:
    """The motion floor of every single move of ``robots`` between the rooms ``among`` (default:
    every room of ``lib``'s roadmap, goals or not), from any heading, and from each robot's start
    pose (origin ``<robot>@start``). Each floor is the same whichever other rooms are among them:
    only the shortest-path trees from the rooms' pose instantiations are computed (one Dijkstra
    each, 8 ms on building-4robots' roadmap of 6,475 nodes)."""
    rooms = tuple(lib.roadmap.instantiations) if among is None else tuple(dict.fromkeys(among))
    starts = {r: _START.format(r) for r in robots}
    return motion_floors(scenario, lib.graph, starts, Goals(rooms, ())).single


def _location(start: str, head: Plan, robot: str) -> str:
    where = start
    for step in head:
        for r, _, t in step:
            if r == robot:
                where = t
    return where
