"""The reference multi-robot EKF on immutable beliefs, built on filterpy.

Each function takes a :class:`~tmpnav.types.Belief` over n robots (joint state of
dimension 3n, robot i in entries 3i..3i+2) and returns a new one; the filterpy object
lives only inside a call. The compiled kernel that runs in the oracle
(:mod:`tmpnav.belief.kernel`) is tested against these functions step by step, through
:func:`tmpnav.belief.reference.propagate_reference`.

After every update the heading entries of the mean are wrapped to [-pi, pi) and the
covariance is symmetrised, P <- (P + Pᵀ)/2 (the kernel computes the upper triangle and
mirrors it).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter

from tmpnav.belief.models import (
    joint_block_diag,
    landmark_obs,
    landmark_obs_jacobian,
    motion,
    motion_jacobians,
    mutual_obs,
    mutual_obs_jacobian,
    observation_residual,
    process_noise,
    wrap_angle,
)
from tmpnav.types import Belief


class _JointUnicycleEKF(ExtendedKalmanFilter):
    """filterpy's EKF whose state prediction is the unicycle model of every robot."""

    def __init__(self, belief: Belief, dt: float = 0.0, midpoint: bool = False):
        super().__init__(dim_x=belief.dim, dim_z=2)
        self.x = np.array(belief.mean, dtype=float)
        self.P = np.array(belief.cov, dtype=float)
        self.dt = dt
        self.midpoint = midpoint

    def predict_x(self, u: np.ndarray | int = 0) -> None:
        # eq. (11): the predicted joint mean is f applied to each robot's mean
        self.x = motion(self.x.reshape(-1, 3), np.asarray(u), self.dt, self.midpoint).reshape(-1)

    def belief(self) -> Belief:
        mean = np.array(self.x, dtype=float).reshape(-1)
        mean[2::3] = wrap_angle(mean[2::3])
        cov = np.array(self.P, dtype=float)
        return Belief(mean, 0.5 * (cov + cov.T))


def predict(belief: Belief, controls: np.ndarray, dt: float, alphas: Sequence[float], midpoint: bool = False) -> Belief:
    """Joint EKF prediction of n robots, paper eqs. (8), (11), (12).

    mean' = [f(mean_1, u_1), ..., f(mean_n, u_n)],   P' = F P Fᵀ + R,
    with F = blockdiag(F_i) and R = blockdiag(V_i W(u_i) V_iᵀ).

    controls: (n, 2) (v m/s, omega rad/s) per robot; dt: s; alphas: (a1, a2, a3, a4);
    ``midpoint``: f's step along the heading at the step's middle (models.motion), else Euler's.
    """
    poses = np.asarray(belief.mean, dtype=float).reshape(-1, 3)
    u = np.asarray(controls, dtype=float).reshape(-1, 2)
    if u.shape[0] != poses.shape[0]:
        raise ValueError(f"{u.shape[0]} controls for {poses.shape[0]} robots")
    F, _ = motion_jacobians(poses, u, dt, midpoint)
    ekf = _JointUnicycleEKF(belief, dt, midpoint)
    ekf.F = joint_block_diag(F)
    ekf.Q = joint_block_diag(process_noise(poses, u, dt, alphas, midpoint))  # filterpy's Q is our R
    ekf.predict(u=u)
    return Belief(np.array(ekf.x, dtype=float), np.array(ekf.P, dtype=float))


_StateFn = Callable[[np.ndarray], np.ndarray]


def _update(belief: Belief, z: np.ndarray, H_of: _StateFn, h_of: _StateFn, Q: np.ndarray) -> Belief:
    ekf = _JointUnicycleEKF(belief)
    # filterpy's update applies the Joseph form (I-KH) P (I-KH)ᵀ + K Q Kᵀ
    ekf.update(
        np.asarray(z, dtype=float),
        HJacobian=H_of,
        Hx=h_of,
        R=np.asarray(Q, dtype=float),
        residual=observation_residual,
    )
    return ekf.belief()


def update_landmark(belief: Belief, i: int, lm: np.ndarray, z: np.ndarray, Q: np.ndarray) -> Belief:
    """EKF update of robot i's observation z = (d m, phi rad) of landmark lm, paper eq. (9).

    H is :func:`landmark_obs_jacobian` in robot i's three columns and zero elsewhere;
    the bearing innovation is wrapped. Q: (2, 2) observation noise (m², rad²).
    """
    lm = np.asarray(lm, dtype=float)
    cols = slice(3 * i, 3 * i + 3)

    def H_of(x: np.ndarray) -> np.ndarray:
        H = np.zeros((2, x.shape[0]))
        H[:, cols] = landmark_obs_jacobian(x[cols], lm)
        return H

    def h_of(x: np.ndarray) -> np.ndarray:
        return landmark_obs(x[cols], lm)

    return _update(belief, z, H_of, h_of, Q)


def update_mutual(belief: Belief, i: int, j: int, z: np.ndarray, Q: np.ndarray) -> Belief:
    """EKF update of robot i's range-bearing observation z of robot j, paper eqs. (13)-(15).

    H fills robot i's and robot j's columns with :func:`mutual_obs_jacobian`, which
    correlates the two robots' estimates (non-zero cross-covariance blocks).
    Q: (2, 2) observation noise (m², rad²).
    """
    if i == j:
        raise ValueError("a robot cannot observe itself")
    ci, cj = slice(3 * i, 3 * i + 3), slice(3 * j, 3 * j + 3)

    def H_of(x: np.ndarray) -> np.ndarray:
        Hij = mutual_obs_jacobian(x[ci], x[cj])
        H = np.zeros((2, x.shape[0]))
        H[:, ci] = Hij[:, :3]
        H[:, cj] = Hij[:, 3:]
        return H

    def h_of(x: np.ndarray) -> np.ndarray:
        return mutual_obs(x[ci], x[cj])

    return _update(belief, z, H_of, h_of, Q)


def update_scan(belief: Belief, i: int, G: np.ndarray, y: np.ndarray) -> Belief:
    """EKF update of robot i's range scan in its compressed form (docs/models.md, "Range sensor").

    A scan of B beams with Jacobians H (B, 3) and noise sigma informs the pose by
    J = Hᵀ H / sigma² and the innovation by Hᵀ y_beams / sigma²; the posterior depends on the
    beams only through these. With J = Gᵀ G (G (3, 3), :func:`tmpnav.world.scan_information.information_matrices`'s
    factor) the same update is the 3-D pseudo-measurement z = G x of unit noise, with innovation
    ``y`` (3,) such that Gᵀ y = Hᵀ y_beams / sigma². G fills robot i's three columns.
    """
    G = np.asarray(G, dtype=float)
    cols = slice(3 * i, 3 * i + 3)
    ekf = _JointUnicycleEKF(belief)
    ekf.dim_z = 3
    H = np.zeros((3, belief.dim))
    H[:, cols] = G
    y = np.asarray(y, dtype=float)
    ekf.update(
        y + G @ np.asarray(belief.mean, dtype=float)[cols],  # z with z - h(mean) = y
        HJacobian=lambda x: H,
        Hx=lambda x: H @ x,
        R=np.eye(3),
    )
    return ekf.belief()
