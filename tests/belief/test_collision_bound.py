"""The collision bound as the compiled kernel sums it, and the oracle's choice under a threshold.

The bound itself (its validity against Monte Carlo) is tested in tests/belief/test_risk.py; here:
the kernel sums exactly the step bound of tmpnav.belief.risk (the numpy reference) over a
robot's driving steps (1 where a sector's reach is 0), and the oracle picks the cheapest
instantiation within max_risk.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.belief.test_kernel import _batch
from tmpnav.belief.risk import step_bound
from tmpnav.belief.sequences import MotionArrays, propagate_sequences
from tmpnav.oracle.results import pick
from tmpnav.types import RISK_PENALTY, risk_penalty
from tmpnav.world.reach import SECTORS


def _reach(margins: np.ndarray) -> np.ndarray:
    """(T+1, K) reach: each step's margin in the sectors facing +y (a wall along the path), far
    elsewhere, so that both the disc and the sectors decide some steps."""
    far = np.full((margins.shape[0], SECTORS), 0.8 if np.isfinite(margins).any() else np.inf)
    far[:, 4:12] = np.maximum(margins, 0.0)[:, None]
    return far


def _motion(T: int, L: int, margins: np.ndarray) -> MotionArrays:
    ctrl = np.column_stack([np.full(T, 0.5), np.zeros(T)])
    poses = np.column_stack([0.1 * np.arange(T + 1), np.zeros(T + 1), np.zeros(T + 1)])
    vis = np.zeros((T + 1, L), dtype=bool)
    return MotionArrays.of([ctrl], [poses], [vis], np.zeros(1, dtype=np.int64), L, [_reach(margins)])


def _expected(covs: np.ndarray, margins: np.ndarray) -> float:
    return float(step_bound(covs[1:, :2, :2], _reach(margins)[1:]).sum())


@pytest.mark.parametrize("low", [0.4, 0.1, 0.0, -0.2])
def test_the_kernel_sums_the_step_bounds_over_the_driving_steps(low: float) -> None:
    T, L = 12, 2
    margins = np.linspace(0.6, low, T + 1)
    out = propagate_sequences(_batch(_motion(T, L, margins), [0], [0], T, L))
    assert out.risk[0, 0] == pytest.approx(_expected(out.last_covs, margins), rel=1e-12)


def test_no_margins_no_bound_and_a_robot_that_waits_adds_nothing() -> None:
    T, L = 8, 2
    free = np.full(T + 1, np.inf)
    out = propagate_sequences(_batch(_motion(T, L, free), [0], [0], T, L))
    assert out.risk[0, 0] == 0.0
    short = _motion(4, L, np.linspace(0.3, 0.2, 5))
    batch = _batch(short, [0], [0], T, L)  # drives 4 steps, then stands 4
    out = propagate_sequences(batch)
    assert out.risk[0, 0] == pytest.approx(_expected(out.last_covs[:5], np.linspace(0.3, 0.2, 5)), rel=1e-12)


def test_the_oracle_picks_the_cheapest_within_the_threshold_else_the_least_risky() -> None:
    cost = np.array([1.0, 2.0, 3.0, 4.0])
    risk = np.array([0.5, 0.04, 0.01, 0.01])
    assert pick(cost, risk, None) == 0
    assert pick(cost, risk, 0.05) == 1
    assert pick(cost, risk, 0.02) == 2
    assert pick(cost, risk, 0.001) == 2  # none within: the least risky, the cheaper of a tie
    pairs = np.array([[0.01, 0.2], [0.03, 0.03], [0.0, 0.0], [0.1, 0.0]])
    assert pick(cost, pairs, 0.05) == 1  # each robot's bound within it


def test_a_move_over_the_threshold_costs_more_than_any_plan_within_it() -> None:
    assert risk_penalty(0.3, None) == 0.0
    assert risk_penalty(0.05, 0.05) == 0.0
    assert risk_penalty(0.051, 0.05) == pytest.approx(RISK_PENALTY * 0.001)
    assert risk_penalty(0.05 + 1e-6, 0.05) > 1e5
