"""The chance constraint through the real command line: ``tmpnav plan --max-risk DELTA``.

A plan within the threshold is written with every move's bound at most DELTA; a threshold no
plan meets ends in one line (exit code 9) naming the least threshold found, and planning at
that threshold succeeds; a threshold outside (0, 1] is a usage error.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tests.test_cli_plan import ROOT, TWO_ROOMS, assert_clean_failure, tmpnav

OFFICE = ROOT / "configs" / "office-rooms.yaml"

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("cache")


def moves_risk(out: Path) -> list[float]:
    doc = json.loads((out / "plan.json").read_text())
    return [move["risk"] for action in doc["actions"] for move in action["moves"]]


def test_a_threshold_no_plan_meets_names_the_least_one_and_that_one_plans(cache_dir: Path, tmp_path: Path) -> None:
    """Without its lidar (the paper's model) the office's robots are decimetres uncertain: no plan
    keeps every move within 1e-20 (through the doors' middles, the best are near 1e-12). (With
    it, they are millimetres uncertain and one does.)"""
    paper = "--no-range-sensor"
    proc = tmpnav(
        "plan",
        str(OFFICE),
        paper,
        "-q",
        "--max-risk",
        "1e-20",
        "--cache-dir",
        str(cache_dir),
        "-o",
        str(tmp_path / "no"),
    )
    assert_clean_failure(proc, 9, "within max_risk 1e-20")
    assert not (tmp_path / "no" / "plan.json").exists()
    found = re.search(r"rerun with --max-risk (\S+),", proc.stderr)
    assert found, proc.stderr
    least = found.group(1)
    assert "what would help there" in proc.stderr or "rerun with --max-risk" in proc.stderr
    taken = tmpnav(
        "plan", str(OFFICE), paper, "-q", "--max-risk", "1e-20", "--accept-risk", "--cache-dir", str(cache_dir)
    )
    assert taken.returncode == 0, taken.stderr
    assert "moves over max_risk 1e-20" in taken.stdout and "every move within" not in taken.stdout
    out = tmp_path / "out"
    again = tmpnav(
        "plan",
        str(OFFICE),
        paper,
        "-q",
        "--max-risk",
        least,
        "--accept-risk",
        "--cache-dir",
        str(cache_dir),
        "-o",
        str(out),
    )
    assert again.returncode == 0, again.stderr
    assert max(moves_risk(out)) <= float(least)


def test_any_risk_allowed_at_one(tmp_path: Path) -> None:
    proc = tmpnav(
        "plan", str(TWO_ROOMS), "-q", "--max-risk", "1", "--cache-dir", str(tmp_path / "c"), "-o", str(tmp_path / "o")
    )
    assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("bad", ["0", "1.5", "nan"])
def test_a_threshold_outside_zero_one_is_a_usage_error(bad: str, tmp_path: Path) -> None:
    proc = tmpnav("plan", str(TWO_ROOMS), "--max-risk", bad, "-o", str(tmp_path / "o"))
    assert proc.returncode == 2, proc.stderr
    assert "--max-risk" in proc.stderr and "Traceback" not in proc.stderr


def test_under_a_threshold_robots_in_each_others_way_are_kept_apart(cache_dir: Path, tmp_path: Path) -> None:
    """The bay of tests/attachment/test_conflicts.py: r1 drives the corridor east while r2
    leaves the bay west. As planned (--no-keep-apart) the conflict is reported; with a
    threshold, the plan is kept apart by a wait (the summary and plan.json say how) and the
    checker finds none; by default too."""
    from tests.attachment.test_conflicts import BAY

    scenario = tmp_path / "bay.yaml"
    scenario.write_text(BAY)
    plain = tmpnav(
        "plan", str(scenario), "--no-keep-apart", "--cache-dir", str(cache_dir), "-o", str(tmp_path / "plain")
    )
    assert plain.returncode == 0, plain.stderr
    assert "robots in each other's way: 1" in plain.stdout and "--keep-apart keeps robots apart" in plain.stdout
    assert json.loads((tmp_path / "plain" / "plan.json").read_text())["risk"]["kept_apart"] is None
    kept = tmpnav("plan", str(scenario), "--max-risk", "1", "--cache-dir", str(cache_dir), "-o", str(tmp_path / "kept"))
    assert kept.returncode == 0, kept.stderr
    assert re.search(r"kept apart: 1 -> 0 conflicts by 1 wait \(step \d \+\d+\.\d s\)", kept.stdout), kept.stdout
    assert "robots in each other's way: none" in kept.stdout
    risk = json.loads((tmp_path / "kept" / "plan.json").read_text())["risk"]
    assert risk["conflicts"] == [] and risk["kept_apart"]["conflicts_left"] == 0
    assert len(risk["kept_apart"]["waits"]) == 1 and risk["kept_apart"]["sidesteps"] == []
    default = tmpnav("plan", str(scenario), "--cache-dir", str(cache_dir), "-q")
    assert default.returncode == 0, default.stderr
    assert "robots in each other's way: none" in default.stdout and "kept apart: 1 -> 0" in default.stdout


LANE = """\
# Two robots that must swap ends of a lane too narrow to pass each other in: nothing can keep them apart.
name: lane
map:
  bounds: [0, 0, 14, 1.1]
  resolution: 0.05
  wall_thickness: 0.1
  walls:
    - [[0, 0], [14, 0], [14, 1.1], [0, 1.1], [0, 0]]
rooms:
  - {name: W, polygon: [[0.2, 0.15], [2.0, 0.15], [2.0, 0.95], [0.2, 0.95]]}
  - {name: E, polygon: [[12.0, 0.15], [13.8, 0.15], [13.8, 0.95], [12.0, 0.95]]}
landmarks:
  - {name: w, position: [0.3, 0.3]}
  - {name: m, position: [7.0, 0.3]}
  - {name: e, position: [13.7, 0.3]}
robots:
  - {name: r1, pose: [1.0, 0.55, 0.0]}
  - {name: r2, pose: [13.0, 0.55, 3.1416]}
roadmap: {samples: 300, instantiations: 3, seed: 1}
goals:
  robots: {r1: [E], r2: [W]}
"""


def test_robots_left_in_each_others_way_end_in_exit_10_unless_accepted(cache_dir: Path, tmp_path: Path) -> None:
    """Nothing can part two robots swapping the ends of a narrow lane: under a chance constraint the
    plan is refused in one line (exit code 10) and nothing is written; --accept-risk writes it, with
    a warning; without one (the paper's model) and with --no-keep-apart the conflict is reported."""
    scenario = tmp_path / "lane.yaml"
    scenario.write_text(LANE)
    risk = ("--max-risk", "1")
    refused = tmpnav("plan", str(scenario), *risk, "-q", "--cache-dir", str(cache_dir), "-o", str(tmp_path / "no"))
    assert_clean_failure(refused, 10, "the plan leaves robots in each other's way: r1 and r2 at")
    assert "--accept-risk takes the plan" in refused.stderr and not (tmp_path / "no").exists()
    taken = tmpnav(
        "plan", str(scenario), *risk, "-q", "--accept-risk", "--cache-dir", str(cache_dir), "-o", str(tmp_path / "yes")
    )
    assert taken.returncode == 0, taken.stderr
    assert "warning: robots stay in each other's way: r1 and r2" in taken.stdout
    assert json.loads((tmp_path / "yes" / "plan.json").read_text())["risk"]["conflicts"]
    paper = tmpnav("plan", str(scenario), "-q", "--cache-dir", str(cache_dir))
    assert paper.returncode == 0 and "robots in each other's way: 1" in paper.stdout
    plain = tmpnav("plan", str(scenario), *risk, "-q", "--no-keep-apart", "--cache-dir", str(cache_dir))
    assert plain.returncode == 0 and "--keep-apart keeps robots apart" in plain.stdout


def test_robots_with_a_lidar_plan_within_005_by_default_and_say_so(cache_dir: Path, tmp_path: Path) -> None:
    """The office's robots carry a lidar: the chance constraint 0.05 is in force without a word
    (the summary names it and its source), every move within it (the unconstrained plan grazes
    door frames, bounds near 1: the paths keep to the middle of corridors and doors);
    --max-risk none lifts it, --no-range-sensor (the paper's model) has none."""
    out = tmp_path / "out"
    default = tmpnav("plan", str(OFFICE), "-q", "--cache-dir", str(cache_dir), "-o", str(out))
    assert default.returncode == 0, default.stderr
    assert "chance constraint: max_risk 0.05 (the default for robots with a range sensor)" in default.stdout
    doc = json.loads((out / "plan.json").read_text())
    assert doc["risk"]["max_risk"] == 0.05 and max(moves_risk(out)) <= 0.05 and doc["risk"]["plan"] <= 0.05
    assert "every move within max_risk 0.05" in default.stdout
    assert "the localiser failing 0.000122 times per m driven (failure_rate)" in default.stdout  # nav2's AMCL
    lifted = tmpnav("plan", str(OFFICE), "-q", "--max-risk", "none", "--cache-dir", str(cache_dir))
    assert lifted.returncode == 0 and "chance constraint: none" in lifted.stdout
    paper = tmpnav("plan", str(OFFICE), "-q", "--no-range-sensor", "--cache-dir", str(cache_dir))
    assert "landmarks and partners only (the paper's model); chance constraint: none" in paper.stdout
    asked = tmpnav("plan", str(OFFICE), "-q", "--max-risk", "0.01", "--cache-dir", str(cache_dir))
    assert "chance constraint: max_risk 0.01 (--max-risk)" in asked.stdout
