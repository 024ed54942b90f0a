"""Waypoint files for nav2, checked against the plan.json they come from.

Same poses, same order: each robot's start pose, then per plan step its roadmap path after the
first node, ending at the step's goal pose; the frame and units are stated in every file; the
synchronisation points of paired moves are marked on both robots.
"""

from __future__ import annotations

import csv
import itertools
import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.export.fake_nav2 import check_order_kept, replay
from tmpnav.errors import InputError
from tmpnav.export.move_files import read_team
from tmpnav.export.nav2 import CSV_COLUMNS, files, waypoints, write_nav2

ROOT = Path(__file__).resolve().parents[2]
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


def tmpnav(*args: Any) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tmpnav", *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=600
    )


def expected_poses(doc: dict[str, Any], robot: str) -> list[tuple[float, float, float, int]]:
    """(x, y, yaw, step) of every waypoint, read from plan.json independently of the exporter."""
    x, y, yaw = doc["trajectories"][robot][0]["mean"]
    poses = [(x, y, yaw, 0)]
    for action in doc["actions"]:
        for move in action["moves"]:
            if move["robot"] != robot:
                continue
            pts = move["path_points"]
            for (x0, y0), (x1, y1) in itertools.pairwise(pts[1:]):
                poses.append((x0, y0, math.atan2(y1 - y0, x1 - x0), action["index"]))
            poses.append((*move["goal_pose"], action["index"]))
    return poses


def read_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    lines = path.read_text().splitlines()
    comments = [line for line in lines if line.startswith("#")]
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    return comments, rows


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    out = tmp_path_factory.mktemp("plan")
    # the paper's objective with table costs pairs the two robots (the weighted default sends them at
    # once), and so does the plan as planned (kept apart, the pair is split so that one robot waits)
    options = ("--objective", "cost", "--costs", "table", "--no-keep-apart")
    proc = tmpnav("plan", TWO_ROOMS, *options, "-o", out, "--export", "nav2", "--cache-dir", out / "cache", "-q")
    assert proc.returncode == 0, proc.stderr
    for name in ("r1.csv", "r1.follow_waypoints.yaml", "r1.rviz_waypoints.yaml", "r2.csv"):
        assert f"nav2/{name}" in proc.stdout.splitlines()[-1]  # one line: wrote OUT/: plan.json, ..., nav2/...
    return json.loads((out / "plan.json").read_text()), out / "nav2"


@pytest.mark.slow
def test_csv_has_the_plans_poses_in_order(exported: tuple[dict[str, Any], Path]) -> None:
    doc, folder = exported
    for robot in ("r1", "r2"):
        comments, rows = read_csv(folder / f"{robot}.csv")
        assert list(rows[0]) == list(CSV_COLUMNS)
        assert any("Frame: map" in c for c in comments) and any("metres and radians" in c for c in comments)
        want = expected_poses(doc, robot)
        assert [(float(r["x"]), float(r["y"]), float(r["yaw"]), int(r["step"])) for r in rows] == want
        assert [int(r["index"]) for r in rows] == list(range(len(want)))
        assert {r["frame"] for r in rows} == {"map"}
        assert rows[0]["kind"] == "start" and rows[-1]["kind"] == "goal"
        times = [float(r["t"]) for r in rows if r["t"]]
        assert times == sorted(times) and len(times) == len(rows)


@pytest.mark.slow
def test_follow_waypoints_goal_is_a_list_of_pose_stamped(exported: tuple[dict[str, Any], Path]) -> None:
    doc, folder = exported
    text = (folder / "r1.follow_waypoints.yaml").read_text()
    assert "Frame: map" in text and "metres and radians" in text
    goal = yaml.safe_load(text)
    assert list(goal) == ["poses"]
    want = expected_poses(doc, "r1")
    assert len(goal["poses"]) == len(want)
    for pose, (x, y, yaw, _) in zip(goal["poses"], want, strict=True):
        assert pose["header"] == {"frame_id": "map"}
        assert (pose["pose"]["position"]["x"], pose["pose"]["position"]["y"], pose["pose"]["position"]["z"]) == (
            x,
            y,
            0.0,
        )
        q = pose["pose"]["orientation"]
        assert q["x"] == q["y"] == 0.0
        assert math.atan2(2 * q["w"] * q["z"], 1 - 2 * q["z"] ** 2) == pytest.approx(yaw, abs=1e-12)


@pytest.mark.slow
def test_rviz_panel_file_has_w_first(exported: tuple[dict[str, Any], Path]) -> None:
    doc, folder = exported
    wps = yaml.safe_load((folder / "r2.rviz_waypoints.yaml").read_text())["waypoints"]
    want = expected_poses(doc, "r2")
    assert list(wps) == [f"waypoint{i}" for i in range(len(want))]
    for wp, (x, y, yaw, _) in zip(wps.values(), want, strict=True):
        assert wp["pose"] == [x, y, 0.0]
        w, qx, qy, qz = wp["orientation"]
        assert (qx, qy) == (0.0, 0.0) and (w, qz) == pytest.approx((math.cos(yaw / 2), math.sin(yaw / 2)))


@pytest.mark.slow
def test_the_paired_move_is_a_sync_point_on_both_robots(exported: tuple[dict[str, Any], Path]) -> None:
    doc, folder = exported
    paired = [a["index"] for a in doc["actions"] if len(a["robots"]) == 2]
    assert paired, "the two-rooms plan pairs its robots"
    for robot, partner in (("r1", "r2"), ("r2", "r1")):
        _, rows = read_csv(folder / f"{robot}.csv")
        marked = [(int(r["index"]), r["sync"], r["partner"]) for r in rows if r["sync"]]
        assert [m[1:] for m in marked] == [(f"step-{k}", partner) for k in paired]
        for index, sync, _ in marked:  # marked on the last waypoint before the paired step
            assert int(rows[index + 1]["step"]) == int(sync.split("-")[1])
    departs = {}
    for robot in ("r1", "r2"):  # both robots of a paired step leave at its planned start
        _, rows = read_csv(folder / f"{robot}.csv")
        departs[robot] = [(r["sync"], float(r["depart"])) for r in rows if r["sync"]]
        assert all(float(r["wait"]) >= 0.0 for r in rows if r["depart"])
    assert departs["r1"] == departs["r2"]


@pytest.mark.slow
def test_the_executor_sends_a_paired_move_to_both_robots_at_once(exported: tuple[dict[str, Any], Path]) -> None:
    _, folder = exported
    team = read_team(folder)
    paired = [m for m in team.all_moves() if m.partner is not None]
    assert paired, "the two-rooms plan pairs its robots"
    for slower in ({}, {"r1": 1.5}, {"r2": 1.5}):
        run, server = replay(team, slower)
        check_order_kept(team, run)  # both moves of each pair sent together
        assert {(s.robot, s.t) for s in server.sent} >= {(m.robot, m.depart) for m in paired if m.index == 1}


def plan_doc() -> dict[str, Any]:
    """A plan: r1 moves alone from A to B, then r1 (B -> C) and r2 (start -> A) together."""

    def steps(*nodes: tuple[float, int | None]) -> list[dict[str, Any]]:
        return [{"t": t, "mean": [0.0, 0.0, 0.5], "cov": [], "node": n, "action": 0} for t, n in nodes]

    def move(robot: str, frm: str, to: str, nodes: list[int], pts: list[list[float]]) -> dict[str, Any]:
        return {
            "robot": robot,
            "from": frm,
            "to": to,
            "goal_node": nodes[-1],
            "goal_pose": [*pts[-1], 1.0],
            "path_nodes": nodes,
            "path_points": pts,
        }

    return {
        "schema": "tmpnav-plan/1",
        "scenario": {"name": "s", "file": "s.yaml", "description": ""},
        "status": "solved-optimally",
        "robots": [{"name": "r1"}, {"name": "r2"}],
        "actions": [
            {
                "index": 1,
                "robots": ["r1"],
                "from": ["A"],
                "to": ["B"],
                "moves": [move("r1", "A", "B", [0, 5, 6], [[0, 0], [1, 0], [1, 1]])],
            },
            {
                "index": 2,
                "robots": ["r1", "r2"],
                "from": ["B", "r2-start"],
                "to": ["C", "A"],
                "moves": [
                    move("r1", "B", "C", [6, 7], [[1, 1], [2, 1]]),
                    move("r2", "r2-start", "A", [9, 0], [[3, 3], [0, 0]]),
                ],
            },
        ],
        "trajectories": {
            "r1": steps((0.0, 0), (1.0, 5), (2.0, 6), (3.0, 7)),
            "r2": steps((0.0, 9), (2.5, None), (3.0, 0)),
        },
    }


def test_sync_goes_on_the_waypoint_before_the_paired_step() -> None:
    wps = waypoints(plan_doc())
    r1, r2 = wps["r1"], wps["r2"]
    assert [(w.kind, w.step, w.room) for w in r1] == [
        ("start", 0, "A"),
        ("via", 1, ""),
        ("goal", 1, "B"),
        ("goal", 2, "C"),
    ]
    assert [(w.kind, w.step) for w in r2] == [("start", 0), ("goal", 2)]
    assert [(w.index, w.sync, w.partner) for w in r1 if w.sync] == [(2, "step-2", "r2")]
    assert [(w.index, w.sync, w.partner) for w in r2 if w.sync] == [(0, "step-2", "r1")]
    assert r1[1].yaw == pytest.approx(math.pi / 2)  # the via node faces the next one
    assert [w.t for w in r1] == [0.0, 1.0, 2.0, 3.0] and r2[1].t == 3.0


def test_a_sequential_plan_json_1_gets_its_waits_from_the_steps() -> None:
    """tmpnav-plan/1 has no schedule: its steps ran one after the other, so r2 waited in its
    start pose while r1 made step 1, and both left for step 2 when r1 was done."""
    r1, r2 = waypoints(plan_doc())["r1"], waypoints(plan_doc())["r2"]
    assert [(w.index, w.depart, w.wait) for w in r1 if w.depart is not None] == [(0, 0.0, 0.0), (2, 2.0, 0.0)]
    assert [(w.index, w.depart, w.wait) for w in r2 if w.depart is not None] == [(0, 2.0, 2.0)]
    assert r1[-1].depart is None and r2[-1].wait is None  # no move leaves from the last goal


def test_a_plan_json_1_whose_robots_moved_at_once_takes_its_times_from_the_trajectories() -> None:
    """A step's t_start that does not fit its trajectories (r2 is at its first node before the
    step's claimed start) is not used: the step starts when its robots are ready."""
    doc = plan_doc()
    doc["actions"][1] = {**doc["actions"][1], "robots": ["r2"], "from": ["r2-start"], "to": ["A"]}
    doc["actions"][1]["moves"] = doc["actions"][1]["moves"][1:]
    doc["actions"][0]["t_start"], doc["actions"][1]["t_start"] = 0.0, 2.0  # as if one after the other
    doc["trajectories"]["r2"] = [doc["trajectories"]["r2"][0], {**doc["trajectories"]["r2"][2], "t": 1.5}]
    r2 = waypoints(doc)["r2"]
    assert [(w.kind, w.t, w.depart, w.wait) for w in r2] == [("start", 0.0, 0.0, 0.0), ("goal", 1.5, None, None)]
    sequential = plan_doc()
    sequential["actions"][1]["t_start"] = 2.5  # fits: after both are ready, before their first node
    r1, r2 = waypoints(sequential)["r1"], waypoints(sequential)["r2"]
    assert [(w.depart, w.wait) for w in (r1[2], r2[0])] == [(2.5, 0.5), (2.5, 2.5)]


def scheduled_doc() -> dict[str, Any]:
    """plan_doc as tmpnav-plan/2: r2 stands 2.5 s for r1, and the paired step is held back 0.5 s."""

    def timed(step: int, frm: str, to: str, partner: str | None, ready: float, start: float, end: float) -> Any:
        return {"step": step, "from": frm, "to": to, "partner": partner, "ready": ready, "start": start, "end": end}

    doc = plan_doc()
    doc["schema"] = "tmpnav-plan/2"
    doc["schedule"] = {
        "makespan": 3.5,
        "robots": {
            "r1": {"moves": [timed(1, "A", "B", None, 0.0, 0.0, 2.0), timed(2, "B", "C", "r2", 2.0, 2.5, 3.5)]},
            "r2": {"moves": [timed(2, "r2-start", "A", "r1", 0.0, 2.5, 3.25)]},
        },
    }
    for steps in doc["trajectories"].values():
        for step in steps:
            step["t"] += 0.5 if step["t"] > 2.0 else 0.0  # the paired step starts at 2.5 s
    return doc


def test_plan_json_2_gives_each_waypoint_its_time_and_each_move_its_wait() -> None:
    wps = waypoints(scheduled_doc())
    r1, r2 = wps["r1"], wps["r2"]
    assert [w.t for w in r1] == [0.0, 1.0, 2.0, 3.5] and [w.t for w in r2] == [0.0, 3.25]  # goals: the moves' ends
    assert [(w.index, w.depart, w.wait, w.sync) for w in r1 if w.depart is not None] == [
        (0, 0.0, 0.0, ""),
        (2, 2.5, 0.5, "step-2"),  # held back: r1 is there at 2 s
    ]
    assert [(w.index, w.depart, w.wait, w.sync, w.partner) for w in r2 if w.depart is not None] == [
        (0, 2.5, 2.5, "step-2", "r1")
    ]


def test_times_and_waits_are_in_the_csv_and_the_yaml_comments() -> None:
    out = files(scheduled_doc())
    lines = out["r2.csv"].splitlines()
    assert "# Planned makespan: 3.5 s (when the last robot is done)." in lines
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    assert list(rows[0]) == list(CSV_COLUMNS) and CSV_COLUMNS[-2:] == ("depart", "wait")
    before = ("index", "x", "y", "yaw", "frame", "step", "kind", "room", "t", "sync", "partner")
    assert CSV_COLUMNS[: len(before)] == before  # the columns of earlier exports keep their places
    assert [(r["t"], r["sync"], r["partner"], r["depart"], r["wait"]) for r in rows] == [
        ("0.0", "step-2", "r1", "2.5", "2.5"),
        ("3.25", "", "", "", ""),
    ]
    for name in ("r2.follow_waypoints.yaml", "r2.rviz_waypoints.yaml"):
        assert (
            "0: step 0, start r2-start, t = 0 s, sync step-2 with r1, depart at t = 2.5 s after a wait of 2.5 s"
            in (out[name])
        )
    assert len(yaml.safe_load(out["r2.follow_waypoints.yaml"])["poses"]) == 2  # the times are comments only
    assert list(yaml.safe_load(out["r2.rviz_waypoints.yaml"])["waypoints"]) == ["waypoint0", "waypoint1"]


def test_a_schedule_of_another_plan_is_refused() -> None:
    doc = scheduled_doc()
    doc["schedule"]["robots"]["r2"]["moves"].append(doc["schedule"]["robots"]["r2"]["moves"][0])
    with pytest.raises(InputError, match="schedule of robot r2 has 2 moves, its actions 1: not the same plan"):
        waypoints(doc)
    doc = scheduled_doc()
    doc["schedule"]["robots"]["r1"]["moves"][1]["to"] = "D"
    with pytest.raises(InputError, match=r"move 2 goes B -> D, its action B -> C"):
        waypoints(doc)
    with pytest.raises(InputError, match="not a complete tmpnav plan document"):
        waypoints({"schema": "tmpnav-plan/2", "robots": [{"name": "r1"}]})


def test_every_robot_gets_four_files_and_the_team_a_schedule() -> None:
    exts = ("csv", "follow_waypoints.yaml", "rviz_waypoints.yaml", "moves.yaml")
    assert sorted(files(plan_doc())) == sorted([*(f"{r}.{ext}" for r in ("r1", "r2") for ext in exts), "schedule.yaml"])


def test_a_document_of_another_schema_is_refused() -> None:
    with pytest.raises(InputError, match="not a tmpnav plan document"):
        waypoints({"schema": "tmpnav-plan/9"})


def test_export_needs_an_output_directory() -> None:
    proc = tmpnav("plan", TWO_ROOMS, "--export", "nav2")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "error: --export needs -o DIR: the waypoint files go to DIR/nav2/ (see 'tmpnav plan --help')"
    ]


def test_a_failed_export_leaves_the_earlier_files_as_they_were(tmp_path: Path) -> None:
    """The files are written through tmpnav.atomic: all or none, errors name the file asked for."""
    folder = tmp_path / "nav2"
    folder.mkdir()
    (folder / "r1.csv").write_text("earlier\n")
    (folder / "r2.rviz_waypoints.yaml").mkdir()  # a rename over a directory fails late
    with pytest.raises(OSError) as caught:
        write_nav2(plan_doc(), folder)
    assert caught.value.filename == str(folder / "r2.rviz_waypoints.yaml")
    assert (folder / "r1.csv").read_text() == "earlier\n"
    assert sorted(p.name for p in folder.iterdir()) == ["r1.csv", "r2.rviz_waypoints.yaml"]
