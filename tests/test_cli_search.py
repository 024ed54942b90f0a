"""``tmpnav plan --search / --costs / --time-budget`` through the real command line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.test_cli_plan import ROOT, assert_clean_failure, tmpnav

CORRIDOR = ROOT / "configs" / "corridor-2robots.yaml"


@pytest.mark.slow
def test_anytime_with_table_costs_reports_the_search_and_its_bound(tmp_path: Path) -> None:
    proc = tmpnav(
        "plan",
        str(CORRIDOR),
        "--search",
        "anytime",
        "--costs",
        "table",
        "--objective",
        "cost",
        "--cache-dir",
        str(tmp_path),
        "--format",
        "json",
    )
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["search"]["mode"] == "anytime" and doc["search"]["costs"] == "table"
    assert doc["search"]["stopped"] in ("optimal", "converged")
    bound = doc["bound"]
    assert bound["value"] <= doc["cost"]["planner"] + 1e-9
    assert bound["gap"] == pytest.approx((doc["cost"]["planner"] - bound["value"]) / doc["cost"]["planner"])
    assert doc["status"] == ("solved-optimally" if bound["proved_optimal"] else "solved-satisficing")
    # progress on stderr: elapsed time, best cost, bound; no other line
    lines = proc.stderr.strip().splitlines()
    assert lines and all(line.startswith("search ") and " best " in line and " bound " in line for line in lines)


@pytest.mark.slow
def test_the_default_plans_with_carried_beliefs(tmp_path: Path) -> None:
    proc = tmpnav("plan", str(CORRIDOR), "--cache-dir", str(tmp_path), "--format", "json", "-q")
    assert proc.returncode == 0, proc.stderr
    doc = json.loads(proc.stdout)
    assert doc["search"]["costs"] == "carried"
    assert doc["cost"]["planner"] == pytest.approx(doc["cost"]["resimulated"], rel=1e-12)
    for action in doc["actions"]:
        assert action["planner_cost"] == pytest.approx(action["resimulated_cost"], rel=1e-12)
    again = tmpnav("plan", str(CORRIDOR), "--cache-dir", str(tmp_path), "--format", "json", "-q")
    assert json.loads(again.stdout)["cache"]["plan_hit"] is True
    assert json.loads(again.stdout)["actions"] == doc["actions"]


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("--search", "anytime", "--encoding", "paper"), "paper's encoding"),
        (("--costs", "carried", "--encoding", "paper"), "paper's encoding"),
        (("--search", "sideways"), "--search"),
        (("--time-budget", "0"), "--time-budget"),
        (("--costs", "both"), "--costs"),
    ],
)
def test_bad_search_options_are_one_line(args: tuple[str, ...], fragment: str, tmp_path: Path) -> None:
    proc = tmpnav("plan", str(ROOT / "configs" / "two-rooms.yaml"), "--cache-dir", str(tmp_path), "-q", *args)
    assert_clean_failure(proc, 2, fragment)
