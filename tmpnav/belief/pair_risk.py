"""The collision bound for two robots: how likely they touch, from their joint belief.

The bound of :mod:`tmpnav.belief.risk` applied to the relative position error e_i - e_j of two
robots against the disc of radius r_i + r_j around the gap between their planned means
(docs/models.md, "Two robots"):

* :func:`contact_bound`: at one instant, from the covariance of the relative error (the joint
  belief's Sigma_ii + Sigma_jj - Sigma_ij - Sigma_ji);
* :func:`passing_bound`: over the steps of a passing, first passage as in
  :func:`tmpnav.belief.risk.move_bound`;
* :func:`pair_bound` and :func:`separation`: the per-instant rule from each robot's own
  covariance alone, whatever their cross-covariance.
"""

from __future__ import annotations

import math

import numpy as np

from tmpnav.belief.risk import WIDTH, first_passage, k_of, position_std, step_bound
from tmpnav.world.reach import REACH, SECTORS


def disc_reach(offset: np.ndarray, radius: float) -> np.ndarray:
    """The sector reach (..., K) of a disc of ``radius`` centred at ``offset`` (..., 2) from the
    origin: the least distance from the origin to the disc within each sector (capped at
    :data:`tmpnav.world.reach.REACH`; 0 everywhere when the origin is inside)."""
    off = np.asarray(offset, dtype=float)[..., None, :]
    D = np.hypot(off[..., 0], off[..., 1])
    psi = np.arctan2(off[..., 1], off[..., 0])
    lo = np.mod(WIDTH * np.arange(SECTORS) - psi + math.pi, 2.0 * math.pi) - math.pi  # each sector's start, from psi
    hi = lo + WIDTH
    holds = (lo <= 0.0) & (hi >= 0.0)
    angle = np.where(holds, 0.0, np.minimum(np.abs(lo), np.abs(hi)))
    with np.errstate(invalid="ignore", divide="ignore"):
        side = D * np.sin(angle)
        near = D * np.cos(angle) - np.sqrt(np.maximum(radius * radius - side * side, 0.0))
        meets = (side < radius) & (np.cos(angle) > 0.0)
    out = np.where(meets, np.minimum(near, REACH), REACH)
    return np.where(radius >= D, 0.0, out)


def contact_bound(mu_i: np.ndarray, mu_j: np.ndarray, cov_rel: np.ndarray, r_i: float, r_j: float) -> np.ndarray:
    """Upper bound on P(robots i and j touch) at one instant, ||x_i - x_j|| < r_i + r_j, from the
    covariance ``cov_rel`` (..., 2, 2) of the relative position error e_i - e_j (the joint
    belief's Sigma_ii + Sigma_jj - Sigma_ij - Sigma_ji): :func:`step_bound` of that error against
    the disc of radius r_i + r_j around mu_j - mu_i (:func:`disc_reach`). mu: (..., 2) m."""
    gap = np.asarray(mu_j, dtype=float)[..., :2] - np.asarray(mu_i, dtype=float)[..., :2]
    return step_bound(cov_rel, disc_reach(gap, r_i + r_j))


def passing_bound(
    mu_i: np.ndarray, mu_j: np.ndarray, cov_rel: np.ndarray, cross_rel: np.ndarray, r_i: float, r_j: float
) -> float:
    """Upper bound on P(robots i and j touch at any of the steps 1..T), first passage as in
    :func:`move_bound`: mu (T+1, 2) m, ``cov_rel`` (T+1, 2, 2) the relative error's covariance,
    ``cross_rel`` (T+1, 2, 2) its Cov(e_t, e_{t-1}) (row 0 unused)."""
    gap = np.asarray(mu_j, dtype=float)[..., :2] - np.asarray(mu_i, dtype=float)[..., :2]
    return first_passage(
        np.asarray(cov_rel, dtype=float), np.asarray(cross_rel, dtype=float), disc_reach(gap, r_i + r_j)
    )


def pair_bound(
    mu_i: np.ndarray,
    mu_j: np.ndarray,
    cov_i: np.ndarray,
    cov_j: np.ndarray,
    r_i: float,
    r_j: float,
) -> np.ndarray:
    """Upper bound on P(robots i and j touch) at one instant from each robot's own covariance.

    m = ||mu_i - mu_j|| - r_i - r_j; P <= 1 if m <= 0, else exp(-m² / (2 (sigma_i + sigma_j)²)),
    sigma = sqrt(lambda_max(Sigma_xy)). Touching needs ||e|| > m for the relative error
    e = (x_i - x_j) - (mu_i - mu_j), whose largest standard deviation is at most
    sigma_i + sigma_j whatever the cross-covariance (std(u·e_i - u·e_j) <= std(u·e_i) + std(u·e_j)).

    mu: (..., 2) m; cov: (..., 3, 3) or (..., 2, 2) m²; radii m. Returns (...,).
    """
    gap = np.asarray(mu_i, dtype=float)[..., :2] - np.asarray(mu_j, dtype=float)[..., :2]
    m = np.hypot(gap[..., 0], gap[..., 1]) - r_i - r_j
    s = position_std(cov_i) + position_std(cov_j)
    with np.errstate(divide="ignore", invalid="ignore"):
        tail = np.where(s > 0.0, np.exp(-(m**2) / (2.0 * s**2)), 0.0)
    return np.where(m <= 0.0, 1.0, tail)


def separation(delta: float, r_i: float, r_j: float, sigma_i: float, sigma_j: float) -> float:
    """s_ij = r_i + r_j + k(delta) (sigma_i + sigma_j) (m): planned means at least this far apart
    keep :func:`pair_bound` at most delta."""
    return r_i + r_j + k_of(delta) * (sigma_i + sigma_j)
