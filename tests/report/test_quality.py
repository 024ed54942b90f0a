"""Warnings about a plan's quality: far from its bound, or more uncertain than a door allows."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from tmpnav.report.plan_json import dumps, plan_document
from tmpnav.report.quality import GAP_WARN, _crossings, plan_warnings
from tmpnav.report.text import plan_summary
from tmpnav.results import BoundSummary, PlanReport, SearchSummary


def with_gap(report: PlanReport, gap: float, stopped: str = "work budget") -> PlanReport:
    cost = report.planner_cost
    bound = BoundSummary(cost * (1 - gap), "motion floors, flow", gap, False)
    search = SearchSummary("anytime", "carried", stopped)
    return dataclasses.replace(report, task=dataclasses.replace(report.task, bound=bound, search=search))


def uncertain(report: PlanReport, factor: float) -> PlanReport:
    """The plan with every covariance ``factor`` times larger (as if localization were poor)."""
    trajectories = {
        robot: [dataclasses.replace(s, cov=tuple(tuple(factor * v for v in row) for row in s.cov)) for s in steps]
        for robot, steps in report.trajectories.items()
    }
    return dataclasses.replace(report, trajectories=trajectories)


def test_crossings_of_a_door() -> None:
    path = np.array([[0.0, 0.0], [0.0, 1.0], [0.0, 2.0], [3.0, 2.0], [3.0, 0.0]])
    door = np.array([-0.5, 1.5]), np.array([0.5, 1.5])  # crossed by the first leg only
    assert _crossings(path, *door) == [2]
    assert _crossings(path[::-1], *door) == [3]


@pytest.mark.slow
def test_a_good_plan_has_no_warning(plan_report: PlanReport) -> None:
    assert plan_warnings(plan_report) == []
    assert "warning:" not in plan_summary(plan_report)
    assert plan_document(plan_report)["warnings"] == []


@pytest.mark.slow
def test_a_plan_far_from_its_bound_says_so_with_the_numbers_and_what_to_try(plan_report: PlanReport) -> None:
    assert plan_warnings(with_gap(plan_report, GAP_WARN - 0.01)) == []
    far = with_gap(plan_report, 0.87)
    (warning,) = plan_warnings(far)
    assert warning.kind == "gap" and warning.value == pytest.approx(0.87) and warning.limit == GAP_WARN
    assert "87% below its cost" in warning.message and "try --anytime-work" in warning.message
    assert "motion floors" in warning.message
    converged = plan_warnings(with_gap(plan_report, 0.87, stopped="converged"))[0].message
    assert "stopped improving" in converged and "time budget" not in converged


@pytest.mark.slow
def test_a_robot_more_uncertain_than_a_door_allows_is_named(plan_report: PlanReport) -> None:
    poor = uncertain(plan_report, 100.0)  # std x10: 2-sigma spreads of metres in 1.2 m doors
    warnings = plan_warnings(poor)
    assert {w.robot for w in warnings if w.kind == "door"} == {"r1", "r2"}
    for w in warnings:
        assert w.value > w.limit == pytest.approx(0.35)  # 1.2 m doors, robots of radius 0.25 m
        assert f"{w.value:.2f} m across it" in w.message and "door-" in w.message
    lines = plan_summary(poor).splitlines()
    shown = [line for line in lines if line.startswith("warning: ")]
    assert len(shown) == 2 and all(len(line) <= 100 for line in lines if line.startswith(("warning", "  ")))
    doc = json.loads(dumps(plan_document(poor)))
    assert [w["kind"] for w in doc["warnings"]] == ["door", "door"] and doc["warnings"][0]["robot"] == "r1"


@pytest.mark.slow
def test_with_a_price_on_time_the_gap_is_on_the_objective(plan_report: PlanReport) -> None:
    planner = dataclasses.replace(plan_report.scenario.planner, objective="weighted")
    weighted = dataclasses.replace(plan_report, scenario=dataclasses.replace(plan_report.scenario, planner=planner))
    (warning,) = plan_warnings(with_gap(weighted, 0.87))
    m_t = weighted.scenario.cost.M_T
    value = weighted.planner_cost + m_t * weighted.task.makespan
    assert f"87% below its objective (weighted: cost + {m_t:g} per s of makespan), {value:.3f}" in warning.message
    assert "no price on the makespan" in warning.message


@pytest.mark.slow
def test_a_door_warning_says_when_on_the_shared_clock_and_which_move(plan_report: PlanReport) -> None:
    for w in plan_warnings(uncertain(plan_report, 100.0)):
        t = float(w.message.split(" at t ")[1].split(" s,")[0])
        move = next(m for m in plan_report.schedule.timeline(str(w.robot)) if m.start < t <= m.end + 0.05)
        assert f"on its way to {move.target} (step {move.step + 1})" in w.message


def test_keeping_robots_apart_is_not_blamed_on_the_search(kept_report: PlanReport) -> None:
    """A plan kept apart costs more than the plan searched; its gap against the bound is in the
    summary, but the "far from the best" warning is the search's: none when the plan searched
    met its bound, one when the plan searched did not."""
    apart = kept_report.apart
    assert apart is not None
    met = BoundSummary(apart.cost_before, "exact", 0.5, False)  # the objective is the cost here
    report = dataclasses.replace(kept_report, task=dataclasses.replace(kept_report.task, bound=met))
    assert not [w for w in plan_warnings(report) if w.kind == "gap"]
    far = BoundSummary(apart.cost_before * 0.5, "flow", 0.5, False)
    report = dataclasses.replace(kept_report, task=dataclasses.replace(kept_report.task, bound=far))
    assert [w.kind for w in plan_warnings(report) if w.kind == "gap"] == ["gap"]


@pytest.mark.slow
def test_a_fleet_the_weighted_objective_leaves_idle_is_told_so(plan_report: PlanReport) -> None:
    """Two more robots that never move, under the weighted objective: half the team idle all
    plan, so the summary says so and names the makespan objective; not under ``cost``, which
    puts no price on time."""
    planner = dataclasses.replace(plan_report.scenario.planner, objective="weighted")
    schedule = dataclasses.replace(plan_report.schedule, robots=(*plan_report.schedule.robots, "r3", "r4"))
    fleet = dataclasses.replace(
        plan_report, scenario=dataclasses.replace(plan_report.scenario, planner=planner), schedule=schedule
    )
    (idle,) = [w for w in plan_warnings(fleet) if w.kind == "idle"]
    assert idle.value == 2 and idle.robot in {"r1", "r2"}
    assert "2 of 4 robots (r3, r4) stand idle" in idle.message and "--objective makespan" in idle.message
    costed = dataclasses.replace(planner, objective="cost")
    plain = dataclasses.replace(fleet, scenario=dataclasses.replace(fleet.scenario, planner=costed))
    assert not [w for w in plan_warnings(plain) if w.kind == "idle"]
    assert not [w for w in plan_warnings(plan_report) if w.kind == "idle"]  # two robots, both at work
