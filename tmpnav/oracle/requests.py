"""What the oracle is asked (a :class:`Request`) and what it counts while answering."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from tmpnav.oracle.motions import MotionLibrary
from tmpnav.oracle.nominal import stable_seed


@dataclass(frozen=True)
class StartState:
    """Where and how a robot begins a move: roadmap node, nominal heading, its belief."""

    node: int
    heading: float
    mean: tuple[float, float, float]
    cov: tuple[tuple[float, float, float], ...]


@dataclass(frozen=True)
class Request:
    """One action to evaluate: robots (1 or 2), their start states and target rooms.

    ``joint_cov`` is the full initial covariance (3n x 3n) when the robots' beliefs are
    correlated (carried over from earlier joint moves); None means block-diagonal.
    ``min_gain`` (pairs): when a lower bound proves the pair cannot save this fraction of
    its two single moves, its joint simulations are skipped and the result is marked
    ``pruned`` with the bound as its cost (:mod:`tmpnav.oracle.bounds`). ``bound_only``
    (pairs): never simulate jointly; the result is that lower bound, marked ``pruned``.
    ``max_risk``: the goal instantiation is the cheapest whose collision bound is within it
    for every robot (the least risky when none is: :func:`tmpnav.oracle.results.pick`).
    """

    robots: tuple[str, ...]
    starts: tuple[StartState, ...]
    rooms: tuple[str, ...]
    joint_cov: tuple[tuple[float, ...], ...] | None = None
    min_gain: float | None = None  # a pair that provably saves less is not simulated
    bound_only: bool = False  # a pair: its lower bound only, no joint simulation
    max_risk: float | None = None  # the threshold on each robot's collision bound (None: none)

    @property
    def n(self) -> int:
        return len(self.robots)

    def mean0(self) -> np.ndarray:
        """The joint initial mean (3n)."""
        return np.concatenate([np.array(s.mean) for s in self.starts])

    def cov0(self) -> np.ndarray:
        """The joint initial covariance (3n, 3n): ``joint_cov``, or the start beliefs' blocks."""
        if self.joint_cov is not None:
            return np.array(self.joint_cov)
        n = self.n
        cov = np.zeros((3 * n, 3 * n))
        for i, s in enumerate(self.starts):
            cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = np.array(s.cov)
        return cov


@dataclass
class EvalStats:
    """Counts for ``tmpnav bench`` and plan.json: what was simulated, what was saved."""

    single_sims: int = 0
    joint_sims: int = 0
    joint_factorized: int = 0
    pairs_pruned: int = 0  # pair requests proved unable to save min_gain (no joint simulation)
    steps_total: int = 0  # EKF steps the simulations span
    steps_computed: int = 0  # EKF steps actually computed (shared prefixes run once)

    def add(self, other: EvalStats) -> None:
        for f in fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))

    def count_steps(self, horizon: np.ndarray, restart: np.ndarray) -> None:
        """Add simulations running to ``horizon`` that restart after ``restart`` shared steps."""
        self.steps_total += int(horizon.sum())
        self.steps_computed += int((horizon - restart).sum())


def mutual_seed(lib: MotionLibrary, robots: tuple[str, ...], starts: tuple[StartState, ...]) -> int:
    """Seed of the simulated mutual observations of robots starting together."""
    return stable_seed(lib.scenario.models.seed, "mutual", robots, tuple(s.node for s in starts))
