"""Seeded replans of the shift (data/hall.yaml): a random time, sometimes a robot down, sometimes
a job added (with a service and a window on the shift's clock). Each revision does every goal
not done once (or names it out of reach), holds every window on the shift's clock, and lets
every robot at its station finish its service before it moves."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from tests.replan.conftest import Planned, moves_of, read_revision
from tests.replan.test_shift import TOL, serving, windows_held

pytestmark = pytest.mark.slow

SEEDS = range(6)


@pytest.mark.parametrize("seed", SEEDS)
def test_a_seeded_replan_does_every_goal_once_on_time_after_the_services(
    hall: Planned, tmp_path: Path, seed: int
) -> None:
    rng = random.Random(seed)
    first = hall.doc()
    makespan = first["schedule"]["makespan"]
    t = round(rng.uniform(5.0, makespan - 5.0), 1)
    robots = sorted(first["schedule"]["robots"])
    lines = [f"time: {t}"]
    down = rng.choice(robots) if rng.random() < 0.5 else None
    if down is not None:
        lines += ["robots:", f"  {down}: {{status: down}}"]
    jobs = dict(first["goals"]["jobs"])
    if rng.random() < 0.5:
        service, opens = rng.choice([10, 20, 30]), round(t + rng.uniform(10.0, 40.0))
        window = [opens, opens + 150]
        lines += ["goals:", "  add:", f"    - {{name: G, service: {service} s, pose: [15.0, 2.0, -90 deg], "
                  f"window: [{window[0]} s, {window[1]} s]}}"]  # fmt: skip
        jobs["G"] = {"service": float(service), "window": window}
    proc = hall.replan(tmp_path, "\n".join(lines) + "\n")
    assert proc.returncode in (0, 12), proc.stderr
    doc = read_revision(tmp_path)
    revision = doc["revision"]
    windows_held(doc, jobs)
    entered = [m["to"] for r in doc["schedule"]["robots"] for m in moves_of(doc, r)]
    left = {e["room"] for e in revision["unreachable"]}
    goals = set(first["goals"]["visit"]) | ({"G"} if "G" in jobs else set())
    # a robot that stands in a goal room (held there for its service) does it by starting there
    standing = {h["room"] for h in revision["held"].values()} - set(revision["done"])
    for goal in goals:
        times = entered.count(goal) + (goal in revision["done"]) + (goal in standing)
        assert times == 1 or (times == 0 and goal in left), (goal, times, revision)
    for robot, (room, free) in serving(first, t).items():
        if robot == down:
            continue
        assert revision["held"][robot]["room"] == room
        ahead = moves_of(doc, robot)
        assert not ahead or ahead[0]["start"] >= free - t - TOL
