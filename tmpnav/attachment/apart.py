"""A plan kept apart: the resolver (:mod:`tmpnav.attachment.conflicts`, :mod:`tmpnav.attachment.passing`)
applied to a task plan.

:func:`keep_apart` turns the waits, detours and sidesteps that keep a plan's robots out of each
other's way into the plan ``tmpnav plan`` returns (a TaskResult, and what was done); where the
scenario's clock drift (:mod:`tmpnav.attachment.drift`) asks for more than can be kept, the plan
is kept apart on its own clock and the rest is reported. :class:`ExecutedCost` prices every plan
the anytime search would take as its best so, remembered per plan.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, replace
from weakref import WeakKeyDictionary

import numpy as np

from tmpnav.attachment.carried import CarriedCosts
from tmpnav.attachment.clock_state import ClockRun
from tmpnav.attachment.conflicts import EPS, Resolution, radii_of
from tmpnav.attachment.drift import clock_drift
from tmpnav.attachment.passing import resolve_with_sidesteps
from tmpnav.belief.conflicts import DEFAULT_DELTA, Conflict, find_conflicts, seen_std
from tmpnav.oracle.motions import MotionLibrary
from tmpnav.results import KeptApart, TaskResult
from tmpnav.task.model import PlanCost
from tmpnav.task.objectives import OBJECTIVES
from tmpnav.task.plans import Plan
from tmpnav.task.stage import action_names
from tmpnav.types import PlanStatus

#: without a chance constraint, robots are kept apart only when that raises the plan's
#: objective by at most this fraction: a wait or a detour changes what the robots observe,
#: and in a landmark-poor hall it can cost them their localisation (7.5 times the cost on
#: the five rooms of tests/attachment/test_unfold.py)
MAX_RISE = 0.5
#: without a chance constraint, the clock runs after which no more sidesteps are tried: the
#: swaps of the shipped configs resolve in 14-15 runs (0.3-0.5 s), while the sidestep search
#: of robots that have lost track of where they are runs 83-143 times (7-17 s) and clears nothing
RUN_BUDGET = 20


@dataclass(frozen=True)
class Kept:
    """A plan kept apart (:func:`keep_apart`): the plan, how to run it (``delays``, ``detours``
    for ``resimulate``) and what was done."""

    task: TaskResult
    delays: dict[int, float]
    detours: dict[tuple[int, str], tuple[int, ...]]
    apart: KeptApart


def keep_apart(
    carried: CarriedCosts, task: TaskResult, delta: float | None, cost_before: float, makespan_before: float
) -> Kept | None:
    """The task plan kept clear of robots in each other's way: waits, detours and split
    pairs, and under a chance constraint ``delta`` sidesteps too
    (:func:`resolve_with_sidesteps`), at the margin k(delta) (k(0.05) without one); the plan
    they belong to as a TaskResult, the delays and detours to run it with, and what was done.
    None when the plan has no conflict, or nothing found removes one (without a move over
    ``delta``), or a move of the plan as planned is over ``delta``. The plan changed is no
    longer the planner's proved optimum: its status becomes satisficing, and its bound's gap is
    measured against it; its steps' costs are their executed costs, waits included (the anytime
    search priced them so: :class:`ExecutedCost`).
    ``cost_before`` and ``makespan_before`` are those of the plan as planned, run on the clock.

    Without a threshold, a plan kept apart is returned only when its objective is at most
    (1 + MAX_RISE) times the plan's as planned, and no sidestep is tried past RUN_BUDGET clock
    runs (the search is long where nothing clears the robots: up to 17 s on the 4-robot building)."""
    res = _kept(carried, task.steps, delta, cost_before, makespan_before)
    if res is None:
        return None
    replanned = res.plan != task.steps  # sidesteps or a split pair: steps the planner never saw
    step_costs = tuple(res.run.step_costs(len(res.plan), carried.scenario.cost, delta))
    w, objective = carried.scenario.cost, OBJECTIVES[carried.scenario.planner.objective]
    value = objective.value(sum(step_costs), res.run.makespan, w)
    kept = replace(
        task,
        status=PlanStatus.SOLVED_SATISFICING,
        steps=res.plan,
        action_names=action_names(res.plan) if replanned else task.action_names,
        step_costs=step_costs,
        schedule=res.run.schedule,
        pddl=None if replanned else task.pddl,
        bound=None if task.bound is None else task.bound.against(value),
    )
    apart = KeptApart(
        conflicts_before=len(res.conflicts_before),
        conflicts_left=len(res.conflicts_left),
        waits=tuple((k + 1, round(v, 6)) for k, v in sorted(res.delays.items()) if v > EPS),
        sidesteps=_sidesteps(task.steps, res.plan),
        cost_before=cost_before,
        makespan_before=makespan_before,
        runs=res.iterations,
        detours=_detour_lengths(carried.clock.lib, res),
    )
    return Kept(kept, dict(res.delays), dict(res.detours), apart)


#: resolutions remembered per cost model (the least recently used dropped first): the anytime
#: search prices its best plans with them (:class:`ExecutedCost`), and ``tmpnav plan`` keeps the
#: plan it returns apart with the same one (:func:`keep_apart`) instead of searching again
MAX_RESOLVED = 64


@dataclass(frozen=True)
class _Resolved:
    """What keeping a plan apart comes to: the resolution :func:`keep_apart` applies (None: the
    plan runs as planned) and, under a chance constraint, the conflicts the plan so executed
    still has at the same planned instant: those ``tmpnav plan`` refuses the plan for
    (tmpnav.pipeline.check_conflicts)."""

    res: Resolution | None
    left: tuple[Conflict, ...] = ()


_RESOLVED: WeakKeyDictionary[CarriedCosts, OrderedDict[tuple[Plan, float | None], _Resolved]] = WeakKeyDictionary()


def _kept(
    carried: CarriedCosts, plan: Plan, delta: float | None, cost_before: float, makespan_before: float
) -> Resolution | None:
    """The resolution :func:`keep_apart` applies to ``plan``, or None (its docstring says when;
    also for a plan with a move over ``delta`` as planned: its run fails the chance constraint
    whatever is done). Remembered by plan and ``delta``: ``cost_before`` and ``makespan_before``
    are the plan's own, as planned on the clock."""
    return _resolved(carried, plan, delta, cost_before, makespan_before).res


def _resolved(
    carried: CarriedCosts, plan: Plan, delta: float | None, cost_before: float, makespan_before: float
) -> _Resolved:
    memo = _RESOLVED.setdefault(carried, OrderedDict())
    key = (tuple(plan), delta)
    if key in memo:
        memo.move_to_end(key)
        return memo[key]
    found = memo[key] = _resolve(carried, key[0], delta, cost_before, makespan_before)
    if len(memo) > MAX_RESOLVED:
        memo.popitem(last=False)
    return found


def _resolve(
    carried: CarriedCosts, plan: Plan, delta: float | None, cost_before: float, makespan_before: float
) -> _Resolved:
    planned = carried.run(plan)
    if planned is None or (delta is not None and max((m.risk for m in planned.moves), default=0.0) > delta):
        return _Resolved(None)  # (a move over the chance constraint: its cost's penalty says so)
    res, tried = _accepted(carried, plan, delta, cost_before, makespan_before)
    if clock_drift(carried.scenario) <= 0.0:
        # without time windows the resolution's conflicts are those at the same instant
        return _Resolved(res, _refused(delta, res.conflicts_left if res is not None else tried.conflicts_before))
    # where the time windows (tmpnav.attachment.drift) leave robots in each other's way on the
    # plan's own clock, or cost too much: the plan kept apart on its own clock, if that leaves
    # fewer conflicts there; what the windows leave is reported with the plan (never hidden:
    # tmpnav.planning.safety.conflicts_left)
    left = _on_own_clock(carried, res.run if res is not None else carried.replay(plan), delta)
    if not left:
        return _Resolved(res)
    own, _ = _accepted(carried, plan, delta, cost_before, makespan_before, drift=0.0)
    if own is not None and len(own.conflicts_left) < len(left):
        return _Resolved(own, _refused(delta, own.conflicts_left))
    return _Resolved(res, _refused(delta, left))


def _refused(delta: float | None, conflicts: Sequence[Conflict]) -> tuple[Conflict, ...]:
    """The conflicts ``tmpnav plan`` refuses a plan for: all of them under a chance constraint,
    none without one (the paper's model reports them)."""
    return tuple(conflicts) if delta is not None else ()


def _accepted(
    carried: CarriedCosts,
    plan: Plan,
    delta: float | None,
    cost_before: float,
    makespan_before: float,
    drift: float | None = None,
) -> tuple[Resolution | None, Resolution]:
    """The plan kept apart (:func:`resolve_with_sidesteps`) with the time windows of ``drift``
    (the scenario's by default), if that is applied (:func:`keep_apart`'s docstring), and the
    resolution tried, applied or not."""
    budget = None if delta is not None else RUN_BUDGET
    res = resolve_with_sidesteps(carried, plan, delta=delta, budget=budget, drift=drift)
    if not res.conflicts_before or len(res.conflicts_left) >= len(res.conflicts_before):
        return None, res
    if delta is not None and max((m.risk for m in res.run.moves), default=0.0) > delta:
        return None, res  # kept apart only by a move over the chance constraint: the conflicts stay reported
    w, objective = carried.scenario.cost, OBJECTIVES[carried.scenario.planner.objective]
    if delta is None:
        value = objective.value(sum(res.run.step_costs(len(res.plan), w)), res.run.makespan, w)
        if value > (1.0 + MAX_RISE) * objective.value(cost_before, makespan_before, w):
            return None, res  # a wait or detour that costs the robots their localisation: reported, not applied
    return res, res


def _on_own_clock(carried: CarriedCosts, run: ClockRun, delta: float | None) -> list[Conflict]:
    """The conflicts of ``run`` (recorded) at the same planned instant (no time window)."""
    assert run.trajectories is not None
    risk = delta if delta is not None else DEFAULT_DELTA
    return find_conflicts(run.trajectories, radii_of(carried.clock), risk, seen=seen_std(carried.scenario.models))


class ExecutedCost:
    """A plan's cost as it will be executed, robots kept apart: what ``tmpnav plan`` does to the
    plan the search returns (:func:`keep_apart`), done to every plan the anytime search would
    take as its best, so that the plan it picks is the plan executed, waits, detours and
    sidesteps priced. ``price(plan, cost)``, with ``cost`` the plan's as planned (run on the
    clock, robots passing through each other), gives the executed cost; ``cost`` itself when
    the plan has no conflict, when nothing removes one, or when a move is over ``delta`` (the
    run then fails its chance constraint whatever is done). Remembered per plan.

    The executed cost is never below the cost as planned on the cases measured (waits and
    detours only add time and motion), so the search prices a candidate only where its cost
    as planned beats its best plan's executed cost (tmpnav.task.search)."""

    def __init__(self, carried: CarriedCosts, delta: float | None):
        self.carried, self.delta = carried, delta
        self._memo: dict[Plan, PlanCost] = {}
        self._apart: dict[Plan, frozenset[str]] = {}
        self._stuck: dict[Plan, frozenset[tuple[str, str]]] = {}
        self.priced = 0  # plans checked for conflicts (runs recorded)

    def __call__(self, plan: Plan, cost: PlanCost) -> PlanCost:
        plan = tuple(plan)
        if plan not in self._memo:
            self._memo[plan] = self._price(plan, cost)
        return self._memo[plan]

    def robots_apart(self, plan: Plan) -> frozenset[str]:
        """The robots whose conflicts keeping ``plan`` apart resolved (a plan priced before)."""
        return self._apart.get(tuple(plan), frozenset())

    def robots_stuck(self, plan: Plan) -> frozenset[tuple[str, str]]:
        """The pairs of robots still in each other's way in ``plan`` kept apart (a plan priced
        before): those its conflicts left are between, each pair in name order."""
        return self._stuck.get(tuple(plan), frozenset())

    def _price(self, plan: Plan, cost: PlanCost) -> PlanCost:
        if not math.isfinite(cost.total):
            return cost
        self.priced += 1
        found = _resolved(self.carried, plan, self.delta, cost.total, cost.makespan)
        res, unsafe = found.res, len(found.left)
        met = (*(res.conflicts_before if res is not None else ()), *found.left)
        if met:
            self._apart[plan] = frozenset(r for c in met for r in c.robots)
        if found.left:
            self._stuck[plan] = frozenset((min(c.robots), max(c.robots)) for c in found.left)
        if res is None:  # the plan as planned; with conflicts left, one the command refuses
            return replace(cost, unsafe=unsafe) if unsafe else cost
        executed = tuple(res.run.step_costs(len(res.plan), self.carried.scenario.cost, self.delta))
        same = len(res.plan) == len(plan)  # no sidestep split a move: the steps are the plan's
        return PlanCost(
            float(sum(executed)),
            executed if same else cost.steps,
            res.run.schedule if same else cost.schedule,
            cost.dropped,
            None if same else res.run.makespan,
            unsafe,
        )


def _detour_lengths(lib: MotionLibrary, res: Resolution) -> tuple[tuple[int, str, float], ...]:
    """(plan step, 1-based; robot; metres the detour is longer than the roadmap's shortest
    path between its ends) of each detour the run drove."""
    out = []
    for (k, robot), path in sorted(res.detours.items()):
        if not any(m.step == k and tuple(m.motion.path) == path for m in res.run.moves):
            continue  # the move started or ended elsewhere: driven as planned
        shortest = lib.graph.path(path[0], path[-1]) or path
        out.append((k + 1, robot, round(_length(lib, path) - _length(lib, shortest), 6)))
    return tuple(out)


def _length(lib: MotionLibrary, path: Sequence[int]) -> float:
    points = lib.roadmap.nodes[list(path)]
    return float(np.sum(np.hypot(*np.diff(points, axis=0).T)))


def _sidesteps(planned: Plan, kept: Plan) -> tuple[tuple[str, str, str, str], ...]:
    """(robot, origin, siding, target) of each move of ``kept`` into a room that ``planned`` never
    sends its robot to, with the room the robot goes on to."""
    targets = {(m[0], m[2]) for step in planned for m in step}
    moves = [m for step in kept for m in step]
    out = []
    for i, (robot, origin, siding) in enumerate(moves):
        if (robot, siding) not in targets:
            onward = next((m[2] for m in moves[i + 1 :] if m[0] == robot), siding)
            out.append((robot, origin, siding, onward))
    return tuple(out)
