"""What a plan costs the anytime search (tmpnav.task.search): as planned, as executed, and ranked.

A plan is costed by the cost model (its action costs and schedule), with the rooms its robots
lack of a minimum per robot (planner.min_rooms, :mod:`tmpnav.task.minimum`); priced as it will
be executed, its robots kept apart (``Executed``); and ranked by its objective plus the prices
of the conflicts it leaves and the rooms it lacks (``PlanCost.ranked``). Of several candidates,
the search keeps the cheapest as executed, pricing them lazily.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TypeVar

from tmpnav.results import StageTimes
from tmpnav.task.minimum import counts, need, shortfall, work_rooms
from tmpnav.task.model import CostModel, PlanCost
from tmpnav.task.objectives import strict_price
from tmpnav.task.plans import Plan
from tmpnav.task.search_run import Executed, SearchOptions
from tmpnav.types import Goals

_T = TypeVar("_T")


class Pricing:
    """The costs of the plans of one search: ``model``'s, with the minimum of rooms of
    ``options`` over ``goals``, as ``executed`` prices them (None: as planned), the oracle's
    time counted in ``times``."""

    def __init__(
        self, model: CostModel, goals: Goals, options: SearchOptions, times: StageTimes, executed: Executed | None
    ):
        self.model, self.times, self.executed = model, times, executed
        self.span_weight = options.span_weight
        self.work = work_rooms(goals)
        self.need = need(goals, model.start_location, options.min_rooms)  # work rooms per robot

    def cost(self, plan: Plan) -> PlanCost:
        """The model's cost of the plan, with the rooms its robots lack of the minimum."""
        with self.times.timed("oracle"):
            cost = self.model.plan_cost(plan)
        return self._with_short(plan, cost)

    def _short(self, plan: Plan) -> int:
        """The work rooms ``plan``'s robots lack of :attr:`need` (tmpnav.task.minimum)."""
        return shortfall(counts(plan, self.work), self.model.robots, self.need) if self.need else 0

    def _with_short(self, plan: Plan, cost: PlanCost) -> PlanCost:
        lacking = self._short(plan)
        return cost if cost.short == lacking else replace(cost, short=lacking)

    def hopeless(self, plan: Plan, best: PlanCost) -> bool:
        """Whether the rooms ``plan``'s robots lack of the minimum alone rank it at or above the
        ``best`` plan's, whatever its cost (every objective is at least 0): it need not be costed."""
        lacking = self._short(plan)
        return lacking > 0 and strict_price(self.span_weight) * lacking >= self.value(best)

    def priced(self, plan: Plan, cost: PlanCost) -> PlanCost:
        """The plan's cost as it will be executed (robots kept apart, ``executed``), from
        ``cost``, its cost as planned; ``cost`` without ``executed``."""
        if self.executed is None:
            return cost
        with self.times.timed("oracle"):
            return self._with_short(plan, self.executed(plan, cost))

    def cheapest(self, costed: list[tuple[Plan, PlanCost, _T]], best: PlanCost) -> tuple[Plan, PlanCost, _T] | None:
        """Of the candidates (plan, cost as planned, what made it), the one of least objective as
        executed (:meth:`priced`), the first of equals; None without candidates. Priced lazily,
        cheapest as planned first: one whose cost as planned is no less than the best found, or
        than the ``best`` plan's, is not priced (executing with robots kept apart adds waits and
        detours, never takes away)."""
        order = sorted(range(len(costed)), key=lambda i: (self.value(costed[i][1]), i))
        if not order:
            return None
        if self.executed is None:
            return costed[order[0]]
        limit = self.value(best)
        found: tuple[Plan, PlanCost, _T] | None = None
        for i in order:
            plan, cost, made = costed[i]
            if self.value(cost) >= min(limit, self.value(found[1]) if found is not None else math.inf):
                break
            executed = self.priced(plan, cost)
            if found is None or self.value(executed) < self.value(found[1]):
                found = (plan, executed, made)
        return found if found is not None else costed[order[0]]

    def value(self, cost: PlanCost) -> float:
        """The objective of a plan of this cost (tmpnav.task.objectives), ranked below every plan
        kept apart where robots are still in each other's way and every plan that keeps the
        minimum where it lacks rooms (``PlanCost.ranked``)."""
        return cost.ranked(self.span_weight)
