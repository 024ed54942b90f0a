"""The oracle's answers: :class:`~tmpnav.types.MotionResult` built in one place each way."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tmpnav.oracle.nominal import NominalMotion
from tmpnav.types import CostTerms, CostWeights, MotionResult, risk_penalty


def motion_result(
    robots: tuple[str, ...],
    terms: tuple[CostTerms, ...],
    mean: np.ndarray,
    cov: np.ndarray,
    mutual_steps: int,
    motions: tuple[NominalMotion, ...],
    weights: CostWeights,
    risk: tuple[float, ...] = (),
) -> MotionResult:
    """The result of moving ``robots`` along ``motions``: its cost is the sum of each
    robot's weighted terms; ``mean`` and ``cov`` are their joint belief at the end;
    ``risk`` each robot's collision bound (summed over its steps: capped here at 1)."""
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
        risk=tuple(min(1.0, float(p)) for p in risk),
    )


def pick(cost: np.ndarray, risk: np.ndarray, max_risk: float | None) -> int:
    """The instantiation the oracle chooses (an index into ``cost``): the cheapest (the first
    on a tie); under a threshold ``max_risk`` on the collision bound (``risk`` (k,) or
    (k, robots): each robot's), the cheapest of those within it, and when none is, the least
    risky (its largest robot's bound; the cheaper on a tie)."""
    if max_risk is None:
        return int(np.argmin(cost))
    worst = risk if risk.ndim == 1 else risk.max(axis=1)
    within = worst <= max_risk
    if within.any():
        return int(np.argmin(np.where(within, cost, np.inf)))
    return int(np.lexsort((cost, worst))[0])


def penalised(result: MotionResult | None, max_risk: float | None) -> MotionResult | None:
    """``result`` with the cost of a collision bound over ``max_risk`` added to its cost (its
    terms unchanged): a move over the threshold is offered only at a prohibitive price."""
    if result is None or result.pruned or not result.risk:
        return result
    extra = sum(risk_penalty(p, max_risk) for p in result.risk)
    return replace(result, cost=result.cost + extra) if extra else result


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
