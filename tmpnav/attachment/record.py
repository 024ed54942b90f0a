"""A run's record on the team's clock: each robot's belief at every control step
(:mod:`tmpnav.attachment.clock`; the re-simulation's trajectories, and what keeping robots
apart checks for conflicts)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from tmpnav.attachment.clock_state import ClockState, Leg
from tmpnav.types import TrajectoryStep, cov3, vec3


class Trace:
    """Each robot's belief at every control step, as a run goes (the re-simulation's record)."""

    def __init__(self, names: tuple[str, ...], dt: float, steps: dict[int, list[TrajectoryStep]]):
        self.names, self.dt, self.steps = names, dt, steps

    @classmethod
    def at_start(cls, dt: float, state: ClockState) -> Trace:
        """The record of a run from its start: each robot's belief at step 0."""
        team = state.team
        steps = {i: [belief_step(0.0, team.mean, team.cov, i, team.node[i])] for i in range(len(team.names))}
        return cls(team.names, dt, steps)

    def extend(self, state: ClockState, a: int, means: np.ndarray, covs: np.ndarray) -> None:
        """The steps (a, a + h] of every robot, from the team's means (h + 1, 3n) and covariances
        (h + 1, 3n, 3n) over them: each robot's block as plain floats (``tolist`` converts each
        number as ``float`` does, a whole block at once)."""
        dt, h = self.dt, means.shape[0] - 1
        times = [round(float((a + k) * dt), 9) for k in range(1, h + 1)]
        for i, steps in self.steps.items():
            nodes = reached(state.legs[i], a, a + h)
            block = slice(3 * i, 3 * i + 3)
            rows = zip(times, means[1:, block].tolist(), covs[1:, block, block].tolist(), strict=True)
            steps.extend(
                TrajectoryStep(t, (m[0], m[1], m[2]), (tuple(c[0]), tuple(c[1]), tuple(c[2])), nodes.get(a + k))
                for k, (t, m, c) in enumerate(rows, start=1)
            )

    @classmethod
    def resumed(
        cls, names: tuple[str, ...], dt: float, steps: Mapping[int, list[TrajectoryStep]], lengths: Sequence[int]
    ) -> Trace:
        """The record of a run resumed from a checkpoint: ``steps``' first ``lengths``."""
        return cls(names, dt, {i: s[:n] for (i, s), n in zip(steps.items(), lengths, strict=True)})

    def lengths(self) -> tuple[int, ...]:
        return tuple(len(s) for s in self.steps.values())

    def trajectories(self) -> dict[str, list[TrajectoryStep]]:
        return {self.names[i]: steps for i, steps in self.steps.items()}


def reached(legs: Sequence[Leg], a: int, b: int) -> dict[int, int]:
    """The roadmap nodes reached along ``legs`` at the steps in (a, b]."""
    out = {}
    for leg in legs:
        if leg.motion is not None:
            for node, k in zip(leg.motion.path, leg.motion.node_steps.tolist(), strict=False):
                if a < leg.start + k <= b:
                    out[leg.start + k] = int(node)
    return out


def belief_step(t: float, mean: np.ndarray, cov: np.ndarray, i: int, node: int | None) -> TrajectoryStep:
    m = mean[3 * i : 3 * i + 3]
    c = cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3]
    return TrajectoryStep(t=round(float(t), 9), mean=vec3(m), cov=cov3(c), node=None if node is None else int(node))
