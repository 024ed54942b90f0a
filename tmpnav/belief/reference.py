"""The reference propagation: one simulation through the filterpy EKF, one update at a time.

This is the readable statement of what the compiled kernel (:mod:`tmpnav.belief.kernel`)
computes, and what the tests hold it to (1e-9, step by step). It is not on the planner's
path and not part of the oracle's cache keys. At each step k = 0..T-1:

1. joint prediction of all robots with their controls of step k, paper eqs. (8), (11), (12);
2. landmark updates, robot by robot (i ascending), landmark by landmark (l ascending),
   each a 2-D EKF update, eq. (9), where ``lm_visible[i, k+1, l]``;
3. range scans, robot by robot, where the rollout has them (``scans``), each the
   three-dimensional update of :func:`tmpnav.belief.ekf.update_scan`;
4. mutual updates for ordered pairs (i, j), i != j, in lexicographic order, where
   ``mutual_visible[i, j, k+1]``, eqs. (13)-(15).

Observations are simulated as z = h(true pose after the step) + chol(Q) noise (noisy
mode) or z = h(current mean) (maximum-likelihood mode: no innovation); a scan's innovation
is G (true pose - mean) + noise, the heading difference wrapped.
"""

from __future__ import annotations

import numpy as np

from tmpnav.belief import ekf
from tmpnav.belief.models import landmark_obs, mutual_obs, noisy_observation, wrap_angle
from tmpnav.belief.rollout import ObservationNoise, Propagation, Rollout, control_usage, observed_mutually
from tmpnav.types import Belief, CostTerms, Models, ObservationMode


def robot_traces(cov: np.ndarray) -> np.ndarray:
    """trace of each robot's 3x3 marginal covariance: (..., 3n, 3n) -> (..., n)."""
    diag = np.diagonal(cov, axis1=-2, axis2=-1)
    return diag.reshape(*diag.shape[:-1], -1, 3).sum(-1)


def cost_terms_from_history(means: np.ndarray, covs: np.ndarray, rollout: Rollout, dt: float) -> tuple[CostTerms, ...]:
    """The cost terms of each robot from a whole history: the definition (docs/models.md).

    means (T+1, 3n), covs (T+1, 3n, 3n), index 0 the initial belief. With T_i robot i's
    own number of motion steps: c_u = sum_{k<T_i} (v_k² + omega_k²) dt,
    c_Sigma = sum_{k=1..T_i} trace(Sigma^i_k) dt, c_G = ||mean^i_{T_i}[:2] - pose^i_{T_i}[:2]||.
    """
    n = rollout.controls.shape[0]
    steps = np.asarray(rollout.active_steps, dtype=int)
    traces = robot_traces(covs)  # (T+1, n)
    k = np.arange(traces.shape[0])[:, None]
    c_sigma = np.where((k >= 1) & (k <= steps[None, :]), traces, 0.0).sum(0) * dt
    final_xy = means.reshape(means.shape[0], n, 3)[steps, np.arange(n), :2]
    goal_xy = rollout.true_poses[np.arange(n), steps, :2]
    c_goal = np.linalg.norm(final_xy - goal_xy, axis=-1)
    c_u = control_usage(rollout, dt)
    return tuple(CostTerms(float(c_u[i]), float(c_goal[i]), float(c_sigma[i])) for i in range(n))


def propagate_reference(
    belief: Belief,
    rollout: Rollout,
    landmarks: np.ndarray,
    models: Models,
    noise: ObservationNoise | None = None,
) -> Propagation:
    """The simulation of :func:`tmpnav.belief.rollout.propagate_rollout`, through filterpy.

    ``belief`` is the joint initial belief (3n); ``landmarks`` (L, 2) in metres; ``noise``
    defaults to :meth:`ObservationNoise.draw` from ``models.seed``.
    """
    n, T, _ = rollout.controls.shape
    landmarks = np.asarray(landmarks, dtype=float).reshape(-1, 2)
    ml = models.observations is ObservationMode.MAX_LIKELIHOOD
    if noise is None:
        noise = ObservationNoise.draw(models.seed, n, T, landmarks.shape[0])
    Q_lm, Q_mu = models.landmark_sensor.Q, models.mutual_sensor.Q
    chol_lm, chol_mu = np.linalg.cholesky(Q_lm), np.linalg.cholesky(Q_mu)
    mutual_visible = observed_mutually(rollout, models)  # none for a localiser of the lidar alone (nav2's AMCL)
    if models.range_sensor is not None and not models.range_sensor.localiser.fuses_others:
        lm_visible = np.zeros_like(rollout.lm_visible)
    else:
        lm_visible = rollout.lm_visible
    poses = rollout.true_poses

    beliefs = [Belief(np.array(belief.mean, dtype=float), np.array(belief.cov, dtype=float))]
    b = beliefs[0]
    for k in range(T):
        t = k + 1
        b = ekf.predict(b, rollout.controls[:, k], models.dt, models.belief_noise, models.midpoint)
        for i in range(n):
            for l_ in np.flatnonzero(lm_visible[i, t]):
                if ml:
                    z = landmark_obs(b.mean[3 * i : 3 * i + 3], landmarks[l_])
                else:
                    z = noisy_observation(landmark_obs(poses[i, t], landmarks[l_]), chol_lm, noise.landmark[i, t, l_])
                b = ekf.update_landmark(b, i, landmarks[l_], z, Q_lm)
        if rollout.scans is not None and models.range_sensor is not None:
            for i in range(n):
                v, omega = rollout.controls[i, k]
                w = models.range_sensor.localiser.update_rate(float(v), float(omega), models.dt) ** 0.5
                if w == 0.0:
                    continue  # a localiser that updates only on the move
                G = w * rollout.scans[i, t]
                if ml:
                    y = np.zeros(3)
                else:
                    delta = poses[i, t] - b.mean[3 * i : 3 * i + 3]
                    delta[2] = wrap_angle(delta[2])
                    y = G @ delta + noise.scan_draws(n, T)[i, t]
                b = ekf.update_scan(b, i, G, y)
        for i in range(n):
            for j in range(n):
                if not mutual_visible[i, j, t]:
                    continue
                if ml:
                    z = mutual_obs(b.mean[3 * i : 3 * i + 3], b.mean[3 * j : 3 * j + 3])
                else:
                    z = noisy_observation(mutual_obs(poses[i, t], poses[j, t]), chol_mu, noise.mutual[i, j, t])
                b = ekf.update_mutual(b, i, j, z, Q_mu)
        beliefs.append(b)

    means = np.stack([x.mean for x in beliefs])
    covs = np.stack([x.cov for x in beliefs])
    return Propagation(
        means=means,
        covs=covs,
        terms=cost_terms_from_history(means, covs, rollout, models.dt),
        mutual_steps=int(np.any(mutual_visible, axis=(0, 1))[1:].sum()),
    )
