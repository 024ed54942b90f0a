"""The shipped depot of a fleet's jobs (configs/depot-jobs.yaml, a `tmpnav rooms` skeleton of a
depot hall): four robots that start at their docks and must end there, eight stations with goal
poses and service times, two windows, and a place one robot may not enter. It plans as shipped,
and every constraint holds in plan.json, read here and nowhere else: the scenario's own goals as
plan.json repeats them, the moves, the goal poses, the schedule."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def plan(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    tmp = tmp_path_factory.mktemp("depot")
    out = tmp / "out"
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", "configs/depot-jobs.yaml", "-q", "--anytime-budget", "4",
         "--cache-dir", str(tmp / "cache"), "-o", str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=900,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert (out / "schedule.png").stat().st_size > 10_000
    return dict(json.loads((out / "plan.json").read_text()))


@pytest.mark.slow
def test_every_job_of_the_depot_holds_in_plan_json(plan: dict[str, Any]) -> None:
    goals, schedule = plan["goals"], plan["schedule"]
    jobs, ends = goals["jobs"], goals["ends"]
    assert len(ends) == 4 and len(goals["visit"]) == 8
    assert sum(j["pose"] is not None and j["service"] > 0 for j in jobs.values()) == 8
    assert sum(j["window"] is not None for j in jobs.values()) == 2
    barred = {room: set(j["robots"]) for room, j in jobs.items() if j["robots"]}
    assert barred  # a place some robot may not enter
    moves = [(a, m) for a in plan["actions"] for m in a["moves"]]
    # every goal visited once, by a robot its job allows
    visits = [m["to"] for _, m in moves if m["to"] in goals["visit"]]
    assert sorted(visits) == sorted(goals["visit"])
    for _, m in moves:
        assert m["to"] not in barred or m["robot"] in barred[m["to"]], m
    # each robot ends at its dock: its last move enters it (or it never moved from it)
    for robot, dock in ends.items():
        mine = [m for _, m in moves if m["robot"] == robot]
        assert (mine[-1]["to"] if mine else None) in (dock, None), robot
        if not mine:
            assert schedule["robots"][robot]["rooms"] == 0
    # each move is sent to the station's pose: a robot driven turn-then-drive stands on it, one
    # driven by RPP stops within nav2's goal tolerances of it (docs/models.md)
    for _, m in moves:
        job = jobs.get(m["to"])
        if job is not None and job["pose"] is not None:
            x, y, theta = m["goal_pose"]
            assert (x, y) == pytest.approx(job["pose"][:2], abs=1e-6)
            assert math.remainder(theta - job["pose"][2], 2 * math.pi) == pytest.approx(0.0, abs=1e-6)
    assert "rpp" in {m["controller"] for _, m in moves if m["to"] in jobs} <= {"rpp", "turn-then-drive"}
    # on the clock: each station's service after the arrival, each window kept
    makespan = schedule["makespan"]
    for entry in schedule["robots"].values():
        for t in entry["moves"]:
            job = jobs.get(t["to"])
            assert t["service"] == pytest.approx(job["service"] if job else 0.0, abs=0.5)  # rounded up to steps
            if job is not None and job["window"] is not None:
                earliest, latest = job["window"]
                assert t["end"] <= latest + 1e-6 and t["end"] + t["opens"] >= earliest - 1e-6
        assert entry["busy"] + entry["waits"] + entry["service"] + entry["idle"] == pytest.approx(makespan)
    assert makespan == pytest.approx(max(t["end"] + t["opens"] + t["service"] for e in schedule["robots"].values()
                                         for t in e["moves"]))  # fmt: skip
