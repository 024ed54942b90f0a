"""plan.json: the document of a real plan against docs/plan-json.md, field by field."""

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

from tmpnav.report.plan_json import SCHEMA, action_spans, dumps, number, plan_document, step_action
from tmpnav.results import STAGES

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
    assert {"Top level", "Actions", "Actions/2", "Trajectories", "Roadmap"} <= set(tables)
    assert "schema" in tables["Top level"] and "cov" in tables["Trajectories"]


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


@pytest.mark.slow
def test_header_fields(plan_doc: dict[str, Any], plan_report: Any) -> None:
    assert plan_doc["schema"] == SCHEMA == "tmpnav-plan/1"
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
    # each step starts where the previous one ended, on the trajectories' clock
    assert actions[0]["t_start"] == 0.0
    for prev, nxt in itertools.pairwise(actions):
        assert nxt["t_start"] == prev["t_end"] < nxt["t_end"]


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
    n_actions = len(plan_doc["actions"])
    for robot, steps in trajectories.items():
        assert steps[0]["t"] == 0.0 and steps[0]["action"] == 0
        times = [s["t"] for s in steps]
        assert all(b > a for a, b in itertools.pairwise(times)), f"{robot}: steps not ordered in time"
        actions = [s["action"] for s in steps]
        assert actions == sorted(actions) and set(actions) <= set(range(n_actions + 1))
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
    # a robot that stands still during a step has no trajectory steps in it
    for action in plan_report.actions:
        for robot in trajectories:
            moving = robot in [m[0] for m in action.moves]
            assert (action.index in {s["action"] for s in trajectories[robot]}) == moving
    # a step ends when its slowest robot arrives
    for a in plan_doc["actions"]:
        assert max(max(s["t"] for s in trajectories[r] if s["action"] == a["index"]) for r in a["robots"]) == a["t_end"]


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
def test_spans_are_none_when_paths_and_trajectories_disagree(plan_report: Any) -> None:
    # drop the steps at roadmap nodes: the paths can no longer be followed along the trajectories
    broken = dataclasses.replace(
        plan_report,
        trajectories={
            r: [s for s in steps if s.node is None or s.t == 0.0] for r, steps in plan_report.trajectories.items()
        },
    )
    assert action_spans(broken) is None
    doc = plan_document(broken)
    assert all(a["t_start"] is None and a["t_end"] is None for a in doc["actions"])
    assert all(s["action"] is None for s in doc["trajectories"]["r1"][1:])


def test_number() -> None:
    assert number(np.float64(0.1)) == 0.1 and type(number(np.float32(2.0))) is float
    assert number(1.23456789, 3) == 1.235
    assert number(float("nan")) is None and number(-math.inf) is None


def test_step_action() -> None:
    spans = [(0.0, 2.0), (2.0, 5.5)]
    assert [step_action(t, spans) for t in (0.0, 0.5, 2.0, 2.5, 5.5, 6.0)] == [0, 1, 1, 2, 2, None]
    assert step_action(1.0, None) is None


def test_dumps_layout() -> None:
    doc = {"a": [1.0, 2.5], "b": {"c": [[1.0, 0.0], [0.0, 1.0]], "d": "x" * 130}, "e": []}
    text = dumps(doc, width=40)
    assert json.loads(text) == doc
    assert '"c": [[1.0, 0.0], [0.0, 1.0]]' in text
    assert text.endswith("}\n")
