"""Jobs' windows, robots' ends and optional goals in the exact search: 50 seeded random instances
of 2 robots and up to 7 goals (rooms to visit and ends), each a table with durations, a few
windows, services, ends (a robot that starts at its dock and must come back to it, one that must
finish in another room) and, in half of them, an optional goal with a penalty. An independent
enumeration of every plan (each robot's rooms in every order, each optional goal done by either
robot or left undone; single moves on one clock: a robot that arrives before a window opens
waits, one that would arrive after it closes may not) gives the optimum of cost + makespan +
penalties; the exact search must reach it, and its plan's schedule must keep every window."""

from __future__ import annotations

import itertools
import math
import random
from concurrent.futures import ThreadPoolExecutor

import pytest

from tmpnav.task.model import TableModel
from tmpnav.task.plans import Plan, Rules
from tmpnav.task.schedules import exact_schedule
from tmpnav.task.search import SearchOptions, search
from tmpnav.task.timing import schedule, table_durations
from tmpnav.types import CostTable, Goals, Job, MoveKey

SPAN_WEIGHT = 1.0


def instance(seed: int) -> tuple[CostTable, Goals]:
    rnd = random.Random(seed)
    robots = ("r1", "r2")
    start = {"r1": "D1", "r2": "r2-start"}  # r1 starts at its dock
    ends: list[tuple[str, str]] = []
    if rnd.random() < 0.6:
        ends.append(("r1", "D1"))
    if rnd.random() < 0.4:
        ends.append(("r2", "D2"))
    rooms = [f"L{i + 1}" for i in range(rnd.randint(3, 7 - len(ends)))]  # up to 7 goals, ends included
    locations = (*rooms, "D1", "D2", "r2-start")
    xy = {x: (rnd.uniform(0, 20), rnd.uniform(0, 10)) for x in locations}
    single: dict[MoveKey, float] = {}
    duration: dict[MoveKey, float] = {}
    service = {x: rnd.choice([0.0, 0.0, 5.0]) for x in rooms}
    for r in robots:
        for a, b in itertools.permutations(locations, 2):
            if b in ("r2-start",) or (b == start[r] and (r, b) not in ends) or (b == "D2" and ("r2", "D2") not in ends):
                continue
            d = math.dist(xy[a], xy[b]) + rnd.uniform(0.5, 2.0)
            single[(r, a, b)] = d
            duration[(r, a, b)] = round(2.0 * d, 1) + service.get(b, 0.0)
    jobs = []
    for x in rnd.sample(rooms, rnd.randint(1, min(3, len(rooms)))):
        earliest = rnd.uniform(0.0, 60.0)
        jobs.append(Job(x, service[x], (), None, (round(earliest, 1), round(earliest + rnd.uniform(5.0, 80.0), 1))))
    jobs += [Job(x, service[x]) for x in rooms if service[x] and x not in {j.room for j in jobs}]
    if rnd.random() < 0.5:  # an optional goal, left undone at a penalty
        room = rnd.choice(rooms)
        jobs = [j for j in jobs if j.room != room]
        jobs.append(Job(room, service[room], (), None, None, round(rnd.uniform(5.0, 60.0), 1)))
    goals = Goals(tuple(rooms), (), tuple(jobs), tuple(ends))
    table = CostTable(robots, tuple(rooms), locations, start, single, {}, duration)
    return table, goals


def enumerate_optimum(table: CostTable, goals: Goals) -> float:
    """The least cost + SPAN_WEIGHT x makespan over every assignment and order of the rooms."""
    rooms = list(goals.visit)
    best = math.inf
    takers = [(*table.robots, None) if x in goals.optional else table.robots for x in rooms]  # None: left undone
    for owners in itertools.product(*takers):
        mine = {r: [x for x, o in zip(rooms, owners, strict=True) if o == r] for r in table.robots}
        dropped = sum(goals.optional[x] for x, o in zip(rooms, owners, strict=True) if o is None)
        for orders in itertools.product(*(itertools.permutations(mine[r]) for r in table.robots)):
            total, span = 0.0, 0.0
            for r, order in zip(table.robots, orders, strict=True):
                route = list(order)
                end = goals.end_of(r)
                if end is not None and (route or table.start_location[r] != end):
                    route.append(end)
                cost, clock = _route(table, goals, r, route)
                total, span = total + cost, max(span, clock)
                if not math.isfinite(total):
                    break
            best = min(best, total + dropped + SPAN_WEIGHT * span)
    return best


def _route(table: CostTable, goals: Goals, robot: str, route: list[str]) -> tuple[float, float]:
    """One robot's route alone on the clock: its cost and when it is done (inf: impossible)."""
    here, clock, cost = table.start_location[robot], 0.0, 0.0
    for x in route:
        m = (robot, here, x)
        if m not in table.single:
            return math.inf, math.inf
        arrive = clock + table.duration[m] - goals.service(x)
        window = goals.window(x)
        if window is not None and arrive > window[1] + 1e-6:
            return math.inf, math.inf
        clock = max(arrive, window[0] if window else arrive) + goals.service(x)
        cost, here = cost + table.single[m], x
    return cost, clock


@pytest.mark.parametrize("seed", range(50))
def test_the_exact_search_keeps_windows_and_ends_and_is_optimal(seed: int) -> None:
    table, goals = instance(seed)
    optimum = enumerate_optimum(table, goals)
    found = exact_schedule(table, goals, 0.0, SPAN_WEIGHT)
    if not math.isfinite(optimum):
        assert found is None  # no plan meets the windows: the search finds none
        return
    assert found is not None
    plan, value = found
    assert value == pytest.approx(optimum, rel=1e-9, abs=1e-6)
    Rules(table.start_location, goals).check(plan)  # every goal, every end, as the rules say
    timed = schedule(plan, table.robots, table_durations(table), goals=goals)
    assert timed is not None and not timed.late(goals.windows)
    for m in timed.moves:
        window = goals.window(m.target)
        if window is not None:  # served within its window: arrived by the latest, served from the earliest
            assert m.end <= window[1] + 1e-6
            assert m.end + m.opens >= window[0] - 1e-6
    for r, end in goals.ends:
        assert ([m.target for m in timed.timeline(r)] or [table.start_location[r]])[-1] == end
    penalty = goals.drop_penalty({*table.start_location.values(), *(m[2] for step in plan for m in step)})
    total = sum(table.single[m] for step in plan for m in step)
    assert timed.makespan + total + penalty == pytest.approx(value, rel=1e-9)


def _anytime(seed: int) -> tuple[int, float, float, Plan]:
    table, goals = instance(seed)
    found = exact_schedule(table, goals, 0.0, SPAN_WEIGHT)
    optimum = math.inf if found is None else found[1]
    options = SearchOptions(budget=60, seed=seed, min_gain=0.0, span_weight=SPAN_WEIGHT, parallel=1)
    result = search(TableModel(table, 0.0, goals), goals, options)
    return seed, result.cost.value(SPAN_WEIGHT), optimum, result.plan


@pytest.mark.slow
def test_the_anytime_search_never_breaks_a_window_and_mostly_finds_the_optimum() -> None:
    """The first 25 instances through the anytime search (OR-Tools' first plan with its time
    windows, ENHSP's sub-problems, every plan priced on the clock with its windows): every plan
    it returns keeps every window, every end and every goal, and most reach the exact optimum."""
    with ThreadPoolExecutor(max_workers=2) as pool:  # each search waits on ENHSP processes
        outcomes = list(pool.map(_anytime, range(25)))
    equal = 0
    for seed, value, optimum, plan in outcomes:
        table, goals = instance(seed)
        Rules(table.start_location, goals).check(plan)
        timed = schedule(plan, table.robots, table_durations(table), goals=goals)
        assert timed is not None and not timed.late(goals.windows), seed
        assert value >= optimum - 1e-6, seed
        equal += abs(value - optimum) <= 1e-6 * max(1.0, optimum)
    assert equal >= 22, f"{equal} of 25 instances at the exact optimum"  # 25 when written (49 of 50)


@pytest.mark.slow
def test_enhsps_problem_holds_the_windows() -> None:
    """The PDDL text ENHSP solves (tmpnav.task.pddl_text) holds the jobs' windows: grounded moves
    into rooms with a window, on the team's clock. On 12 of the instances, ENHSP's plan of the
    whole problem keeps every window, end and goal, and its value is the exact optimum or above."""
    from tmpnav.task.pddl_text import write_task
    from tmpnav.task.plans import with_origins

    for seed in range(12):
        table, goals = instance(seed)
        task = write_task(table, goals, "mixed", span_weight=SPAN_WEIGHT)
        assert bool(goals.windows) == ("(windowed " in task.problem) == bool(task.window_actions)
        steps = task.decode(task.solve("enhsp-blind", 120))
        plan = with_origins([[(r, t) for r, _, t in step] for step in steps], table.start_location)
        Rules(table.start_location, goals).check(plan)
        timed = schedule(plan, table.robots, table_durations(table), goals=goals)
        assert timed is not None and not timed.late(goals.windows), seed
        value = TableModel(table, 0.0, goals).plan_cost(plan).value(SPAN_WEIGHT)
        found = exact_schedule(table, goals, 0.0, SPAN_WEIGHT)
        assert found is not None and value >= found[1] - 1e-6, seed
