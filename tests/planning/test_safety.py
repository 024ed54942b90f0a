"""Safe by default: a threshold the unconstrained plan meets costs nothing; what would help a move over it."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from tmpnav.pipeline import PlanOptions, plan
from tmpnav.planning.safety import riskiest_point, what_would_help
from tmpnav.report.schedule import objective_values

pytestmark = pytest.mark.slow


def four_rooms(seed: int) -> dict:  # type: ignore[type-arg]
    """Four rooms off a corridor, two robots with a lidar placed at random in the corridor, two or
    three goal rooms drawn at random."""
    rng = np.random.default_rng(seed)
    doors = [(2.4, 3.6), (6.4, 7.6), (10.4, 11.6), (14.4, 15.6)]
    walls = [[[0, 0], [16, 0], [16, 8], [0, 8], [0, 0]], [[4, 4], [4, 8]], [[8, 4], [8, 8]], [[12, 4], [12, 8]]]
    edges = [0.0, *(x for d in doors for x in d), 16.0]
    walls += [[[edges[k], 4], [edges[k + 1], 4]] for k in range(0, len(edges), 2)]
    rooms = [
        {
            "name": f"R{k + 1}",
            "polygon": [[4 * k + 0.2, 4.2], [4 * k + 3.8, 4.2], [4 * k + 3.8, 7.8], [4 * k + 0.2, 7.8]],
        }
        for k in range(4)
    ]
    robots = [
        {"name": f"r{i + 1}", "pose": [float(rng.uniform(1, 15)), float(rng.uniform(1, 3)), 0.0]} for i in range(2)
    ]
    goals = [f"R{k + 1}" for k in rng.choice(4, size=int(rng.integers(2, 4)), replace=False)]
    return {
        "name": f"four-rooms-{seed}",
        "map": {"bounds": [0, 0, 16, 8], "resolution": 0.05, "walls": walls},
        "rooms": rooms,
        "doors": [
            {"name": f"door-R{k + 1}", "segment": [[a, 4], [b, 4]], "state": "open"} for k, (a, b) in enumerate(doors)
        ],
        "robots": robots,
        "models": {"range_sensor": {"range": 12, "beams": 60, "sigma_range": 0.03, "divergence": 0.01}},
        "roadmap": {"samples": 400, "instantiations": 3, "seed": seed},
        "goals": {"visit": goals},
    }


@pytest.mark.parametrize("seed", range(4))
def test_a_threshold_the_unconstrained_plan_meets_returns_that_plan_or_a_better_one(seed: int, tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(four_rooms(seed)))
    free = plan(path, PlanOptions.of(cache_dir=tmp_path / "c", max_risk=-1.0, accept_risk=True))  # --max-risk none
    if free.worst_risk > 0.05:
        pytest.skip(f"the unconstrained plan is at {free.worst_risk:.2g}")
    held = plan(path, PlanOptions.of(cache_dir=tmp_path / "c", max_risk=0.05, accept_risk=True))
    assert held.scenario.planner.max_risk == 0.05 and held.worst_risk <= 0.05
    assert objective_values(held).value <= objective_values(free).value + 1e-6


def test_the_riskiest_point_is_where_the_bound_is_made_and_what_would_help_there(tmp_path: Path) -> None:
    """Without its lidar (the paper's model) a robot of the four rooms is decimetres uncertain at a
    door: the advice names the door, its std against the room it has, and landmarks or a lidar."""
    path = tmp_path / "s.yaml"
    doc = four_rooms(0)
    doc["models"] = {"motion_noise": {"alpha1": 0.05, "alpha3": 0.1}}
    path.write_text(yaml.safe_dump(doc))
    report = plan(path, PlanOptions.of(cache_dir=tmp_path / "c", max_risk=0.001, accept_risk=True))
    point = riskiest_point(report)
    assert point is not None and point.bound == pytest.approx(report.worst_risk)
    text = what_would_help(report, point)
    assert f"{point.robot}'s move {point.origin} -> {point.target}" in text
    assert "what would help there: a landmark or a partner near" in text and "a range sensor" in text


def test_where_the_localisers_failures_make_the_bound_the_advice_says_so(tmp_path: Path) -> None:
    """With a localiser that fails often along its paths (failure_rate), a move's bound is mostly
    those failures: the advice says how much, and names shorter moves and the rate."""
    path = tmp_path / "s.yaml"
    doc = four_rooms(0)
    doc["models"]["range_sensor"]["localiser"] = {"model": "amcl", "failure_rate": 0.01}
    path.write_text(yaml.safe_dump(doc))
    report = plan(path, PlanOptions.of(cache_dir=tmp_path / "c", max_risk=0.001, accept_risk=True))
    point = riskiest_point(report)
    assert point is not None and point.bound == pytest.approx(report.worst_risk)
    assert 0.5 * point.bound <= point.failures <= point.bound * 1.2  # a path's metres at 1% each
    text = what_would_help(report, point)
    assert "of it the localiser's failures along its path" in text
    assert "shorter moves, or a localiser that fails less often" in text and "failure_rate" in text
