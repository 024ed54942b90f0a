"""Pair pruning: a lower bound on a pair's joint cost from its two single-robot runs.

Until the robots of a combination first see each other (step k0), their joint EKF equals
the two single ones (uncorrelated starts, separate noise streams). Since trace(Sigma) and
c_G are never negative, the combination's joint cost is at least

    M_u (c_u1 + c_u2) + M_Sigma (C1(k0 - 1) + C2(k0 - 1)),

with C_i the running c_Sigma of robot i alone (:attr:`SingleRuns.csig_hist`). A
combination whose robots never see each other is factorised: it costs exactly the sum of
its singles. A pair request whose best bound cannot save ``min_gain`` of its two single
moves is pruned: the encoding would never offer it, so it is not simulated jointly.
"""

from __future__ import annotations

import numpy as np

from tmpnav.oracle.motionsets import MotionSet
from tmpnav.oracle.singles import SingleRuns
from tmpnav.types import CostWeights


def pair_lower_bound(
    singles: SingleRuns,
    s1: MotionSet,
    s2: MotionSet,
    a: np.ndarray,
    b: np.ndarray,
    first_sight: np.ndarray,
    weights: CostWeights,
) -> float:
    """The least cost any of the combinations (motions ``a[k]`` of ``s1``, ``b[k]`` of
    ``s2``) can have, given the first step each sees the other robot (-1: never)."""
    bound = np.inf
    for k in range(a.shape[0]):
        r1, r2 = singles.index(s1, int(a[k])), singles.index(s2, int(b[k]))
        k0 = int(first_sight[k])
        if k0 < 0:  # factorised: exactly the sum of its singles
            bound = min(bound, singles.cost[r1] + singles.cost[r2])
            continue
        before = max(k0 - 1, 0)
        c1 = singles.csig_hist[r1][min(before, int(s1.steps[a[k]]))]
        c2 = singles.csig_hist[r2][min(before, int(s2.steps[b[k]]))]
        bound = min(bound, weights.combine(singles.c_u[r1] + singles.c_u[r2], 0.0, c1 + c2))
    return float(bound)


def cannot_save(bound: float, alone: float, min_gain: float) -> bool:
    """Does a pair whose cost is at least ``bound`` fail to save ``min_gain`` of ``alone``,
    the cost of its two single moves? (With a margin that absorbs rounding.)"""
    return bound > (1.0 - min_gain) * alone + 1e-9 * alone + 0.002
