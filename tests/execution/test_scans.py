"""The range scans' iterated update (tmpnav.execution.scans) and the casts it saves: the scan cast
again only where the estimate has moved by a share of a beam's standard deviation
(``beam_shift``, ``RECAST``), the beams with no true return left out of the predicted casts
(``scan_beams``), and a standing robot's true scan kept (``CompiledJointEkf``)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from tmpnav.execution import Draws, scans
from tmpnav.execution.fast_ekf import CompiledJointEkf
from tmpnav.execution.scans import ScanSimulator, beam_shift
from tmpnav.pipeline import load_world
from tmpnav.types import Belief, RangeSensor, Scenario
from tmpnav.world import World
from tmpnav.world.lidar import scan, scan_beams
from tmpnav.world.visibility import LandmarkVisibility

ROOT = Path(__file__).resolve().parents[2]
#: the shipped scenarios' lidar (docs/scenario.md's defaults)
LIDAR = RangeSensor(
    range=12.0, fov=2 * math.pi, beams=60, sigma_range=0.03, min_range=0.1, max_incidence=math.radians(75),
    divergence=0.01,
)  # fmt: skip


@pytest.fixture(scope="module")
def corridor() -> tuple[Scenario, World]:
    scenario, world = load_world(ROOT / "configs" / "corridor.yaml")
    scenario = dataclasses.replace(scenario, models=dataclasses.replace(scenario.models, range_sensor=LIDAR))
    return scenario, world


def test_beam_shift_is_the_largest_first_order_change_in_standard_deviations() -> None:
    H = np.array([[1.0, 0.0, 2.0], [0.0, -1.0, 10.0], [0.5, 0.5, 0.0]])
    var = np.array([0.03, 0.1, 0.05]) ** 2
    moved = np.array([0.003, -0.001, 0.0002])
    by_beam = [abs(H[b] @ moved) / math.sqrt(var[b]) for b in range(3)]
    assert beam_shift(moved, H, var) == pytest.approx(max(by_beam))
    assert beam_shift(np.zeros(3), H, var) == 0.0
    assert beam_shift(moved, H[:0], var[:0]) == 0.0  # no beam: nothing to shift


def test_scan_beams_casts_the_wanted_beams_as_scan_does(corridor: tuple[Scenario, World]) -> None:
    _, world = corridor
    sim = ScanSimulator(world, LIDAR)
    pose = np.array([5.0, 9.5, 0.3])
    ranges, H, var = sim.ranges(pose)
    wanted = np.random.default_rng(0).random(ranges.size) < 0.7
    r2, H2, v2 = np.empty(ranges.size), np.empty((ranges.size, 3)), np.empty(ranges.size)
    scan_beams(world.signed_distance, *sim.origin, sim.res, pose, sim.angles, sim.params, wanted, r2, H2, v2)
    np.testing.assert_array_equal(r2[wanted], ranges[wanted])
    np.testing.assert_array_equal(H2[wanted], H[wanted])
    np.testing.assert_array_equal(v2[wanted], var[wanted])
    assert np.isnan(r2[~wanted]).all() and not H2[~wanted].any() and not v2[~wanted].any()
    r3 = np.empty(ranges.size)
    scan(world.signed_distance, *sim.origin, sim.res, pose, sim.angles, sim.params, r3, H2, v2)
    np.testing.assert_array_equal(r3, ranges)


def test_a_small_move_carried_to_first_order_is_the_scan_cast_there(corridor: tuple[Scenario, World]) -> None:
    """What the update assumes when it does not cast again: a move that shifts every beam by less
    than RECAST of its standard deviation changes the ranges as their Jacobians say, to a small
    share of that (away from the beams that cross an edge, which the gate judges)."""
    _, world = corridor
    sim = ScanSimulator(world, LIDAR)
    rng = np.random.default_rng(1)
    errors = []
    for _ in range(40):
        pose = np.array([rng.uniform(1.0, 9.0), rng.uniform(9.0, 10.0), rng.uniform(-math.pi, math.pi)])
        r0, H, var = sim.ranges(pose)
        both = ~np.isnan(r0)
        direction = rng.normal(size=3)
        moved = direction * (0.9 * scans.RECAST / beam_shift(direction, H[both], var[both]))
        r1, _, _ = sim.ranges(pose + moved)
        ok = both & ~np.isnan(r1)
        errors.append(np.abs(r1[ok] - r0[ok] - H[ok] @ moved) / np.sqrt(var[ok]))
    e = np.concatenate(errors)
    assert np.median(e) < 1e-3 * scans.RECAST and np.quantile(e, 0.95) < 0.1 * scans.RECAST


def test_casting_again_only_for_larger_moves_keeps_the_update(
    corridor: tuple[Scenario, World], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The reference update with RECAST against the one cast again at every iteration (RECAST 0),
    on 60 scans from priors centimetres off: the same beams used and rejected, and estimates apart
    by a small share of their standard deviation; the few apart by more are scans whose every-cast
    update went on to its last iteration (beams at an edge in and out of the gate), and there the
    estimate cast less often is as near the truth."""
    _, world = corridor
    sim = ScanSimulator(world, LIDAR)
    rng = np.random.default_rng(0)
    apart, nearer = [], []
    for _ in range(60):
        truth = np.array([rng.uniform(1.0, 9.0), rng.uniform(9.0, 10.0), rng.uniform(-math.pi, math.pi)])
        cov = np.diag([0.05, 0.05, 0.03]) ** 2
        prior = Belief(truth + rng.multivariate_normal(np.zeros(3), cov), cov)
        draws = rng.standard_normal(LIDAR.beams)
        post, count = sim.update(prior, 0, truth, draws)
        monkeypatch.setattr(scans, "RECAST", 0.0)
        every, count_every = sim.update(prior, 0, truth, draws)
        monkeypatch.undo()
        assert count == count_every
        apart.append(_mahalanobis(post.mean - every.mean, every.cov))
        nearer.append(_mahalanobis(post.mean - truth, post.cov) - _mahalanobis(every.mean - truth, every.cov))
    apart_ = np.array(apart)
    assert np.median(apart_) < 0.01 and np.mean(apart_ < 0.05) >= 0.9 and apart_.max() < 0.5
    assert max(nearer) < 0.1


def _mahalanobis(d: np.ndarray, cov: np.ndarray) -> float:
    d = np.array(d, dtype=float)
    d[2] = (d[2] + math.pi) % (2 * math.pi) - math.pi
    return float(math.sqrt(d @ np.linalg.solve(cov, d)))


def test_a_standing_robots_true_scan_is_kept_with_the_same_update(corridor: tuple[Scenario, World]) -> None:
    """The compiled filter keeps a robot's last true scan while its true pose stays the same: the
    update is the one with the scan cast again."""
    scenario, world = corridor
    vis = LandmarkVisibility(world, scenario.models.landmark_sensor.range)
    n = len(scenario.robots)
    draws = Draws.draw(0, 0, n, 4, world.landmark_xy.shape[0], LIDAR.beams)
    mean = np.concatenate([r.pose.as_array() for r in scenario.robots])
    cov = np.kron(np.eye(n), np.diag([0.05, 0.05, 0.03]) ** 2)
    truth = np.array([r.pose.as_array() + np.array([0.02, -0.01, 0.01]) for r in scenario.robots])
    kept, fresh = (CompiledJointEkf(scenario, world, vis, draws, Belief(mean, cov), mutual=False) for _ in range(2))
    for step in range(3):
        fresh.last[:] = np.nan  # nothing kept: every true scan cast
        assert kept.observe(truth, step) == fresh.observe(truth, step)
        np.testing.assert_array_equal(kept.mean, fresh.mean)
        np.testing.assert_array_equal(kept.cov, fresh.cov)
    assert not np.isnan(kept.last).any()
