"""``tmpnav replan``: the plan of the rest of the work from where the team is, read from the
revision's plan.json: a robot down (the others do its goals), a door closed (a goal no robot can
reach is named, the rest is planned, exit 12), goals added mid-run, a robot's belief given as
AMCL publishes it; and bad input, one line and exit 2 each, nothing written."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: three rooms off a corridor, each behind a door; two robots in the corridor
WORLD = """
name: replan
map:
  bounds: [0, 0, 18, 8]
  walls:
    - [[0, 0], [18, 0], [18, 8], [0, 8], [0, 0]]
    - [[0, 4], [2.4, 4]]
    - [[3.6, 4], [8.4, 4]]
    - [[9.6, 4], [14.4, 4]]
    - [[15.6, 4], [18, 4]]
    - [[6, 4], [6, 8]]
    - [[12, 4], [12, 8]]
rooms:
  - {name: A, polygon: [[0.2, 4.2], [5.8, 4.2], [5.8, 7.8], [0.2, 7.8]]}
  - {name: B, polygon: [[6.2, 4.2], [11.8, 4.2], [11.8, 7.8], [6.2, 7.8]]}
  - {name: D, polygon: [[12.2, 4.2], [17.8, 4.2], [17.8, 7.8], [12.2, 7.8]]}
  - {name: C, polygon: [[0.2, 0.2], [17.8, 0.2], [17.8, 3.8], [0.2, 3.8]]}
doors:
  - {name: dA, segment: [[2.4, 4], [3.6, 4]]}
  - {name: dB, segment: [[8.4, 4], [9.6, 4]]}
  - {name: dD, segment: [[14.4, 4], [15.6, 4]]}
landmarks:
  - {name: printer, position: [1.0, 7.5]}
  - {name: plant, position: [17.0, 0.5]}
  - {name: desk, position: [9.0, 0.5]}
robots:
  - {name: r1, pose: [3.0, 2.0, 0.0]}
  - {name: r2, pose: [15.0, 2.0, 3.1416]}
roadmap: {samples: 400, instantiations: 3, seed: 1}
goals:
  visit: [A, B]
planner: {costs: table}
"""


def tmpnav(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tmpnav", *map(str, args)], capture_output=True, text=True, cwd=ROOT, timeout=600
    )


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    """The scenario, its first plan (plan.json) and the cache both were made with."""
    tmp = tmp_path_factory.mktemp("replan")
    scenario = tmp / "replan.yaml"
    scenario.write_text(WORLD)
    proc = tmpnav("plan", scenario, "-q", "--cache-dir", tmp / "cache", "-o", tmp / "first")
    assert proc.returncode == 0, proc.stderr
    return scenario, tmp / "first" / "plan.json", tmp / "cache"


def replan(planned: tuple[Path, Path, Path], tmp: Path, state: str, *more: str) -> subprocess.CompletedProcess[str]:
    scenario, plan, cache = planned
    (tmp / "state.yaml").write_text(state)
    return tmpnav("replan", scenario, "--plan", plan, "--state", tmp / "state.yaml", "--cache-dir", cache, *more)


def revision(tmp: Path) -> dict[str, Any]:
    return dict(json.loads((tmp / "out" / "plan.json").read_text()))


def flat(rows: list[list[float]]) -> list[float]:
    return [v for row in rows for v in row]


def entered(doc: dict[str, Any]) -> list[tuple[str, str]]:
    return [(m["robot"], m["to"]) for a in doc["actions"] for m in a["moves"]]


@pytest.mark.slow
def test_a_robot_down_leaves_its_goals_to_the_others(planned: tuple[Path, Path, Path], tmp_path: Path) -> None:
    first = json.loads(planned[1].read_text())
    mine = [to for robot, to in entered(first) if robot == "r2"]
    assert mine, "the first plan gives r2 some goals"
    proc = replan(planned, tmp_path, "time: 0\nrobots:\n  r2: {status: down}\n", "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    doc = revision(tmp_path)
    assert doc["revision"]["number"] == 1 and doc["revision"]["down"] == ["r2"]
    assert sorted(doc["trajectories"]) == ["r1"]
    assert sorted(to for _, to in entered(doc)) == ["A", "B"]  # r1 does every goal, each once
    assert "revision 1 of plan.json, from 0.0 s" in proc.stdout


@pytest.mark.slow
def test_a_closed_door_leaves_its_room_out_and_plans_the_rest(planned: tuple[Path, Path, Path], tmp_path: Path) -> None:
    """At 5 s, door dB closes: room B is out of reach (one line, exit 12); A is planned from the
    robots' beliefs in the first plan at 5 s, and nothing done is done again."""
    proc = replan(planned, tmp_path, "time: 5\ndoors: {dB: closed}\n", "-o", tmp_path / "out")
    assert proc.returncode == 12, proc.stderr
    errors = [
        line for line in proc.stderr.strip().splitlines() if not line.startswith("search ")
    ]  # the search's progress
    assert errors == [
        "error: goal B is left out: no robot allowed there can reach it (a closed door, or no way through)"
    ]
    doc = revision(tmp_path)
    assert doc["revision"]["unreachable"] == [
        {"room": "B", "why": "no robot allowed there can reach it (a closed door, or no way through)"}
    ]
    assert doc["revision"]["start_time"] == 5.0
    assert [to for _, to in entered(doc)] == ([] if "A" in doc["revision"]["done"] else ["A"])
    first = json.loads(planned[1].read_text())
    at5 = [s for s in first["trajectories"]["r1"] if s["t"] <= 5.0][-1]
    assert doc["trajectories"]["r1"][0]["mean"] == pytest.approx(at5["mean"], abs=1e-6)
    assert flat(doc["trajectories"]["r1"][0]["cov"]) == pytest.approx(flat(at5["cov"]), abs=1e-9)


@pytest.mark.slow
def test_a_revision_of_a_revision_keeps_the_doors_closed(planned: tuple[Path, Path, Path], tmp_path: Path) -> None:
    """dB closed in the first revision stays closed in a revision of it whose state says nothing
    of doors: B, asked for again, is still out of reach (it used to be planned through dB)."""
    first = tmp_path / "first"
    first.mkdir()
    proc = replan(planned, first, "time: 5\ndoors: {dB: closed}\n", "-o", first / "out")
    assert proc.returncode == 12, proc.stderr
    assert revision(first)["revision"]["doors"] == {"dB": "closed"}
    scenario, _, cache = planned
    (tmp_path / "state.yaml").write_text("time: 2\ngoals: {add: [B]}\n")
    proc = tmpnav(
        "replan", scenario, "--plan", first / "out" / "plan.json", "--state", tmp_path / "state.yaml",
        "--cache-dir", cache, "-o", tmp_path / "out",
    )  # fmt: skip
    assert proc.returncode == 12, proc.stderr
    assert "error: goal B is left out" in proc.stderr
    doc = revision(tmp_path)
    assert doc["revision"]["number"] == 2 and doc["revision"]["doors"] == {"dB": "closed"}
    assert "B" not in [to for _, to in entered(doc)]


@pytest.mark.slow
def test_goals_added_mid_run_and_a_belief_as_amcl_publishes_it(
    planned: tuple[Path, Path, Path], tmp_path: Path
) -> None:
    """The state gives r1 a pose and AMCL's 6x6 covariance (36 numbers, x, y, yaw at 0, 7, 35),
    marks A done and adds D: the revision plans B and D from there."""
    amcl = [0.0] * 36
    amcl[0], amcl[7], amcl[35], amcl[1], amcl[6] = 0.04, 0.09, 0.01, 0.01, 0.01
    state = (
        "time: 3\nvisited: [A]\ngoals: {add: [D]}\n"
        f"robots:\n  r1: {{pose: [9.0, 2.0, 0.0], covariance: {json.dumps(amcl)}}}\n"
    )
    proc = replan(planned, tmp_path, state, "-o", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    doc = revision(tmp_path)
    assert sorted(to for _, to in entered(doc)) == ["B", "D"]
    assert doc["revision"]["done"] == ["A"]
    start = doc["trajectories"]["r1"][0]
    assert start["mean"] == pytest.approx([9.0, 2.0, 0.0])
    assert flat(start["cov"]) == pytest.approx([0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 0.01])


@pytest.mark.parametrize(
    ("state", "fragment"),
    [
        ("time: 1\nrobots:\n  r9: {status: down}\n", "robots.r9: not a robot of scenario 'replan'"),
        ("time: 1\nvisited: [Q]\n", "visited: 'Q' is not a room of scenario 'replan'"),
        ("time: 1\ndoors: {dQ: closed}\n", "doors.dQ: not a door of scenario 'replan'"),
        ("time: 1\nrobots:\n  r1: {pose: [6.0, 6.0, 0.0]}\n", "robots.r1.pose: a robot of radius 0.25 m at [6, 6]"),
        ("time: -1\n", "time: -1 s is outside the plan"),
        ("time: 100000\n", "time: 100000 s is outside the plan"),
        (
            "time: 1\nrobots:\n  r1: {covariance: [[1, 0, 0], [0, -1, 0], [0, 0, 1]]}\n",
            "robots.r1.covariance: is not positive semi-definite",
        ),
        ("time: 1\nrobots:\n  r1: {status: asleep}\n", "robots.r1.status: 'asleep' is not a status; expected down"),
        ("robots: {}\n", "time: missing"),
        (
            "time: 1\nrobots:\n  r1: {pose: [3.0, 4.1, 1.57]}\ndoors: {dA: closed}\n",
            "doors: a door closed on r1, which stands at [3.00, 4.10] in the way of the doors closed (dA)",
        ),
    ],
    ids=[
        "robot",
        "room",
        "door",
        "pose-in-wall",
        "before",
        "after",
        "covariance",
        "status",
        "no-time",
        "door-on-robot",
    ],
)
def test_bad_state_is_one_line_and_writes_nothing(
    planned: tuple[Path, Path, Path], tmp_path: Path, state: str, fragment: str
) -> None:
    """In-process (click's runner): every one of these is refused before any planning."""
    from click.testing import CliRunner

    from tmpnav.cli import cli

    scenario, plan, cache = planned
    (tmp_path / "state.yaml").write_text(state)
    args = ["replan", str(scenario), "--plan", str(plan), "--state", str(tmp_path / "state.yaml")]
    result = CliRunner().invoke(cli, [*args, "--cache-dir", str(cache), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and fragment in lines[0], lines
    assert "Traceback" not in result.stderr and not (tmp_path / "out").exists()


def test_a_plan_of_another_scenario_is_refused(planned: tuple[Path, Path, Path], tmp_path: Path) -> None:
    other = tmp_path / "other.yaml"
    other.write_text(WORLD.replace("name: replan", "name: another"))
    (tmp_path / "state.yaml").write_text("time: 1\n")
    proc = tmpnav(
        "replan", other, "--plan", planned[1], "--state", tmp_path / "state.yaml", "--cache-dir", planned[2],
        "-o", tmp_path / "out",
    )  # fmt: skip
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "a plan of scenario 'replan'" in lines[0] and "not of 'another'" in lines[0], lines
    assert not (tmp_path / "out").exists()


def test_the_plans_own_folder_is_not_overwritten(planned: tuple[Path, Path, Path], tmp_path: Path) -> None:
    before = planned[1].read_bytes()
    proc = replan(planned, tmp_path, "time: 1\n", "-o", planned[1].parent)
    assert proc.returncode == 2 and "holds the plan being revised" in proc.stderr
    assert planned[1].read_bytes() == before


@pytest.mark.slow
def test_a_session_plans_updates_and_names_each_revisions_nav2_files(tmp_path: Path) -> None:
    """The fleet manager's API: load once, plan, update twice (the second revises the first
    revision: its time counts from the revision's start), each revision's nav2 files named with
    its number."""
    from tmpnav.pipeline import PlanOptions
    from tmpnav.replan import Session, TeamState, nav2_files
    from tmpnav.replan.state import RobotState

    scenario = tmp_path / "replan.yaml"
    scenario.write_text(WORLD.replace("visit: [A, B]", "visit: [A, B, D]"))
    session = Session(scenario, PlanOptions.of(cache_dir=tmp_path / "cache"))
    first = session.plan()
    assert first.revision is None and "r1.moves.yaml" in nav2_files(first)
    one = session.update(TeamState(tmp_path / "s1", 2.0, robots={"r2": RobotState("r2", down=True)}))
    assert one.revision is not None and (one.revision.number, one.revision.start_time) == (1, 2.0)
    assert [r.name for r in one.scenario.robots] == ["r1"]
    names = set(nav2_files(one))
    assert "r1.moves.rev1.yaml" in names and "schedule.rev1.yaml" in names and not any("r2" in n for n in names)
    two = session.update(TeamState(tmp_path / "s2", 1.5))
    assert two.revision is not None and (two.revision.number, two.revision.start_time) == (2, 3.5)
    left = {m[2] for step in two.task.steps for m in step}
    assert left <= {"A", "B", "D"} and not left & set(two.revision.done)
