"""Belief propagation along planned motions: the belief stage's entry points.

- :func:`simulate`: one simulation of n robots (the fast path with B = 1), full history;
- :func:`simulate_batch`: many simulations at once, for the cost oracle;
- :func:`simulate_reference`: the same algorithm through the filterpy EKF of
  :mod:`tmpnav.belief.ekf`, step by step; used by the tests, and a readable statement of
  the order of predictions and updates that :mod:`tmpnav.belief.batch` implements.

Which landmarks and robots are visible at each step is the caller's business (it needs the
map); this stage only consumes the masks. Simulated observation noise is drawn from
``Models.seed`` unless the caller passes its own draws, and the same draws are shared by
every simulation of a batch, so a candidate's cost does not depend on its batch.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from tmpnav.belief import ekf
from tmpnav.belief.batch import (
    BatchInputs,
    BatchResult,
    FilterParams,
    cost_terms_from_history,
    propagate,
)
from tmpnav.belief.controls import PathControls, pad
from tmpnav.belief.models import landmark_obs, mutual_obs, noisy_observation
from tmpnav.types import Belief, CostTerms, Models, ObservationMode


@dataclass(frozen=True, eq=False)
class Rollout:
    """What n robots do and see in one simulation of T steps.

    ``controls`` (n, T, 2) (v m/s, omega rad/s), zero-padded after arrival;
    ``true_poses`` (n, T+1, 3) nominal poses; ``active_steps`` (n,) each robot's own
    number of motion steps T_i; ``lm_visible`` (n, T+1, L) and ``mutual_visible``
    (n, n, T+1) bool masks (robot i sees landmark l / robot j at step k).
    """

    controls: np.ndarray
    true_poses: np.ndarray
    active_steps: np.ndarray
    lm_visible: np.ndarray
    mutual_visible: np.ndarray

    @property
    def n_steps(self) -> int:
        return int(self.controls.shape[1])


@dataclass(frozen=True)
class ObservationNoise:
    """Standard-normal draws for simulated observations of one simulation.

    ``landmark`` (n, T+1, L, 2) and ``mutual`` (n, n, T+1, 2), or with a leading batch axis.
    """

    landmark: np.ndarray
    mutual: np.ndarray

    @staticmethod
    def draw(seed: int, n: int, T: int, L: int) -> ObservationNoise:
        """Reproducible draws for n robots, T steps, L landmarks from ``seed``."""
        rng = np.random.default_rng(seed)
        return ObservationNoise(
            landmark=rng.standard_normal((n, T + 1, L, 2)),
            mutual=rng.standard_normal((n, n, T + 1, 2)),
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


def filter_params(models: Models) -> FilterParams:
    """The EKF constants of a scenario's models."""
    return FilterParams(
        dt=models.dt,
        alphas=models.motion_noise,
        Q_landmark=_pair(models.landmark_sensor.Q),
        Q_mutual=_pair(models.mutual_sensor.Q),
        max_likelihood=models.observations is ObservationMode.MAX_LIKELIHOOD,
    )


def _pair(Q: np.ndarray) -> tuple[tuple[float, float], tuple[float, float]]:
    return ((float(Q[0, 0]), float(Q[0, 1])), (float(Q[1, 0]), float(Q[1, 1])))


def _mutual_mask(mutual_visible: np.ndarray, models: Models) -> np.ndarray:
    if models.mutual_observations:
        return mutual_visible
    return np.zeros_like(mutual_visible, dtype=bool)


def simulate_batch(inputs: BatchInputs, models: Models, keep_history: bool = False) -> BatchResult:
    """Propagate B simulations with the fast path (:func:`tmpnav.belief.batch.propagate`).

    Mutual observations are dropped when ``models.mutual_observations`` is false. In noisy
    mode, missing noise arrays are drawn from ``models.seed`` once and shared by all B
    simulations. Returns costs and final beliefs (and histories if ``keep_history``).
    """
    B, n, T, L = inputs.shape
    inputs = replace(inputs, mutual_visible=_mutual_mask(inputs.mutual_visible, models))
    max_likelihood = models.observations is ObservationMode.MAX_LIKELIHOOD
    if not max_likelihood and (inputs.lm_noise is None or inputs.mutual_noise is None):
        noise = ObservationNoise.draw(models.seed, n, T, L)
        if inputs.lm_noise is None:
            lm_noise = np.broadcast_to(noise.landmark, (B, *noise.landmark.shape))
            inputs = replace(inputs, lm_noise=lm_noise)
        if inputs.mutual_noise is None:
            mutual_noise = np.broadcast_to(noise.mutual, (B, *noise.mutual.shape))
            inputs = replace(inputs, mutual_noise=mutual_noise)
    return propagate(inputs, filter_params(models), keep_history=keep_history)


def simulate(
    belief: Belief,
    rollout: Rollout,
    landmarks: np.ndarray,
    models: Models,
    noise: ObservationNoise | None = None,
) -> Propagation:
    """One simulation of n robots through the fast path, with its full history.

    ``belief`` is the joint initial belief (3n); ``landmarks`` (L, 2) in metres; ``noise``
    defaults to draws from ``models.seed``.
    """
    inputs = BatchInputs(
        mean0=np.asarray(belief.mean, dtype=float)[None],
        cov0=np.asarray(belief.cov, dtype=float)[None],
        controls=rollout.controls[None],
        true_poses=rollout.true_poses[None],
        active_steps=np.asarray(rollout.active_steps)[None],
        landmarks=np.asarray(landmarks, dtype=float).reshape(-1, 2),
        lm_visible=rollout.lm_visible[None],
        mutual_visible=rollout.mutual_visible[None],
        lm_noise=None if noise is None else noise.landmark[None],
        mutual_noise=None if noise is None else noise.mutual[None],
    )
    result = simulate_batch(inputs, models, keep_history=True)
    assert result.means is not None and result.covs is not None
    return Propagation(
        means=result.means[0],
        covs=result.covs[0],
        terms=result.terms(0),
        mutual_steps=int(result.mutual_steps[0]),
    )


def simulate_reference(
    belief: Belief,
    rollout: Rollout,
    landmarks: np.ndarray,
    models: Models,
    noise: ObservationNoise | None = None,
) -> Propagation:
    """The same simulation as :func:`simulate`, through the filterpy EKF, one update at a time.

    At each step k: predict all robots with their controls; then robot by robot, landmark
    by landmark (ascending), update with each visible landmark; then each ordered pair
    (i, j), i != j, lexicographically, update with robot i's observation of robot j.
    """
    n, T, _ = rollout.controls.shape
    landmarks = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    L = landmarks.shape[0]
    params = filter_params(models)
    ml = params.max_likelihood
    if noise is None and not ml:
        noise = ObservationNoise.draw(models.seed, n, T, L)
    Q_lm, Q_mu = np.array(params.Q_landmark), np.array(params.Q_mutual)
    chol_lm, chol_mu = np.linalg.cholesky(Q_lm), np.linalg.cholesky(Q_mu)
    mutual_visible = _mutual_mask(rollout.mutual_visible, models)
    poses = rollout.true_poses

    beliefs = [Belief(np.array(belief.mean, dtype=float), np.array(belief.cov, dtype=float))]
    b = beliefs[0]
    for k in range(T):
        t = k + 1
        b = ekf.predict(b, rollout.controls[:, k], params.dt, params.alphas)
        for i in range(n):
            for l_ in np.flatnonzero(rollout.lm_visible[i, t]):
                if ml:
                    z = landmark_obs(b.mean[3 * i : 3 * i + 3], landmarks[l_])
                else:
                    assert noise is not None
                    z_true = landmark_obs(poses[i, t], landmarks[l_])
                    z = noisy_observation(z_true, chol_lm, noise.landmark[i, t, l_])
                b = ekf.update_landmark(b, i, landmarks[l_], z, Q_lm)
        for i in range(n):
            for j in range(n):
                if i == j or not mutual_visible[i, j, t]:
                    continue
                if ml:
                    z = mutual_obs(b.mean[3 * i : 3 * i + 3], b.mean[3 * j : 3 * j + 3])
                else:
                    assert noise is not None
                    z_true = mutual_obs(poses[i, t], poses[j, t])
                    z = noisy_observation(z_true, chol_mu, noise.mutual[i, j, t])
                b = ekf.update_mutual(b, i, j, z, Q_mu)
        beliefs.append(b)

    means = np.stack([x.mean for x in beliefs])
    covs = np.stack([x.cov for x in beliefs])
    c_u, c_g, c_sigma = cost_terms_from_history(
        means[None],
        covs[None],
        rollout.controls[None],
        poses[None],
        np.asarray(rollout.active_steps)[None],
        params.dt,
    )
    off_diagonal = mutual_visible & ~np.eye(n, dtype=bool)[:, :, None]
    return Propagation(
        means=means,
        covs=covs,
        terms=tuple(CostTerms(float(c_u[0, r]), float(c_g[0, r]), float(c_sigma[0, r])) for r in range(n)),
        mutual_steps=int(np.any(off_diagonal, axis=(0, 1))[1:].sum()),
    )
