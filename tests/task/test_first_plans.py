"""The anytime search's first plans where the objective prices time: OR-Tools' routes with the
objective's price of a second and with the longest route first, the better by the objective
(tmpnav.task.search.AnytimeSearch._makespan_routing). OR-Tools is replaced by routes given here,
so that the choice is tested whatever its local search finds; the table is eight rooms on a line
and four robots (tests/task/test_balance.py)."""

from __future__ import annotations

from typing import Any

import pytest

from tests.task.test_balance import ROBOTS, ROOMS, line_table
from tmpnav.task import search as search_module
from tmpnav.task.model import TableModel
from tmpnav.task.objectives import MAKESPAN_WEIGHT
from tmpnav.task.routing import Routes
from tmpnav.task.search import UNDER_WAY, SearchOptions, search
from tmpnav.types import Goals

GOALS = Goals(visit=ROOMS, per_robot=())
#: r1 and r2 take every room, r3 and r4 stand idle: cheap in moves (each robot drives its end
#: of the line), 40 s of makespan
IDLE = {"r1": ROOMS[:4], "r2": tuple(reversed(ROOMS[4:])), "r3": (), "r4": ()}
#: each robot takes two rooms near it, r1 and r2 the far one first: dearer in moves (90 m), 30 s
SPREAD = {"r1": (ROOMS[1], ROOMS[0]), "r2": (ROOMS[6], ROOMS[7]), "r3": ROOMS[2:4], "r4": ROOMS[4:6]}


def routed(monkeypatch: pytest.MonkeyPatch, by_weight: dict[float, dict[str, tuple[str, ...]]]) -> list[float]:
    """OR-Tools' first routes replaced: the routes of ``by_weight`` for each span weight asked
    (IDLE for any other); returns the span weights the search asked for, in order."""
    asked: list[float] = []

    def fake(*args: Any, span_weight: float, **kwargs: Any) -> tuple[Routes, bool]:
        asked.append(span_weight)
        rooms = by_weight.get(span_weight, IDLE)
        return Routes(dict(rooms), 0.0, "ROUTING_SUCCESS", "nothing"), False

    monkeypatch.setattr(search_module, "first_routes", fake)
    return asked


def run(span_weight: float, seeds: dict | None = None) -> Any:
    options = SearchOptions(budget=30, work=0, span_weight=span_weight, parallel=1, route_candidates=0)
    return search(TableModel(line_table()), GOALS, options, seeds=seeds)


def rooms_per_robot(plan: Any) -> dict[str, int]:
    out = dict.fromkeys(ROBOTS, 0)
    for step in plan:
        for r, _, _ in step:
            out[r] += 1
    return out


def test_the_makespan_first_routes_start_the_search_where_they_are_better_by_the_objective(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    asked = routed(monkeypatch, {1.0: IDLE, MAKESPAN_WEIGHT: SPREAD})
    result = run(span_weight=1.0)
    assert sorted(asked) == [1.0, MAKESPAN_WEIGHT]  # the second beside the first
    assert result.start.endswith("the makespan first")
    assert min(rooms_per_robot(result.plan).values()) == 2
    # IDLE: 8 + 40 s; SPREAD: 9 + 30 s (a move costs a tenth of its metres)
    assert result.cost.value(1.0) == pytest.approx(39.0)


def test_the_objectives_own_routes_stay_where_they_are_as_good(monkeypatch: pytest.MonkeyPatch) -> None:
    asked = routed(monkeypatch, {0.01: IDLE, MAKESPAN_WEIGHT: SPREAD})
    result = run(span_weight=0.01)  # IDLE: 8 + 0.4; SPREAD: 9 + 0.3
    assert sorted(asked) == [0.01, MAKESPAN_WEIGHT]
    assert not result.start.endswith("the makespan first")
    assert result.cost.value(0.01) == pytest.approx(8.4)


@pytest.mark.parametrize("span_weight", [0.0, MAKESPAN_WEIGHT])
def test_routes_are_asked_once_where_time_is_free_or_already_first(
    monkeypatch: pytest.MonkeyPatch, span_weight: float
) -> None:
    asked = routed(monkeypatch, {})
    run(span_weight=span_weight)
    assert asked == [span_weight]


def test_a_replan_starts_from_the_plan_under_way_only(monkeypatch: pytest.MonkeyPatch) -> None:
    """A replan's routes start from the plan being executed, which already settles the team's
    balance: no second routing from scratch."""
    asked = routed(monkeypatch, {1.0: IDLE, MAKESPAN_WEIGHT: SPREAD})
    under_way = tuple(
        ((r, origin, room),)
        for r, rooms in IDLE.items()
        for origin, room in zip((f"{r}-start", *rooms), rooms, strict=False)
    )
    result = run(span_weight=1.0, seeds={UNDER_WAY: under_way})
    assert asked == [1.0]
    assert not result.start.endswith("the makespan first")


def test_no_second_first_plan_after_a_first_routing_that_ran_out_of_time(monkeypatch: pytest.MonkeyPatch) -> None:
    """The second routing ran beside the first; its routes are dropped: the first plan is the
    machine's already, and a second would only add to what depends on its speed."""
    asked: list[float] = []

    def slow(*args: Any, span_weight: float, **kwargs: Any) -> tuple[Routes, bool]:
        asked.append(span_weight)
        return Routes(dict(IDLE), 0.0, "ROUTING_SUCCESS", "nothing", timed_out=True), True

    monkeypatch.setattr(search_module, "first_routes", slow)
    result = run(span_weight=1.0)
    assert sorted(asked) == [1.0, MAKESPAN_WEIGHT]
    assert not result.start.endswith("the makespan first")
