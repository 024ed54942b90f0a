"""Stations end to end: a plan of two places holding five stations and a dock station (the
fixture tests/fixtures/stations.yaml) names every station in plan.json, the schedule and the
nav2 files, and reaches each at its own pose; its replan holds a robot in service at a station.
The schema's and the roadmap's parts are tested in tests/scenario/test_stations.py."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "fixtures" / "stations.yaml"


@pytest.mark.slow
def test_a_plan_names_every_station_and_reaches_its_pose(tmp_path: Path) -> None:
    out = tmp_path / "out"
    cache = ("--cache-dir", str(tmp_path / "c"))
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", "plan", str(FIXTURE), "-q", *cache, "-o", str(out), "--export", "nav2"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    poses = {j["name"]: j["pose"] for j in yaml.safe_load(FIXTURE.read_text())["goals"]["jobs"]}
    doc = json.loads((out / "plan.json").read_text())
    assert doc["goals"]["stations"] == {"A1": "A", "A2": "A", "B1": "B", "B2": "B", "B3": "B", "dock2": "C"}
    moves = [m for a in doc["actions"] for m in a["moves"]]
    assert sorted(m["to"] for m in moves) == sorted(poses)  # each station once, the dock last for r2
    for m in moves:
        x, y, _ = m["goal_pose"]
        assert (x, y) == pytest.approx(tuple(poses[m["to"]][:2]), abs=1e-9)
    assert next(m for m in moves if m["to"] == "B2")["robot"] == "r2"  # the station's robots
    assert [m["to"] for m in doc["schedule"]["robots"]["r2"]["moves"]][-1] == "dock2"
    # nav2: one goal waypoint per station, at its pose, named by it
    goals = []
    for robot in ("r1", "r2"):
        lines = [x for x in (out / "nav2" / f"{robot}.csv").read_text().splitlines() if not x.startswith("#")]
        goals += [row for row in csv.DictReader(lines) if row["kind"] == "goal"]
    assert sorted(row["room"] for row in goals) == sorted(poses)
    for row in goals:
        assert (float(row["x"]), float(row["y"])) == pytest.approx(tuple(poses[row["room"]][:2]), abs=1e-9)
    schedule = yaml.safe_load((out / "nav2" / "schedule.yaml").read_text())
    assert sorted(m["to"] for m in schedule["moves"]) == sorted(poses)
    assert (out / "plan.png").stat().st_size > 0
    # a replan with r1 down: r2, at B1 in its service then, finishes it; the stations left are planned
    state = tmp_path / "state.yaml"
    serving = next(m for m in doc["schedule"]["robots"]["r2"]["moves"] if m["to"] == "B1")
    t = serving["end"] + serving["service"] - 1.0
    state.write_text(f"time: {t}\nrobots:\n  r1: {{status: down}}\n")
    revised = tmp_path / "rev"
    replan = ("replan", str(FIXTURE), "--plan", str(out / "plan.json"), "--state", str(state))
    proc = subprocess.run(
        [sys.executable, "-m", "tmpnav", *replan, *cache, "-o", str(revised)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    assert "r2 at B1 for 1.0 s" in proc.stdout
    rev = json.loads((revised / "plan.json").read_text())
    reached = {m["to"] for r in doc["schedule"]["robots"].values() for m in r["moves"] if m["end"] <= t}
    assert {m["to"] for a in rev["actions"] for m in a["moves"]} == set(poses) - reached
