"""The nav2 files of configs/building-4robots.yaml, as `tmpnav plan --export nav2` writes them: every
NavigateThroughPoses goal well-formed, via points at most one per turn (tests/export/nav2_schema.py
says what a turn is), the times the schedule's, and the executor replaying the schedule against a
fake nav2 with every start time and sync kept, on time and with a late robot."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.export.fake_nav2 import check_order_kept, replay
from tests.export.nav2_schema import check_goal
from tests.export.test_nav2 import ROOT, tmpnav
from tmpnav.export.executor import ExecutionStatus
from tmpnav.export.move_files import read_team
from tmpnav.export.moves import ROUTE_TOLERANCE, Team

BUILDING = ROOT / "configs" / "building-4robots.yaml"

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    out = tmp_path_factory.mktemp("building")
    # the files of any plan of the building: a short anytime search keeps the test short
    args = ("--export", "nav2", "--anytime-budget", "4", "--cache-dir", out / "cache", "-q")
    proc = tmpnav("plan", BUILDING, "-o", out, *args)
    assert proc.returncode == 0, proc.stderr
    return json.loads((out / "plan.json").read_text()), out / "nav2"


def plan_moves(doc: dict[str, Any], robot: str) -> list[tuple[dict[str, Any], dict[str, Any]]]:
    """(its move of the action, its schedule entry) of each of ``robot``'s moves, in order."""
    mine = [m for a in doc["actions"] for m in a["moves"] if m["robot"] == robot]
    return list(zip(mine, doc["schedule"]["robots"][robot]["moves"], strict=True))


def test_every_request_is_well_formed_with_its_times_as_data(exported: tuple[dict[str, Any], Path]) -> None:
    doc, folder = exported
    requests = via_before = via_after = 0
    for robot in (r["name"] for r in doc["robots"]):
        text = (folder / f"{robot}.moves.yaml").read_text()
        assert "Frame: map" in text and "metres and radians" in text
        data = yaml.safe_load(text)
        assert (data["format"], data["robot"], data["frame"]) == ("tmpnav-nav2/1", robot, "map")
        assert len(data["moves"]) == len(plan_moves(doc, robot))
        for k, (entry, (move, timed)) in enumerate(zip(data["moves"], plan_moves(doc, robot), strict=True), 1):
            via_after += check_goal(entry["goal"], move, ROUTE_TOLERANCE)
            via_before += max(0, len(move["path_points"]) - 2)
            requests += 1
            assert entry["index"] == k and entry["roadmap_nodes"] == len(move["path_points"])
            assert (entry["step"], entry["from"], entry["to"], entry["partner"]) == (
                timed["step"],
                timed["from"],
                timed["to"],
                timed["partner"],
            )
            assert entry["sync"] == (None if timed["partner"] is None else f"step-{timed['step']}")
            assert (entry["ready"], entry["wait"], entry["depart"], entry["arrive"]) == (
                timed["ready"],
                timed["wait"],
                timed["start"],
                timed["end"],
            )
    assert requests == sum(len(a["moves"]) for a in doc["actions"]) == len(doc["goals"]["visit"])  # a move a room
    assert via_after <= via_before / 2  # the roadmap's nodes every 1-2 m, thinned to the turns


def test_the_schedule_lists_every_move_with_what_it_waits_for(exported: tuple[dict[str, Any], Path]) -> None:
    doc, folder = exported
    schedule = yaml.safe_load((folder / "schedule.yaml").read_text())
    assert schedule["makespan"] == doc["schedule"]["makespan"]
    robots = [r["name"] for r in doc["robots"]]
    assert list(schedule["robots"]) == robots
    rows = schedule["moves"]
    assert [r["depart"] for r in rows] == sorted(r["depart"] for r in rows)
    for row in rows:
        previous = [f"{row['robot']}/{row['index'] - 1}"] if row["index"] > 1 else []
        partner = next((r for r in rows if r["step"] == row["step"] and r["robot"] == row["partner"]), None)
        if partner is not None and partner["index"] > 1:
            previous.append(f"{partner['robot']}/{partner['index'] - 1}")
        assert row["after"] == previous


def test_the_executor_keeps_every_start_time_and_sync(exported: tuple[dict[str, Any], Path]) -> None:
    _, folder = exported
    team = read_team(folder)
    run, server = replay(team)
    assert run.status is ExecutionStatus.COMPLETED
    check_order_kept(team, run)
    assert len(server.sent) == sum(len(ms) for ms in team.moves.values())
    for move in team.all_moves():  # on time: each move leaves and arrives as planned
        record = run.record(move.robot, move.index)
        assert (record.sent, record.ended) == pytest.approx((move.depart, move.arrive), abs=1e-9)
    assert run.makespan == pytest.approx(team.makespan, abs=1e-9)


def test_a_late_robot_is_waited_for_and_holds_no_one_else(exported: tuple[dict[str, Any], Path]) -> None:
    _, folder = exported
    team = read_team(folder)
    # the robot that arrives last: its lateness is the team's, whichever plan the short search
    # returned (a robot done early could be late and leave the makespan as it was)
    late = max(team.all_moves(), key=lambda m: m.arrive or 0.0).robot
    run, _ = replay(team, slower={late: 1.3})
    assert run.status is ExecutionStatus.COMPLETED
    check_order_kept(team, run)
    held = paired_with(team, late)
    for move in team.all_moves():
        record = run.record(move.robot, move.index)
        assert record.sent is not None and move.depart is not None
        if move.robot not in held:  # robots that never wait for the late one keep their times
            assert record.sent == pytest.approx(move.depart, abs=1e-9)
        elif move.robot == late and move.index > 1:
            before = run.record(move.robot, move.index - 1)
            assert record.sent >= move.depart and before.ended is not None
            if before.ended > move.depart:  # no slack left before it: it starts late, when the last one ends
                assert record.sent > move.depart
    assert (run.makespan or 0.0) > (team.makespan or 0.0)


def paired_with(team: Team, robot: str) -> set[str]:
    """``robot`` and the robots its lateness reaches through sync points (pairs of pairs...)."""
    out = {robot}
    grown = True
    while grown:
        grown = False
        for move in team.all_moves():
            if move.partner is not None and (move.robot in out) != (move.partner in out):
                out |= {move.robot, move.partner}
                grown = True
    return out
