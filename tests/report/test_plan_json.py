"""plan.json: the document of a real plan against docs/plan-json.md, field by field, and its schedule
against its actions and trajectories."""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tmpnav.report.plan_json import SCHEMA, dumps, number, plan_document
from tmpnav.results import STAGES, Schedule
from tmpnav.task.objectives import OBJECTIVES

DOC = Path(__file__).resolve().parents[2] / "docs" / "plan-json.md"


def documented_fields() -> dict[str, list[str]]:
    """Field names of every table of docs/plan-json.md: "<section>" or "<section>/<n>" -> names.

    A row's first cell lists its fields in backticks (`t_start`, `t_end`).
    """
    tables: dict[str, list[str]] = {}
    section, n, in_table = "", 0, False
    for line in DOC.read_text(encoding="utf-8").splitlines():
        if line.startswith("## "):
            section, n, in_table = line[3:].strip(), 0, False
            continue
        is_row = line.startswith("|")
        if is_row and not in_table:
            n += 1
        in_table = is_row
        if not is_row or line.startswith("|---") or line.startswith("| field"):
            continue
        key = section if n == 1 else f"{section}/{n}"
        tables.setdefault(key, []).extend(re.findall(r"`([^`]+)`", line.split("|")[1]))
    return tables


def test_schema_doc_lists_the_tables() -> None:
    tables = documented_fields()
    assert {
        "Top level",
        "Actions",
        "Actions/2",
        "Schedule",
        "Schedule/2",
        "Schedule/3",
        "Trajectories",
        "Roadmap",
    } <= set(tables)
    assert "schema" in tables["Top level"] and "cov" in tables["Trajectories"] and "wait" in tables["Schedule/3"]


@pytest.mark.slow
def test_every_documented_field_is_present_and_every_field_documented(plan_doc: dict[str, Any]) -> None:
    tables = documented_fields()
    assert set(tables["Top level"]) == set(plan_doc)
    for action in plan_doc["actions"]:
        assert set(tables["Actions"]) == set(action)
        for move in action["moves"]:
            assert set(tables["Actions/2"]) == set(move)
    for steps in plan_doc["trajectories"].values():
        for step in steps:
            assert set(tables["Trajectories"]) == set(step)
    assert set(tables["Roadmap"]) == set(plan_doc["roadmap"])
    assert set(tables["Schedule"]) == set(plan_doc["schedule"])
    for entry in plan_doc["schedule"]["robots"].values():
        assert set(tables["Schedule/2"]) == set(entry)
        for move in entry["moves"]:
            assert set(tables["Schedule/3"]) == set(move)


@pytest.mark.slow
def test_header_fields(plan_doc: dict[str, Any], plan_report: Any) -> None:
    assert plan_doc["schema"] == SCHEMA == "tmpnav-plan/2"
    assert plan_doc["scenario"]["name"] == "three-rooms"
    assert plan_doc["scenario"]["file"].endswith("three_rooms.yaml")
    assert plan_doc["encoding"] == plan_report.encoding == "mixed"
    assert plan_doc["planner"] == plan_report.planner
    assert plan_doc["status"] in ("solved-optimally", "solved-satisficing")
    assert plan_doc["mutual_observations"] is True
    assert plan_doc["dt"] == plan_report.scenario.models.dt
    assert plan_doc["goals"] == {"visit": [], "per_robot": {"r1": ["C", "B"], "r2": ["A"]}}
    assert [r["name"] for r in plan_doc["robots"]] == ["r1", "r2"]
    assert plan_doc["cost"] == {"planner": plan_report.planner_cost, "resimulated": plan_report.resimulated_cost}
    weights = plan_report.scenario.cost
    assert plan_doc["cost_weights"] == {
        "M_u": weights.M_u,
        "M_G": weights.M_G,
        "M_Sigma": weights.M_Sigma,
        "M_T": weights.M_T,
    }


@pytest.mark.slow
def test_makespan_and_objective(plan_doc: dict[str, Any], plan_report: Any) -> None:
    makespan = plan_report.schedule.makespan
    assert plan_doc["makespan"] == {"planner": plan_report.task.makespan, "resimulated": makespan}
    assert makespan == plan_doc["schedule"]["makespan"] > 0
    # the test plan's objective is the paper's: the sum of action costs, no price on time
    assert plan_doc["objective"] == {
        "name": "cost",
        "units": "cost",
        "span_weight": 0.0,
        "planner": plan_doc["cost"]["planner"],
        "resimulated": plan_doc["cost"]["resimulated"],
    }


@pytest.mark.slow
@pytest.mark.parametrize("name", ["weighted", "makespan"])
def test_an_objective_that_prices_time(plan_report: Any, name: str) -> None:
    planner = dataclasses.replace(plan_report.scenario.planner, objective=name)
    report = dataclasses.replace(plan_report, scenario=dataclasses.replace(plan_report.scenario, planner=planner))
    doc = plan_document(report)
    weights = report.scenario.cost
    w = OBJECTIVES[name].span_weight(weights)
    assert w > 0 and doc["objective"]["name"] == name and doc["objective"]["span_weight"] == w
    if name == "makespan":  # in its own units: the makespan's seconds, not cost + 10^4 per s
        assert doc["objective"]["units"] == "s"
        assert doc["objective"]["resimulated"] == doc["makespan"]["resimulated"]
        assert doc["objective"]["planner"] == doc["makespan"]["planner"]
    else:
        assert doc["objective"]["units"] == "cost"
        assert doc["objective"]["resimulated"] == pytest.approx(
            doc["cost"]["resimulated"] + w * doc["makespan"]["resimulated"]
        )
        assert doc["objective"]["planner"] == pytest.approx(doc["cost"]["planner"] + w * doc["makespan"]["planner"])
    # a planner whose costs had no durations saw no makespan: null, and so is its objective
    blind = dataclasses.replace(report, task=dataclasses.replace(report.task, schedule=None))
    doc = plan_document(blind)
    assert doc["makespan"]["planner"] is None and doc["objective"]["planner"] is None
    json.dumps(doc, allow_nan=False)


@pytest.mark.slow
def test_document_is_strict_json_and_dumps_round_trips(plan_doc: dict[str, Any]) -> None:
    json.dumps(plan_doc, allow_nan=False)  # raises on NaN / infinity and on non-JSON types
    text = dumps(plan_doc)
    assert json.loads(text) == plan_doc
    # a trajectory step's pose and covariance each stay on one line
    assert re.search(r'^\s*"cov": \[\[[^\n]*\]\],?$', text, flags=re.M)


@pytest.mark.slow
def test_actions(plan_doc: dict[str, Any], plan_report: Any) -> None:
    actions = plan_doc["actions"]
    assert [a["index"] for a in actions] == list(range(1, len(actions) + 1))
    steps = [list(a.moves) for a in plan_report.actions]
    assert [a["robots"] for a in actions] == [[m[0] for m in step] for step in steps]
    assert [a["from"] for a in actions] == [[m[1] for m in step] for step in steps]
    assert [a["to"] for a in actions] == [[m[2] for m in step] for step in steps]
    # the goals of the test scenario: r1 visits C and B, r2 visits A
    visited = {(robot, to) for a in actions for robot, to in zip(a["robots"], a["to"], strict=True)}
    assert {("r1", "C"), ("r1", "B"), ("r2", "A")} <= visited
    assert sum(a["planner_cost"] for a in actions) == pytest.approx(plan_doc["cost"]["planner"])
    assert sum(a["resimulated_cost"] for a in actions) == pytest.approx(plan_doc["cost"]["resimulated"])
    nodes = plan_report.roadmap.nodes
    for a in actions:
        assert len(a["moves"]) == len(a["robots"]) == len(a["from"]) == len(a["to"])
        for move, robot, origin, target in zip(a["moves"], a["robots"], a["from"], a["to"], strict=True):
            assert (move["robot"], move["from"], move["to"]) == (robot, origin, target)
            assert move["path_nodes"][-1] == move["goal_node"]
            assert move["goal_node"] in plan_doc["roadmap"]["pose_instantiations"][target]["nodes"]
            assert len(move["goal_pose"]) == 3
            assert move["path_points"] == [list(nodes[n]) for n in move["path_nodes"]]
            assert move["goal_pose"][:2] == pytest.approx(move["path_points"][-1])
    # each step's window on the shared clock: from when its moves start to when its last robot arrives
    moves = {(m["step"], robot): m for robot, e in plan_doc["schedule"]["robots"].items() for m in e["moves"]}
    for a in actions:
        mine = [moves[(a["index"], robot)] for robot in a["robots"]]
        assert a["t_start"] == min(m["start"] for m in mine) and a["t_end"] == max(m["end"] for m in mine)
    assert actions[0]["t_start"] == 0.0
    assert max(a["t_end"] for a in actions) == plan_doc["schedule"]["makespan"]


@pytest.mark.slow
def test_moves_continue_from_where_the_robot_is(plan_doc: dict[str, Any]) -> None:
    at = dict(plan_doc["roadmap"]["starts"])
    for a in plan_doc["actions"]:
        for move in a["moves"]:
            assert move["path_nodes"][0] == at[move["robot"]]
            at[move["robot"]] = move["goal_node"]


@pytest.mark.slow
def test_trajectories(plan_doc: dict[str, Any], plan_report: Any) -> None:
    trajectories = plan_doc["trajectories"]
    assert list(trajectories) == ["r1", "r2"]
    dt, makespan = plan_doc["dt"], plan_doc["schedule"]["makespan"]
    for robot, steps in trajectories.items():
        # every robot at every control step of the shared clock, from 0 to the makespan
        times = [s["t"] for s in steps]
        assert times == pytest.approx([k * dt for k in range(round(makespan / dt) + 1)], abs=1e-9)
        assert steps[0]["action"] is None
        for step in steps:
            assert len(step["mean"]) == 3
            cov = np.array(step["cov"], dtype=float)
            assert cov.shape == (3, 3)
            # symmetric up to rounding: the EKF's products leave ~1 ulp of asymmetry, kept as computed
            assert np.allclose(cov, cov.T, rtol=1e-12, atol=1e-18), f"{robot} t={step['t']}: covariance not symmetric"
            assert np.linalg.eigvalsh(cov).min() > -1e-12
            assert step["node"] is None or isinstance(step["node"], int)
        # full precision: the document holds exactly the re-simulated beliefs
        report_steps = plan_report.trajectories[robot]
        assert [s["cov"] for s in steps] == [[list(row) for row in s.cov] for s in report_steps]
        assert [s["mean"] for s in steps] == [list(s.mean) for s in report_steps]


@pytest.mark.slow
def test_trajectory_steps_say_which_step_the_robot_drives_in(plan_doc: dict[str, Any]) -> None:
    dt = plan_doc["dt"]
    for robot, entry in plan_doc["schedule"]["robots"].items():
        steps = plan_doc["trajectories"][robot]
        for move in entry["moves"]:
            inside = [s["action"] for s in steps if move["start"] < s["t"] <= move["end"]]
            assert inside == [move["step"]] * round((move["end"] - move["start"]) / dt)
        driving = [s for s in steps if s["action"] is not None]
        assert len(driving) * dt == pytest.approx(entry["busy"])
        # standing (waiting, done), the robot's mean stays where it is but for its observations' updates
        assert {s["action"] for s in driving} == {m["step"] for m in entry["moves"]}
    # the robot that waits for its partner stands still meanwhile
    r2 = plan_doc["schedule"]["robots"]["r2"]["moves"][0]
    standing = [s for s in plan_doc["trajectories"]["r2"] if s["t"] <= r2["start"]]
    assert r2["wait"] > 0 and all(s["action"] is None for s in standing)
    xy = np.array([s["mean"][:2] for s in standing])
    assert np.ptp(xy, axis=0).max() < 0.05  # m: no driving, only updates


@pytest.mark.slow
def test_schedule_is_consistent_with_the_actions(plan_doc: dict[str, Any], plan_report: Any) -> None:
    schedule = plan_doc["schedule"]
    assert list(schedule["robots"]) == ["r1", "r2"]
    moves = [(robot, m) for robot, e in schedule["robots"].items() for m in e["moves"]]
    # every move of every plan step, once, with its rooms and partner
    expected = sorted(
        (a["index"], robot, origin, to, next((r for r in a["robots"] if r != robot), None))
        for a in plan_doc["actions"]
        for robot, origin, to in zip(a["robots"], a["from"], a["to"], strict=True)
    )
    assert sorted((m["step"], robot, m["from"], m["to"], m["partner"]) for robot, m in moves) == expected
    paths = {(a["index"], mv["robot"]): mv["path_nodes"] for a in plan_doc["actions"] for mv in a["moves"]}
    for robot, m in moves:
        assert m["start"] >= m["ready"] and m["wait"] == pytest.approx(m["start"] - m["ready"], abs=1e-9)
        # a move lasts while the robot drives its path; one of no path (already there) takes no time
        assert m["end"] > m["start"] if len(paths[(m["step"], robot)]) > 1 else m["end"] == m["start"]
    assert schedule["makespan"] == max(m["end"] for _, m in moves)
    for entry in schedule["robots"].values():
        timeline = entry["moves"]
        assert entry["rooms"] == len(timeline)
        assert timeline[0]["ready"] == 0.0
        for prev, nxt in itertools.pairwise(timeline):
            assert nxt["ready"] == prev["end"] + prev["service"] and nxt["step"] > prev["step"]
        busy = sum(m["end"] - m["start"] for m in timeline)
        waits = sum(m["wait"] for m in timeline)
        assert entry["busy"] == pytest.approx(busy) and entry["waits"] == pytest.approx(waits)
        assert entry["busy"] + entry["waits"] + entry["idle"] == pytest.approx(schedule["makespan"])
    # the two moves of a paired step start together
    for a in plan_doc["actions"]:
        if len(a["robots"]) == 2:
            starts = {m["start"] for robot, m in moves if m["step"] == a["index"]}
            assert len(starts) == 1
    # the test plan: r2 waits for r1, then they move together; r1 is idle after its last move
    r1, r2 = schedule["robots"]["r1"], schedule["robots"]["r2"]
    assert r2["waits"] > 0 and r2["moves"][0]["partner"] == "r1" and r2["moves"][0]["start"] == r1["moves"][0]["end"]
    assert r1["idle"] > 0 and r1["waits"] == 0.0
    assert plan_report.schedule.makespan == schedule["makespan"]


@pytest.mark.slow
def test_timings_cache_and_counters(plan_doc: dict[str, Any], plan_report: Any) -> None:
    timings = plan_doc["timings"]
    assert {*STAGES, "total"} <= set(timings)
    assert all(isinstance(v, float) and v >= 0.0 for v in timings.values())
    assert timings["total"] == pytest.approx(sum(v for k, v in timings.items() if k not in ("load", "total")), abs=1e-5)
    cache = plan_doc["cache"]
    assert isinstance(cache["hits"], int) and isinstance(cache["misses"], int)
    assert (cache["hits"], cache["misses"]) == (plan_report.cache.hits, plan_report.cache.misses)
    assert (cache["hits"], cache["misses"]) == (plan_doc["oracle"]["cache_hits"], plan_doc["oracle"]["cache_misses"])
    assert all(isinstance(v, int) for v in plan_doc["oracle"].values())  # counters (and booleans)
    assert plan_doc["task"]["pair_actions"] >= 1 and plan_doc["task"]["actions"] >= 2


@pytest.mark.slow
def test_non_finite_numbers_become_null(plan_report: Any) -> None:
    first, *rest = plan_report.actions
    broken = dataclasses.replace(
        plan_report,
        task=dataclasses.replace(plan_report.task, step_costs=(math.inf, *plan_report.task.step_costs[1:])),
        actions=(dataclasses.replace(first, resimulated_cost=math.nan), *rest),
    )
    doc = plan_document(broken)
    assert doc["cost"] == {"planner": None, "resimulated": None}
    json.dumps(doc, allow_nan=False)


@pytest.mark.slow
def test_a_step_missing_from_the_schedule_has_no_window(plan_report: Any) -> None:
    """Never expected: a schedule without one of the plan's steps. Its window is null, the rest stands."""
    kept = tuple(m for m in plan_report.schedule.moves if m.step != 0)
    broken = dataclasses.replace(plan_report, schedule=Schedule(plan_report.schedule.robots, kept))
    doc = plan_document(broken)
    assert doc["actions"][0]["t_start"] is None and doc["actions"][0]["t_end"] is None
    assert doc["actions"][1]["t_end"] == doc["schedule"]["makespan"]
    json.dumps(doc, allow_nan=False)


def test_number() -> None:
    assert number(np.float64(0.1)) == 0.1 and type(number(np.float32(2.0))) is float
    assert number(1.23456789, 3) == 1.235
    assert number(float("nan")) is None and number(-math.inf) is None


def test_dumps_layout() -> None:
    doc = {"a": [1.0, 2.5], "b": {"c": [[1.0, 0.0], [0.0, 1.0]], "d": "x" * 130}, "e": []}
    text = dumps(doc, width=40)
    assert json.loads(text) == doc
    assert '"c": [[1.0, 0.0], [0.0, 1.0]]' in text
    assert text.endswith("}\n")
