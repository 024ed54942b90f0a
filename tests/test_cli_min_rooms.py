"""``tmpnav plan --min-rooms N`` (planner.min_rooms) through the real command line: the corridor's
eight rooms, which the sum of action costs gives to one robot, shared so that each robot visits
at least N; a minimum the robots' jobs make impossible is warned of by name; a minimum with a
search that cannot keep it, or a bad value, is one line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from tests.test_cli_plan import ROOT, assert_clean_failure, tmpnav

ROOMS = [f"L{k}" for k in range(1, 9)]


def corridor(tmp_path: Path, **goals: object) -> Path:
    """configs/corridor.yaml with every room of L1-L8 to visit (and ``goals``' other keys)."""
    doc = yaml.safe_load((ROOT / "configs" / "corridor.yaml").read_text())
    doc["map"]["image"] = str(ROOT / "configs" / doc["map"]["image"]) if "image" in doc["map"] else None
    if doc["map"]["image"] is None:
        del doc["map"]["image"]
    doc["goals"] = {"visit": ROOMS, **goals}
    path = tmp_path / "corridor-8.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def rooms_per_robot(out: Path) -> dict[str, int]:
    doc = json.loads((out / "plan.json").read_text())
    visits = {r["name"]: 0 for r in doc["robots"]}
    for action in doc["actions"]:
        for robot in action["robots"]:
            visits[robot] += 1
    return visits


@pytest.mark.slow
def test_a_minimum_shares_the_rooms_the_sum_of_costs_gives_one_robot(tmp_path: Path) -> None:
    scenario, cache = corridor(tmp_path), str(tmp_path / "cache")
    base = ("plan", str(scenario), "--objective", "cost", "--cache-dir", cache)
    alone = tmpnav(*base, "-o", str(tmp_path / "alone"))
    assert alone.returncode == 0, alone.stderr
    assert min(rooms_per_robot(tmp_path / "alone").values()) == 0, "the sum of costs leaves a robot idle"
    shared = tmpnav(*base, "--min-rooms", "3", "-o", str(tmp_path / "shared"))
    assert shared.returncode == 0, shared.stderr
    assert min(rooms_per_robot(tmp_path / "shared").values()) >= 3
    assert "every robot to visit at least 3 goal rooms (--min-rooms 3)" in shared.stdout
    assert "warning: 1 of" not in shared.stdout  # kept: no warning
    doc = json.loads((tmp_path / "shared" / "plan.json").read_text())
    assert doc["search"]["mode"] == "anytime"
    assert not [w for w in doc["warnings"] if w["kind"] == "short"]


@pytest.mark.slow
def test_a_minimum_the_jobs_forbid_is_warned_of_by_name(tmp_path: Path) -> None:
    only_r1 = [{"name": x, "robots": ["r1"]} for x in ROOMS[1:]]  # r1 starts in L1
    scenario = corridor(tmp_path, jobs=only_r1)
    out = tmp_path / "out"
    proc = tmpnav("plan", str(scenario), "--min-rooms", "2", "--cache-dir", str(tmp_path / "c"), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    short = [w for w in json.loads((out / "plan.json").read_text())["warnings"] if w["kind"] == "short"]
    assert len(short) == 1 and short[0]["robot"] == "r2" and short[0]["limit"] == 2
    assert "r2 (0)" in " ".join(proc.stdout.split())


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("--min-rooms", "3", "--search", "exact"), "planner.min_rooms 3 needs the anytime search"),
        (("--min-rooms", "2", "--encoding", "paper"), "paper's encoding does not"),
        (("--min-rooms", "-1"), "--min-rooms"),
    ],
)
def test_a_minimum_a_search_cannot_keep_or_a_bad_value_is_one_line(
    args: tuple[str, ...], fragment: str, tmp_path: Path
) -> None:
    proc = tmpnav("plan", str(ROOT / "configs" / "corridor.yaml"), *args, "--cache-dir", str(tmp_path))
    assert_clean_failure(proc, 2, fragment)


def test_a_bad_minimum_in_the_scenario_names_its_key(tmp_path: Path) -> None:
    doc = yaml.safe_load((ROOT / "configs" / "corridor.yaml").read_text())
    doc["planner"]["min_rooms"] = 1.5
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(doc))
    proc = tmpnav("plan", str(path), "--cache-dir", str(tmp_path))
    assert_clean_failure(proc, 2, "planner.min_rooms")


@pytest.mark.slow
def test_a_fleet_plans_with_its_default_minimum(tmp_path: Path) -> None:
    """configs/building-8robots.yaml with a ninth robot is a fleet: with no objective or minimum
    named, it plans for the makespan with every robot on at least 3 of its 20 goal rooms, lowered
    to the share of 2, and the summary says where the minimum comes from."""
    from tests.scenario.test_default_objective import fleet

    out = tmp_path / "out"
    result = tmpnav("plan", str(fleet(tmp_path)), "--cache-dir", str(tmp_path / "cache"), "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert "objective makespan" in result.stdout
    assert (
        "every robot to visit at least 2 goal rooms (3: the default for a fleet of 9 robots or more, "
        "lowered to the goal rooms' share per robot)" in result.stdout
    )
    assert min(rooms_per_robot(out).values()) >= 2
