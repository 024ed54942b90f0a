"""The objective a scenario gets when it names none (tmpnav.choices.default_objective): the
makespan for a team on a shift (robots back to their docks, or jobs with service times), the
weighted objective otherwise, and always the one a scenario names."""

from __future__ import annotations

from pathlib import Path

import pytest

from tmpnav.choices import default_objective
from tmpnav.scenario import load

ROOT = Path(__file__).resolve().parents[2]
DEPOT = ROOT / "configs" / "depot-jobs.yaml"


def depot_variant(tmp_path: Path, old: str, new: str) -> Path:
    """configs/depot-jobs.yaml with one edit, its map found where it is."""
    text = DEPOT.read_text().replace('ros: "depot/depot.yaml"', f'ros: "{DEPOT.parent / "depot" / "depot.yaml"}"')
    assert old in text
    path = tmp_path / "depot.yaml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(
    ("scenario", "objective"),
    [
        ("configs/depot-jobs.yaml", "makespan"),  # four robots, docks, service times
        ("benchmarks/shift/warehouse-shift.yaml", "makespan"),
        ("configs/corridor.yaml", "weighted"),  # the paper's swap: a tour of rooms, no jobs
        ("configs/building-4robots.yaml", "weighted"),
    ],
)
def test_a_team_on_a_shift_plans_for_the_makespan_by_default(scenario: str, objective: str) -> None:
    assert load(ROOT / scenario).planner.objective == objective


def test_the_objective_a_scenario_names_is_kept(tmp_path: Path) -> None:
    path = depot_variant(tmp_path, "roadmap:\n", "planner: {objective: weighted}\n\nroadmap:\n")
    assert load(path).planner.objective == "weighted"


def test_jobs_without_service_and_no_ends_are_no_shift(tmp_path: Path) -> None:
    text = depot_variant(tmp_path, "  ends: {r1: P1, r2: P4, r3: P13, r4: P14}  # back to the docks\n", "")
    no_service = text.read_text()
    for s in ("20 s", "15 s", "30 s", "10 s", "25 s"):
        no_service = no_service.replace(f"service: {s}", "service: 0 s")
    text.write_text(no_service)
    assert load(text).planner.objective == "weighted"


def test_one_robot_is_no_team() -> None:
    assert default_objective(1, True) == "weighted"
    assert default_objective(2, True) == "makespan"
    assert default_objective(4, False) == "weighted"
