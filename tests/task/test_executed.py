"""The anytime search judges a plan as it will be executed: a plan that is cheap as planned but
dear as executed (robots kept apart by waits) loses to the plan that is cheapest as executed,
and only the plans that could beat the best are priced."""

from __future__ import annotations

import random

from tests.task.instances import small_instance
from tmpnav.task.model import PlanCost, TableModel
from tmpnav.task.plans import Plan
from tmpnav.task.search import SearchOptions, search
from tmpnav.types import Goals

MIN_GAIN = 0.05
PENALTY = 1000.0


def problem(seed: int) -> tuple[TableModel, Goals, SearchOptions]:
    """A random cost table of 5 rooms and 2 robots (tests/task/instances.py), its goals, options."""
    table, goals = small_instance(random.Random(seed), 2, 5, 0.3)
    return TableModel(table, MIN_GAIN), goals, SearchOptions(budget=60, seed=seed, min_gain=MIN_GAIN, parallel=1)


def test_a_plan_dear_as_executed_is_not_the_plan_returned() -> None:
    model, goals, options = problem(3)
    planned = search(model, goals, options)
    dear = planned.plan
    priced: list[Plan] = []

    def executed(plan: Plan, cost: PlanCost) -> PlanCost:
        priced.append(plan)
        if plan != dear:
            return cost
        return PlanCost(cost.total + PENALTY, cost.steps, cost.schedule, cost.dropped)

    result = search(model, goals, options, executed=executed)
    assert result.plan != dear
    assert result.cost == executed(result.plan, model.plan_cost(result.plan))  # its cost is as executed
    assert result.cost.total < planned.cost.total + PENALTY
    # the first plan and every plan that beat the best as planned, not every candidate
    assert len(set(priced)) <= result.stats.subproblems + result.stats.improvements + 4


def test_without_a_price_the_search_is_unchanged() -> None:
    model, goals, options = problem(5)
    plain = search(model, goals, options)
    same = search(model, goals, options, executed=lambda plan, cost: cost)
    assert (same.plan, same.cost.total) == (plain.plan, plain.cost.total)
