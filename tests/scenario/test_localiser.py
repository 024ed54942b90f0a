"""models.range_sensor.localiser: what the robots' localiser makes of a scan."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tests.scenario.helpers import base_scenario, write_yaml
from tmpnav.errors import ScenarioError
from tmpnav.execution.moves import QueuedMove
from tmpnav.scenario import load
from tmpnav.types import NAV2_AMCL, ScanModel, ScanModelKind


def with_lidar(tmp_path: Path, localiser: dict | None = None) -> Path:
    doc = base_scenario()
    sensor: dict = {"range": 12, "beams": 60}
    if localiser is not None:
        sensor["localiser"] = localiser
    doc.setdefault("models", {})["range_sensor"] = sensor
    return write_yaml(tmp_path / "s.yaml", doc)


def test_a_lidar_without_a_localiser_is_localised_by_nav2_amcl_at_its_defaults(tmp_path: Path) -> None:
    sensor = load(with_lidar(tmp_path)).models.range_sensor
    assert sensor is not None and sensor.localiser == NAV2_AMCL
    assert not sensor.localiser.fuses_others


def test_the_sensor_bound_is_asked_for_by_name(tmp_path: Path) -> None:
    sensor = load(with_lidar(tmp_path, {"model": "beams"})).models.range_sensor
    assert sensor is not None and sensor.localiser.kind is ScanModelKind.BEAMS
    assert sensor.localiser.fuses_others


def test_the_amcl_model_takes_nav2_defaults_and_fuses_the_lidar_alone(tmp_path: Path) -> None:
    sensor = load(with_lidar(tmp_path, {"model": "amcl"})).models.range_sensor
    assert sensor is not None and sensor.localiser == NAV2_AMCL
    assert not sensor.localiser.fuses_others
    keyed = load(with_lidar(tmp_path, {"model": "amcl", "information": 0.5, "lidar_only": False}))
    assert keyed.models.range_sensor is not None
    assert keyed.models.range_sensor.localiser.information == 0.5 and keyed.models.range_sensor.localiser.fuses_others


def test_a_bad_localiser_value_is_one_line_naming_the_key(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError) as err:
        load(with_lidar(tmp_path, {"model": "amcl", "information": -1}))
    assert len(err.value.problems) == 1 and "models.range_sensor.localiser.information" in str(err.value)


def test_amcl_updates_on_the_move_only() -> None:
    """A step's share of a scan: its distance or turn over AMCL's thresholds, at most 1, none standing."""
    assert NAV2_AMCL.update_rate(0.0, 0.0, 0.5) == 0.0
    assert NAV2_AMCL.update_rate(0.25, 0.0, 0.5) == pytest.approx(0.5)
    assert NAV2_AMCL.update_rate(0.0, 1.0, 0.5) == 1.0
    assert ScanModel().update_rate(0.0, 0.0, 0.5) == 1.0
    assert 0.7 < NAV2_AMCL.mixture_factor(12.0) < 0.9 and ScanModel().mixture_factor(12.0) == 1.0
    assert math.isclose(ScanModel(ScanModelKind.AMCL, z_rand=0.0).mixture_factor(12.0), 1.0, rel_tol=1e-3)


def test_a_robot_is_compared_with_the_plan_at_the_same_point_of_its_path() -> None:
    """The planned track is followed by position, not by time: a robot that drives at half the
    planned speed is compared with the plan where it is."""
    means = np.column_stack([np.arange(11.0), np.zeros(11)])  # 1 m per planned step
    move = QueuedMove(0, "r1", "a", "b", None, (0, 1), means[[0, -1]], 0, 10, (None,), (), None, means)
    k = 0
    for x in np.arange(0.0, 10.01, 0.5):  # half the speed: 0.5 m per step
        k = move.planned_from(k, np.array([x, 0.1]))
        assert k == math.ceil(x - 1e-9)  # the nearest planned point (the later one at a tie), never behind


def test_the_comparison_follows_a_path_that_first_moves_away_from_where_the_robot_goes() -> None:
    """A planned mean that first swings east (the turn on the spot before a move, the way out of a
    room) and then runs west: a robot that drives west at once is compared with the plan's
    westward steps, not held at the plan's first step."""
    east = np.column_stack([65.0 + np.linspace(0.0, 0.6, 6), np.linspace(7.0, 7.3, 6)])
    west = np.column_stack([np.linspace(65.0, 45.0, 41), np.full(41, 7.0)])
    means = np.vstack([east, west])
    move = QueuedMove(0, "r1", "a", "b", None, (0, 1), means[[0, -1]], 0, len(means) - 1, (None,), (), None, means)
    k = 0
    for x in np.linspace(64.5, 45.0, 40):
        k = move.planned_from(k, np.array([x, 7.1]))
        assert np.hypot(*(means[k] - (x, 7.0))) <= 0.25 + 1e-9
    assert k == len(means) - 1
