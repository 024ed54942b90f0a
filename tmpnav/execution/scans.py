"""The range scans of ``tmpnav simulate``: what a robot's lidar measures, and the EKF update with it.

A true scan is ray cast from the robot's true pose (:func:`tmpnav.world.lidar.scan`) with
Gaussian noise on every beam that returns, of the beam's variance there (the sensor's range
noise and its spot's spread). The filter predicts
each beam by ray casting from its estimate, with the beam's Jacobian there (docs/models.md,
"Range sensor"); a beam is used when both return. A beam whose innovation lies beyond
:data:`GATE` standard deviations of its predicted spread is rejected, as a robot's filter
rejects a return from another surface than the one it expects (an edge seen past, a door
frame missed): without the gate one such beam, metres off, would throw the estimate. The
beams used update the joint belief at once, through their compressed 3-D form
(:func:`tmpnav.belief.models.compressed_scan`, :func:`tmpnav.belief.ekf.update_scan`).

The update is iterated (Gauss-Newton, relinearised at each new estimate, the gate applied
again with the new spread). The scan is cast again only when the estimate has moved since the
last cast by enough to change some beam's predicted range by :data:`RECAST` of its standard
deviation; a smaller move is carried to the beams to first order (:func:`beam_shift`,
docs/models.md, "Range sensor").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tmpnav.belief import ekf
from tmpnav.belief.models import compressed_scan, wrap_angle
from tmpnav.types import Belief, RangeSensor
from tmpnav.world import World
from tmpnav.world.lidar import scan, sensor_params

#: innovation gate of one beam, in standard deviations of its predicted spread sqrt(H P Hᵀ + var)
GATE = 3.0
#: Gauss-Newton iterations of the scan's update (an iterated EKF): relinearised at each new estimate
ITERATIONS = 6
#: an iteration that moves the estimate less than this (m, rad) ends them
CONVERGED = 1e-4
#: the scan is cast again at the new estimate when the move since the last cast changes some used
#: beam's predicted range, to first order, by this share of its standard deviation or more
RECAST = 0.1


@dataclass(frozen=True)
class ScanCount:
    """Beams of one scan: returned in both the true and the predicted scan, and of those rejected by the gate."""

    used: int
    rejected: int


class ScanSimulator:
    """Simulated scans of one sensor in one world (see the module docstring)."""

    def __init__(self, world: World, sensor: RangeSensor):
        self.sensor = sensor
        self.sdf = world.signed_distance
        self.origin = (float(world.grid.origin[0]), float(world.grid.origin[1]))
        self.res = float(world.grid.resolution)
        self.angles = sensor.beam_angles()
        self.params = sensor_params(sensor)

    def ranges(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The noise-free scan from ``pose`` (3,): ranges (B,) m (nan: no return), Jacobians (B, 3)
        and the variances of the ranges (B,) m²."""
        B = self.angles.size
        r, H, var = np.empty(B), np.empty((B, 3)), np.empty(B)
        scan(self.sdf, *self.origin, self.res, np.asarray(pose, dtype=float), self.angles, self.params, r, H, var)
        return r, H, var

    def update(self, belief: Belief, i: int, truth: np.ndarray, draws: np.ndarray) -> tuple[Belief, ScanCount]:
        """Robot i scans from its true pose ``truth`` with the standard-normal ``draws`` (B,); the
        joint belief updated with the beams that pass the gate, relinearised at each new estimate
        (cast again there when it has moved by :data:`RECAST` of a beam's standard deviation).

        The iterations move robot i's estimate only (its own block of the belief: the update of
        the robot's mean does not depend on the others'); the last one updates the joint belief
        through the filterpy reference (:func:`tmpnav.belief.ekf.update_scan`)."""
        true_r, _, true_var = self.ranges(truth)
        z = true_r + np.sqrt(true_var) * draws
        cols = slice(3 * i, 3 * i + 3)
        prior, P = belief.mean[cols], belief.cov[cols, cols]
        at, spread_cov, count = prior, P, ScanCount(0, 0)
        update: tuple[np.ndarray, np.ndarray] | None = None
        cast_at = prior
        predicted, H, var = self.ranges(prior)
        for it in range(ITERATIONS):
            both = ~np.isnan(z) & ~np.isnan(predicted)
            moved = at - cast_at
            moved[2] = wrap_angle(moved[2])
            if it > 0 and beam_shift(moved, H[both], var[both]) >= RECAST:
                predicted, H, var = self.ranges(at)
                cast_at, moved = at, np.zeros(3)
                both = ~np.isnan(z) & ~np.isnan(predicted)
            Hb, vb = H[both], var[both]
            residual = z[both] - predicted[both] - Hb @ moved  # at `at`: the last cast carried to first order
            spread = np.sqrt(np.einsum("bi,ij,bj->b", Hb, spread_cov, Hb) + vb)
            keep = np.abs(residual) <= GATE * spread
            if it == 0:
                count = ScanCount(int(both.sum()), int((~keep).sum()))
            if not keep.any():
                break
            shift = at - prior
            shift[2] = wrap_angle(shift[2])
            G, y_G = compressed_scan(Hb[keep], residual[keep] + Hb[keep] @ shift, np.sqrt(vb[keep]))
            update = (G, y_G)
            K = P @ G.T @ np.linalg.inv(G @ P @ G.T + np.eye(3))
            step = prior + K @ y_G - at
            at = prior + K @ y_G
            at[2] = wrap_angle(at[2])
            spread_cov = P - K @ G @ P
            if np.hypot(step[0], step[1]) < CONVERGED and abs(wrap_angle(step[2])) < CONVERGED:
                break
        if update is None:
            return belief, count
        return ekf.update_scan(belief, i, *update), count


def beam_shift(moved: np.ndarray, H: np.ndarray, var: np.ndarray) -> float:
    """How far a move of the pose by ``moved`` (3,) (m, m, rad) shifts the beams' predicted ranges,
    to first order: max_b |H_b moved| / sqrt(var_b) over the beams (Jacobians H (B, 3), range
    variances var (B,) m²), in standard deviations; 0 for no beam."""
    if not len(var):
        return 0.0
    return float(np.max(np.abs(H @ moved) / np.sqrt(var)))
