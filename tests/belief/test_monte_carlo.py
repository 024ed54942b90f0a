"""The collision bound along whole paths against Monte Carlo: never below the sampled rate, and on
the test paths with the paper's models at most 10 times above it.

The paths, the filter along them and the samplers are tests/belief/risk_paths.py. Trajectories
are drawn as the filter's error process (``walk``: the bound's assumption, exactly) and, on the
paths driven without observations, as the nonlinear motion model with noisy controls
(``unicycle``: the filter's covariance is then its linearisation). 20,000 trajectories a case,
seeded (100,000 for the passing robots, whose contact bound is within 30% of the rate). A
bound must not be below the sampled rate (the rate's 95% Clopper-Pearson interval is in the
message); it must be at most 10 times the rate where that rests on enough hits to say so.
The measured figures are in benchmarks/risk/paths.txt (``benchmarks/bench_risk.py paths``).
"""

from __future__ import annotations

from functools import cache

import pytest

from tests.belief import risk_paths
from tmpnav.belief import intervals

SAMPLES = {"passing": 100_000}
#: a rate measured from this many hits is resolved well enough to hold the bound to 10 times it
RESOLVED = 40

#: (path, noise) -> the wall bound of each robot, and (passing) the contact bound, as computed
#: when this test was written; paths of the paper's models, the passing's lanes 0.56 m apart
PAPER = {
    ("straight", 0.5): (0.026976,),
    ("straight", 1.0): (0.12848,),
    ("corner", 0.25): (0.0082826,),
    ("corner", 0.5): (0.067033,),
    ("corner", 1.0): (0.26913,),
    ("door", 0.5): (0.0056089,),
    ("door", 1.0): (0.063221,),
    ("door", 2.0): (0.29494,),
    ("passing", 1.0): (0.004732, 0.0048318, 0.0055905),
    ("passing", 2.0): (0.036889, 0.037654, 0.0064305),
}
#: the same for the paths driven without observations at dt 0.1 s
OPEN_LOOP = {
    ("open-straight", 0.035): (0.0031992,),
    ("open-straight", 0.06): (0.032167,),
    ("open-straight", 0.09): (0.11641,),
    ("open-corner", 0.05): (0.0088891,),
    ("open-corner", 0.1): (0.15062,),
    ("open-inner", 0.045): (0.0056695,),
    ("open-inner", 0.07): (0.039573,),
}


@cache
def measured(name: str, noise: float, how: str) -> tuple[risk_paths.Measured, ...]:
    d = risk_paths.drive(risk_paths.path(name, offset=0.56), noise)
    return tuple(risk_paths.measure(d, SAMPLES.get(name, 20_000), how))


def _never_below(m: risk_paths.Measured) -> None:
    lower, upper = intervals.clopper_pearson(m.hits, m.n)
    assert m.rate <= m.bound, f"{m.what}: sampled {m.rate:.4g} [{lower:.4g}, {upper:.4g}] > bound {m.bound:.4g}"


@pytest.mark.parametrize(("name", "noise"), list(PAPER) + list(OPEN_LOOP))
def test_the_bounds_are_as_recorded(name: str, noise: float) -> None:
    got = [m.bound for m in measured(name, noise, "walk")]
    assert got == pytest.approx(list({**PAPER, **OPEN_LOOP}[(name, noise)]), rel=1e-4)


@pytest.mark.parametrize(("name", "noise"), list(PAPER))
def test_on_the_test_paths_the_bound_is_never_below_the_rate_and_at_most_ten_times_it(name: str, noise: float) -> None:
    for m in measured(name, noise, "walk"):
        _never_below(m)
        if m.hits >= RESOLVED:
            assert m.bound <= 10.0 * m.rate, f"{name} {noise} {m.what}: bound {m.bound:.4g}, rate {m.rate:.4g}"


@pytest.mark.parametrize("how", ["walk", "unicycle"])
@pytest.mark.parametrize(("name", "noise"), list(OPEN_LOOP))
def test_without_observations_the_bound_is_never_below_the_rate(name: str, noise: float, how: str) -> None:
    for m in measured(name, noise, how):
        _never_below(m)


def test_the_cases_are_informative_and_tighter_than_the_union_over_steps() -> None:
    """Rates between 0.2% and 20% on every paper path, each bound below the union of its steps'
    (with whole cells' reach: the bound before first passage and sub-cells)."""
    for name, noise in PAPER:
        for m in measured(name, noise, "walk"):
            assert m.bound <= m.before
    resolved = {name for name, noise in PAPER for m in measured(name, noise, "walk") if 0.002 < m.rate < 0.2}
    assert resolved == {"straight", "corner", "door", "passing"}
    contact = measured("passing", 1.0, "walk")[2]
    assert contact.what == "contact" and contact.hits >= RESOLVED
