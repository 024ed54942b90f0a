"""Move requests: via points thinned to the turns of a path, NavigateThroughPoses goals with the
planned heading last, the times as data, and the files read back as they were written."""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest
import yaml

from tests.export.nav2_schema import check_goal, covered, fewest
from tests.export.test_nav2 import plan_doc, scheduled_doc
from tmpnav.errors import InputError
from tmpnav.export.move_files import files, read_team
from tmpnav.export.moves import ROUTE_TOLERANCE, team, turns
from tmpnav.export.nav2 import write_nav2


def test_a_straight_path_has_no_via_points() -> None:
    assert turns([(float(x), 0.0) for x in range(10)]) == []
    jitter = random.Random(3)  # a roadmap's nodes wander a little off a straight corridor
    assert turns([(1.5 * x, jitter.uniform(-0.2, 0.2)) for x in range(12)]) == []


def test_a_corner_keeps_one_via_point_and_a_u_turn_two() -> None:
    ell = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (3.0, 0.0), (3.0, 1.0), (3.0, 2.0)]
    assert turns(ell) == [3]
    u = [(0.0, 0.0), (2.0, 0.0), (4.0, 0.0), (4.0, 1.0), (4.0, 2.0), (2.0, 2.0), (0.0, 2.0)]
    assert turns(u) == [2, 4]
    assert turns([(0.0, 0.0), (5.0, 5.0)]) == [] and turns([(0.0, 0.0)]) == []


def test_a_gradual_bend_keeps_the_route_within_the_tolerance() -> None:
    """A quarter circle of 5 m radius in 10 nodes, each turning 10 degrees: no node turns much,
    but a straight leg from end to end would cut 1.5 m across the bend."""
    arc = [(5 * math.sin(a), 5 - 5 * math.cos(a)) for a in (math.pi / 2 * k / 9 for k in range(10))]
    kept = turns(arc)
    assert 1 <= len(kept) == fewest(arc, ROUTE_TOLERANCE) and covered(arc, kept, ROUTE_TOLERANCE)


def test_turns_are_the_fewest_that_cover_random_paths() -> None:
    rng = random.Random(11)
    for _ in range(200):
        points, heading = [(0.0, 0.0)], 0.0
        for _ in range(rng.randint(2, 14)):
            heading += rng.choice([0.0, rng.gauss(0.0, 0.3), rng.uniform(-2.0, 2.0)])
            step = rng.uniform(0.2, 3.0)
            x, y = points[-1]
            points.append((x + step * math.cos(heading), y + step * math.sin(heading)))
        tolerance = rng.choice([0.1, ROUTE_TOLERANCE, 1.0])
        kept = turns(points, tolerance)
        assert covered(points, kept, tolerance) and len(kept) == fewest(points, tolerance)


def test_every_goal_of_a_plan_is_well_formed() -> None:
    doc = scheduled_doc()
    moves = team(doc)
    plan_moves = [m for a in doc["actions"] for m in a["moves"]]
    assert sum(len(ms) for ms in moves.moves.values()) == len(plan_moves)
    for request in moves.all_moves():
        plan_move = next(
            m for a in doc["actions"] if a["index"] == request.step for m in a["moves"] if m["robot"] == request.robot
        )
        check_goal(yaml.safe_load(yaml.safe_dump(request.goal.message(), sort_keys=False)), plan_move, ROUTE_TOLERANCE)


def test_the_times_and_syncs_are_the_schedules() -> None:
    moves = team(scheduled_doc())
    assert [(m.name, m.step, m.ready, m.wait, m.depart, m.arrive, m.partner, m.sync) for m in moves.all_moves()] == [
        ("r1/1", 1, 0.0, 0.0, 0.0, 2.0, None, None),
        ("r1/2", 2, 2.0, 0.5, 2.5, 3.5, "r2", "step-2"),
        ("r2/1", 2, 0.0, 2.5, 2.5, 3.25, "r1", "step-2"),
    ]
    assert [m.name for m in moves.after(moves.moves["r1"][1])] == ["r1/1"]
    assert [m.name for m in moves.after(moves.moves["r2"][0])] == ["r1/1"]  # r1 reaching the sync point
    assert moves.makespan == 3.5


def test_files_read_back_as_written(tmp_path: Path) -> None:
    doc = scheduled_doc()
    write_nav2(doc, tmp_path)
    written, read = team(doc), read_team(tmp_path)
    assert read.robots == written.robots and read.makespan == written.makespan
    for a, b in zip(written.all_moves(), read.all_moves(), strict=True):
        assert (a.name, a.step, a.origin, a.target, a.partner, a.ready, a.depart, a.arrive, a.roadmap_nodes) == (
            b.name,
            b.step,
            b.origin,
            b.target,
            b.partner,
            b.ready,
            b.depart,
            b.arrive,
            b.roadmap_nodes,
        )
        assert [(p.x, p.y) for p in a.goal.poses] == [(p.x, p.y) for p in b.goal.poses]
        assert [p.yaw for p in b.goal.poses] == pytest.approx([p.yaw for p in a.goal.poses], abs=1e-12)
    schedule = yaml.safe_load((tmp_path / "schedule.yaml").read_text())
    assert [(m["move"], m["depart"], m["after"]) for m in schedule["moves"]] == [
        ("r1/1", 0.0, []),
        ("r1/2", 2.5, ["r1/1"]),
        ("r2/1", 2.5, ["r1/1"]),
    ]


def test_a_plan_json_1_gets_requests_too() -> None:
    moves = team(plan_doc())
    assert [(m.name, m.depart, m.arrive, len(m.goal.poses)) for m in moves.all_moves()] == [
        ("r1/1", 0.0, 2.0, 2),  # the corner at node 5 is a via point, then the goal
        ("r1/2", 2.0, 3.0, 1),
        ("r2/1", 2.0, 3.0, 1),
    ]


def test_bad_input_is_one_clear_line(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="not a tmpnav plan document: schema 'tmpnav-plan/9'"):
        team({"schema": "tmpnav-plan/9"})
    with pytest.raises(InputError, match=r"cannot read .*schedule.yaml"):
        read_team(tmp_path)
    out = files(team(scheduled_doc()))
    for name, text in out.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "r2.moves.yaml").write_text(out["r2.moves.yaml"].replace("export: ", "export: 0"))
    with pytest.raises(InputError, match=r"r2\.moves\.yaml is not robot r2's file of schedule\.yaml's export"):
        read_team(tmp_path)
    (tmp_path / "r2.moves.yaml").write_text(out["r2.moves.yaml"].replace("x: 0.0", "x: .nan", 1))
    with pytest.raises(InputError, match=r"r2.moves.yaml: moves\[0\].goal.poses\[0\] is nan, not a finite number"):
        read_team(tmp_path)
    (tmp_path / "schedule.yaml").write_text("format: tmpnav-nav2/0\n")
    with pytest.raises(InputError, match="is not a tmpnav nav2 move file: format 'tmpnav-nav2/0'"):
        read_team(tmp_path)
