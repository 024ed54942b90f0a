"""The test paths of the collision bound, built in code, and trajectories sampled along them.

Four small maps on a 5 cm grid with the paper's models (dt 0.5 s, 0.5 m/s, radius 0.25 m, motion
noise alpha = (0.01, 0, 0.02, 0.01), landmarks seen within 5 m with 0.1 m and 3 degrees of noise,
partners within 4 m): *straight* along a corridor 1.4 m wide, *corner* through an L-shaped
corridor 1.4 m wide, *door* along a corridor, through a 0.9 m door into a room, and *passing*:
two robots driving past each other in a corridor 2 m wide, their paths ``offset`` apart. A
case's ``noise`` scales the motion noise and the start covariance (diag(0.01, 0.01, 0.003)
m², rad²) together, so that the rates are measurable. Three more (:data:`OPEN_LOOP`) drive
without observations at dt 0.1 s, where the steps are most strongly correlated.

:func:`drive` runs the EKF along the nominal path (maximum-likelihood observations: the mean
stays on it) and keeps, for every step, the transition of the filter's error
e_t = A_t e_{t-1} + nu_t (A_t = (I - K H) F over the step's prediction and updates, nu_t of
covariance N_t independent of the past), so that :func:`sample` draws trajectories whose
errors have exactly the filter's covariances Sigma_t and cross-covariances
Cov(e_t, e_{t-1}) = A_t Sigma_{t-1}: the assumption of the bound (docs/models.md,
"Collision bound"). :func:`sample_unicycle` drives the nonlinear motion model with noisy
controls instead (open loop: for cases without observations, where the filter's covariance
is the linearisation of exactly that).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tmpnav.belief import pair_risk, risk
from tmpnav.belief.controls import pad, path_controls
from tmpnav.belief.models import (
    landmark_obs_jacobian,
    motion,
    motion_jacobians,
    motion_noise_cov,
    mutual_obs_jacobian,
    process_noise,
)
from tmpnav.belief.sequences import EKFConstants, MotionArrays, SequenceBatch, Sequences, StartGroups
from tmpnav.types import Models, ObservationMode, RangeBearingSensor
from tmpnav.world.grid import OccupancyGrid, clearance
from tmpnav.world.reach import SectorReach

RES = 0.05  # m per cell
RADIUS = 0.25  # m
DT = 0.5  # s
SPEED = 0.5  # m/s
TURN_RATE = 1.0  # rad/s
ALPHAS = (0.01, 0.0, 0.02, 0.01)  # the paper's, scaled by a case's noise
START_COV = np.diag([0.01, 0.01, 0.003])  # likewise
LANDMARK_RANGE = 5.0  # m
Q_LANDMARK = np.diag([0.1**2, math.radians(3.0) ** 2])
MUTUAL_RANGE = 4.0  # m
Q_MUTUAL = np.diag([0.1**2, math.radians(3.0) ** 2])


def grid_of(width: float, height: float, free: list[tuple[float, float, float, float]]) -> OccupancyGrid:
    """A grid occupied everywhere but the cells whose centres lie in the rectangles ``free``
    (x0, y0, x1, y1), m."""
    rows, cols = round(height / RES), round(width / RES)
    gx, gy = np.meshgrid((np.arange(cols) + 0.5) * RES, (np.arange(rows) + 0.5) * RES)
    occupied = np.ones((rows, cols), dtype=bool)
    for x0, y0, x1, y1 in free:
        occupied[(gx > x0) & (gx < x1) & (gy > y0) & (gy < y1)] = False
    return OccupancyGrid(occupied, (0.0, 0.0), RES)


@dataclass(frozen=True)
class Path:
    """A test path: its map, each robot's waypoints and start heading, the landmarks; the
    robots' radius (m), the time step (s) and the motion noise at noise 1."""

    grid: OccupancyGrid
    waypoints: tuple[tuple[tuple[float, float], ...], ...]
    headings: tuple[float, ...]
    landmarks: tuple[tuple[float, float], ...]
    radius: float = RADIUS
    dt: float = DT
    alphas: tuple[float, float, float, float] = ALPHAS


def path(name: str, offset: float = 0.6) -> Path:
    """The test path ``name`` (module docstring); ``offset``: the passing robots' lanes apart (m)."""
    if name == "straight":
        grid = grid_of(10.0, 1.6, [(0.1, 0.1, 9.9, 1.5)])
        return Path(grid, (((1.0, 0.8), (9.0, 0.8)),), (0.0,), ((0.5, 0.8), (9.5, 0.8)))
    if name == "corner":
        grid = grid_of(6.0, 7.0, [(0.1, 0.1, 5.5, 1.5), (4.1, 0.1, 5.5, 6.9)])
        return Path(grid, (((0.8, 0.8), (4.8, 0.8), (4.8, 6.0)),), (0.0,), ((0.5, 0.8), (4.8, 6.5)))
    if name == "door":
        grid = grid_of(10.0, 6.1, [(0.1, 0.1, 9.9, 1.9), (0.1, 2.05, 9.9, 6.0), (4.55, 1.8, 5.45, 2.2)])
        return Path(grid, (((1.0, 1.0), (5.0, 1.0), (5.0, 4.5)),), (0.0,), ((0.5, 1.0), (9.0, 5.0)))
    if name == "passing":
        grid = grid_of(10.0, 2.2, [(0.1, 0.1, 9.9, 2.1)])
        low, high = 1.1 - offset / 2, 1.1 + offset / 2
        lanes = (((1.0, low), (9.0, low)), ((9.0, high), (1.0, high)))
        return Path(grid, lanes, (0.0, math.pi), ((0.5, 1.1), (9.5, 1.1)))
    if name in OPEN_LOOP:
        return Path(*OPEN_LOOP[name], (0.0,), (), 0.2, 0.1, (0.02, 0.0, 0.02, 0.01))
    raise ValueError(f"no test path {name!r}")


_OPEN_STRAIGHT = grid_of(6.0, 1.6, [(0.1, 0.1, 5.9, 1.5)])  # a corridor 1.4 m wide
_OPEN_CORNER = grid_of(3.6, 4.0, [(0.1, 0.1, 3.3, 1.3), (2.1, 0.1, 3.3, 3.9)])  # east, then north
#: paths driven without observations at dt 0.1 s by a robot of radius 0.2 m: along a wall, into
#: the corner of two outer walls (turning there), around an inner corner
OPEN_LOOP = {
    "open-straight": (_OPEN_STRAIGHT, (((0.5, 0.5), (5.5, 0.5)),)),
    "open-corner": (_OPEN_CORNER, (((0.5, 0.5), (2.9, 0.5), (2.9, 3.5)),)),
    "open-inner": (_OPEN_CORNER, (((0.5, 0.85), (2.5, 0.85), (2.5, 3.5)),)),
}


@dataclass(frozen=True, eq=False)
class Drive:
    """The EKF along a path's nominal poses, and the transitions of its error.

    ``poses`` (n, T+1, 3) and ``controls`` (n, T, 2) per robot (a robot that arrives first
    waits, u = 0); ``steps`` (n,): each robot's driving steps; ``covs`` (T+1, 3n, 3n): the
    joint covariance after each step; ``A``, ``N`` (T+1, 3n, 3n): e_t = A_t e_{t-1} + nu_t,
    Cov(nu_t) = N_t (row 0: identity and zero); ``alphas``: the motion noise used.
    """

    path: Path
    grid: OccupancyGrid
    poses: np.ndarray
    controls: np.ndarray
    steps: np.ndarray
    covs: np.ndarray
    A: np.ndarray
    N: np.ndarray
    alphas: tuple[float, float, float, float]
    landmarks: np.ndarray

    def cross(self, i: int = 0) -> np.ndarray:
        """(T+1, 2, 2) Cov(e_t, e_{t-1}) of robot i's position (row 0: Sigma_0's block)."""
        C = self.A @ np.concatenate([self.covs[:1], self.covs[:-1]])
        return C[:, 3 * i : 3 * i + 2, 3 * i : 3 * i + 2]

    def relative(self, i: int = 0, j: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Covariance (T+1, 2, 2) of the relative position error e_i - e_j, and its
        cross-covariance Cov(e_t, e_{t-1}) (T+1, 2, 2)."""
        M = np.zeros((2, self.covs.shape[1]))
        M[:, 3 * i : 3 * i + 2], M[:, 3 * j : 3 * j + 2] = np.eye(2), -np.eye(2)
        C = self.A @ np.concatenate([self.covs[:1], self.covs[:-1]])
        return M @ self.covs @ M.T, M @ C @ M.T


def drive(p: Path, noise: float, scan: np.ndarray | None = None) -> Drive:
    """The filter along ``p`` with the motion noise and start covariance scaled by ``noise``;
    ``scan``: a range scan's information factor G (3, 3), the same at every step (the update
    z = G x with unit noise, as the kernel's pseudo-measurements), or none."""
    legs = [path_controls(np.array(w), h, SPEED, TURN_RATE, p.dt) for w, h in zip(p.waypoints, p.headings, strict=True)]
    T = max(leg.n_steps for leg in legs)
    padded = [pad(leg.controls, leg.poses, T) for leg in legs]
    controls, poses = np.array([c for c, _ in padded]), np.array([q for _, q in padded])
    alphas = (noise * p.alphas[0], noise * p.alphas[1], noise * p.alphas[2], noise * p.alphas[3])
    n, D = len(legs), 3 * len(legs)
    landmarks = np.array(p.landmarks, dtype=float).reshape(-1, 2)
    P = np.kron(np.eye(n), noise * START_COV)
    covs, As, Ns = [P], [np.eye(D)], [np.zeros((D, D))]
    for k in range(T):
        F, R = np.eye(D), np.zeros((D, D))
        for i in range(n):
            block = slice(3 * i, 3 * i + 3)
            F[block, block] = motion_jacobians(poses[i, k], controls[i, k], p.dt)[0]
            R[block, block] = process_noise(poses[i, k], controls[i, k], p.dt, alphas)
        P, A, N = F @ P @ F.T + R, F, R
        for H, Q in _observations(poses[:, k + 1], landmarks, scan):
            K = P @ H.T @ np.linalg.inv(H @ P @ H.T + Q)
            J = np.eye(D) - K @ H  # Joseph form, as the filter
            P = J @ P @ J.T + K @ Q @ K.T
            P, A, N = 0.5 * (P + P.T), J @ A, J @ N @ J.T + K @ Q @ K.T
        covs.append(P)
        As.append(A)
        Ns.append(N)
    steps = np.array([leg.n_steps for leg in legs])
    return Drive(p, p.grid, poses, controls, steps, np.array(covs), np.array(As), np.array(Ns), alphas, landmarks)


def _observations(
    poses: np.ndarray, landmarks: np.ndarray, scan: np.ndarray | None
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The updates at the nominal poses (n, 3), in the filter's order: each robot's landmarks in
    range, each robot's scan, then each ordered pair of robots in range (H (m, 3n), Q)."""
    n = poses.shape[0]
    out = []
    for i in range(n):
        for lm in landmarks:
            if math.hypot(*(lm - poses[i, :2])) <= LANDMARK_RANGE:
                H = np.zeros((2, 3 * n))
                H[:, 3 * i : 3 * i + 3] = landmark_obs_jacobian(poses[i], lm)
                out.append((H, Q_LANDMARK))
    for i in range(n if scan is not None else 0):
        H = np.zeros((3, 3 * n))
        H[:, 3 * i : 3 * i + 3] = scan
        out.append((H, np.eye(3)))
    for i in range(n):
        for j in range(n):
            if i != j and math.hypot(*(poses[i, :2] - poses[j, :2])) <= MUTUAL_RANGE:
                Hij = mutual_obs_jacobian(poses[i], poses[j])
                H = np.zeros((2, 3 * n))
                H[:, 3 * i : 3 * i + 3], H[:, 3 * j : 3 * j + 3] = Hij[:, :3], Hij[:, 3:]
                out.append((H, Q_MUTUAL))
    return out


def _factor(cov: np.ndarray) -> np.ndarray:
    """L with L Lᵀ = cov for a symmetric PSD matrix (singular ones too)."""
    w, V = np.linalg.eigh(0.5 * (cov + cov.T))
    return V * np.sqrt(np.maximum(w, 0.0))


def sample(d: Drive, rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, robots, T, 2) true positions after steps 1..T: the nominal plus an error drawn as
    e_0 ~ N(0, Sigma_0), e_t = A_t e_{t-1} + nu_t."""
    T, D = d.covs.shape[0] - 1, d.covs.shape[1]
    e = rng.standard_normal((n, D)) @ _factor(d.covs[0]).T
    out = np.empty((n, D // 3, T, 2))
    for t in range(1, T + 1):
        e = e @ d.A[t].T + rng.standard_normal((n, D)) @ _factor(d.N[t]).T
        for i in range(D // 3):
            out[:, i, t - 1] = d.poses[i, t, :2] + e[:, 3 * i : 3 * i + 2]
    return out


def sample_unicycle(d: Drive, rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, robots, T, 2) true positions of the motion model driven open loop by the nominal
    controls plus their noise W(u) (no observations: the start drawn from Sigma_0)."""
    T, robots = d.controls.shape[1], d.poses.shape[0]
    out = np.empty((n, robots, T, 2))
    for i in range(robots):
        block = slice(3 * i, 3 * i + 3)
        x = d.poses[i, 0] + rng.standard_normal((n, 3)) @ _factor(d.covs[0][block, block]).T
        for t in range(T):
            u = d.controls[i, t]
            noisy = u + rng.standard_normal((n, 2)) * np.sqrt(np.diag(motion_noise_cov(u, d.alphas)))
            x = motion(x, noisy, d.path.dt)
            out[:, i, t] = x[:, :2]
    return out


def models(p: Path, noise: float, max_likelihood: bool = True) -> Models:
    """The scenario models of the test path ``p`` at ``noise``."""
    alphas = (noise * p.alphas[0], noise * p.alphas[1], noise * p.alphas[2], noise * p.alphas[3])
    lm = RangeBearingSensor(LANDMARK_RANGE, 2 * math.pi, 0.1, math.radians(3.0))
    mu = RangeBearingSensor(MUTUAL_RANGE, 2 * math.pi, 0.1, math.radians(3.0))
    mode = ObservationMode.MAX_LIKELIHOOD if max_likelihood else ObservationMode.NOISY
    return Models(p.dt, alphas, lm, mu, True, mode, seed=0)


def kernel_batch(
    d: Drive, noise: float, copies: int = 1, bound: bool = True, scan: np.ndarray | None = None
) -> SequenceBatch:
    """The drive as the oracle's kernel runs it (``copies`` simulations from scratch), each
    robot's nominal poses with their sector reach (``bound``) or none; ``scan`` as :func:`drive`."""
    n, T = d.poses.shape[0], d.controls.shape[1]
    steps = [int(s) for s in d.steps]
    seen = np.hypot(*(d.poses[:, :, None, :2] - d.landmarks[None, None]).transpose(3, 0, 1, 2)) <= LANDMARK_RANGE
    reach = None
    if bound:
        table = SectorReach(d.grid, clearance(d.grid), d.path.radius)
        reach = [table.at(d.poses[i, : steps[i] + 1, :2]) for i in range(n)]
    motions = MotionArrays.of(
        [d.controls[i, : steps[i]] for i in range(n)],
        [d.poses[i, : steps[i] + 1] for i in range(n)],
        [seen[i, : steps[i] + 1] for i in range(n)],
        np.arange(n),
        d.landmarks.shape[0],
        reach,
        None
        if scan is None
        else (np.ones(int((d.steps + 1).sum()), dtype=np.int64), np.stack([np.zeros((3, 3)), scan])),
    )
    gap = np.hypot(*(d.poses[:, None, :, :2] - d.poses[None, :, :, :2]).transpose(3, 0, 1, 2))
    visible = ((gap <= MUTUAL_RANGE) & ~np.eye(n, dtype=bool)[:, :, None]).transpose(2, 0, 1)
    ekf = EKFConstants.of(models(d.path, noise), d.landmarks)
    return SequenceBatch(
        n=n,
        ekf=ekf if scan is None else ekf._replace(scans=True),
        motions=motions,
        landmark_noise=np.zeros((n, T + 1, d.landmarks.shape[0], 2)),
        groups=StartGroups(d.poses[:, 0].reshape(1, -1), d.covs[:1].copy(), np.zeros((1, T + 1, n, n, 2))),
        sequences=Sequences(
            group=np.zeros(copies, dtype=np.int64),
            motions=np.tile(np.arange(n, dtype=np.int64), (copies, 1)),
            restart=np.zeros(copies, dtype=np.int64),
            horizon=np.full(copies, T, dtype=np.int64),
            mutual_offset=np.zeros(copies, dtype=np.int64),
        ),
        mutual_visible=np.ascontiguousarray(visible),
        scan_noise=np.zeros((n, T + 1, 3)),
    )


@dataclass(frozen=True)
class Measured:
    """A bound of a drive against trajectories sampled along it: ``what`` ("wall r0", "contact"),
    the bound (first passage), the bound before it (the union of the per-step bounds over the
    steps, Boole's inequality, with reach measured from whole cells; for a contact, of the
    per-instant rule :func:`tmpnav.belief.pair_risk.pair_bound`), and how many of the ``n`` sampled
    trajectories hit a wall (touch)."""

    what: str
    bound: float
    before: float
    hits: int
    n: int

    @property
    def rate(self) -> float:
        return self.hits / self.n


def measure(d: Drive, n: int, how: str = "walk", seed: int = 0) -> list[Measured]:
    """Each robot's wall bound, and with two robots their contact bound, against ``n``
    trajectories drawn by :func:`sample` (``how`` "walk") or :func:`sample_unicycle` ("unicycle")."""
    rng = np.random.default_rng(seed)
    xs = sample(d, rng, n) if how == "walk" else sample_unicycle(d, rng, n)
    clear, r = clearance(d.grid), d.path.radius
    cells = SectorReach(d.grid, clear, r, subdivisions=1)
    out = []
    for i in range(d.poses.shape[0]):
        T, b = int(d.steps[i]), slice(3 * i, 3 * i + 2)
        bound = risk.move_bound(d.poses[i, : T + 1], d.covs[: T + 1, b, b], d.cross(i)[: T + 1], d.grid, r)
        union = float(risk.step_bound(d.covs[1 : T + 1, b, b], cells.at(d.poses[i, 1 : T + 1, :2])).sum())
        hits = int(risk.hits_wall(d.grid, clear, xs[:, i, :T], r).any(axis=1).sum())
        out.append(Measured(f"wall r{i}", bound, min(union, 1.0), hits, n))
    if d.poses.shape[0] == 2:
        rel, cross = d.relative()
        bound = pair_risk.passing_bound(d.poses[0, :, :2], d.poses[1, :, :2], rel, cross, r, r)
        union = float(
            pair_risk.pair_bound(d.poses[0, 1:], d.poses[1, 1:], d.covs[1:, :3, :3], d.covs[1:, 3:, 3:], r, r).sum()
        )
        hits = int((np.hypot(*(xs[:, 0] - xs[:, 1]).transpose(2, 0, 1)) < 2 * r).any(axis=1).sum())
        out.append(Measured("contact", bound, min(union, 1.0), hits, n))
    return out
