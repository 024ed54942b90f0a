"""``tmpnav replan`` of a shift with jobs (data/hall.yaml: service times, two windows, a room
only two robots may serve, docks as ends): a robot in service finishes its service, unless the
state says it was interrupted; goals added with their jobs; windows on the first plan's clock
through a revision of a revision; a revision's nav2 files read back and run by tmpnav's executor."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from tests.export.fake_nav2 import replay
from tests.replan.conftest import Planned, moves_of, read_revision
from tmpnav.export.executor import ExecutionStatus
from tmpnav.export.move_files import read_team

pytestmark = pytest.mark.slow

#: seconds of slack for times rounded to the control steps (0.5 s)
TOL = 0.51


def serving(doc: dict[str, Any], t: float) -> dict[str, tuple[str, float]]:
    """robot -> (room, when it is free) for each robot at its station at ``t`` in a plan."""
    out = {}
    for robot in doc["schedule"]["robots"]:
        ended = [m for m in moves_of(doc, robot) if m["end"] <= t]
        if ended and ended[-1]["end"] + ended[-1]["opens"] + ended[-1]["service"] > t:
            m = ended[-1]
            out[robot] = (m["to"], m["end"] + m["opens"] + m["service"])
    return out


def windows_held(doc: dict[str, Any], scenario_jobs: dict[str, Any]) -> None:
    """Every arrival at a room with a window is within it, on the first plan's clock."""
    t0 = doc["revision"]["start_time"] if doc.get("revision") else 0.0
    for robot in doc["schedule"]["robots"]:
        for m in moves_of(doc, robot):
            window = scenario_jobs.get(m["to"], {}).get("window")
            if window is not None:
                assert m["end"] + t0 <= window[1] + TOL, (robot, m, t0, window)
                assert m["end"] + m["opens"] + t0 >= window[0] - TOL, (robot, m, t0, window)


def test_a_robot_in_service_finishes_its_service(hall: Planned, tmp_path: Path) -> None:
    """At 20 s robots stand at their stations (a service, or a wait for a window): each stays
    there until its service ends, then goes on; its station is done."""
    first = hall.doc()
    busy = serving(first, 20.0)
    assert busy, "the first plan has a robot at its station at 20 s"
    proc = hall.replan(tmp_path, "time: 20\n")
    assert proc.returncode == 0, proc.stderr
    doc = read_revision(tmp_path)
    for robot, (room, free) in busy.items():
        assert doc["revision"]["held"][robot] == {"room": room, "seconds": pytest.approx(free - 20.0)}
        assert room in doc["revision"]["done"]
        ahead = moves_of(doc, robot)
        if ahead:
            assert ahead[0]["from"] == room and ahead[0]["start"] >= free - 20.0 - 1e-9
    assert "finishing their services first: " in proc.stdout
    windows_held(doc, first["goals"]["jobs"])


def test_an_interrupted_service_is_not_waited_for(hall: Planned, tmp_path: Path) -> None:
    """A service the state says was cut short is not done: its station is served again, from the
    start. A robot that has left it (the state gives its pose outside) is free at once and the
    station is planned again; a robot still standing in it serves it again there (a room where
    a robot stands counts visited, so no other robot could)."""
    first = hall.doc()
    robot, (room, _) = sorted(serving(first, 20.0).items())[0]
    service = first["goals"]["jobs"][room]["service"]
    proc = hall.replan(tmp_path, f"time: 20\nrobots:\n  {robot}: {{interrupted: true}}\n")
    assert proc.returncode == 0, proc.stderr
    doc = read_revision(tmp_path)
    assert room not in doc["revision"]["done"]
    assert doc["revision"]["held"][robot]["room"] == room
    assert doc["revision"]["held"][robot]["seconds"] >= service - 1e-9  # the whole service again
    moved = tmp_path / "moved"
    moved.mkdir()
    x = {"C1": 3.0, "C2": 9.0, "C3": 15.0}[first["goals"]["ends"][robot]]
    proc = hall.replan(moved, f"time: 20\nrobots:\n  {robot}: {{interrupted: true, pose: [{x}, 6.0, 0.0]}}\n")
    assert proc.returncode == 0, proc.stderr
    doc = read_revision(moved)
    assert room not in doc["revision"]["done"]
    served = [m for r in doc["schedule"]["robots"] for m in moves_of(doc, r) if m["to"] == room]
    assert len(served) == 1 and served[0]["service"] == first["goals"]["jobs"][room]["service"]


def test_goals_added_with_their_jobs(hall: Planned, tmp_path: Path) -> None:
    """G, no goal of the scenario, comes with a service, a pose, a window on the first plan's
    clock and the one robot that may serve it; C2 comes by its name alone."""
    state = (
        "time: 20\n"
        "goals:\n"
        "  add:\n"
        "    - {name: G, service: 30 s, pose: [15.0, 2.0, -90 deg], window: [40 s, 200 s], robots: [r3]}\n"
    )
    proc = hall.replan(tmp_path, state)
    assert proc.returncode == 0, proc.stderr
    doc = read_revision(tmp_path)
    assert doc["goals"]["jobs"]["G"]["service"] == 30.0 and doc["goals"]["jobs"]["G"]["robots"] == ["r3"]
    assert doc["goals"]["jobs"]["G"]["window"] == [20.0, 180.0]  # on the revision's clock, from 20 s
    into = [(r, m) for r in doc["schedule"]["robots"] for m in moves_of(doc, r) if m["to"] == "G"]
    assert len(into) == 1 and into[0][0] == "r3" and into[0][1]["service"] == 30.0
    arrive = into[0][1]["end"] + 20.0
    assert arrive + into[0][1]["opens"] >= 40.0 - TOL and arrive <= 200.0 + TOL
    goal = next(a for a in doc["actions"] for m in a["moves"] if m["to"] == "G")["moves"][0]["goal_pose"]
    assert goal[:2] == pytest.approx([15.0, 2.0])


@pytest.mark.parametrize(
    ("add", "fragment"),
    [
        ("[{name: G, service: -5}]", "goals.add[0].service: -5 is out of range"),
        ("[{name: G, colour: red}]", "goals.add[0].colour: unknown key"),
        ("[{service: 5 s}]", "goals.add[0].name"),
        ("[A, {name: G, robots: [r9]}]", "goals.add[1].robots[0]: 'r9' is not a robot"),
        ("[{name: G, pose: [3.0, 2.0, 0]}]", "goals.add[0].pose: [3, 2] is not inside room 'G'"),
        ("[{name: G, window: [90 s, 10 s]}]", "goals.add[0].window: [90, 10] s is no window"),
        ("[{name: Q}]", "goals.add: 'Q' is not a room of scenario 'hall'"),
        ("[7]", "goals.add[0]: 7 is neither a room name nor a job"),
    ],
)
def test_a_bad_added_job_is_one_line_and_writes_nothing(hall: Planned, tmp_path: Path, add: str, fragment: str) -> None:
    from click.testing import CliRunner

    from tmpnav.cli import cli

    (tmp_path / "state.yaml").write_text(f"time: 20\ngoals:\n  add: {add}\n")
    args = ["replan", str(hall.scenario), "--plan", str(hall.plan), "--state", str(tmp_path / "state.yaml")]
    result = CliRunner().invoke(cli, [*args, "--cache-dir", str(hall.cache), "-o", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0] and str(tmp_path / "state.yaml") in lines[0], lines
    assert "Traceback" not in result.stderr and not (tmp_path / "out").exists()


def test_a_revisions_nav2_files_are_read_back_and_run(hall: Planned, tmp_path: Path) -> None:
    proc = hall.replan(tmp_path, "time: 20\nrobots:\n  r1: {status: down}\n", "--export", "nav2")
    assert proc.returncode == 0, proc.stderr
    folder = tmp_path / "out" / "nav2"
    names = {p.name for p in folder.iterdir()}
    assert "schedule.rev1.yaml" in names and "r2.moves.rev1.yaml" in names and "r1.moves.rev1.yaml" not in names
    team = read_team(folder)
    assert team == read_team(folder, revision=1) and team.robots == ("r2", "r3")
    doc = read_revision(tmp_path)
    assert team.makespan == pytest.approx(doc["schedule"]["makespan"])
    run, _ = replay(team)
    assert run.status is ExecutionStatus.COMPLETED
    # a held robot's first move leaves when its service ends
    for robot, held in doc["revision"]["held"].items():
        if team.moves.get(robot):
            assert team.moves[robot][0].depart >= held["seconds"] - 1e-9


def test_windows_on_the_first_plans_clock_through_a_revision_of_a_revision(hall: Planned, tmp_path: Path) -> None:
    """Revision 1 from 20 s; revision 2 from 25 s of it (45 s of the shift) with r2 down. The
    goals done before revision 1 stay done; B's window closes at 60 s of the shift, before r1 or
    r3 can get there: it is named out of reach on the shift's clock and the rest is planned."""
    first = hall.doc()
    jobs = first["goals"]["jobs"]
    one = tmp_path / "one"
    one.mkdir()
    proc = hall.replan(one, "time: 20\n")
    assert proc.returncode == 0, proc.stderr
    rev1 = read_revision(one)
    windows_held(rev1, jobs)
    two = tmp_path / "two"
    two.mkdir()
    proc = hall.replan(two, "time: 25\nrobots:\n  r2: {status: down}\n", plan=one / "out" / "plan.json")
    assert proc.returncode == 12, proc.stderr
    rev2 = read_revision(two)
    assert rev2["revision"]["number"] == 2 and rev2["revision"]["start_time"] == pytest.approx(45.0)
    assert set(rev1["revision"]["done"]) <= set(rev2["revision"]["done"])
    assert [e["room"] for e in rev2["revision"]["unreachable"]] == ["B"]
    assert rev2["revision"]["unreachable"][0]["why"].startswith("its window closes at 60 s, before any robot")
    assert "error: goal B is left out: its window closes at 60 s" in proc.stderr
    windows_held(rev2, jobs)
    entered = [m["to"] for r in rev2["schedule"]["robots"] for m in moves_of(rev2, r)]
    goals = set(first["goals"]["visit"])
    done = set(rev2["revision"]["done"]) | {
        m["to"] for r in rev1["schedule"]["robots"] for m in moves_of(rev1, r) if m["end"] <= 25.0
    }
    assert not done & set(entered) and goals <= done | {"B"} | set(entered)


def test_the_progress_line_says_how_much_of_the_budget_the_run_had_spent(hall: Planned, tmp_path: Path) -> None:
    """The line's first time is the command's; the budget is the run's, and the run had spent
    part of it (or more) before the search's first plan: the line says how much."""
    proc = hall.replan(tmp_path, "time: 21.5\n", "--anytime-budget", "3")
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("search ")]
    assert lines and all(re.search(r"; the run at \d+\.\d s of its budget of 3 s\)$", line) for line in lines), lines


def test_a_robot_standing_in_a_station_left_to_do_serves_it_first(hall: Planned, tmp_path: Path) -> None:
    """At 1 s r1 stands in A (a 10 s job) and r2 in E (12 s, its window opening at 20 s), neither
    done: a room where a robot stands is done, so each does its job there first (it waits for E's
    window), instead of counting the station done with its service never done."""
    state = "time: 1\nrobots:\n  r1: {pose: [3.0, 10.0, 1.57]}\n  r2: {pose: [3.0, 2.0, -1.57]}\n"
    proc = hall.replan(tmp_path, state)
    assert proc.returncode == 0, proc.stderr
    doc = read_revision(tmp_path)
    held = doc["revision"]["held"]
    assert held["r1"] == {"room": "A", "seconds": pytest.approx(10.0)}
    assert held["r2"] == {"room": "E", "seconds": pytest.approx(19.0 + 12.0)}
    for robot, seconds in (("r1", 10.0), ("r2", 31.0)):
        ahead = moves_of(doc, robot)
        assert not ahead or ahead[0]["start"] >= seconds - 1e-9
    entered = [m["to"] for r in doc["schedule"]["robots"] for m in moves_of(doc, r)]
    assert "A" not in entered and "E" not in entered
