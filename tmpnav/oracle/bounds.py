"""Pair pruning: a lower bound on a pair's joint cost from its two single-robot runs.

Until the robots of a combination first see each other (step k0), their joint EKF equals
the two single ones (uncorrelated starts, separate noise streams). Since trace(Sigma) and
c_G are never negative, the combination's joint cost is at least

    M_u (c_u1 + c_u2) + M_Sigma (C1(k0 - 1) + C2(k0 - 1)),

with C_i the running c_Sigma of robot i alone (:attr:`SingleRuns.csig_hist`). A
combination whose robots never see each other is factorised: it costs exactly the sum of
its singles. A pair request whose best bound cannot save ``min_gain`` of its two single
moves is pruned: the encoding would never offer it, so it is not simulated jointly.

Within a request that is not pruned, a combination whose bound is above its **cutoff** --
the least of what would save ``min_gain`` and the exact cost of a factorised combination of
the same request -- is not simulated either (:func:`skippable`): it cannot be the request's
cheapest combination when that one saves ``min_gain``, being dearer than either. After the
joint runs, the request's result is exact when its cheapest simulated or factorised
combination is within the cutoff (each skipped one costs more); otherwise none can save
``min_gain`` and the request is pruned like the others, with the least of its bounds. On the
10-room corridor's carried sub-problems, 2,532 of 9,156 joint simulations were such
combinations (tmpnav.oracle.pairs). Not under a threshold on the collision bound
(``max_risk``): there a dearer combination may be the one chosen, being within it.

**Before any simulation** (:class:`ControlFloors`): a paired move drives its robots' own
nominal motions, the very ones of their single moves from the same start states, so it costs
at least the sum of each robot's least M_u c_u to its room, whatever the beliefs and their
correlations. The callers that make pair requests (the carried sub-problems, the canonical
table) ask for none whose control effort alone cannot save ``min_gain``: with a lidar, a
robot's single move costs little more than its control effort, and on the generated 20-room
offices every pair of the carried sub-problems was pruned this way before being simulated
alone (tests/oracle/test_bounds.py).
"""

from __future__ import annotations

import numpy as np

from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.motionsets import MotionSet
from tmpnav.oracle.requests import Request
from tmpnav.oracle.singles import SingleRuns
from tmpnav.types import CostWeights


def combination_bounds(
    singles: SingleRuns,
    s1: MotionSet,
    s2: MotionSet,
    a: np.ndarray,
    b: np.ndarray,
    first_sight: np.ndarray,
    weights: CostWeights,
) -> np.ndarray:
    """The least cost each of the combinations (motions ``a[k]`` of ``s1``, ``b[k]`` of
    ``s2``) can have, given the first step each sees the other robot (-1: never, and then
    exactly the sum of its singles)."""
    r1, r2 = singles.rows(s1, a), singles.rows(s2, b)
    before = np.maximum(first_sight - 1, 0)
    c1 = singles.csig_hist[r1, np.minimum(before, s1.steps[a])]
    c2 = singles.csig_hist[r2, np.minimum(before, s2.steps[b])]
    seen = weights.combine(singles.c_u[r1] + singles.c_u[r2], 0.0, c1 + c2)
    # factorised (never in sight): exactly the sum of its singles
    return np.where(first_sight < 0, singles.cost[r1] + singles.cost[r2], seen)


def cutoff(bounds: np.ndarray, factorised: np.ndarray, alone: float, min_gain: float) -> float:
    """The cost above which a combination of a request need not be simulated (the module
    docstring): the most that saves ``min_gain`` of ``alone`` (with :func:`cannot_save`'s
    margin), or the exact cost of the request's cheapest ``factorised`` combination (whose
    ``bounds`` are exact) where that is less, with a margin for rounding."""
    saving = (1.0 - min_gain) * alone + 1e-9 * alone + 0.002
    exact = float(bounds[factorised].min(initial=np.inf))
    return min(saving, exact + 1e-9 * abs(exact) + 1e-9)


def skippable(bounds: np.ndarray, seen: np.ndarray, limit: float) -> np.ndarray:
    """The combinations not worth simulating: robots that see each other, bound above ``limit``."""
    return seen & (bounds > limit)


def cannot_save(bound: float, alone: float, min_gain: float) -> bool:
    """Does a pair whose cost is at least ``bound`` fail to save ``min_gain`` of ``alone``,
    the cost of its two single moves? (With a margin that absorbs rounding.)"""
    return bound > (1.0 - min_gain) * alone + 1e-9 * alone + 0.002


class ControlFloors:
    """The least control effort M_u c_u of a robot's nominal motions from a start state (its
    node and heading: the motion does not depend on the belief) to the instantiations of a
    room (the module docstring), each found once."""

    #: floors remembered before the memory is cleared
    MAX = 1 << 17

    def __init__(self, lib: MotionLibrary):
        self.lib = lib
        self._least: dict[tuple[str, int, float, str], float] = {}

    def least(self, robot: str, node: int, heading: float, room: str) -> float:
        """The least M_u c_u from ``node`` with ``heading`` to ``room`` (0 when none reaches it)."""
        key = (robot, node, heading, room)
        found = self._least.get(key)
        if found is None:
            if len(self._least) >= self.MAX:
                self._least.clear()
            lib = self.lib
            dt, weights = lib.scenario.models.dt, lib.scenario.cost
            motions = (lib.motion(robot, node, heading, g) for g in lib.roadmap.instantiations.get(room, ()))
            found = self._least[key] = min((weights.M_u * m.c_u(dt) for m in motions if m is not None), default=0.0)
        return found

    def cannot_pair(self, request: Request, alone: float, min_gain: float) -> bool:
        """Whether the pair ``request`` cannot save ``min_gain`` of ``alone`` (its two single
        moves' cost) on its robots' control effort alone."""
        least = sum(
            self.least(r, s.node, s.heading, room)
            for r, s, room in zip(request.robots, request.starts, request.rooms, strict=True)
        )
        return cannot_save(least, alone, min_gain)
