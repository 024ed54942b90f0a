"""Jobs at goal rooms (``goals.jobs``): the robots that may do a job, its time at the station
and its goal pose hold in every search, as plan.json reports them; bad jobs get one line each."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: two rooms off a corridor; the robots start in the corridor, r1 alone may do either job
WORLD = """
name: jobs
map:
  bounds: [0, 0, 12, 8]
  walls:
    - [[0, 0], [12, 0], [12, 8], [0, 8], [0, 0]]
    - [[0, 4], [2.4, 4]]
    - [[3.6, 4], [8.4, 4]]
    - [[9.6, 4], [12, 4]]
    - [[6, 4], [6, 8]]
rooms:
  - {name: A, polygon: [[0.2, 4.2], [5.8, 4.2], [5.8, 7.8], [0.2, 7.8]]}
  - {name: B, polygon: [[6.2, 4.2], [11.8, 4.2], [11.8, 7.8], [6.2, 7.8]]}
  - {name: C, polygon: [[0.2, 0.2], [11.8, 0.2], [11.8, 3.8], [0.2, 3.8]]}
landmarks:
  - {name: printer, position: [1.0, 7.5]}
  - {name: plant, position: [11.0, 0.5]}
robots:
  - {name: r1, pose: [3.0, 2.0, 0.0]}
  - {name: r2, pose: [9.0, 2.0, 3.1416]}
roadmap: {samples: 300, instantiations: 3, seed: 1}
"""

GOALS = """
goals:
  visit: [A, B]
  jobs:
    - {name: A, robots: [r1], pose: [1.0, 6.5, 90 deg]}
    - {name: B, robots: [r1], service: 20 s}
"""


def tmpnav(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "tmpnav", *args], capture_output=True, text=True, cwd=ROOT, timeout=600
    )


def scenario(tmp_path: Path, goals: str = GOALS, world: str = WORLD) -> Path:
    path = tmp_path / "jobs.yaml"
    path.write_text(world + goals)
    return path


def moves(doc: dict[str, Any]) -> list[dict[str, Any]]:
    return [m for a in doc["actions"] for m in a["moves"]]


@pytest.mark.slow
@pytest.mark.parametrize(
    "mode",
    [("--search", "exact", "--costs", "carried"), ("--search", "anytime", "--costs", "table")],
    ids=[
        "exact-carried",
        "anytime-table",
    ],  # the team's clock and its unfolded search; the cost tables, OR-Tools and ENHSP
)
def test_every_search_keeps_the_jobs(tmp_path: Path, mode: tuple[str, ...]) -> None:
    """Read from plan.json only: the robots that do the jobs, the goal pose, the service time on
    the team's clock (the robot stands, then goes on; the makespan counts it)."""
    out = tmp_path / "out"
    proc = tmpnav("plan", str(scenario(tmp_path)), "-q", *mode, "--cache-dir", str(tmp_path / "c"), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    doc = json.loads((out / "plan.json").read_text())
    done = {m["to"]: m for m in moves(doc)}
    assert set(done) == {"A", "B"} and {m["robot"] for m in done.values()} == {"r1"}  # only r1 may do them
    x, y, theta = done["A"]["goal_pose"]
    assert (x, y) == pytest.approx((1.0, 6.5)) and theta == pytest.approx(math.pi / 2)
    timeline = doc["schedule"]["robots"]["r1"]
    into = {m["to"]: m for m in timeline["moves"]}
    assert into["B"]["service"] == 20.0 and into["A"]["service"] == 0.0
    for prev, nxt in zip(timeline["moves"], timeline["moves"][1:], strict=False):
        assert nxt["ready"] == pytest.approx(prev["end"] + prev["service"])
    makespan = doc["schedule"]["makespan"]
    assert makespan == pytest.approx(max(m["end"] + m["service"] for m in timeline["moves"]))
    assert timeline["service"] == 20.0
    assert timeline["busy"] + timeline["waits"] + timeline["service"] + timeline["idle"] == pytest.approx(makespan)
    # the re-simulated beliefs go on through the service: the robot stands at B until then (its
    # mean shifts only with what it observes)
    steps = doc["trajectories"]["r1"]
    assert steps[-1]["t"] == pytest.approx(makespan)
    arrived = next(s for s in steps if s["t"] == pytest.approx(into["B"]["end"]))
    assert steps[-1]["mean"][:2] == pytest.approx(arrived["mean"][:2], abs=0.05)


@pytest.mark.parametrize(
    ("goals", "fragment"),
    [
        (
            "goals:\n  visit: [A]\n  jobs:\n    - {name: B, service: 5 s}\n",
            "goals.jobs.B: 'B' is no goal room; expected a room named in goals.visit, goals.robots or goals.ends",
        ),
        (
            "goals:\n  visit: [A]\n  jobs:\n    - {name: A, robots: [r9]}\n",
            "goals.jobs.A.robots[0]: 'r9' is not a robot",
        ),
        (
            "goals:\n  robots: {r2: [A]}\n  jobs:\n    - {name: A, robots: [r1]}\n",
            "goals.jobs.A.robots: goals.robots sends r2 to 'A', which its job allows only to r1",
        ),
        (
            "goals:\n  visit: [A]\n  jobs:\n    - {name: A, pose: [9.0, 6.0, 0]}\n",
            "goals.jobs.A.pose: [9, 6] is not inside room 'A'",
        ),
        (
            "goals:\n  visit: [A]\n  jobs:\n    - {name: A, pose: [1.0, 4.3, 0]}\n",
            "touches a wall or an obstacle",
        ),
        (
            "goals:\n  visit: [C]\n  jobs:\n    - {name: C, service: 5 s}\n",
            "goals.jobs.C: robot r1 starts in 'C', so the job would count as done at 0 s",
        ),
        (
            "goals:\n  visit: [A]\n  jobs:\n    - {name: A, service: -5 s}\n",
            "goals.jobs.A.service",
        ),
        (
            "goals:\n  visit: [A]\n  ends: {r9: C}\n",
            "goals.ends.r9: 'r9' is not a robot",
        ),
        (
            "goals:\n  visit: [A]\n  ends: {r1: D}\n",
            "goals.ends.r1: 'D' is not a room",
        ),
        (
            "goals:\n  visit: [A]\n  ends: {r1: A}\n",
            "goals.ends.r1: 'A' is also a goal room (goals.visit or goals.robots); expected a room only r1 ends in",
        ),
        (
            "goals:\n  visit: [A]\n  ends: {r1: C, r2: C}\n",
            "goals.ends.r2: r1 ends in 'C' too; expected one robot per end room",
        ),
        (
            "goals:\n  visit: [A]\n  ends: {r1: C}\nplanner: {encoding: paper}\n",
            "goals.ends.r1: the paper's encoding moves two robots in every action and has no end",
        ),
        (
            "goals:\n  visit: [A]\n  jobs:\n    - {name: A, window: [60 s, 30 s]}\n",
            "goals.jobs.A.window: [60, 30] s is no window; expected [earliest, latest] with 0 <= earliest <= latest",
        ),
        (
            "goals:\n  robots: {r1: [A]}\n  jobs:\n    - {name: A, penalty: 10}\n",
            "goals.jobs.A.penalty: 'A' is a robot's target or end, which every plan must reach",
        ),
    ],
    ids=[
        "not-a-goal",
        "unknown-robot",
        "robot-not-allowed",
        "pose-outside",
        "pose-in-wall",
        "start-inside",
        "negative",
        "end-unknown-robot",
        "end-not-a-room",
        "end-also-a-goal",
        "end-shared",
        "end-paper",
        "window-reversed",
        "penalty-on-a-target",
    ],
)
def test_bad_jobs_get_one_line_each(tmp_path: Path, goals: str, fragment: str) -> None:
    proc = tmpnav("validate", str(scenario(tmp_path, goals)))
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert all(line.startswith("error: ") for line in lines) and fragment in lines[0], lines
    assert len(lines) == (2 if "starts in" in fragment else 1)  # there both robots start in C
    assert "Traceback" not in proc.stderr


def test_a_job_allowed_to_no_robot_that_can_reach_it_has_no_plan(tmp_path: Path) -> None:
    """The paper's encoding moves two robots in every action: r2 may enter neither room, so
    no plan exists (exit code 6), said in one line."""
    proc = tmpnav(
        "plan", str(scenario(tmp_path)), "-q", "--encoding", "paper", "--costs", "table",
        "--cache-dir", str(tmp_path / "c"),
    )  # fmt: skip
    assert proc.returncode == 6, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_a_robot_comes_back_to_its_end_and_a_window_is_kept(tmp_path: Path) -> None:
    """Read from plan.json only: r1 starts in C and must end there, so its last move enters C;
    B's window opens at 60 s, so its robot waits there until then, serves 10 s, and arrives
    before the window closes."""
    goals = "goals:\n  visit: [A, B]\n  ends: {r1: C}\n  jobs:\n    - {name: B, service: 10 s, window: [60 s, 120 s]}\n"
    out = tmp_path / "out"
    proc = tmpnav("plan", str(scenario(tmp_path, goals)), "-q", "--cache-dir", str(tmp_path / "c"), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    doc = json.loads((out / "plan.json").read_text())
    assert doc["goals"]["ends"] == {"r1": "C"}
    assert doc["goals"]["jobs"]["B"]["window"] == [60.0, 120.0]
    r1 = doc["schedule"]["robots"]["r1"]["moves"]
    assert r1 and r1[-1]["to"] == "C"
    into_b = next(m for r in doc["schedule"]["robots"].values() for m in r["moves"] if m["to"] == "B")
    assert into_b["end"] <= 120.0 and into_b["end"] + into_b["opens"] == pytest.approx(60.0, abs=0.5)
    assert into_b["end"] + into_b["opens"] >= 60.0 and into_b["service"] == 10.0
    makespan = doc["schedule"]["makespan"]
    for entry in doc["schedule"]["robots"].values():
        assert entry["busy"] + entry["waits"] + entry["service"] + entry["idle"] == pytest.approx(makespan)


def test_a_window_nobody_can_reach_gets_one_line_and_exit_11(tmp_path: Path) -> None:
    goals = "goals:\n  visit: [A, B]\n  jobs:\n    - {name: B, window: [0 s, 2 s]}\n"
    out = tmp_path / "out"
    proc = tmpnav("plan", str(scenario(tmp_path, goals)), "-q", "--cache-dir", str(tmp_path / "c"), "-o", str(out))
    assert proc.returncode == 11, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "jobs.yaml: goals.jobs.B.window: it closes at 2 s" in lines[0], lines
    assert "the earliest arrival possible is" in lines[0] and not out.exists()


@pytest.mark.slow
@pytest.mark.parametrize(("penalty", "dropped"), [(5.0, ["B"]), (500.0, [])])
def test_an_optional_goal_is_left_undone_only_when_that_is_cheaper(
    tmp_path: Path, penalty: float, dropped: list[str]
) -> None:
    """B is optional and r1 alone may do it: left undone at a penalty of 5, done at 500; the
    objective in plan.json holds the penalty of what is left undone."""
    goals = (
        f"goals:\n  visit: [A, B]\n  jobs:\n    - {{name: A, robots: [r1]}}\n"
        f"    - {{name: B, robots: [r1], penalty: {penalty}}}\n"
    )
    out = tmp_path / "out"
    proc = tmpnav(
        "plan", str(scenario(tmp_path, goals)), "-q", "--search", "exact", "--costs", "table",
        "--cache-dir", str(tmp_path / "c"), "-o", str(out),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    doc = json.loads((out / "plan.json").read_text())
    assert doc["goals"]["dropped"] == dropped and doc["goals"]["jobs"]["B"]["penalty"] == penalty
    entered = {m["to"] for a in doc["actions"] for m in a["moves"]}
    assert ("B" in entered) == (not dropped) and "A" in entered
    o = doc["objective"]
    expected = doc["cost"]["planner"] + o["span_weight"] * doc["makespan"]["planner"] + (penalty if dropped else 0.0)
    assert o["planner"] == pytest.approx(expected)
