"""The team's joint EKF in ``tmpnav simulate``, compiled: what sessions run.

:class:`CompiledJointEkf` is :class:`tmpnav.execution.joint_ekf.JointEkf` (the filterpy
reference) as one numba call per control step (:func:`_observe`), on a mean and covariance
updated in place: the prediction, landmark and mutual updates of the planner's kernel
(:mod:`tmpnav.belief.kernel`: eqs. (8), (9), (11)-(15), Joseph form), and the range scan as
:class:`tmpnav.execution.scans.ScanSimulator` does it (the true scan ray cast from the true
pose, the iterated update of the robot's own block with the innovation gate, then the joint
update with the compressed scan, here as three scalar updates of unit noise). The two agree to
floating-point rounding (``tests/execution/test_fast_ekf.py``); what the profile of a session
showed and what this gained is in benchmarks/README.md, "simulate".
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from tmpnav.belief.kernel import _landmark_observation, _predict, _robot_observation, _update, _update_scalar
from tmpnav.execution.joint_ekf import mutually_visible, sensing_pairs
from tmpnav.execution.localisers import substep_noise
from tmpnav.execution.scans import CONVERGED, GATE, ITERATIONS, RECAST
from tmpnav.execution.trace import Draws
from tmpnav.types import Belief, Scenario
from tmpnav.world import World
from tmpnav.world.geometry import wrap_angle_scalar
from tmpnav.world.lidar import SENSOR_PARAMS, scan, scan_beams, sensor_params
from tmpnav.world.visibility import LandmarkVisibility


class CompiledJointEkf:
    """One joint EKF over the team (``mutual``: with mutual observations, config 1), compiled."""

    def __init__(
        self, scenario: Scenario, world: World, vis: LandmarkVisibility, draws: Draws, belief: Belief, mutual: bool
    ):
        self.scenario, self.draws = scenario, draws
        self.names = tuple(r.name for r in scenario.robots)
        n = self.n = len(self.names)
        self.mean = np.array(belief.mean, dtype=float)
        self.cov = np.array(belief.cov, dtype=float)
        self.sensing = sensing_pairs(scenario, self.names) if mutual else {}
        models = scenario.models
        self.alphas = np.asarray(models.motion_noise, dtype=float)
        self.q_lm = np.asarray(models.landmark_sensor.Q, dtype=float)
        self.q_mu = np.asarray(models.mutual_sensor.Q, dtype=float)
        self.chol_lm, self.chol_mu = np.linalg.cholesky(self.q_lm), np.linalg.cholesky(self.q_mu)
        sensor = models.range_sensor
        self.angles = sensor.beam_angles() if sensor is not None else np.zeros(0)
        self.params = sensor_params(sensor) if sensor is not None else np.zeros(SENSOR_PARAMS)
        self.work = np.empty((3 * n, 3 * n))
        self.counts = np.zeros((n, 2), dtype=np.int64)
        # each robot's last true scan: its pose (nan: none yet), ranges and variances (n, B)
        self.last = np.full((n, 3), np.nan)
        self.last_r, self.last_var = np.empty((n, self.angles.size)), np.empty((n, self.angles.size))
        self.set_world(world, vis)

    def estimate(self, i: int) -> np.ndarray:
        """Robot i's estimated pose (3,): its part of the joint mean."""
        return self.mean[3 * i : 3 * i + 3].copy()

    def estimate_cov(self, i: int) -> np.ndarray:
        """Robot i's covariance (3, 3): its block of the joint covariance."""
        return self.cov[3 * i : 3 * i + 3, 3 * i : 3 * i + 3].copy()

    def predict(self, u: np.ndarray, steps: np.ndarray | None = None) -> None:
        """The prediction with the commands (n, 2), eqs. (8), (11), (12); with ``steps`` (n, N, 2)
        one by one (:meth:`tmpnav.execution.localisers.TeamLocaliser.predict`)."""
        dt = self.scenario.models.dt
        if steps is None:
            _predict(self.mean, self.cov, np.ascontiguousarray(u, dtype=float), self.n, dt, self.alphas, self.work)
            return
        n, alphas = steps.shape[1], substep_noise(self.alphas, steps.shape[1])
        for k in range(n):
            _predict(self.mean, self.cov, np.ascontiguousarray(steps[:, k]), self.n, dt / n, alphas, self.work, 1.0)

    def observe(self, truth: np.ndarray, step: int) -> list[tuple[int, int]]:
        """As :meth:`tmpnav.execution.joint_ekf.JointEkf.observe`: landmarks, scans, partners."""
        models = self.scenario.models
        truth = np.ascontiguousarray(truth, dtype=float)
        seen = np.ascontiguousarray(self.vis.visible(truth, models.landmark_sensor.fov), dtype=np.bool_)
        pairs = mutually_visible(self.sensing, self.world, truth) if self.sensing else []
        d = self.draws
        _observe(
            self.mean, self.cov, self.n, truth,
            self.landmarks, seen, np.ascontiguousarray(d.landmark[:, step]), self.chol_lm, self.q_lm,
            self.scanning, self.sdf, self.x0, self.y0, self.res, self.angles, self.params,
            np.ascontiguousarray(d.scan[:, step]),
            np.array(pairs, dtype=np.int64).reshape(-1, 2), np.ascontiguousarray(d.mutual[:, :, step]),
            self.chol_mu, self.q_mu, self.counts, self.last, self.last_r, self.last_var,
        )  # fmt: skip
        return [(a, b) for a, b in self.counts.tolist()]

    def set_world(self, world: World, vis: LandmarkVisibility) -> None:
        """The world changed (a door closed): the robots' sightings and scans see the new one."""
        self.world, self.vis = world, vis
        self.landmarks = np.ascontiguousarray(world.landmark_xy, dtype=float).reshape(-1, 2)
        self.scanning = self.scenario.models.range_sensor is not None
        self.sdf = world.signed_distance if self.scanning else np.zeros((1, 1))
        self.x0, self.y0 = (float(world.grid.origin[0]), float(world.grid.origin[1]))
        self.res = float(world.grid.resolution)
        self.last[:] = np.nan  # scans of the old world are not kept


@nb.njit(cache=True)
def _observe(
    mean, cov, n, truth, landmarks, seen, lm_draws, chol_lm, q_lm,
    scanning, sdf, x0, y0, res, angles, params, scan_draws, pairs, mu_draws, chol_mu, q_mu, counts,
    last, last_r, last_var,
):  # fmt: skip
    """One control step's observations, in the reference's order: every robot's landmarks
    (``seen`` (n, L), draws (n, L, 2)), every robot's scan (draws (n, B)), then the ordered
    ``pairs`` (k, 2) of robots that see each other (draws (n, n, 2)); ``counts`` (n, 2) gets the
    beams each robot's scan used and rejected; ``last``, ``last_r``, ``last_var`` keep each robot's
    last true scan (:func:`_scan`)."""
    D = 3 * n
    work, PHt, K = np.empty((D, D)), np.empty((D, 2)), np.empty((D, 2))
    H, cols, y = np.zeros((2, D)), np.zeros(5, dtype=np.int64), np.empty(2)
    for i in range(n):
        for lm in range(landmarks.shape[0]):
            if not seen[i, lm]:
                continue
            H[:, :] = 0.0
            _landmark_observation(
                mean, i, landmarks[lm, 0], landmarks[lm, 1], truth[i, 0], truth[i, 1], truth[i, 2],
                lm_draws[i, lm, 0], lm_draws[i, lm, 1], False, chol_lm, H, cols, y,
            )  # fmt: skip
            _update(mean, cov, H, cols, 3, y, q_lm, n, work, PHt, K)
    for i in range(n):
        counts[i, 0], counts[i, 1] = 0, 0
        if scanning:
            _scan(
                mean, cov, n, i, truth[i], scan_draws[i], sdf, x0, y0, res, angles, params, work, PHt, K, counts,
                last, last_r, last_var,
            )  # fmt: skip
    for p in range(pairs.shape[0]):
        i, j = pairs[p, 0], pairs[p, 1]
        H[:, :] = 0.0
        _robot_observation(
            mean, i, j, truth[i], truth[j], mu_draws[i, j, 0], mu_draws[i, j, 1], False, chol_mu, H, cols, y
        )
        _update(mean, cov, H, cols, 5, y, q_mu, n, work, PHt, K)


@nb.njit(cache=True)
def _scan(
    mean, cov, n, i, truth, draws, sdf, x0, y0, res, angles, params, work, PHt, K, counts, last, last_r, last_var
):
    """Robot i's scan from its true pose, as :meth:`tmpnav.execution.scans.ScanSimulator.update`:
    the beams that return in both the true and the predicted scan and pass the gate, the update
    iterated on the robot's own block (cast again where it has moved by RECAST of a beam's
    standard deviation), then the joint update with their compressed form. Only the beams with a
    true return are cast from the estimate, and the true scan of a robot that has not moved since
    its last one is the one kept in ``last`` (n, 3) (its pose), ``last_r`` and ``last_var`` (n, B)."""
    B = angles.shape[0]
    Hb, var = np.empty((B, 3)), np.empty(B)
    true_r, true_var = last_r[i], last_var[i]
    if not (truth[0] == last[i, 0] and truth[1] == last[i, 1] and truth[2] == last[i, 2]):
        scan(sdf, x0, y0, res, truth, angles, params, true_r, Hb, true_var)
        last[i, :] = truth
    z = true_r + np.sqrt(true_var) * draws
    wanted = ~np.isnan(z)
    c = 3 * i
    prior = mean[c : c + 3].copy()
    P = cov[c : c + 3, c : c + 3].copy()
    at, spread_cov, cast_at = prior.copy(), P.copy(), prior.copy()
    predicted = np.empty(B)
    scan_beams(sdf, x0, y0, res, prior, angles, params, wanted, predicted, Hb, var)
    G, y_G, residual = np.zeros((3, 3)), np.zeros(3), np.empty(B)
    updated = False
    keep = np.zeros(B, dtype=np.bool_)
    for it in range(ITERATIONS):
        m0, m1, m2 = at[0] - cast_at[0], at[1] - cast_at[1], wrap_angle_scalar(at[2] - cast_at[2])
        if it > 0 and _beam_shift(m0, m1, m2, z, predicted, Hb, var) >= RECAST:
            scan_beams(sdf, x0, y0, res, at, angles, params, wanted, predicted, Hb, var)
            cast_at[:] = at
            m0 = m1 = m2 = 0.0
        both = kept = 0
        for b in range(B):
            keep[b] = False
            if math.isnan(z[b]) or math.isnan(predicted[b]):
                continue
            both += 1
            h0, h1, h2 = Hb[b, 0], Hb[b, 1], Hb[b, 2]
            residual[b] = (z[b] - predicted[b]) - (h0 * m0 + h1 * m1 + h2 * m2)
            quad = 0.0
            for r in range(3):
                quad += (h0 * spread_cov[0, r] + h1 * spread_cov[1, r] + h2 * spread_cov[2, r]) * Hb[b, r]
            if abs(residual[b]) <= GATE * math.sqrt(quad + var[b]):
                keep[b] = True
                kept += 1
        if it == 0:
            counts[i, 0], counts[i, 1] = both, both - kept
        if kept == 0:
            break
        s0, s1, s2 = at[0] - prior[0], at[1] - prior[1], wrap_angle_scalar(at[2] - prior[2])
        J, rhs = np.zeros((3, 3)), np.zeros(3)  # compressed_scan: J = sum H'H / s², rhs = sum H' y / s²
        for b in range(B):
            if not keep[b]:
                continue
            sd = math.sqrt(var[b])
            w = 1.0 / (sd * sd)
            yb = residual[b] + (Hb[b, 0] * s0 + Hb[b, 1] * s1 + Hb[b, 2] * s2)
            for r in range(3):
                rhs[r] += Hb[b, r] * (yb * w)
                for q in range(3):
                    J[r, q] += Hb[b, r] * w * Hb[b, q]
        lam, vec = np.linalg.eigh(J)
        top = max(lam[2], 0.0)
        for k in range(3):
            if lam[k] > 1e-12 * top:
                root = math.sqrt(lam[k])
                y_G[k] = (vec[0, k] * rhs[0] + vec[1, k] * rhs[1] + vec[2, k] * rhs[2]) / root
                for q in range(3):
                    G[k, q] = root * vec[q, k]
            else:
                y_G[k] = 0.0
                G[k, :] = 0.0
        updated = True
        Gt = np.ascontiguousarray(G.T)
        Kr = P @ Gt @ np.linalg.inv(G @ P @ Gt + np.eye(3))
        new = prior + Kr @ y_G
        d0, d1, d2 = new[0] - at[0], new[1] - at[1], new[2] - at[2]
        at = new
        at[2] = wrap_angle_scalar(at[2])
        spread_cov = P - Kr @ G @ P
        if math.hypot(d0, d1) < CONVERGED and abs(wrap_angle_scalar(d2)) < CONVERGED:
            break
    if not updated:
        return
    # the joint update with z = G x (unit noise, innovation y_G at the prior mean), as three scalar
    # updates: each row's innovation against the mean the rows before it left
    g = np.empty(3)
    for k in range(3):
        g[0], g[1], g[2] = G[k, 0], G[k, 1], G[k, 2]
        if g[0] == 0.0 and g[1] == 0.0 and g[2] == 0.0:
            continue
        moved = (
            g[0] * (prior[0] - mean[c])
            + g[1] * (prior[1] - mean[c + 1])
            + g[2] * wrap_angle_scalar(prior[2] - mean[c + 2])
        )
        _update_scalar(mean, cov, g, c, y_G[k] + moved, n, work, PHt, K)


@nb.njit(cache=True)
def _beam_shift(m0, m1, m2, z, predicted, H, var):
    """:func:`tmpnav.execution.scans.beam_shift` of the move (m0, m1, m2) over the beams that
    return in both ``z`` and ``predicted``."""
    out = 0.0
    for b in range(z.shape[0]):
        if math.isnan(z[b]) or math.isnan(predicted[b]):
            continue
        out = max(out, abs(H[b, 0] * m0 + H[b, 1] * m1 + H[b, 2] * m2) / math.sqrt(var[b]))
    return out
