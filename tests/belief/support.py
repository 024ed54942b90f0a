"""Random multi-robot simulations for the belief tests, built in code."""

from __future__ import annotations

import numpy as np

from tmpnav.belief.models import motion, wrap_angle
from tmpnav.belief.rollout import ObservationNoise, Rollout
from tmpnav.types import Belief, Models, ObservationMode, RangeBearingSensor

DT = 0.2
ALPHAS = (0.05, 0.01, 0.02, 0.05)
LM_SENSOR = RangeBearingSensor(range=8.0, fov=2 * np.pi, sigma_range=0.1, sigma_bearing=0.05)
MUTUAL_SENSOR = RangeBearingSensor(range=4.0, fov=2 * np.pi, sigma_range=0.15, sigma_bearing=0.08)


def models(
    max_likelihood: bool = False, mutual: bool = True, dt: float = DT, seed: int = 0, controller: str = "auto"
) -> Models:
    """Test models; ``controller="rpp"``: steps that turn while they drive (the midpoint step)."""
    mode = ObservationMode.MAX_LIKELIHOOD if max_likelihood else ObservationMode.NOISY
    return Models(dt, ALPHAS, LM_SENSOR, MUTUAL_SENSOR, mutual, mode, seed=seed, controller=controller)


def random_case(
    rng: np.random.Generator, n: int, T: int, L: int, p_see: float = 0.4
) -> tuple[Belief, Rollout, np.ndarray, ObservationNoise]:
    """n robots 4 m apart near y = 0 driving at most 1.6 m for T_i <= T steps, then waiting;
    L landmarks at 4 <= y <= 8 seen at random; a correlated initial belief."""
    start = np.zeros((n, 3))
    start[:, 0] = 4.0 * np.arange(n) + rng.uniform(-0.5, 0.5, n)
    start[:, 1] = rng.uniform(-0.5, 0.5, n)
    start[:, 2] = rng.uniform(-np.pi, np.pi, n)
    controls = np.stack([rng.uniform(0.0, 1.0, (n, T)), rng.uniform(-1.0, 1.0, (n, T))], -1)
    steps = rng.integers(0, T + 1, n)
    controls[np.arange(T)[None, :] >= steps[:, None]] = 0.0  # waiting after arrival
    poses = [start]
    for k in range(T):
        poses.append(motion(poses[-1], controls[:, k], DT))
    true_poses = np.stack(poses, axis=1)
    lm_visible = rng.random((n, T + 1, L)) < p_see
    for i in range(n):  # a robot that arrived keeps seeing what it saw on arrival
        lm_visible[i, steps[i] + 1 :] = lm_visible[i, steps[i]]
    mutual = (rng.random((n, n, T + 1)) < p_see) & ~np.eye(n, dtype=bool)[:, :, None]
    A = rng.normal(0, 0.1, (3 * n, 3 * n))
    mean0 = start.reshape(-1) + rng.normal(0, 0.05, 3 * n)
    mean0[2::3] = wrap_angle(mean0[2::3])
    belief = Belief(mean0, A @ A.T + 1e-3 * np.eye(3 * n))
    landmarks = np.column_stack([rng.uniform(-2, 4 * n, L), rng.uniform(4, 8, L)])
    noise = ObservationNoise(rng.standard_normal((n, T + 1, L, 2)), rng.standard_normal((n, n, T + 1, 2)))
    return belief, Rollout(controls, true_poses, steps, lm_visible, mutual), landmarks, noise
