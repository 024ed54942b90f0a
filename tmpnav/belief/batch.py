"""The vectorised multi-robot EKF: B independent simulations of n robots at once.

This is the planner's fast path. Every array carries a leading batch axis B; Python loops
run only over time steps, robots and observation "slots", never over B. The equations are
those of :mod:`tmpnav.belief.models`; the order of the updates within a step is the
definition that the filterpy reference (:func:`tmpnav.belief.propagate.simulate_reference`)
follows identically. At step k = 0..T-1:

1. joint prediction with ``controls[:, :, k]`` (paper eqs. (8), (11)-(12));
2. landmark updates, robot by robot (i ascending), landmark by landmark (l ascending),
   each a separate 2-D EKF update (eq. (9)) applied where ``lm_visible[:, i, k+1, l]``;
3. mutual updates for ordered pairs (i, j), i != j, in lexicographic order, applied where
   ``mutual_visible[:, i, j, k+1]`` (eqs. (13)-(15)).

Observations are simulated as z = h(true_poses[k+1]) + chol(Q) @ noise (noisy mode) or
z = h(current mean) (maximum-likelihood mode, the innovation is zero). A masked update is
an exact no-op: per step the visible landmarks of each robot are compacted into slots and
each slot's update touches only the simulations where it exists.

The cost terms (docs/models.md), per simulation b and robot i with T_i = active_steps[b, i]:

    c_u     = sum_{k=0}^{T_i-1} (v_k² + omega_k²) dt
    c_Sigma = sum_{k=1}^{T_i}   trace(Sigma^i_k) dt
    c_G     = || mean^i_{T_i}[:2] - true_poses^i_{T_i}[:2] ||
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tmpnav.belief.models import (
    joint_block_diag,
    landmark_obs,
    landmark_obs_jacobian,
    motion,
    motion_jacobians,
    mutual_obs,
    mutual_obs_jacobian,
    noisy_observation,
    observation_residual,
    process_noise,
    wrap_angle,
)
from tmpnav.types import CostTerms, CostWeights


@dataclass(frozen=True, eq=False)
class BatchInputs:
    """B simulations of the same n robots over T steps with L landmarks, as plain arrays.

    - ``mean0`` (B, 3n), ``cov0`` (B, 3n, 3n): initial joint beliefs (m, m, rad);
    - ``controls`` (B, n, T, 2): (v m/s, omega rad/s); robots that arrived early are padded
      with zeros;
    - ``true_poses`` (B, n, T+1, 3): nominal poses, used to simulate observations and c_G;
    - ``active_steps`` (B, n) int: each robot's own number of motion steps T_i <= T;
    - ``landmarks`` (L, 2): landmark positions (m);
    - ``lm_visible`` (B, n, T+1, L) bool: robot i sees landmark l at step k;
    - ``mutual_visible`` (B, n, n, T+1) bool: robot i sees robot j at step k (the diagonal
      is ignored);
    - ``lm_noise`` (B, n, T+1, L, 2), ``mutual_noise`` (B, n, n, T+1, 2): standard-normal
      draws for the simulated observations; may be None in maximum-likelihood mode.

    Step index 0 of the visibility and noise arrays is never used: observations are made
    after each motion step, the initial belief is given. Broadcast (read-only) views are
    fine: nothing here is written to.
    """

    mean0: np.ndarray
    cov0: np.ndarray
    controls: np.ndarray
    true_poses: np.ndarray
    active_steps: np.ndarray
    landmarks: np.ndarray
    lm_visible: np.ndarray
    mutual_visible: np.ndarray
    lm_noise: np.ndarray | None = None
    mutual_noise: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """(B, n, T, L)."""
        B, n, T, _ = self.controls.shape
        return B, n, T, int(self.landmarks.shape[0])

    def check(self, max_likelihood: bool) -> None:
        """Raise ValueError naming the first array whose shape does not fit (B, n, T, L)."""
        if self.controls.ndim != 4 or self.controls.shape[-1] != 2:
            raise ValueError(f"controls must be (B, n, T, 2), got {self.controls.shape}")
        B, n, T, L = self.shape
        expected: dict[str, tuple[int, ...]] = {
            "mean0": (B, 3 * n),
            "cov0": (B, 3 * n, 3 * n),
            "true_poses": (B, n, T + 1, 3),
            "active_steps": (B, n),
            "landmarks": (L, 2),
            "lm_visible": (B, n, T + 1, L),
            "mutual_visible": (B, n, n, T + 1),
        }
        if not max_likelihood:
            expected["lm_noise"] = (B, n, T + 1, L, 2)
            expected["mutual_noise"] = (B, n, n, T + 1, 2)
        for name, shape in expected.items():
            value = getattr(self, name)
            if value is None:
                raise ValueError(f"{name} is required in noisy mode")
            if tuple(value.shape) != shape:
                raise ValueError(f"{name} must have shape {shape}, got {tuple(value.shape)}")
        steps = np.asarray(self.active_steps)
        if steps.size and (steps.min() < 0 or steps.max() > T):
            raise ValueError(f"active_steps must lie in [0, {T}]")


@dataclass(frozen=True)
class FilterParams:
    """The EKF's constants: time step (s), motion noise alphas, sensor noise (m², rad²)."""

    dt: float
    alphas: tuple[float, float, float, float]
    Q_landmark: tuple[tuple[float, float], tuple[float, float]]
    Q_mutual: tuple[tuple[float, float], tuple[float, float]]
    max_likelihood: bool = False


@dataclass(frozen=True, eq=False)
class BatchResult:
    """Final beliefs and cost terms of B simulations (and the history if it was kept).

    ``final_mean`` (B, 3n), ``final_cov`` (B, 3n, 3n): belief after the last step T;
    ``c_u``, ``c_G``, ``c_Sigma`` (B, n): cost terms per robot; ``mutual_steps`` (B,):
    number of steps with at least one mutual observation; ``means`` (B, T+1, 3n) and
    ``covs`` (B, T+1, 3n, 3n), index 0 the initial belief, or None when not kept.
    """

    final_mean: np.ndarray
    final_cov: np.ndarray
    c_u: np.ndarray
    c_G: np.ndarray
    c_Sigma: np.ndarray
    mutual_steps: np.ndarray
    means: np.ndarray | None = None
    covs: np.ndarray | None = None

    def terms(self, b: int) -> tuple[CostTerms, ...]:
        """The cost terms of each robot of simulation b."""
        return tuple(
            CostTerms(float(cu), float(cg), float(cs))
            for cu, cg, cs in zip(self.c_u[b], self.c_G[b], self.c_Sigma[b], strict=True)
        )

    def totals(self, weights: CostWeights) -> np.ndarray:
        """Weighted cost M_u c_u + M_G c_G + M_Sigma c_Sigma per simulation and robot (B, n)."""
        return weights.M_u * self.c_u + weights.M_G * self.c_G + weights.M_Sigma * self.c_Sigma


# --------------------------------------------------------------------------- EKF steps


def predict(
    mean: np.ndarray, cov: np.ndarray, u: np.ndarray, dt: float, alphas: Sequence[float]
) -> tuple[np.ndarray, np.ndarray]:
    """Joint prediction of B beliefs, paper eqs. (8), (11)-(12).

    mean (B, 3n), cov (B, 3n, 3n), u (B, n, 2) -> predicted (mean, cov).
    """
    B = mean.shape[0]
    poses = mean.reshape(B, -1, 3)
    F, _ = motion_jacobians(poses, u, dt)
    F_joint = joint_block_diag(F)
    R_joint = joint_block_diag(process_noise(poses, u, dt, alphas))
    new_cov = F_joint @ cov @ np.swapaxes(F_joint, -1, -2) + R_joint
    return motion(poses, u, dt).reshape(B, -1), new_cov


def update(
    mean: np.ndarray, cov: np.ndarray, H: np.ndarray, y: np.ndarray, Q: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """EKF update of B beliefs with 2-D observations, paper eq. (9), Joseph form.

    K = P Hᵀ S⁻¹ with S = H P Hᵀ + Q (explicit 2x2 inverse); mean' = mean + K y (headings
    wrapped); P' = (I - K H) P (I - K H)ᵀ + K Q Kᵀ, then symmetrised.
    mean (b, D), cov (b, D, D), H (b, 2, D), y (b, 2) innovation (bearing wrapped), Q (2, 2).
    """
    Ht = np.swapaxes(H, -1, -2)
    PHt = cov @ Ht
    S = H @ PHt + Q
    det = S[:, 0, 0] * S[:, 1, 1] - S[:, 0, 1] * S[:, 1, 0]
    S_inv = np.empty_like(S)
    S_inv[:, 0, 0] = S[:, 1, 1] / det
    S_inv[:, 1, 1] = S[:, 0, 0] / det
    S_inv[:, 0, 1] = -S[:, 0, 1] / det
    S_inv[:, 1, 0] = -S[:, 1, 0] / det
    K = PHt @ S_inv
    new_mean = mean + (K @ y[:, :, None])[:, :, 0]
    new_mean[:, 2::3] = wrap_angle(new_mean[:, 2::3])
    A = np.eye(mean.shape[1]) - K @ H
    new_cov = A @ cov @ np.swapaxes(A, -1, -2) + K @ Q @ np.swapaxes(K, -1, -2)
    return new_mean, 0.5 * (new_cov + np.swapaxes(new_cov, -1, -2))


# --------------------------------------------------------------------------- costs


def control_cost(controls: np.ndarray, active_steps: np.ndarray, dt: float) -> np.ndarray:
    """c_u = sum_{k < T_i} (v_k² + omega_k²) dt. controls (B, n, T, 2) -> (B, n)."""
    T = controls.shape[2]
    active = np.arange(T) < np.asarray(active_steps)[..., None]  # (B, n, T)
    return np.where(active, (controls**2).sum(-1), 0.0).sum(-1) * dt


def robot_traces(cov: np.ndarray) -> np.ndarray:
    """trace of each robot's 3x3 marginal covariance: (..., 3n, 3n) -> (..., n)."""
    diag = np.diagonal(cov, axis1=-2, axis2=-1)
    return diag.reshape(*diag.shape[:-1], -1, 3).sum(-1)


def cost_terms_from_history(
    means: np.ndarray,
    covs: np.ndarray,
    controls: np.ndarray,
    true_poses: np.ndarray,
    active_steps: np.ndarray,
    dt: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(c_u, c_G, c_Sigma), each (B, n), from full histories: the cost's definition.

    means (B, T+1, 3n), covs (B, T+1, 3n, 3n), controls (B, n, T, 2), true_poses
    (B, n, T+1, 3), active_steps (B, n). :func:`propagate` keeps running sums instead.
    """
    B, n, T, _ = controls.shape
    steps = np.asarray(active_steps)
    traces = robot_traces(covs)  # (B, T+1, n)
    counted = (np.arange(T + 1)[None, :, None] >= 1) & (np.arange(T + 1)[None, :, None] <= steps[:, None, :])
    c_sigma = np.where(counted, traces, 0.0).sum(1) * dt
    b_idx = np.arange(B)[:, None]
    r_idx = np.arange(n)[None, :]
    final_xy = means.reshape(B, T + 1, n, 3)[b_idx, steps, r_idx, :2]
    goal_xy = true_poses[b_idx, r_idx, steps, :2]
    c_goal = np.linalg.norm(final_xy - goal_xy, axis=-1)
    return control_cost(controls, steps, dt), c_goal, c_sigma


# --------------------------------------------------------------------------- propagation


@dataclass(frozen=True, eq=False)
class _Slots:
    """The visible landmarks of each (b, i, k), compacted in ascending l into slots.

    ``landmark`` (B, n, T+1, S): index of the s-th visible landmark (meaningless where
    s >= count); ``count`` (B, n, T+1); ``n_slots[i][k]``: the largest count over B.
    """

    landmark: np.ndarray
    count: np.ndarray
    n_slots: list[list[int]]

    @staticmethod
    def of(lm_visible: np.ndarray) -> _Slots:
        count = lm_visible.sum(-1)
        S = int(count.max()) if count.size else 0
        order = np.argsort(~lm_visible, axis=-1, kind="stable")[..., :S]
        n_slots = count.max(axis=0) if count.shape[0] else np.zeros(count.shape[1:], dtype=int)
        return _Slots(order, count, n_slots.tolist())


def _rows(selected: np.ndarray) -> np.ndarray | slice:
    """Indices of the simulations an update applies to (a slice when it is all of them)."""
    rows = np.flatnonzero(selected)
    return slice(None) if rows.size == selected.shape[0] else rows


def _embed(blocks: np.ndarray, robots: tuple[int, ...], n: int) -> np.ndarray:
    """(b, 2, 3m) Jacobian over m robots -> (b, 2, 3n), zero outside their columns."""
    H = np.zeros((blocks.shape[0], 2, 3 * n))
    for m, r in enumerate(robots):
        H[:, :, 3 * r : 3 * r + 3] = blocks[:, :, 3 * m : 3 * m + 3]
    return H


class _Costs:
    """Running sums of the cost terms (module docstring), updated after every step."""

    def __init__(self, mean0: np.ndarray, steps: np.ndarray, dt: float):
        B, n = steps.shape
        self.steps, self.dt = steps, dt
        self.c_sigma = np.zeros((B, n))
        self.final_xy = mean0.reshape(B, n, 3)[:, :, :2].copy()  # for robots with T_i = 0

    def add(self, t: int, mean: np.ndarray, cov: np.ndarray) -> None:
        B, n = self.steps.shape
        self.c_sigma += np.where(t <= self.steps, robot_traces(cov) * self.dt, 0.0)
        arrived = np.equal(self.steps, t)[:, :, None]
        self.final_xy = np.where(arrived, mean.reshape(B, n, 3)[:, :, :2], self.final_xy)

    def c_goal(self, true_poses: np.ndarray) -> np.ndarray:
        B, n = self.steps.shape
        goal_xy = true_poses[np.arange(B)[:, None], np.arange(n)[None, :], self.steps, :2]
        return np.linalg.norm(self.final_xy - goal_xy, axis=-1)


class _Observations:
    """Steps 2 and 3 of a time step: the landmark and mutual updates, in their order."""

    def __init__(self, inputs: BatchInputs, params: FilterParams):
        B, n, _, _ = inputs.shape
        self.n, self.batch = n, np.arange(B)
        self.max_likelihood = params.max_likelihood
        self.Q_lm = np.array(params.Q_landmark, dtype=float)
        self.Q_mu = np.array(params.Q_mutual, dtype=float)
        self.chol_lm, self.chol_mu = np.linalg.cholesky(self.Q_lm), np.linalg.cholesky(self.Q_mu)
        self.landmarks = np.asarray(inputs.landmarks, dtype=float)
        self.true_poses = np.asarray(inputs.true_poses, dtype=float)
        self.lm_noise, self.mutual_noise = inputs.lm_noise, inputs.mutual_noise
        self.slots = _Slots.of(np.asarray(inputs.lm_visible, dtype=bool))
        not_self = ~np.eye(n, dtype=bool)[None, :, :, None]
        self.mutual_visible = np.asarray(inputs.mutual_visible, dtype=bool) & not_self
        self.pair_seen: list[list[list[bool]]] = np.any(self.mutual_visible, axis=0).tolist()

    def landmark_updates(self, mean: np.ndarray, cov: np.ndarray, t: int) -> tuple[np.ndarray, np.ndarray]:
        """Robot i ascending, its visible landmarks ascending (slot by slot), eq. (9)."""
        for i in range(self.n):
            cols = slice(3 * i, 3 * i + 3)
            for s in range(self.slots.n_slots[i][t]):
                rows = _rows(self.slots.count[:, i, t] > s)
                lm_idx = self.slots.landmark[rows, i, t, s]
                lm = self.landmarks[lm_idx]
                x_i = mean[rows, cols]
                H = _embed(landmark_obs_jacobian(x_i, lm), (i,), self.n)
                if self.max_likelihood:  # z = h(mean): no innovation
                    y = np.zeros((x_i.shape[0], 2))
                else:  # z = h(true pose) + chol(Q) noise, eq. (5)
                    assert self.lm_noise is not None
                    noise = self.lm_noise[self.batch[rows], i, t, lm_idx]
                    z_true = landmark_obs(self.true_poses[rows, i, t], lm)
                    z = noisy_observation(z_true, self.chol_lm, noise)
                    y = observation_residual(z, landmark_obs(x_i, lm))
                mean[rows], cov[rows] = update(mean[rows], cov[rows], H, y, self.Q_lm)
        return mean, cov

    def mutual_updates(self, mean: np.ndarray, cov: np.ndarray, t: int) -> tuple[np.ndarray, np.ndarray]:
        """Ordered pairs (i, j), i != j, lexicographically: i observes j, eqs. (13)-(15)."""
        for i in range(self.n):
            for j in range(self.n):
                if not self.pair_seen[i][j][t]:
                    continue
                rows = _rows(self.mutual_visible[:, i, j, t])
                x_i, x_j = mean[rows, 3 * i : 3 * i + 3], mean[rows, 3 * j : 3 * j + 3]
                H = _embed(mutual_obs_jacobian(x_i, x_j), (i, j), self.n)
                if self.max_likelihood:
                    y = np.zeros((x_i.shape[0], 2))
                else:
                    assert self.mutual_noise is not None
                    noise = self.mutual_noise[rows, i, j, t]
                    z_true = mutual_obs(self.true_poses[rows, i, t], self.true_poses[rows, j, t])
                    z = noisy_observation(z_true, self.chol_mu, noise)
                    y = observation_residual(z, mutual_obs(x_i, x_j))
                mean[rows], cov[rows] = update(mean[rows], cov[rows], H, y, self.Q_mu)
        return mean, cov

    def mutual_steps(self) -> np.ndarray:
        """(B,) number of steps with at least one mutual observation."""
        return np.any(self.mutual_visible, axis=(1, 2))[:, 1:].sum(-1)


def propagate(inputs: BatchInputs, params: FilterParams, keep_history: bool = True) -> BatchResult:
    """Propagate B joint beliefs through T steps of predictions and updates.

    See the module docstring for the order of the updates and the cost terms. With
    ``keep_history=False`` only the running cost sums and the final beliefs are kept
    (the oracle's mode: memory independent of T).
    """
    inputs.check(params.max_likelihood)
    B, n, T, _ = inputs.shape
    controls = np.asarray(inputs.controls, dtype=float)
    steps = np.asarray(inputs.active_steps, dtype=int)
    observations = _Observations(inputs, params)

    mean = np.array(inputs.mean0, dtype=float)
    cov = np.array(inputs.cov0, dtype=float)
    means = np.empty((B, T + 1, 3 * n)) if keep_history else None
    covs = np.empty((B, T + 1, 3 * n, 3 * n)) if keep_history else None
    if means is not None and covs is not None:
        means[:, 0], covs[:, 0] = mean, cov
    costs = _Costs(mean, steps, params.dt)

    for k in range(T):
        mean, cov = predict(mean, cov, controls[:, :, k], params.dt, params.alphas)
        mean, cov = observations.landmark_updates(mean, cov, k + 1)
        mean, cov = observations.mutual_updates(mean, cov, k + 1)
        costs.add(k + 1, mean, cov)
        if means is not None and covs is not None:
            means[:, k + 1], covs[:, k + 1] = mean, cov

    return BatchResult(
        final_mean=mean,
        final_cov=cov,
        c_u=control_cost(controls, steps, params.dt),
        c_G=costs.c_goal(observations.true_poses),
        c_Sigma=costs.c_sigma,
        mutual_steps=observations.mutual_steps(),
        means=means,
        covs=covs,
    )
