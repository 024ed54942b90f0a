"""A run's record on the team's clock: each robot's belief at every control step
(:mod:`tmpnav.attachment.clock`; the re-simulation's trajectories, and what keeping robots
apart checks for conflicts)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np

from tmpnav.attachment.clock_state import ClockState, Leg
from tmpnav.belief.conflicts import position_sigma
from tmpnav.types import TrajectoryStep, cov3, vec3


class Rows(Protocol):
    """Where a robot's record comes from, as arrays: rows lo..hi-1 of it as positions (n, 2) m
    and position stds (n,) m (:func:`tmpnav.belief.conflicts.position_sigma`)."""

    def track(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]: ...


class Arrays:
    """Positions (n, 2) and position stds (n,) kept as they are (:class:`Rows`)."""

    def __init__(self, xy: np.ndarray, sigma: np.ndarray):
        self.xy, self.sigma = xy, sigma

    def track(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
        return self.xy[lo:hi], self.sigma[lo:hi]


#: rows lo..hi-1 of a source (:class:`Rows`): a stretch of a robot's record
Segment = tuple[Rows, int, int]


class Trace:
    """Each robot's belief at every control step, as a run goes (the re-simulation's record).

    Beside the steps, ``segments`` say where each robot's steps came from (:class:`Rows`), so
    that :meth:`tracks` gives their positions and position stds as arrays, from the same rows:
    what keeping robots apart checks (tmpnav.belief.conflicts.find_conflicts' ``tracks``) a
    few thousand times a fleet's search, where reading them back from the steps took longer
    than the check."""

    def __init__(
        self,
        names: tuple[str, ...],
        dt: float,
        steps: dict[int, list[TrajectoryStep]],
        segments: dict[int, list[Segment]],
    ):
        self.names, self.dt, self.steps, self.segments = names, dt, steps, segments

    @classmethod
    def at_start(cls, dt: float, state: ClockState) -> Trace:
        """The record of a run from its start: each robot's belief at step 0."""
        team = state.team
        steps: dict[int, list[TrajectoryStep]] = {}
        segments: dict[int, list[Segment]] = {}
        for i in range(len(team.names)):
            steps[i] = [belief_step(0.0, team.mean, team.cov, i, team.node[i])]
            cov = team.cov[None, 3 * i : 3 * i + 3, 3 * i : 3 * i + 3]
            segments[i] = [(Arrays(team.mean[None, 3 * i : 3 * i + 2].copy(), position_sigma(cov)), 0, 1)]
        return cls(team.names, dt, steps, segments)

    def add(self, i: int, steps: list[TrajectoryStep], source: Rows, lo: int, hi: int) -> None:
        """Robot i's next ``steps``, rows lo..hi-1 of ``source``; a stretch that goes on from the
        last one of the same source is one segment with it."""
        self.steps[i].extend(steps)
        parts = self.segments[i]
        if parts and parts[-1][0] is source and parts[-1][2] == lo:
            parts[-1] = (source, parts[-1][1], hi)
        elif hi > lo:
            parts.append((source, lo, hi))

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
            source = Arrays(means[1:, 3 * i : 3 * i + 2].copy(), position_sigma(covs[1:, block, block]))
            self.segments[i].append((source, 0, h))

    @classmethod
    def resumed(
        cls,
        names: tuple[str, ...],
        dt: float,
        steps: Mapping[int, list[TrajectoryStep]],
        segments: Mapping[int, list[Segment]],
        lengths: Sequence[int],
    ) -> Trace:
        """The record of a run resumed from a checkpoint: ``steps``' and ``segments``' first
        ``lengths``."""
        kept = {i: s[:n] for (i, s), n in zip(steps.items(), lengths, strict=True)}
        return cls(names, dt, kept, {i: _first(segments[i], len(kept[i])) for i in kept})

    def lengths(self) -> tuple[int, ...]:
        return tuple(len(s) for s in self.steps.values())

    def trajectories(self) -> dict[str, list[TrajectoryStep]]:
        return {self.names[i]: steps for i, steps in self.steps.items()}

    def tracks(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Each robot's positions (T, 2) m and position stds (T,) m at the steps of its
        trajectory (:meth:`trajectories`)."""
        out = {}
        for i, parts in self.segments.items():
            pieces = [source.track(lo, hi) for source, lo, hi in parts]
            if len(pieces) == 1:
                out[self.names[i]] = pieces[0]
            else:
                out[self.names[i]] = (np.concatenate([p[0] for p in pieces]), np.concatenate([p[1] for p in pieces]))
        return out


def _first(parts: Sequence[Segment], n: int) -> list[Segment]:
    """The segments of a record's first ``n`` steps."""
    out: list[Segment] = []
    for source, lo, hi in parts:
        if n <= 0:
            break
        out.append((source, lo, min(hi, lo + n)))
        n -= hi - lo
    return out


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
