"""The schedule's readings shared by the reports: step windows, driving steps, the objective."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from tmpnav.report.schedule import driving_steps, move_at, objective_values, step_windows
from tmpnav.results import Schedule, TimedMove

#: r1 drives to C (step 0), then with r2 to B (step 1, paired: r2 waits 2 s for r1); r3 stays
#: where it is: its move (step 2) has no length
SCHEDULE = Schedule(
    ("r1", "r2", "r3"),
    (
        TimedMove(0, "r1", "A", "C", None, 0.0, 0.0, 2.0),
        TimedMove(1, "r1", "C", "B", "r2", 2.0, 2.0, 3.5),
        TimedMove(1, "r2", "B", "A", "r1", 0.0, 2.0, 4.0),
        TimedMove(2, "r3", "A", "A", None, 0.0, 0.0, 0.0),
    ),
)


def test_step_windows() -> None:
    assert step_windows(SCHEDULE, 3) == [(0.0, 2.0), (2.0, 4.0), (0.0, 0.0)]
    assert step_windows(SCHEDULE, 4)[3] is None  # a step the schedule does not hold (never expected)
    assert step_windows(Schedule((), ()), 0) == []


def test_driving_steps_count_the_control_steps_of_each_move() -> None:
    times = [0.5 * k for k in range(9)]  # the shared clock, 0 to the makespan (4 s)
    assert driving_steps(SCHEDULE, "r1", times) == [None, 1, 1, 1, 1, 2, 2, 2, None]
    assert driving_steps(SCHEDULE, "r2", times) == [None, None, None, None, None, 2, 2, 2, 2]
    assert driving_steps(SCHEDULE, "r3", times) == [None] * 9
    # rounded times (1e-9 s) fall in the same steps
    assert driving_steps(SCHEDULE, "r1", [2.0 + 1e-9, 2.0 + 5e-1 - 1e-9]) == [1, 2]
    busy = sum(a is not None for a in driving_steps(SCHEDULE, "r2", times)) * 0.5
    assert busy == SCHEDULE.busy("r2")


def test_move_at() -> None:
    assert move_at(SCHEDULE, "r2", 1.0) is None  # waiting
    found = move_at(SCHEDULE, "r2", 3.0)
    assert found is not None and found.target == "A" and found.partner == "r1"
    assert move_at(SCHEDULE, "r1", 4.0) is None  # done


@pytest.mark.slow
def test_objective_values(plan_report: Any) -> None:
    o = objective_values(plan_report)
    assert (o.name, o.span_weight) == ("cost", 0.0)  # the test plan's: the paper's objective
    assert o.value == plan_report.resimulated_cost and o.planner_value == plan_report.planner_cost
    assert o.makespan == plan_report.schedule.makespan and o.planner_makespan == plan_report.task.makespan
    planner = dataclasses.replace(plan_report.scenario.planner, objective="weighted")
    weighted = dataclasses.replace(plan_report, scenario=dataclasses.replace(plan_report.scenario, planner=planner))
    o = objective_values(weighted)
    m_t = plan_report.scenario.cost.M_T
    assert o.span_weight == m_t and o.value == pytest.approx(plan_report.resimulated_cost + m_t * o.makespan)
    slower = dataclasses.replace(
        plan_report.task.schedule,
        moves=tuple(dataclasses.replace(m, end=m.end + 1.0) for m in plan_report.task.schedule.moves),
    )
    o = objective_values(dataclasses.replace(weighted, task=dataclasses.replace(plan_report.task, schedule=slower)))
    assert o.planner_makespan == o.makespan + 1.0 and o.differs()
