"""Time in the objective: the exact search's plan is the optimum over every schedule.

Random small instances (up to 6 rooms, 2-3 robots) get durations for every move. An
independent search enumerates every plan of the ``mixed`` encoding's rules, robot by robot on
the team's clock (a move starts when its robot is free, a paired move when both are), with a
dynamic programme over (task state, clocks): the objective of the best schedule is its table
cost plus ``span_weight`` times its makespan. ENHSP's plan of the clock encoding
(tmpnav.task.pddl_text) must reach it, and its own schedule (tmpnav.task.timing) must score it.
"""

from __future__ import annotations

import functools
import math
import random

import pytest

from tests.task.instances import Rules, small_instance
from tmpnav.task.model import PlanCost, TableModel
from tmpnav.task.objectives import MAKESPAN_WEIGHT, OBJECTIVES
from tmpnav.task.schedules import exact_schedule
from tmpnav.task.timing import schedule, table_durations
from tmpnav.types import CostTable, CostWeights, Goals

MIN_GAIN = 0.05


def with_durations(table: CostTable, rnd: random.Random) -> CostTable:
    """The table with a duration for every move: its cost's drive, and a little noise; a pair's
    two robots take about their single moves' times."""
    duration = {m: round(c * rnd.uniform(1.5, 3.0), 1) for m, c in table.single.items()}
    pair_duration = {
        (m1, m2): (duration[m1] * rnd.uniform(0.9, 1.1), duration[m2] * rnd.uniform(0.9, 1.1)) for m1, m2 in table.pair
    }
    return CostTable(
        table.robots,
        table.rooms,
        table.locations,
        table.start_location,
        table.single,
        table.pair,
        duration,
        pair_duration,
    )


def schedule_optimum(table: CostTable, goals: Goals, span_weight: float, min_gain: float = MIN_GAIN) -> float:
    """The least cost + span_weight x makespan over every plan (every schedule), by enumeration."""
    rules = Rules(table, goals, min_gain)
    robots = table.robots

    @functools.cache
    def best(state: tuple, clocks: tuple[float, ...], span: float) -> float:
        if rules.done(state):
            return 0.0
        out = math.inf
        for cost, step, nxt in _steps(rules, state):
            idx = [robots.index(m[0]) for m in step]
            start = max(clocks[i] for i in idx)
            times = _durations(table, step)
            new = list(clocks)
            for i, d in zip(idx, times, strict=True):
                new[i] = start + d
            new_span = max(span, *(new[i] for i in idx))
            out = min(out, cost + span_weight * (new_span - span) + best(nxt, tuple(new), new_span))
        return out

    return best(rules.start(), (0.0,) * len(robots), 0.0)


def _steps(rules: Rules, state: tuple):  # type: ignore[no-untyped-def]
    """(cost, step, next state) of every step the rules allow in ``state``."""
    import itertools

    pos = state[0]
    for r, o in zip(rules.robots, pos, strict=True):
        for m in rules.singles.get((r, o), ()):
            if rules.may_enter(r, m[2], state):
                yield rules.table.single[m], (m,), rules.apply(state, (m,))
    for (r1, o1), (r2, o2) in itertools.combinations(zip(rules.robots, pos, strict=True), 2):
        for step, c in rules.pairs.get((r1, o1, r2, o2), ()):
            if all(rules.may_enter(r, t, state) for r, _, t in step):
                yield c, step, rules.apply(state, step)


def _durations(table: CostTable, step: tuple) -> tuple[float, ...]:
    found = table_durations(table)(step)
    assert found is not None
    return found


def instance(seed: int) -> tuple[CostTable, Goals]:
    rnd = random.Random(seed)
    table, goals = small_instance(rnd, rnd.choice([2, 3]), rnd.randint(3, 6), 0.3)
    return with_durations(table, rnd), goals


#: 24 instances: seeds 0 and 9 gave way to 24 and 25, the next ones. On seed 0 (3 robots, 6 rooms,
#: 800 pairs) the enumeration of every schedule took 40 s per objective, on seed 9 (3 robots, 4
#: rooms) 11-14 s, where the other instances take at most 2 s; seeds 24 and 25 are 3-robot ones too
SEEDS = [s for s in range(26) if s not in (0, 9)]


@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("objective", ["weighted", "makespan"])
def test_the_exact_search_is_the_optimum_over_every_schedule(seed: int, objective: str) -> None:
    table, goals = instance(seed)
    span = OBJECTIVES[objective].span_weight(CostWeights(1.0, 1.0, 1.0, 2.0))  # type: ignore[index]
    found = exact_schedule(table, goals, MIN_GAIN, span)
    assert found is not None
    plan, value = found
    optimum = schedule_optimum(table, goals, span)
    ours = TableModel(table, MIN_GAIN).plan_cost(plan)
    assert ours.value(span) == pytest.approx(value, rel=1e-9)
    scale = MAKESPAN_WEIGHT if objective == "makespan" else 1.0
    assert value == pytest.approx(optimum, rel=1e-9, abs=1e-6 * scale), (seed, plan)


def test_a_paired_move_starts_when_both_robots_are_free() -> None:
    table = CostTable(
        ("r1", "r2"),
        ("A", "B", "C"),
        ("A", "B", "C", "s1", "s2"),
        {"r1": "s1", "r2": "s2"},
        {("r1", "s1", "A"): 1.0, ("r2", "s2", "B"): 1.0, ("r1", "A", "C"): 1.0, ("r2", "B", "C"): 1.0},
        {},
        {("r1", "s1", "A"): 10.0, ("r2", "s2", "B"): 4.0, ("r1", "A", "C"): 5.0, ("r2", "B", "C"): 5.0},
        {(("r1", "A", "C"), ("r2", "B", "C")): (5.0, 7.0)},
    )
    plan = ((("r1", "s1", "A"),), (("r2", "s2", "B"),), (("r1", "A", "C"), ("r2", "B", "C")))
    found = schedule(plan, table.robots, table_durations(table))
    assert found is not None
    r2 = found.timeline("r2")
    assert [(m.ready, m.start, m.end) for m in r2] == [(0.0, 0.0, 4.0), (4.0, 10.0, 17.0)]  # r2 waits 6 s for r1
    assert found.makespan == 17.0 and found.waits("r2") == 6.0 and found.waits("r1") == 0.0
    assert found.busy("r1") == 15.0 and found.idle("r1") == 2.0
    assert found.busy("r2") == 11.0 and found.idle("r2") == 0.0  # busy + waits + idle = makespan


@pytest.mark.parametrize("objective", ["weighted", "cost", "makespan"])
def test_a_conflict_left_or_a_room_short_ranks_below_any_plan_without_under_every_objective(objective: str) -> None:
    """The search's rank puts a plan ``tmpnav plan`` would refuse (a conflict left) or one short of
    the minimum below every plan without, whatever its objective: under ``makespan`` too, where a
    price of 10^6 cost units alone would be worth only 100 s, and a plan 100 s shorter that the
    command refuses would win."""
    weight = OBJECTIVES[objective].span_weight(CostWeights(1.0, 1.0, 1.0))
    refused = PlanCost(50.0, (50.0,), span=100.0, unsafe=1)
    short = PlanCost(50.0, (50.0,), span=100.0, short=1)
    slow = PlanCost(5000.0, (5000.0,), span=5000.0)  # 50 times as long, 100 times the cost
    assert refused.ranked(weight) > slow.ranked(weight) and short.ranked(weight) > slow.ranked(weight)
    assert refused.value(weight) < slow.value(weight)  # its own objective is its own
