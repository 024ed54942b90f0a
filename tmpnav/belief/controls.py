"""A roadmap path (a polyline of positions) turned into unicycle controls.

The robot follows a path point by point: it turns on the spot towards the next point,
then drives straight to it. Its nominal poses are the motion model, paper eq. (4), applied
step by step (compiled: the oracle turns thousands of paths into controls), so the belief
layer and the nominal trajectory agree to rounding error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from tmpnav.world.geometry import wrap_angle_scalar

#: below these a turn or an edge is treated as already done (rad, m)
ANGLE_EPS = 1e-9
LENGTH_EPS = 1e-9


@dataclass(frozen=True, eq=False)
class PathControls:
    """Controls along a path and the nominal poses they produce.

    ``controls`` (T, 2): (v m/s, omega rad/s) per step; ``poses`` (T+1, 3): nominal pose
    before step 0 up to after step T-1; ``node_steps`` (P,): the step index at which each
    path point is reached (0 for the first point).
    """

    controls: np.ndarray
    poses: np.ndarray
    node_steps: np.ndarray
    pursued: bool = False  # by nav2's Regulated Pure Pursuit (tmpnav.belief.pursuit), not turn-then-drive

    @property
    def n_steps(self) -> int:
        """T, the number of motion steps."""
        return int(self.controls.shape[0])


def path_controls(points: np.ndarray, start_theta: float, speed: float, turn_rate: float, dt: float) -> PathControls:
    """Turn-then-drive controls that take a robot through ``points`` (P, 2), in metres.

    For each next point: turn on the spot with constant omega = dtheta / (n_turn dt),
    n_turn = ceil(|dtheta| / (turn_rate dt)) (skipped when |dtheta| < 1e-9 rad), then drive
    straight with v = length / (n_drive dt), n_drive = ceil(length / (speed dt)).
    Heading and length are measured from the current nominal pose, so rounding does not
    accumulate along the path; a skipped turn below 1e-9 rad can miss the next point by at
    most 1e-9 x the edge length. Repeated points (zero-length edges) produce no steps.
    speed (m/s), turn_rate (rad/s) and dt (s) must be positive.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if pts.shape[0] == 0:
        raise ValueError("path_controls needs at least one point")
    if speed <= 0 or turn_rate <= 0 or dt <= 0:
        raise ValueError("speed, turn_rate and dt must be positive")
    controls, poses, node_steps = _turn_then_drive(
        np.ascontiguousarray(pts), float(start_theta), float(speed), float(turn_rate), float(dt), ANGLE_EPS, LENGTH_EPS
    )
    return PathControls(controls=controls, poses=poses, node_steps=node_steps.astype(int))


def turn_to(
    controls: np.ndarray, poses: np.ndarray, heading: float, turn_rate: float, dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """Controls (T, 2) and poses (T+1, 3) of a path followed by a turn on the spot to ``heading``
    (rad), as :func:`path_controls` turns: omega = dtheta / (n dt), n = ceil(|dtheta| / (turn_rate
    dt)), dtheta the wrapped difference from the last pose's heading (no steps below 1e-9 rad)."""
    theta = float(poses[-1, 2])
    dtheta = wrap_angle_scalar(heading - theta)
    if abs(dtheta) < ANGLE_EPS:
        return controls, poses
    n = _n_steps(abs(dtheta), turn_rate, dt)
    omega = dtheta / (n * dt)
    turn = np.tile(np.array([[0.0, omega]]), (n, 1))
    headings = np.empty(n)
    for k in range(n):  # step by step, as the turns of path_controls
        theta = wrap_angle_scalar(theta + omega * dt)
        headings[k] = theta
    turned = np.column_stack([np.repeat(poses[-1:, :2], n, axis=0), headings])
    return np.vstack([controls.reshape(-1, 2), turn]), np.vstack([poses, turned])


def pad(controls: np.ndarray, poses: np.ndarray, T_total: int) -> tuple[np.ndarray, np.ndarray]:
    """Extend a robot that arrived early to ``T_total`` steps.

    It waits at its final pose with u = 0 (and keeps observing). controls (T, 2) ->
    (T_total, 2); poses (T+1, 3) -> (T_total+1, 3). T_total must be at least T.
    """
    T = controls.shape[0]
    if T_total < T:
        raise ValueError(f"cannot pad {T} steps to {T_total}")
    extra = T_total - T
    padded_controls = np.concatenate([controls, np.zeros((extra, 2))], axis=0)
    padded_poses = np.concatenate([poses, np.repeat(poses[-1:], extra, axis=0)], axis=0)
    return padded_controls, padded_poses


@nb.njit(cache=True)
def _n_steps(amount, rate, dt):
    """Whole steps to cover ``amount`` at ``rate`` per second (at least one)."""
    return max(1, math.ceil(amount / (rate * dt)))


@nb.njit(cache=True)
def _turn_then_drive(pts, theta0, speed, turn_rate, dt, angle_eps, length_eps):
    """Controls (T, 2), nominal poses (T+1, 3) and the step reaching each point (P,) of
    :func:`tmpnav.belief.controls.path_controls`, which documents the rule."""
    P = pts.shape[0]
    bound = 1
    for k in range(1, P):
        d = math.hypot(pts[k, 0] - pts[k - 1, 0], pts[k, 1] - pts[k - 1, 1])
        bound += _n_steps(math.pi, turn_rate, dt) + _n_steps(d + 1e-6, speed, dt) + 2
    controls = np.zeros((bound, 2))
    poses = np.zeros((bound + 1, 3))
    node_steps = np.zeros(P, dtype=np.int64)
    poses[0, 0], poses[0, 1], poses[0, 2] = pts[0, 0], pts[0, 1], wrap_angle_scalar(theta0)
    T = 0
    for k in range(1, P):
        dx, dy = pts[k, 0] - poses[T, 0], pts[k, 1] - poses[T, 1]
        length = math.hypot(dx, dy)
        if length >= length_eps:
            dtheta = wrap_angle_scalar(math.atan2(dy, dx) - poses[T, 2])
            if abs(dtheta) >= angle_eps:
                n = _n_steps(abs(dtheta), turn_rate, dt)
                omega = dtheta / (n * dt)
                for _ in range(n):
                    controls[T, 0], controls[T, 1] = 0.0, omega
                    th = poses[T, 2]
                    poses[T + 1, 0] = poses[T, 0] + 0.0 * dt * math.cos(th)
                    poses[T + 1, 1] = poses[T, 1] + 0.0 * dt * math.sin(th)
                    poses[T + 1, 2] = wrap_angle_scalar(th + omega * dt)
                    T += 1
            n = _n_steps(length, speed, dt)
            v = length / (n * dt)
            for _ in range(n):
                controls[T, 0], controls[T, 1] = v, 0.0
                th = poses[T, 2]
                poses[T + 1, 0] = poses[T, 0] + v * dt * math.cos(th)
                poses[T + 1, 1] = poses[T, 1] + v * dt * math.sin(th)
                poses[T + 1, 2] = wrap_angle_scalar(th + 0.0 * dt)
                T += 1
        node_steps[k] = T
    return controls[:T].copy(), poses[: T + 1].copy(), node_steps
