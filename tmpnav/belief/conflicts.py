"""Robots in each other's way: the independent checker over trajectories.

Two robots i, j are in each other's way at an instant when their planned means come closer
than the sum of their radii plus a margin from their uncertainty:

    ||mu_i - mu_j|| < s_ij,    s_ij = r_i + r_j + k(delta) (sigma_i + sigma_j),
    k(delta) = sqrt(2 ln(1/delta)),

with sigma = sqrt(lambda_max(Sigma_xy)) the standard deviation of a robot's position along
its most uncertain direction (the largest eigenvalue of the 2x2 position block of its
covariance). Outside a conflict the gap m = ||mu_i - mu_j|| - r_i - r_j is at least
k(delta) (sigma_i + sigma_j), so the chance that the robots touch, bounded by
exp(-m^2 / (2 (sigma_i + sigma_j)^2)), is at most delta (the plan's risk threshold,
``planner.max_risk``). The same convention is used by the chance constraints.

The checker knows nothing of plans, clocks or the oracle: it reads trajectories only (each
robot's :class:`~tmpnav.types.TrajectoryStep` list on one grid of the models' ``dt``, a
robot's last step holding after its trajectory ends), so it can confirm what the planner or
the resolver (:mod:`tmpnav.attachment.conflicts`) claims. Consecutive conflicting steps of
one pair of robots are one :class:`Conflict`.

Robots run off the plan's clock when executed. Given a pair's **time window** w(t) (s, at each
step: how far apart their clocks may be; :mod:`tmpnav.attachment.drift` derives it from a
schedule), robot i at t and robot j at any t' with |t - t'| <= w(t) must keep the separation
(with sigma_j taken at t'); w = 0 is the rule above. :func:`contacts` checks sampled true
trajectories (``tmpnav simulate``): there a contact is ||x_i - x_j|| < r_i + r_j, no margin.

Where the robots keep clear of what their lidar sees (nav2's AMCL model with ``walls: local``,
the collision bound's own convention), nav2's obstacle layer marks another robot where the scans
see it: what separates two robots is then their positions as each other's costmaps place them,
each off by the local error (``localiser.local_std``), not by their global estimates' spread
(:func:`seen_std`; sigma_i = sigma_j = local_std in the rule above).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numba as nb
import numpy as np

from tmpnav.types import Models, TrajectoryStep

#: the plan's risk threshold when the scenario names none (``planner.max_risk``)
DEFAULT_DELTA = 0.05
#: two trajectories are on one grid when their times agree to this (s)
GRID_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Conflict:
    """Two robots in each other's way from ``t_from`` to ``t_to`` (s, both conflicting steps):
    the closest their centres came (m), the separation required at that instant (m), and
    where it was (the midpoint of the two centres, m)."""

    robots: tuple[str, str]
    t_from: float
    t_to: float
    closest_distance: float
    required_separation: float
    where: tuple[float, float]
    #: the largest time window (s) of the pair over the conflict's steps (0: the same instant)
    window: float = 0.0

    @property
    def shortfall(self) -> float:
        """How much closer than required the robots came at their closest (m)."""
        return self.required_separation - self.closest_distance


def margin_factor(delta: float) -> float:
    """k(delta) = sqrt(2 ln(1/delta)): standard deviations of margin for a touch risk of at most
    delta; 0 at delta = 1 (any risk allowed: the radii alone), as ``--max-risk 1`` may ask."""
    if not 0.0 < delta <= 1.0:
        raise ValueError(f"the risk threshold must be in (0, 1], not {delta}")
    return math.sqrt(2.0 * math.log(1.0 / delta))


def seen_std(models: Models) -> float | None:
    """The std (m) of a robot's position as the other robots' costmaps place it, where the
    robots keep clear of what their lidar sees (ScanModel.local_walls): the local error; None
    where their beliefs' spread separates them (module docstring)."""
    sensor = models.range_sensor
    if sensor is None or not sensor.localiser.local_walls:
        return None
    return sensor.localiser.local_std


def separation_std(steps: Sequence[TrajectoryStep], seen: float | None = None) -> np.ndarray:
    """Each step's position std as the separation rule takes it (m): its belief's
    (:func:`position_sigma`), or ``seen`` where the others see the robot (:func:`seen_std`)."""
    if seen is not None:
        return np.full(len(steps), seen)
    return position_sigma(np.array([s.cov for s in steps]))


def position_sigma(covs: np.ndarray) -> np.ndarray:
    """sqrt(lambda_max) of the 2x2 position blocks of covariances (..., 3, 3) -> (...,) in m."""
    xy = np.asarray(covs, dtype=float)[..., :2, :2]
    a, b, c = xy[..., 0, 0], 0.5 * (xy[..., 0, 1] + xy[..., 1, 0]), xy[..., 1, 1]
    top = 0.5 * (a + c) + np.sqrt(0.25 * (a - c) ** 2 + b**2)  # closed form of the largest eigenvalue
    return np.sqrt(np.maximum(top, 0.0))


def find_conflicts(
    trajectories: Mapping[str, Sequence[TrajectoryStep]],
    radii: Mapping[str, float],
    delta: float = DEFAULT_DELTA,
    windows: Mapping[tuple[str, str], np.ndarray] | None = None,
    seen: float | None = None,
    tracks: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
) -> list[Conflict]:
    """Every conflict (module docstring) of the planned beliefs, by start time, then robots.
    The trajectories must share one time grid from a common start; ValueError otherwise.
    ``windows``: (a, b) with a < b -> the pair's time window (s) at each step of the grid (a
    pair without one: 0, the same instant only); ``seen``: each robot's std as the others see it
    (:func:`seen_std`) in place of its belief's. ``tracks``: each robot's positions (T, 2) and
    position stds (:func:`position_sigma`, (T,)) at its trajectory's steps, as arrays made from
    the same beliefs (a clock run's record, ``ClockRun.tracks``): read in place of the steps,
    which then give only the grid, from the longest (the same conflicts, found sooner)."""
    names = sorted(trajectories)
    if tracks is None:
        times = _grid([[s.t for s in trajectories[r]] for r in names])
        xy = [np.array([s.mean[:2] for s in trajectories[r]], dtype=float) for r in names]
        spread = [separation_std(trajectories[r], seen) for r in names]
    else:
        times = np.array([s.t for s in max((trajectories[r] for r in names), key=len, default=[])], dtype=float)
        xy = [tracks[r][0] for r in names]
        spread = [tracks[r][1] if seen is None else np.full(len(tracks[r][1]), seen) for r in names]
    means, sigmas = _held(xy, len(times)), _held(spread, len(times))
    k = margin_factor(delta)
    if windows:
        dt = float(times[1] - times[0]) if len(times) > 1 else 1.0
        shifts = {p: np.floor(np.asarray(w, dtype=float) / dt + GRID_TOLERANCE).astype(int) for p, w in windows.items()}
        return _windowed(names, times, means, sigmas, radii, k, shifts)
    return _pairs(names, times, means, lambda i, j: radii[names[i]] + radii[names[j]] + k * (sigmas[i] + sigmas[j]))


def contacts(positions: Mapping[str, np.ndarray], radii: Mapping[str, float], dt: float) -> list[Conflict]:
    """Every contact of sampled true trajectories: robot -> (T, 2 or 3) true poses at the
    steps 0, dt, 2 dt, ... (the last held); a contact is ||x_i - x_j|| < r_i + r_j."""
    names = sorted(positions)
    arrays = [np.asarray(positions[r], dtype=float)[:, :2] for r in names]
    steps = max((len(a) for a in arrays), default=0)
    times = np.arange(steps) * dt
    means = _held(arrays, steps)
    return _pairs(names, times, means, lambda i, j: np.full(steps, radii[names[i]] + radii[names[j]]))


def _grid(times: Sequence[Sequence[float]]) -> np.ndarray:
    """The longest time grid, after checking that every robot's times are a start of it."""
    longest = np.array(max(times, key=len, default=[]), dtype=float)
    for t in times:
        if len(t) == 0 or not np.allclose(t, longest[: len(t)], rtol=0.0, atol=GRID_TOLERANCE):
            raise ValueError("the trajectories are not on one time grid from one start")
    return longest


def _held(series: Sequence[np.ndarray], steps: int) -> list[np.ndarray]:
    """Each series padded to ``steps`` rows with its last row (a robot stands where it ended)."""
    return [np.concatenate([s, np.repeat(s[-1:], steps - len(s), axis=0)]) if len(s) < steps else s for s in series]


def _pairs(
    names: Sequence[str], times: np.ndarray, means: Sequence[np.ndarray], required: Callable[[int, int], np.ndarray]
) -> list[Conflict]:
    """The runs of steps at which each pair is closer than ``required(i, j)`` (per step),
    each reported at its closest instant."""
    found = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            gap = np.hypot(*(means[i] - means[j]).T)
            need = np.broadcast_to(required(i, j), gap.shape)
            for lo, hi in _runs(gap < need):
                c = lo + int(np.argmin(gap[lo:hi]))
                mid = 0.5 * (means[i][c] + means[j][c])
                span = (float(times[lo]), float(times[hi - 1]))
                where = (float(mid[0]), float(mid[1]))
                found.append(Conflict((names[i], names[j]), *span, float(gap[c]), float(need[c]), where))
    return sorted(found, key=lambda c: (c.t_from, c.robots))


def _windowed(
    names: Sequence[str],
    times: np.ndarray,
    means: Sequence[np.ndarray],
    sigmas: Sequence[np.ndarray],
    radii: Mapping[str, float],
    k: float,
    shifts: Mapping[tuple[str, str], np.ndarray],
) -> list[Conflict]:
    """The runs of steps t at which robot i comes within the separation of robot j at some
    step t + d, |d| <= the pair's window in steps at t; each reported at its step and shift of
    largest shortfall. A pair without a window is checked at the same instant (d = 0)."""
    found, steps = [], len(times)
    dt = float(times[1] - times[0]) if steps > 1 else 0.0
    for i, j in itertools.combinations(range(len(names)), 2):
        window = shifts.get((names[i], names[j]), np.zeros(steps, dtype=int))
        worst, gap_at, need_at, other = _shortfalls(
            means[i], means[j], sigmas[i], sigmas[j], radii[names[i]] + radii[names[j]], k, window.astype(np.int64)
        )
        for lo, hi in _runs(worst > 0.0):
            c = lo + int(np.argmax(worst[lo:hi]))
            mid = 0.5 * (means[i][c] + means[j][other[c]])
            span = (float(times[lo]), float(times[hi - 1]))
            late = float(window[lo:hi].max()) * dt
            where = (float(mid[0]), float(mid[1]))
            found.append(Conflict((names[i], names[j]), *span, float(gap_at[c]), float(need_at[c]), where, late))
    return sorted(found, key=lambda c: (c.t_from, c.robots))


#: steps of one block of :func:`_shortfalls`' test of whether a pair comes near at all
SHORTFALL_BLOCK = 32


@nb.njit(cache=True)
def _shortfalls(
    mi: np.ndarray, mj: np.ndarray, si: np.ndarray, sj: np.ndarray, rr: float, k: float, window: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At each step t of robots i and j (positions ``mi``, ``mj`` (T, 2); separation stds
    ``si``, ``sj`` (T,); radii summed ``rr``; margin factor ``k``) where robot i comes within
    the separation of robot j: the largest shortfall of the gap below the separation,
    rr + k (si[t] + sj[t + d]) - |mi[t] - mj[t + d]|, over the shifts d with |d| <= ``window[t]``
    (t + d clipped to the grid), the first of equals by ascending d; its gap, separation and step
    t + d. Where it does not (every shortfall negative), a negative shortfall (-inf where a block
    of steps was passed over). Compiled: over every shift of every pair, numpy's broadcasting took
    two thirds of keeping 16 robots apart.

    Steps are taken in blocks of SHORTFALL_BLOCK: a block is passed over when the box around robot
    i's positions in it and the box around robot j's positions its shifts reach are farther apart
    than the largest separation there (at 16 robots most pairs are rooms apart most of the time).
    Rounding is monotone, so every gap there is computed beyond every separation, as the box says."""
    steps = mi.shape[0]
    worst = np.full(steps, -np.inf)
    gap_at, need_at = np.zeros(steps), np.zeros(steps)
    other = np.arange(steps)
    for t0 in range(0, steps, SHORTFALL_BLOCK):
        t1 = min(t0 + SHORTFALL_BLOCK, steps)
        reach = 0
        ix0, ix1, iy0, iy1, smax_i = np.inf, -np.inf, np.inf, -np.inf, 0.0
        for t in range(t0, t1):
            reach = max(reach, window[t])
            ix0, ix1 = min(ix0, mi[t, 0]), max(ix1, mi[t, 0])
            iy0, iy1 = min(iy0, mi[t, 1]), max(iy1, mi[t, 1])
            smax_i = max(smax_i, si[t])
        jx0, jx1, jy0, jy1, smax_j = np.inf, -np.inf, np.inf, -np.inf, 0.0
        for a in range(max(t0 - reach, 0), min(t1 - 1 + reach, steps - 1) + 1):
            jx0, jx1 = min(jx0, mj[a, 0]), max(jx1, mj[a, 0])
            jy0, jy1 = min(jy0, mj[a, 1]), max(jy1, mj[a, 1])
            smax_j = max(smax_j, sj[a])
        dx = max(0.0, max(jx0 - ix1, ix0 - jx1))
        dy = max(0.0, max(jy0 - iy1, iy0 - jy1))
        if math.hypot(dx, dy) > rr + k * (smax_i + smax_j):
            continue
        for t in range(t0, t1):
            w = window[t]
            for d in range(-w, w + 1):
                a = min(max(t + d, 0), steps - 1)
                gap = math.hypot(mi[t, 0] - mj[a, 0], mi[t, 1] - mj[a, 1])
                need = rr + k * (si[t] + sj[a])
                if need - gap > worst[t]:
                    worst[t], gap_at[t], need_at[t], other[t] = need - gap, gap, need, a
    return worst, gap_at, need_at, other


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """The [lo, hi) index ranges of the runs of True in ``flags``."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist(), strict=True))
