"""The makespan's lower bound counts what a robot must do: its way to a goal from its start, the
wait for the goal's window, the service, and its way on to its end (tmpnav.task.bound.makespan_bound).

Small shifts in the plane: robots start at their docks and must end there, stations have
service times, windows and robots that may serve them. Durations are distances over a speed
(they obey the triangle inequality, as time floors do); the optimum over every schedule is the
exact A* of tmpnav.task.schedules, which the bound must never exceed, and on a shift whose
optimum is one robot's unavoidable round trip the bound must reach it.
"""

from __future__ import annotations

import math
import random

import pytest

from tmpnav.task.bound import makespan_bound, round_trip
from tmpnav.task.objectives import MAKESPAN_WEIGHT
from tmpnav.task.schedules import exact_schedule
from tmpnav.task.timing import schedule, table_durations
from tmpnav.types import CostTable, Goals, Job

SPEED = 0.5  # m/s


def shift_table(points: dict[str, tuple[float, float]], docks: dict[str, str], goals: Goals) -> CostTable:
    """Every robot's moves between the stations and its own dock (back to it included), at a cost
    of their length and a duration of length / SPEED plus the service at the target."""
    rooms = tuple(goals.all_rooms)
    single, duration = {}, {}
    for r, dock in docks.items():
        for o in (dock, *goals.visit):
            for t in (*goals.visit, dock):
                if o == t or not goals.may_visit(r, t):
                    continue
                length = math.dist(points[o], points[t])
                single[(r, o, t)] = length
                duration[(r, o, t)] = length / SPEED
    table = CostTable(tuple(docks), rooms, rooms, dict(docks), single, {}, duration)
    return table.with_service(goals)


def optimal_makespan(table: CostTable, goals: Goals) -> float:
    found = exact_schedule(table, goals, 0.0, MAKESPAN_WEIGHT)
    assert found is not None
    plan, _ = found
    timed = schedule(plan, table.robots, table_durations(table), goals=goals)
    assert timed is not None
    return timed.makespan


def the_issues_shift() -> tuple[CostTable, Goals]:
    """r1's dock is near A, whose window opens late; B is r2's alone. The best shift: r1 serves A
    and goes back (20 m there, a wait until 50 s, 30 s of service, 20 m back: 100 s), r2 serves B."""
    points = {"D1": (0.0, 0.0), "D2": (30.0, 0.0), "A": (10.0, 0.0), "B": (30.0, 5.0)}
    jobs = (Job("A", service=30.0, window=(50.0, 200.0)), Job("B", service=10.0, robots=("r2",)))
    goals = Goals(visit=("A", "B"), per_robot=(), jobs=jobs, ends=(("r1", "D1"), ("r2", "D2")))
    return shift_table(points, {"r1": "D1", "r2": "D2"}, goals), goals


def test_a_plan_at_the_optimum_is_within_a_few_percent_of_the_bound() -> None:
    """Before the bound counted the way back, the service and the window, it was 50 s here (r1's
    quickest arrival at A with the service), half the optimum."""
    table, goals = the_issues_shift()
    optimum = optimal_makespan(table, goals)
    assert optimum == pytest.approx(100.0)
    assert round_trip(table, goals, "r1", "A") == pytest.approx(100.0)
    assert makespan_bound(table, goals) == pytest.approx(optimum)


def test_a_robot_not_allowed_at_a_station_does_not_lower_its_trip() -> None:
    """B is r2's alone: r1, whose dock is as near, does not count (r2: 10 s there, 10 s of
    service, 10 s back)."""
    table, goals = the_issues_shift()
    only_b = Goals(visit=("B",), per_robot=(), jobs=goals.jobs, ends=goals.ends)
    assert makespan_bound(table, only_b) == pytest.approx(30.0)


def test_of_three_stations_two_robots_serve_one_twice() -> None:
    """Two robots, three stations of 30 s a metre apart, 20 m east of both docks: one robot
    serves two of them, so the shift lasts at least the least trip through two (40 s out, 30 s,
    2 s on, 30 s, 40 s back: 142 s), more than any one station's round trip (110 s). Without
    this pigeonhole bound the makespan's bound was 110.4 s."""
    points = {"D1": (0.0, 0.0), "D2": (0.0, 1.0), "A": (20.0, 0.0), "B": (20.0, 1.0), "C": (20.0, 2.0)}
    jobs = tuple(Job(x, service=30.0) for x in "ABC")
    goals = Goals(visit=("A", "B", "C"), per_robot=(), jobs=jobs, ends=(("r1", "D1"), ("r2", "D2")))
    table = shift_table(points, {"r1": "D1", "r2": "D2"}, goals)
    assert max(round_trip(table, goals, r, x) for r in ("r1", "r2") for x in "ABC") < 111.0
    bound, optimum = makespan_bound(table, goals), optimal_makespan(table, goals)
    assert 140.0 <= bound <= optimum + 1e-9
    assert bound == pytest.approx(optimum, rel=0.02)


def random_shift(seed: int) -> tuple[CostTable, Goals]:
    rnd = random.Random(seed)
    robots = rnd.choice([2, 3])
    stations = rnd.randint(2, 4)
    points = {f"D{k + 1}": (rnd.uniform(0, 30), rnd.uniform(0, 15)) for k in range(robots)}
    points |= {f"S{k + 1}": (rnd.uniform(0, 30), rnd.uniform(0, 15)) for k in range(stations)}
    names = [f"r{k + 1}" for k in range(robots)]
    jobs = []
    for k in range(stations):
        window = (rnd.uniform(0, 60), 1e4) if rnd.random() < 0.4 else None
        allowed = tuple(rnd.sample(names, robots - 1)) if rnd.random() < 0.3 else ()
        jobs.append(Job(f"S{k + 1}", service=float(rnd.choice([0, 10, 30, 60])), robots=allowed, window=window))
    docks = {r: f"D{k + 1}" for k, r in enumerate(names)}
    goals = Goals(visit=tuple(j.room for j in jobs), per_robot=(), jobs=tuple(jobs), ends=tuple(docks.items()))
    return shift_table(points, docks, goals), goals


@pytest.mark.parametrize("seed", range(20))
def test_the_bound_never_exceeds_the_optimal_makespan(seed: int) -> None:
    table, goals = random_shift(seed)
    optimum = optimal_makespan(table, goals)
    bound = makespan_bound(table, goals)
    assert bound <= optimum + 1e-6
    # the station farthest from every robot allowed there is a round trip every plan makes
    assert bound >= max(min(round_trip(table, goals, r, x) for r in table.robots if goals.may_visit(r, x))
                        for x in goals.visit) - 1e-9  # fmt: skip
