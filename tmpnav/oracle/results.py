"""The oracle's answers: :class:`~tmpnav.types.MotionResult` built in one place each way."""

from __future__ import annotations

import numpy as np

from tmpnav.oracle.motions import NominalMotion
from tmpnav.types import CostTerms, CostWeights, MotionResult


def motion_result(
    robots: tuple[str, ...],
    terms: tuple[CostTerms, ...],
    mean: np.ndarray,
    cov: np.ndarray,
    mutual_steps: int,
    motions: tuple[NominalMotion, ...],
    weights: CostWeights,
) -> MotionResult:
    """The result of moving ``robots`` along ``motions``: its cost is the sum of each
    robot's weighted terms; ``mean`` and ``cov`` are their joint belief at the end."""
    return MotionResult(
        cost=float(sum(t.total(weights) for t in terms)),
        robots=robots,
        goal_nodes=tuple(int(m.path[-1]) for m in motions),
        paths=tuple(m.path for m in motions),
        terms=tuple(terms),
        final_mean=tuple(float(v) for v in mean),
        final_cov=tuple(tuple(float(v) for v in row) for row in cov),
        mutual_steps=mutual_steps,
        final_headings=tuple(m.final_heading for m in motions),
        steps=tuple(m.n_steps for m in motions),
    )


def pruned_result(robots: tuple[str, ...], bound: float) -> MotionResult:
    """A pair proved unable to save its ``min_gain``: only a lower bound of its cost,
    no motion (:mod:`tmpnav.oracle.bounds`)."""
    return MotionResult(float(bound), robots, (), (), (), (), (), pruned=True)


def block_diagonal(
    mean_a: np.ndarray, cov_a: np.ndarray, mean_b: np.ndarray, cov_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The joint belief of two robots that never observed each other (a factorised pair):
    means side by side, covariances on the diagonal, no correlation."""
    cov = np.zeros((6, 6))
    cov[:3, :3], cov[3:, 3:] = cov_a, cov_b
    return np.concatenate([mean_a, mean_b]), cov
