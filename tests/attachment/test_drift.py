"""The time windows of the conflict rule (tmpnav/attachment/drift.py): a robot falls behind the
plan's clock while it drives, a planned wait absorbs it, and partners of a paired move start it
together; the rate is the scenario's, by default only for robots localised by AMCL."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from tmpnav.attachment.drift import DEFAULT_CLOCK_DRIFT, clock_drift, lateness, pair_windows
from tmpnav.results import Schedule, TimedMove
from tmpnav.scenario.load import load
from tmpnav.types import ScanModelKind

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
TIMES = np.arange(0.0, 60.5, 0.5)


def move(step: int, robot: str, start: float, end: float, partner: str | None = None) -> TimedMove:
    return TimedMove(step, robot, "A", "B", partner, start, start, end)


def at(values: np.ndarray, t: float) -> float:
    return float(values[round(t / 0.5)])


def test_a_robot_falls_behind_while_it_drives_and_a_planned_wait_absorbs_it() -> None:
    # a drives 0-10 s, stands, drives 12-20 s (2 s of planned wait), stands, drives 40-50 s
    schedule = Schedule(("a",), (move(0, "a", 0.0, 10.0), move(1, "a", 12.0, 20.0), move(2, "a", 40.0, 50.0)))
    late = lateness(schedule, 0.25, TIMES)["a"]
    assert at(late, 0.0) == 0.0 and at(late, 4.0) == pytest.approx(1.0) and at(late, 10.0) == pytest.approx(2.5)
    assert at(late, 11.0) == pytest.approx(2.5)  # it may still be driving the first move
    assert at(late, 12.0) == pytest.approx(0.5) and at(late, 20.0) == pytest.approx(2.5)  # 2 s absorbed
    assert at(late, 40.0) == 0.0 and at(late, 50.0) == pytest.approx(2.5)  # 20 s of wait: on time again
    assert at(late, 60.0) == pytest.approx(2.5)


def test_partners_of_a_paired_move_start_it_together() -> None:
    # a drives alone 0-20 s, then a and b make a paired move 20-30 s; b stood until then
    schedule = Schedule(
        ("a", "b"), (move(0, "a", 0.0, 20.0), move(1, "a", 20.0, 30.0, "b"), move(1, "b", 20.0, 30.0, "a"))
    )
    late = lateness(schedule, 0.1, TIMES)
    assert at(late["b"], 20.0) == pytest.approx(2.0)  # b waits for a, who may be 2 s late
    window = pair_windows(schedule, 0.1, TIMES)[("a", "b")]
    assert at(window, 10.0) == pytest.approx(1.0)  # a 1 s late, b on time
    assert at(window, 20.0) == 0.0 and at(window, 25.0) == pytest.approx(0.5)  # together since 20 s
    assert at(window, 40.0) == pytest.approx(3.0)  # afterwards: as late as either may be


def test_no_drift_no_window() -> None:
    schedule = Schedule(("a", "b"), (move(0, "a", 0.0, 10.0), move(1, "b", 0.0, 10.0)))
    assert pair_windows(schedule, 0.0, TIMES) == {}


def test_the_default_drift_is_for_robots_localised_by_amcl() -> None:
    with_amcl = load(CONFIGS / "building-2robots.yaml")
    sensor = with_amcl.models.range_sensor
    assert sensor is not None and sensor.localiser.kind is ScanModelKind.AMCL  # the shipped default
    assert clock_drift(with_amcl) == DEFAULT_CLOCK_DRIFT
    beams = replace(sensor, localiser=replace(sensor.localiser, kind=ScanModelKind.BEAMS))
    lidar = replace(with_amcl, models=replace(with_amcl.models, range_sensor=beams))
    assert clock_drift(lidar) == 0.0 and clock_drift(load(CONFIGS / "corridor.yaml")) == 0.0
    named = replace(with_amcl, planner=replace(with_amcl.planner, clock_drift=0.02))
    assert clock_drift(named) == 0.02
