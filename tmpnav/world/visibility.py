"""Who sees what: landmark visibility polygons and robot-to-robot line of sight.

A landmark is observed from pose x when it is within the sensor's range, inside its field
of view (|bearing| <= fov/2) and not hidden behind an occupied cell. The occlusion test is
precomputed once per landmark as a visibility polygon: ``RAYS`` rays are cast from the
landmark up to the sensor range and the free distance along each is stored; a point is in
line of sight when it is no farther than the free distance of its ray. At 5 m the rays are
about 2.5 cm apart, half a grid cell.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from tmpnav.types import Scenario
from tmpnav.world.build import World
from tmpnav.world.geometry import wrap_angle_scalar

RAYS = 1440


class LandmarkVisibility:
    """Visibility polygons of all landmarks of a world for one sensor range."""

    def __init__(self, world: World, sensor_range: float):
        self.world = world
        self.range = sensor_range
        self.landmarks = world.landmark_xy
        angles = np.linspace(-np.pi, np.pi, RAYS, endpoint=False)
        self._angles = angles
        step = 0.5 * world.grid.resolution
        radii = np.arange(1, int(np.ceil(sensor_range / step)) + 1) * step
        free = np.empty((len(self.landmarks), RAYS))
        directions = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        margin = 1.5 * world.grid.resolution  # a landmark on a wall sees past its own cell
        for k, lm in enumerate(self.landmarks):
            pts = lm[None, None, :] + radii[None, :, None] * directions[:, None, :]
            blocked = world.grid.is_occupied(pts) & (radii[None, :] > margin)
            first = np.where(blocked.any(axis=1), blocked.argmax(axis=1), len(radii))
            free[k] = np.where(first < len(radii), radii[np.minimum(first, len(radii) - 1)] - step, sensor_range)
        self._free = free

    def visible(self, poses: np.ndarray, fov: float, min_range: float = 0.0) -> np.ndarray:
        """Which landmarks each pose sees: poses (..., 3) -> bool (..., L).

        A landmark closer than ``min_range`` (the robot's radius: it would be under the
        robot) is not observed; the range-bearing model is singular there.
        """
        flat = np.ascontiguousarray(poses, dtype=float).reshape(-1, 3)
        seen = np.zeros((flat.shape[0], len(self.landmarks)), dtype=bool)
        if self._free.size:
            _landmarks_seen(flat, self.landmarks, self._free, self.range, fov, min_range, seen)
        return seen.reshape(*poses.shape[:-1], len(self.landmarks))


@nb.njit(cache=True)
def _landmarks_seen(
    poses: np.ndarray,
    landmarks: np.ndarray,
    free: np.ndarray,
    sensor_range: float,
    fov: float,
    min_range: float,
    seen: np.ndarray,
) -> None:
    """:meth:`LandmarkVisibility.visible`, compiled: ``seen[p, l]`` when pose p (x, y, theta)
    has landmark l within [min_range, sensor_range], inside the field of view, and no farther
    than the free distance ``free[l, ray]`` of the landmark's ray towards the pose (the ray
    nearest its angle, ties to the even one). A motion's poses were checked one numpy call per
    motion: 0.77 s of the 20-room building's oracle for 4,700 motions."""
    limited = fov < 2 * np.pi - 1e-9
    for p in range(poses.shape[0]):
        x, y, theta = poses[p, 0], poses[p, 1], poses[p, 2]
        for k in range(landmarks.shape[0]):
            dx, dy = landmarks[k, 0] - x, landmarks[k, 1] - y
            dist = math.hypot(dx, dy)
            if not (dist <= sensor_range and dist >= min_range):
                continue
            if limited and not abs(wrap_angle_scalar(math.atan2(dy, dx) - theta)) <= fov / 2:
                continue
            ray = round((math.atan2(-dy, -dx) + np.pi) / (2 * np.pi) * RAYS) % RAYS
            seen[p, k] = dist <= free[k, ray]


class SightGrid(NamedTuple):
    """The occupancy grid as compiled line-of-sight code reads it."""

    occupied: np.ndarray  # (rows, cols) bool
    clearance: np.ndarray  # (rows, cols) m, distance to the nearest occupied cell
    x0: float  # m, the grid's origin
    y0: float
    resolution: float  # m per cell

    @staticmethod
    def of(world: World) -> SightGrid:
        grid = world.grid
        return SightGrid(grid.occupied, world.clearance, grid.origin[0], grid.origin[1], grid.resolution)


class MutualSensing(NamedTuple):
    """How two robots observe each other: within ``range`` and ``fov`` of the mutual sensor
    and in line of sight, but not closer than ``min_range``, the sum of their radii (they
    would touch, and the range-bearing model is singular where they coincide)."""

    range: float  # m
    fov: float  # rad, centred on the observer's heading
    min_range: float  # m

    @staticmethod
    def between(scenario: Scenario, robot_a: str, robot_b: str) -> MutualSensing | None:
        """The sensing between two robots of a scenario; None when their beliefs take in no
        mutual observations (switched off, or AMCL fusing its lidar alone: Models.partners_fused),
        so that what they would see of each other changes nothing."""
        if not scenario.models.partners_fused:
            return None
        return MutualSensing.of_sensor(scenario, robot_a, robot_b)

    @staticmethod
    def of_sensor(scenario: Scenario, robot_a: str, robot_b: str) -> MutualSensing:
        """The scenario's mutual sensor between two of its robots, whether or not its models
        switch mutual observations on (``tmpnav simulate`` runs with them on and off)."""
        sensor = scenario.models.mutual_sensor
        radii = scenario.robot(robot_a).radius + scenario.robot(robot_b).radius
        return MutualSensing(sensor.range, sensor.fov, radii)

    def visible(self, world: World, observer: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Whether robots at poses ``observer`` (k, 3) see robots at ``target`` (k, 3)."""
        return mutual_visible(world, observer, target, self.range, self.fov, self.min_range)

    def sequences(
        self,
        world: World,
        motions: tuple[np.ndarray, np.ndarray, np.ndarray],
        pairs: np.ndarray,
        restart: np.ndarray,
        horizon: np.ndarray,
        row_offset: np.ndarray,
        out: np.ndarray,
    ) -> np.ndarray:
        """Who sees whom at every step of two-robot simulations in trie order; see
        :func:`mutual_visibility_sequences`. ``motions`` is (offset, steps, poses) of the
        motions laid end to end. Returns each simulation's first step with a mutual
        observation (-1: none)."""
        offset, steps, poses = motions
        return mutual_visibility_sequences(
            SightGrid.of(world), self, offset, steps, poses, pairs, restart, horizon, row_offset, out
        )


def mutual_visible(
    world: World, observer: np.ndarray, target: np.ndarray, sensor_range: float, fov: float, min_range: float = 0.0
) -> np.ndarray:
    """Whether robot poses ``observer`` (k, 3) see robot poses ``target`` (k, 3).

    Range between ``min_range`` and ``sensor_range``, field of view, and a sphere-traced
    line of sight (the same compiled code the oracle uses for whole sequences).
    """
    return _visible_pairs(
        SightGrid.of(world),
        MutualSensing(sensor_range, fov, min_range),
        np.ascontiguousarray(observer, dtype=float),
        np.ascontiguousarray(target, dtype=float),
    )


@nb.njit(cache=True)
def _traced_los(grid, ax, ay, bx, by):
    """Sphere-traced line of sight between two points (see grid.line_of_sight_traced)."""
    occupied, clear, x0, y0, res = grid
    rows, cols = occupied.shape
    dx, dy = bx - ax, by - ay
    length = math.hypot(dx, dy)
    if length <= 0.0:
        return True
    ux, uy = dx / length, dy / length
    margin = 1.5 * res
    t = margin
    while t < length - margin:
        px, py = ax + t * ux, ay + t * uy
        j = math.floor((px - x0) / res)
        i = math.floor((py - y0) / res)
        if i < 0 or i >= rows or j < 0 or j >= cols or occupied[i, j]:
            return False
        step = clear[i, j] - 1.5 * res
        t += step if step > 0.5 * res else 0.5 * res
    return True


@nb.njit(cache=True)
def _sees(px, py, pth, qx, qy, sensing):
    """Is (qx, qy) within range and field of view of a sensor at pose (px, py, pth)?"""
    d = math.hypot(qx - px, qy - py)
    if d > sensing.range or d < sensing.min_range:
        return False
    if sensing.fov < 2.0 * math.pi - 1e-9:
        b = wrap_angle_scalar(math.atan2(qy - py, qx - px) - pth)
        if abs(b) > sensing.fov / 2.0:
            return False
    return True


@nb.njit(cache=True)
def mutual_visibility_sequences(grid, sensing, m_off, m_T, pose, c_motion, c_start, c_horizon, c_off, out):
    """Who sees whom at every step of C two-robot simulations in trie order.

    Motion m has ``m_T[m]`` steps and its poses are rows ``m_off[m] + m`` to
    ``m_off[m] + m + m_T[m]`` of ``pose`` (the layout of
    :class:`tmpnav.belief.sequences.MotionArrays`); a robot that arrived waits at its last
    pose. Simulation c moves the two robots along motions ``c_motion[c]`` to step
    ``c_horizon[c]``; its steps 0..c_start[c] are copied from the previous simulation,
    which shares them; the others are computed: range, field of view and a sphere-traced
    line of sight (:class:`MutualSensing`, :class:`SightGrid`).
    ``out[c_off[c] + t, i, j]``: robot i sees robot j at step t. Returns, per simulation,
    the first step with a mutual observation (-1 if there is none).
    """
    C = c_motion.shape[0]
    first_seen = np.full(C, -1, dtype=np.int64)
    for c in range(C):
        first = 0
        if c > 0:
            first = c_start[c] + 1
            for t in range(min(c_start[c], c_horizon[c]) + 1):
                for i in range(2):
                    for j in range(2):
                        out[c_off[c] + t, i, j] = out[c_off[c - 1] + t, i, j]
                        if out[c_off[c] + t, i, j] and first_seen[c] < 0:
                            first_seen[c] = t
        ma, mb = c_motion[c, 0], c_motion[c, 1]
        for t in range(first, c_horizon[c] + 1):
            ra = m_off[ma] + ma + (t if t <= m_T[ma] else m_T[ma])
            rb = m_off[mb] + mb + (t if t <= m_T[mb] else m_T[mb])
            ax, ay, ath = pose[ra, 0], pose[ra, 1], pose[ra, 2]
            bx, by, bth = pose[rb, 0], pose[rb, 1], pose[rb, 2]
            ab = _sees(ax, ay, ath, bx, by, sensing)
            ba = _sees(bx, by, bth, ax, ay, sensing)
            if (ab or ba) and not _traced_los(grid, ax, ay, bx, by):
                ab = False
                ba = False
            out[c_off[c] + t, 0, 1] = ab
            out[c_off[c] + t, 1, 0] = ba
            if (ab or ba) and first_seen[c] < 0:
                first_seen[c] = t
    return first_seen


@nb.njit(cache=True)
def _visible_pairs(grid, sensing, A, B):
    out = np.zeros(A.shape[0], dtype=np.bool_)
    for k in range(A.shape[0]):
        if _sees(A[k, 0], A[k, 1], A[k, 2], B[k, 0], B[k, 1], sensing):
            out[k] = _traced_los(grid, A[k, 0], A[k, 1], B[k, 0], B[k, 1])
    return out
