"""How sure a sampled rate is: exact confidence limits of a proportion and of a Poisson rate.

``tmpnav simulate`` reports each wall-hit and contact rate with :func:`clopper_pearson`'s
interval, ``tmpnav calibrate`` counts the localiser's failures per metre with
:func:`rate_limits`, and the tests hold the collision bounds to sampled rates with both.
"""

from __future__ import annotations

import math


def rate_limits(events: int, exposure: float, level: float = 0.95) -> tuple[float, float]:
    """The exact one-sided ``level`` limits (lower, upper) of a Poisson rate seen ``events`` times
    in ``exposure`` (metres driven, say): chi²_{1-level}(2 events) / (2 exposure) and
    chi²_{level}(2 (events + 1)) / (2 exposure); (0, inf) without exposure."""
    from scipy import stats  # imported here, as in clopper_pearson

    if exposure <= 0:
        return 0.0, math.inf
    lower = 0.0 if events <= 0 else float(stats.chi2.ppf(1.0 - level, 2 * events)) / (2.0 * exposure)
    return lower, float(stats.chi2.ppf(level, 2 * (events + 1))) / (2.0 * exposure)


def clopper_pearson(hits: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """The exact (Clopper-Pearson) confidence interval of a rate seen ``hits`` times in ``n``
    trials: (lower, upper), from the beta distribution's quantiles; (0, 1) when n = 0."""
    from scipy import stats  # imported here: the clock imports this module, and scipy.stats is slow to load

    if n <= 0:
        return 0.0, 1.0
    a = 0.5 * (1.0 - level)
    lo = 0.0 if hits <= 0 else float(stats.beta.ppf(a, hits, n - hits + 1))
    hi = 1.0 if hits >= n else float(stats.beta.ppf(1.0 - a, hits + 1, n - hits))
    return lo, hi
