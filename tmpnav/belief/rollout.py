"""One simulation of n robots as plain arrays, and its propagation through the compiled EKF.

A :class:`Rollout` says what n robots do and see over T steps; :func:`propagate_rollout`
runs it through the production path (:func:`tmpnav.belief.sequences.propagate_sequences`,
one simulation) and :func:`tmpnav.belief.reference.propagate_reference` through the filterpy
reference, step by step. Both return a :class:`Propagation` with the whole history, so the
tests and ``benchmarks/bench_belief.py`` hold the two side by side. The oracle does not use
this module: it lays out thousands of simulations itself (:mod:`tmpnav.oracle.motionsets`).

Which landmarks and robots are visible at each step is the caller's business (it needs the
map); this stage only consumes the masks. Simulated observation noise is drawn from
``Models.seed`` unless the caller passes its own draws.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tmpnav.belief.controls import PathControls, pad
from tmpnav.belief.sequences import (
    EKFConstants,
    MotionArrays,
    SequenceBatch,
    Sequences,
    StartGroups,
    propagate_sequences,
)
from tmpnav.types import Belief, CostTerms, Models


@dataclass(frozen=True, eq=False)
class Rollout:
    """What n robots do and see in one simulation of T steps.

    ``controls`` (n, T, 2) (v m/s, omega rad/s), zero-padded after arrival;
    ``true_poses`` (n, T+1, 3) nominal poses; ``active_steps`` (n,) each robot's own
    number of motion steps T_i; ``lm_visible`` (n, T+1, L) and ``mutual_visible``
    (n, n, T+1) bool masks (robot i sees landmark l / robot j at step k). A robot that
    arrived waits: its poses and landmark visibility after step T_i repeat those at T_i.
    ``scans`` (n, T+1, 3, 3), with a range sensor: the factor G (J = Gᵀ G) of the information
    of robot i's scan at step k (tmpnav.world.lidar); None without one.
    """

    controls: np.ndarray
    true_poses: np.ndarray
    active_steps: np.ndarray
    lm_visible: np.ndarray
    mutual_visible: np.ndarray
    scans: np.ndarray | None = None

    @property
    def n_steps(self) -> int:
        return int(self.controls.shape[1])


@dataclass(frozen=True)
class ObservationNoise:
    """Standard-normal draws for the simulated observations of one simulation.

    ``landmark`` (n, T+1, L, 2): robot i's draw for landmark l at step k; ``mutual``
    (n, n, T+1, 2): robot i's draw for its observation of robot j at step k; ``scan``
    (n, T+1, 3): robot i's draws for the three pseudo-measurements of its scan at step k.
    """

    landmark: np.ndarray
    mutual: np.ndarray
    scan: np.ndarray | None = None

    def scan_draws(self, n: int, T: int) -> np.ndarray:
        """The scans' draws (n, T+1, 3); zeros where none were drawn."""
        return np.zeros((n, T + 1, 3)) if self.scan is None else np.asarray(self.scan, dtype=float)

    @staticmethod
    def draw(seed: int, n: int, T: int, L: int) -> ObservationNoise:
        """Reproducible draws for n robots, T steps, L landmarks from ``seed``."""
        rng = np.random.default_rng(seed)
        return ObservationNoise(
            landmark=rng.standard_normal((n, T + 1, L, 2)),
            mutual=rng.standard_normal((n, n, T + 1, 2)),
            scan=rng.standard_normal((n, T + 1, 3)),
        )


@dataclass(frozen=True, eq=False)
class Propagation:
    """Beliefs of one simulation: ``means`` (T+1, 3n), ``covs`` (T+1, 3n, 3n) (index 0 is
    the initial belief), the cost ``terms`` per robot and the number of steps with at
    least one mutual observation."""

    means: np.ndarray
    covs: np.ndarray
    terms: tuple[CostTerms, ...]
    mutual_steps: int

    @property
    def final(self) -> Belief:
        return Belief(self.means[-1].copy(), self.covs[-1].copy())

    def belief(self, k: int) -> Belief:
        """The joint belief after step k (0 = initial)."""
        return Belief(self.means[k].copy(), self.covs[k].copy())


def stack_paths(paths: Sequence[PathControls]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pad the paths of n robots to a common length T = max T_i.

    Returns controls (n, T, 2), nominal poses (n, T+1, 3) and active_steps (n,).
    """
    T = max((p.n_steps for p in paths), default=0)
    padded = [pad(p.controls, p.poses, T) for p in paths]
    return (
        np.stack([c for c, _ in padded]),
        np.stack([q for _, q in padded]),
        np.array([p.n_steps for p in paths], dtype=int),
    )


def observed_mutually(rollout: Rollout, models: Models) -> np.ndarray:
    """The rollout's mutual visibility (n, n, T+1), all False when the beliefs take in no
    mutual observations (Models.partners_fused); the diagonal is always False."""
    n = rollout.mutual_visible.shape[0]
    if not models.partners_fused:
        return np.zeros_like(rollout.mutual_visible, dtype=bool)
    return np.asarray(rollout.mutual_visible, dtype=bool) & ~np.eye(n, dtype=bool)[:, :, None]


def control_usage(rollout: Rollout, dt: float) -> np.ndarray:
    """c_u = sum_{k < T_i} (v_k² + omega_k²) dt of each robot (n,) (docs/models.md)."""
    T = rollout.controls.shape[1]
    active = np.arange(T)[None, :] < np.asarray(rollout.active_steps)[:, None]
    return np.where(active, (rollout.controls**2).sum(-1), 0.0).sum(-1) * dt


def propagate_rollout(
    belief: Belief,
    rollout: Rollout,
    landmarks: np.ndarray,
    models: Models,
    noise: ObservationNoise | None = None,
) -> Propagation:
    """One simulation of n robots through the compiled EKF, with its full history.

    ``belief`` is the joint initial belief (3n); ``landmarks`` (L, 2) in metres; ``noise``
    defaults to :meth:`ObservationNoise.draw` from ``models.seed``.
    """
    n, T, _ = rollout.controls.shape
    landmarks = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    L = landmarks.shape[0]
    if noise is None:
        noise = ObservationNoise.draw(models.seed, n, T, L)
    steps = [int(s) for s in rollout.active_steps]
    scans = None
    if rollout.scans is not None and models.range_sensor is not None:
        table = np.concatenate([np.zeros((1, 3, 3)), *(rollout.scans[i, : steps[i] + 1] for i in range(n))])
        scans = (np.arange(1, table.shape[0]), table)
    motions = MotionArrays.of(
        [rollout.controls[i, : steps[i]] for i in range(n)],
        [rollout.true_poses[i, : steps[i] + 1] for i in range(n)],
        [rollout.lm_visible[i, : steps[i] + 1] for i in range(n)],
        np.arange(n),  # robot i observes landmarks with its own draws
        L,
        scans=scans,
    )
    batch = SequenceBatch(
        n=n,
        ekf=EKFConstants.of(models, landmarks),
        motions=motions,
        landmark_noise=np.ascontiguousarray(noise.landmark, dtype=float),
        groups=StartGroups(
            np.asarray(belief.mean, dtype=float)[None],
            np.asarray(belief.cov, dtype=float)[None],
            np.ascontiguousarray(np.asarray(noise.mutual, dtype=float).transpose(2, 0, 1, 3))[None],
        ),
        sequences=Sequences.one(n, T),
        mutual_visible=np.ascontiguousarray(observed_mutually(rollout, models).transpose(2, 0, 1)),
        scan_noise=np.ascontiguousarray(noise.scan_draws(n, T)),
    )
    result = propagate_sequences(batch)
    goal_xy = rollout.true_poses[np.arange(n), np.asarray(steps, dtype=int), :2]
    c_goal = np.hypot(*(result.arrival_xy[0] - goal_xy).T)
    c_u = control_usage(rollout, models.dt)
    return Propagation(
        means=result.last_means[: T + 1].copy(),
        covs=result.last_covs[: T + 1].copy(),
        terms=tuple(CostTerms(float(c_u[i]), float(c_goal[i]), float(result.c_sigma[0, i])) for i in range(n)),
        mutual_steps=int(result.mutual_steps[0]),
    )
