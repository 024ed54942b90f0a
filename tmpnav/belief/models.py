"""The EKF's model equations, one function per equation of the paper.

Equation numbers are those of the paper's source as compiled (Thomas, Mastrogiovanni,
Baglietto, "Towards Multi-Robot Task-Motion Planning for Navigation in Belief Space"):
(4) motion model, (5) observation model, (8) EKF prediction, (9) EKF update,
(11)-(12) joint prediction of two robots, (14) mutual range-bearing observation,
(15) its Jacobian. docs/models.md derives every Jacobian and lists the paper's labels.

Every function is vectorised: poses may carry leading batch dimensions, ``x`` of shape
(..., 3), controls (..., 2), landmark positions (..., 2), all broadcast against each other
with numpy rules. The filterpy reference (:mod:`tmpnav.belief.ekf`) and ``tmpnav simulate``
call these functions; the compiled kernel that runs in the oracle
(:mod:`tmpnav.belief.kernel`) writes the same equations out scalar by scalar and is held
to the reference by the tests. Angles are wrapped by :func:`tmpnav.world.geometry.wrap_angle`
(re-exported here). Units: metres, radians, seconds; u = (v, omega) in m/s and rad/s.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tmpnav.world.geometry import wrap_angle

__all__ = [
    "beam_jacobian",
    "beam_variance",
    "compressed_scan",
    "joint_block_diag",
    "landmark_obs",
    "landmark_obs_jacobian",
    "motion",
    "motion_jacobians",
    "motion_noise_cov",
    "mutual_obs",
    "mutual_obs_jacobian",
    "noisy_observation",
    "observation_residual",
    "process_noise",
    "scan_information",
    "wrap_angle",
]

# --------------------------------------------------------------------------- motion


def motion(x: np.ndarray, u: np.ndarray, dt: float, midpoint: bool = False) -> np.ndarray:
    """Unicycle motion model, paper eq. (4) with w = 0: one step of length dt.

    f(x, u) = [x + v dt cos(phi), y + v dt sin(phi), wrap(theta + omega dt)]

    with phi = theta (an Euler step, the paper's turn-then-drive) or, with ``midpoint``,
    phi = theta + omega dt / 2, the heading at the step's middle (a second-order step of the arc
    the command drives; RPP turns while it drives). Where a step either turns or drives
    (v omega = 0) the two are the same.

    x: (..., 3) pose (m, m, rad); u: (..., 2) control (v m/s, omega rad/s); dt: s.
    Returns the next pose, shape broadcast(x, u)[..., 3].
    """
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    theta, v, omega = x[..., 2], u[..., 0], u[..., 1]
    phi = theta + 0.5 * omega * dt if midpoint else theta
    out = np.empty((*np.broadcast_shapes(x.shape[:-1], u.shape[:-1]), 3))
    out[..., 0] = x[..., 0] + v * dt * np.cos(phi)
    out[..., 1] = x[..., 1] + v * dt * np.sin(phi)
    out[..., 2] = wrap_angle(theta + omega * dt)
    return out


def motion_jacobians(x: np.ndarray, u: np.ndarray, dt: float, midpoint: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Jacobians of :func:`motion` for the EKF prediction, paper eq. (8).

    F = df/dx = [[1, 0, -v dt sin(phi)],      V = df/du = [[dt cos(phi), -v dt² sin(phi) / 2],
                 [0, 1,  v dt cos(phi)],                   [dt sin(phi),  v dt² cos(phi) / 2],
                 [0, 0,  1            ]]                   [0,            dt                ]]

    with phi as in :func:`motion`; V's second column's first two entries are those of the
    ``midpoint`` step only (0 for the Euler step).

    x: (..., 3); u: (..., 2). Returns F (..., 3, 3) and V (..., 3, 2).
    """
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    shape = np.broadcast_shapes(x.shape[:-1], u.shape[:-1])
    v = u[..., 0]
    phi = x[..., 2] + 0.5 * u[..., 1] * dt if midpoint else x[..., 2]
    c, s = np.cos(phi), np.sin(phi)
    F = np.zeros((*shape, 3, 3))
    F[..., 0, 0] = F[..., 1, 1] = F[..., 2, 2] = 1.0
    F[..., 0, 2] = -v * dt * s
    F[..., 1, 2] = v * dt * c
    V = np.zeros((*shape, 3, 2))
    V[..., 0, 0] = dt * c
    V[..., 1, 0] = dt * s
    V[..., 2, 1] = dt
    if midpoint:
        V[..., 0, 1] = -0.5 * v * dt * dt * s
        V[..., 1, 1] = 0.5 * v * dt * dt * c
    return F, V


def motion_noise_cov(u: np.ndarray, alphas: Sequence[float]) -> np.ndarray:
    """Covariance W(u) of the noise on the control (Thrun et al., table 5.3), paper eq. (4).

    W = diag(a1 v² + a2 omega², a3 v² + a4 omega²)   in (m/s)², (rad/s)²

    A robot standing still (u = 0) gets no noise. The linearised process noise of the
    prediction, paper eq. (8), is R = V W Vᵀ. u: (..., 2); returns (..., 2, 2).
    """
    u = np.asarray(u, dtype=float)
    a1, a2, a3, a4 = alphas
    v2, w2 = u[..., 0] ** 2, u[..., 1] ** 2
    W = np.zeros((*u.shape[:-1], 2, 2))
    W[..., 0, 0] = a1 * v2 + a2 * w2
    W[..., 1, 1] = a3 * v2 + a4 * w2
    return W


def process_noise(
    x: np.ndarray, u: np.ndarray, dt: float, alphas: Sequence[float], midpoint: bool = False
) -> np.ndarray:
    """Linearised process noise R = V W Vᵀ of paper eq. (8), V that of :func:`motion`'s step
    (``midpoint`` or Euler). x: (..., 3); u: (..., 2).

    Returns (..., 3, 3) in m², m², rad² (per step).
    """
    _, V = motion_jacobians(x, u, dt, midpoint)
    W = motion_noise_cov(u, alphas)
    return V @ W @ np.swapaxes(V, -1, -2)


def joint_block_diag(blocks: np.ndarray) -> np.ndarray:
    """Block-diagonal joint matrix of n robots, the structure of paper eq. (12).

    blocks: (..., n, 3, 3), one per robot (F_i or R_i); returns (..., 3n, 3n).
    """
    blocks = np.asarray(blocks, dtype=float)
    n = blocks.shape[-3]
    out = np.zeros((*blocks.shape[:-3], 3 * n, 3 * n))
    for i in range(n):
        out[..., 3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = blocks[..., i, :, :]
    return out


# --------------------------------------------------------------------------- observations


def _range_bearing(dx: np.ndarray, dy: np.ndarray, theta: np.ndarray) -> np.ndarray:
    out = np.empty((*np.broadcast_shapes(dx.shape, theta.shape), 2))
    out[..., 0] = np.hypot(dx, dy)
    out[..., 1] = wrap_angle(np.arctan2(dy, dx) - theta)
    return out


def landmark_obs(x: np.ndarray, lm: np.ndarray) -> np.ndarray:
    """Range and bearing of a landmark seen from pose x, paper eq. (5) without noise.

    h(x) = [d, wrap(atan2(ly - y, lx - x) - theta)],   d = ||lm - x[:2]||

    x: (..., 3) pose; lm: (..., 2) landmark position (m). Returns (..., 2): m, rad.
    """
    x = np.asarray(x, dtype=float)
    lm = np.asarray(lm, dtype=float)
    return _range_bearing(lm[..., 0] - x[..., 0], lm[..., 1] - x[..., 1], x[..., 2])


def landmark_obs_jacobian(x: np.ndarray, lm: np.ndarray) -> np.ndarray:
    """H = dh/dx of :func:`landmark_obs`, used in the EKF update, paper eq. (9).

    With dx = lx - x, dy = ly - y, d² = dx² + dy²:

    H = [[-dx/d,  -dy/d,   0],
         [ dy/d², -dx/d², -1]]

    Singular at d = 0. x: (..., 3); lm: (..., 2); returns (..., 2, 3).
    """
    x = np.asarray(x, dtype=float)
    lm = np.asarray(lm, dtype=float)
    dx, dy = lm[..., 0] - x[..., 0], lm[..., 1] - x[..., 1]
    d2 = dx * dx + dy * dy
    d = np.sqrt(d2)
    H = np.zeros((*dx.shape, 2, 3))
    H[..., 0, 0] = -dx / d
    H[..., 0, 1] = -dy / d
    H[..., 1, 0] = dy / d2
    H[..., 1, 1] = -dx / d2
    H[..., 1, 2] = -1.0
    return H


def mutual_obs(x_r: np.ndarray, x_s: np.ndarray) -> np.ndarray:
    """Robot r measures range and bearing of robot s, paper eq. (14).

    zeta = [d, wrap(atan2(ys - yr, xs - xr) - theta_r)],   d = ||x_s[:2] - x_r[:2]||

    x_r, x_s: (..., 3) poses. Returns (..., 2): m, rad. Robot s's heading is not observed.
    """
    x_r = np.asarray(x_r, dtype=float)
    x_s = np.asarray(x_s, dtype=float)
    return _range_bearing(x_s[..., 0] - x_r[..., 0], x_s[..., 1] - x_r[..., 1], x_r[..., 2])


def mutual_obs_jacobian(x_r: np.ndarray, x_s: np.ndarray) -> np.ndarray:
    """H = d zeta / d[x_r, x_s] of :func:`mutual_obs`, paper eq. (15) corrected.

    With dx = xs - xr, dy = ys - yr, d² = dx² + dy²:

    H = [[-dx/d,  -dy/d,   0,  dx/d,   dy/d,  0],
         [ dy/d², -dx/d², -1, -dy/d²,  dx/d², 0]]

    The paper prints -dx/d² and dy/d² for the bearing row's x_s, y_s entries (dx and dy
    swapped); the entries above are the derivatives (docs/models.md).
    x_r, x_s: (..., 3); returns (..., 2, 6), columns ordered (x_r, y_r, th_r, x_s, y_s, th_s).
    """
    x_r = np.asarray(x_r, dtype=float)
    x_s = np.asarray(x_s, dtype=float)
    dx, dy = x_s[..., 0] - x_r[..., 0], x_s[..., 1] - x_r[..., 1]
    d2 = dx * dx + dy * dy
    d = np.sqrt(d2)
    H = np.zeros((*dx.shape, 2, 6))
    H[..., 0, 0] = -dx / d
    H[..., 0, 1] = -dy / d
    H[..., 0, 3] = dx / d
    H[..., 0, 4] = dy / d
    H[..., 1, 0] = dy / d2
    H[..., 1, 1] = -dx / d2
    H[..., 1, 2] = -1.0
    H[..., 1, 3] = -dy / d2
    H[..., 1, 4] = dx / d2
    return H


def noisy_observation(z_nominal: np.ndarray, chol_Q: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """A simulated range-bearing measurement z = h(x) + v, v ~ N(0, Q), paper eq. (5).

    v = chol(Q) @ noise, with ``noise`` standard-normal draws (..., 2); the bearing is
    wrapped. z_nominal: (..., 2) noise-free observation h(x); chol_Q: (2, 2) lower
    Cholesky factor of Q (``np.linalg.cholesky(Q)``, Q in m², rad²).
    """
    z = np.asarray(z_nominal, dtype=float) + np.asarray(noise, dtype=float) @ np.asarray(chol_Q).T
    z[..., 1] = wrap_angle(z[..., 1])
    return z


def observation_residual(z: np.ndarray, z_pred: np.ndarray) -> np.ndarray:
    """Innovation z - h(mean) of a range-bearing observation, bearing wrapped. (..., 2)."""
    y = np.asarray(z, dtype=float) - np.asarray(z_pred, dtype=float)
    y[..., 1] = wrap_angle(y[..., 1])
    return y


# --------------------------------------------------------------------------- range sensor


def beam_jacobian(r: np.ndarray, gradient: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Jacobian H_i = d r_i / d(x, y, theta) of range beams (docs/models.md, "Range sensor").

    A beam from the robot's position p in direction psi = theta + phi_i meets the wall where
    the signed distance field vanishes, phi(p + r d) = 0, d = (cos psi, sin psi). The
    implicit-function theorem gives, with g the field's gradient at the hit point and
    d' = (-sin psi, cos psi):

        H_i = [-g_x / (g.d),  -g_y / (g.d),  -r (g.d') / (g.d)]

    which is Censi's -[v(alpha); r sin(beta)] / cos(beta), alpha the normal into the wall
    and beta the incidence (the angle between the beam and that normal).

    r: (...,) m; gradient: (..., 2) (any length: only its direction matters); psi: (...,) rad.
    Returns (..., 3).
    """
    g = np.asarray(gradient, dtype=float)
    c, s = np.cos(psi), np.sin(psi)
    gd = g[..., 0] * c + g[..., 1] * s
    gdp = -g[..., 0] * s + g[..., 1] * c
    return np.stack([-g[..., 0] / gd, -g[..., 1] / gd, -np.asarray(r) * gdp / gd], axis=-1)


def beam_variance(sigma: float, divergence: float, r: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """A beam's range variance sigma² + (r divergence tan beta)² (m²): the sensor's range noise
    ``sigma`` (m), and the spread of a spot that widens by ``divergence`` (rad) per metre of
    range, met by a surface at incidence beta (rad) and so stretched along it by 1/cos beta
    (a beam along a wall returns anything from its whole spot). r, beta: (...,)."""
    return sigma**2 + (np.asarray(r) * divergence * np.tan(beta)) ** 2


def scan_information(H: np.ndarray, sigma: np.ndarray | float) -> np.ndarray:
    """The information J = sum_i H_iᵀ H_i / sigma_i² (3, 3) of a scan's beams H (B, 3) of noise
    ``sigma`` m (one for all, or one per beam (B,)), the beams taken as independent (Censi's
    Fisher information of one scan)."""
    H = np.asarray(H, dtype=float).reshape(-1, 3)
    w = np.broadcast_to(1.0 / np.square(np.asarray(sigma, dtype=float)), H.shape[:1])
    return (H * w[:, None]).T @ H


def compressed_scan(H: np.ndarray, y: np.ndarray, sigma: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """A scan's update as a 3-D pseudo-measurement: (G (3, 3), y_G (3,)) with
    Gᵀ G = sum_i H_iᵀ H_i / sigma_i² and Gᵀ y_G = sum_i H_iᵀ y_i / sigma_i².

    The EKF's posterior with the B beams (Jacobians H (B, 3), innovations y (B,), independent
    noise of standard deviation ``sigma``, one for all or one per beam) depends on them only
    through these two products (its information form), so the update with z = G x of unit
    noise and innovation y_G is the same update in three dimensions instead of B. G's rows are
    sqrt(lambda_k) e_kᵀ over the eigenpairs of J; a direction the scan does not see has
    lambda = 0, a zero row and a zero innovation.
    """
    H = np.asarray(H, dtype=float).reshape(-1, 3)
    J = scan_information(H, sigma)
    w = np.broadcast_to(1.0 / np.square(np.asarray(sigma, dtype=float)), H.shape[:1])
    b = H.T @ (np.asarray(y, dtype=float).reshape(-1) * w)
    lam, vec = np.linalg.eigh(J)
    seen = lam > 1e-12 * max(float(lam[-1]), 0.0)
    root = np.where(seen, np.sqrt(np.where(seen, lam, 1.0)), 0.0)
    G = root[:, None] * vec.T
    y_G = np.where(seen, (vec.T @ b) / np.where(seen, root, 1.0), 0.0)
    return G, y_G
