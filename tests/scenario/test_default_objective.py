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


def fleet(tmp_path: Path, planner: str = "") -> Path:
    """configs/building-8robots.yaml with a ninth robot (in corridor A, east of r1): a fleet."""
    text = (ROOT / "configs" / "building-8robots.yaml").read_text()
    old = "  - {name: r8, pose: [35.5, 11, 1.5708]}"
    assert old in text
    text = text.replace(old, old + "\n  - {name: r9, pose: [6.5, 7.25, 0]}")
    if planner:
        text = text.replace("\nrobots:\n", f"\nplanner: {planner}\n\nrobots:\n", 1)
    path = tmp_path / "fleet.yaml"
    path.write_text(text)
    return path


def test_a_fleet_plans_for_the_makespan_with_a_minimum_of_rooms_by_default(tmp_path: Path) -> None:
    """From 9 robots on, a tour too plans with the makespan first and every robot on at least 3
    goal rooms (tmpnav.choices.FLEET); 8 robots keep the weighted objective and no minimum."""
    from tmpnav.types import FLEET_DEFAULT

    nine = load(fleet(tmp_path)).planner
    assert (nine.objective, nine.min_rooms, nine.min_rooms_from) == ("makespan", 3, FLEET_DEFAULT)
    eight = load(ROOT / "configs" / "building-8robots.yaml").planner
    assert (eight.objective, eight.min_rooms, eight.min_rooms_from) == ("weighted", 0, "")
    named = load(fleet(tmp_path, "{objective: weighted, min_rooms: 0}")).planner
    assert (named.objective, named.min_rooms) == ("weighted", 0)


def test_a_fleets_default_minimum_gives_way_to_a_search_that_keeps_none(tmp_path: Path) -> None:
    """--search exact and the paper's encoding keep no minimum: a fleet's default one is set aside
    for them, one the scenario or the command line names is refused (one line)."""
    from tmpnav.errors import InputError
    from tmpnav.options import Overrides, apply_options

    scenario = load(fleet(tmp_path))
    exact = apply_options(scenario, Overrides(search="exact")).planner
    assert (exact.min_rooms, exact.min_rooms_from) == (0, "")
    assert apply_options(scenario, Overrides(min_rooms=2)).planner.min_rooms_from == "--min-rooms"
    with pytest.raises(InputError, match=r"planner\.min_rooms 3 needs the anytime search"):
        apply_options(load(fleet(tmp_path, "{min_rooms: 3}")), Overrides(search="exact"))
