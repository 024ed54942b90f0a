"""Plan execution (``tmpnav simulate``): the waypoint switching, and the paper's result."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tmpnav.execution import ARRIVED, execute, reached
from tmpnav.pipeline import PlanOptions, plan

ROOT = Path(__file__).resolve().parents[1]
START = np.array([0.0, 0.0])
WAYPOINT = np.array([2.0, 0.0])


def est(x: float, y: float) -> np.ndarray:
    return np.array([x, y, 0.0])


def test_a_waypoint_is_reached_when_the_estimate_is_close() -> None:
    assert reached(est(2.0 - 0.9 * ARRIVED, 0.0), START, WAYPOINT)
    assert reached(est(2.0, 0.9 * ARRIVED), START, WAYPOINT)


def test_a_waypoint_is_reached_when_the_robot_is_abreast_of_it_or_past_it() -> None:
    # 30 cm to the side: turning on the spot towards it would only add heading noise
    assert reached(est(2.0, 0.3), START, WAYPOINT)
    assert reached(est(2.2, -0.3), START, WAYPOINT)


def test_a_waypoint_ahead_is_not_reached() -> None:
    assert not reached(est(1.8, 0.0), START, WAYPOINT)
    assert not reached(est(1.0, 0.5), START, WAYPOINT)
    assert not reached(est(-0.5, 0.0), START, WAYPOINT)


@pytest.mark.slow
def test_mutual_observations_cut_the_worst_error_of_the_landmark_starved_robot(tmp_path: Path) -> None:
    """The paper's Fig. 3(a) on the corridor: 25 sessions, seeded, so the numbers are exact.

    r2 starts in L10, out of every landmark's range; with mutual observations its error
    never exceeds what it starts with, without them it grows along the corridor."""
    report = plan(ROOT / "configs" / "corridor.yaml", PlanOptions.of(cache_dir=tmp_path))
    result = execute(report, sessions=25)
    assert result.starved == "r2"
    assert result.reduction("r2") >= 80.0
    assert result.worst(1, "r2") <= float(result.mean_errors(1, "r2")[:2].max()) + 1e-12  # before they meet
    assert result.truncated_sessions == 0
    for robot in ("r1", "r2"):
        assert result.worst(1, robot) < result.worst(2, robot)
