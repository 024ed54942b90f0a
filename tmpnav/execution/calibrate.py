"""``tmpnav calibrate``: fit the planner's scan model to what nav2's AMCL achieves on a scenario.

The planner's ``amcl`` scan model (docs/models.md, "What a localiser achieves") derives a
scan's information from nav2's likelihood-field model: the endpoint noise ``sigma_hit``, the
map's resolution, the mixture of hits and random returns, ``max_beams`` and the update
thresholds. What the derivation cannot give (beams correlated through the map's errors, AMCL's
sum of cubed beam likelihoods, its particles) is one factor, ``information``. Calibration
finds it:

1. plan the scenario with the current factor kappa_n and execute the plan ``sessions`` times
   with AMCL localising every robot on a site that differs from the map
   (:func:`tmpnav.execution.execute`), recording every driving step's actual error e and the
   plan's predicted covariance P (:mod:`tmpnav.execution.consistency`);
2. a scan's information scales with kappa, and the predicted covariance with about kappa^-g
   (g = 1 where the scans' information dominates, 1/2 where motion noise balances it), so
   each step's NEES eᵀ P⁻¹ e scales with about kappa^g, and scaling every NEES by s scales its
   median m and its quantiles alike. Two targets bound s (:func:`scale`): a median NEES of at
   least 1 (s >= 1 / m; at most 4: s <= 4 / m) and at most 5% of the steps beyond 3 sigma
   (s <= 9 / t, t the NEES's 95% quantile). Where the band they leave is not empty, s is its
   middle (on a log scale: the margin against both is the same); where it is (AMCL's errors
   have tails too long for any Gaussian), the tail wins: s puts the NEES's :data:`QUANTILE`
   quantile at 9. The next factor is kappa_n+1 = kappa_n s^(1/g), with g measured from the last
   two rounds once there are two (1 before), and no more than :data:`STEP` times or a
   :data:`STEP`th of kappa_n;
3. repeat until a round meets both targets within :data:`CENTRED` of the band's middle, or,
   where none can, its quantile is within :data:`TOLERANCE` of 9, or the rounds run out. The
   fit is the round that met both targets with the least change asked of it, else the round
   nearest the tail target.

The plan is re-made each round: the factor changes the beliefs, and with them the moves.

The same executions count the wall hits the Gaussian error does not explain (AMCL converging
off the robot's pose, a recovery behaviour backing it off its path): over every round, the
executions of a move with a wall hit per metre of the moves' planned paths driven, a Poisson
rate (docs/models.md, "Localisation failures"). The scenario's ``failure_rate`` stays where
the count agrees with it (within the rate's 95% limits); where the count rejects it, either
way, the fitted rate is the upper 95% limit. Without a hit it takes about 3 / failure_rate
metres driven (25 km for the default) to bound the rate below the scenario's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from tmpnav.belief.intervals import rate_limits
from tmpnav.belief.risk import step_lengths
from tmpnav.errors import Problem, ScenarioError
from tmpnav.execution.consistency import Agreement, overall, planned_nees
from tmpnav.execution.localisers import Localisation
from tmpnav.execution.moves import queues
from tmpnav.types import NAV2_AMCL, ScanModel, ScanModelKind, Scenario

if TYPE_CHECKING:
    from tmpnav.execution.result import ExecutionResult
    from tmpnav.results import PlanReport

#: the share of driving steps the fitted model keeps within 3 predicted sigma where no scale of the
#: belief meets both targets (at most 5% may lie out; AMCL's errors have long tails, so a higher share
#: would inflate the median step's belief further)
QUANTILE = 0.96
#: issue-level targets of the plan's belief against AMCL: the median NEES between these, and at most
#: BEYOND of the driving steps beyond 3 sigma (NEES > 9)
MEDIAN_RANGE = (1.0, 4.0)
BEYOND = 0.05
#: a round whose quantile is within this ratio of 9 ends a fit that cannot meet both targets
TOLERANCE = 0.1
#: a round that meets both targets ends the fit where the scale it asks for is within this factor of
#: 1 (near the band's middle: 8 sessions' figures move by a few tens of percent from run to run)
CENTRED = 1.5
#: the exponent g of NEES ~ kappa^g assumed before two rounds measure it, and the range it is kept in
FIRST_EXPONENT = 1.0
EXPONENTS = (0.25, 2.0)
#: the most one round changes the factor by (either way): the plan, and with it the errors, change too
STEP = 4.0


@dataclass(frozen=True)
class Round:
    """One round: the factor planned with and how the executions agreed with that plan."""

    information: float
    agreement: Agreement
    quantile: float  # the NEES's QUANTILE quantile over the driving steps
    hits: int = 0  # executions of a move with a wall hit
    metres: float = 0.0  # the moves' planned paths times their executions
    scale: float = 1.0  # the factor on every step's NEES the targets ask for (:func:`scale`)

    @property
    def meets_both(self) -> bool:
        """The round's median NEES lies within MEDIAN_RANGE and at most BEYOND of its steps beyond 3 sigma."""
        a = self.agreement
        return MEDIAN_RANGE[0] <= a.nees <= MEDIAN_RANGE[1] and a.beyond <= BEYOND


@dataclass(frozen=True)
class Failures:
    """Wall hits per metre driven over the rounds' executions: the count, the exposure (the moves'
    planned paths times their executions), the rate, its 95% limits and the rate it fits."""

    hits: int
    metres: float

    @staticmethod
    def of(rounds: tuple[Round, ...]) -> Failures:
        """The count over every round."""
        return Failures(sum(r.hits for r in rounds), math.fsum(r.metres for r in rounds))

    @property
    def rate(self) -> float:
        return self.hits / self.metres if self.metres > 0 else math.nan

    @property
    def limits(self) -> tuple[float, float]:
        """The rate's one-sided 95% limits, (lower, upper)."""
        return rate_limits(self.hits, self.metres)

    def fitted(self, current: float) -> float:
        """The rate the model takes: ``current`` where the count agrees with it, else the upper limit."""
        lower, upper = self.limits
        return min(upper, 1.0) if upper < current or lower > current else current


@dataclass(frozen=True)
class Calibration:
    """The fitted scan model, and the rounds that fitted it."""

    model: ScanModel
    rounds: tuple[Round, ...]
    localiser: str  # the executing localiser, the site and the true motion noise, in words
    rate_before: float = 0.0  # the scenario's failure_rate before the fit

    @property
    def kept_rate(self) -> bool:
        """The executions' wall hits agree with the scenario's failure_rate, which the model keeps."""
        return self.model.failure_rate == self.rate_before

    @property
    def failures(self) -> Failures:
        """The wall hits per metre driven over every round's executions."""
        return Failures.of(self.rounds)

    @property
    def verdict(self) -> str:
        """Which round the model takes, and why, in words."""
        kept = fitted_round(list(self.rounds))
        k = self.rounds.index(kept) + 1
        if kept.meets_both:
            return (
                f"kept round {k}: median NEES within {MEDIAN_RANGE[0]:g}-{MEDIAN_RANGE[1]:g} and at most "
                f"{100 * BEYOND:g}% of the steps beyond 3 sigma (both targets met)"
            )
        return (
            f"kept round {k}: the nearest to {100 * QUANTILE:g}% of the steps within 3 sigma (no round met both "
            f"a median NEES of {MEDIAN_RANGE[0]:g}-{MEDIAN_RANGE[1]:g} and at most {100 * BEYOND:g}% beyond; "
            "the tail comes first)"
        )

    def yaml(self, scenario: str) -> str:
        """The result as the scenario takes it (models.range_sensor.localiser), with the rounds as comments."""
        m = self.model
        lines = [
            f"# tmpnav calibrate {scenario}: the planner's scan model fitted to nav2's AMCL",
            f"# {self.localiser}",
            "# round  information  steps  rms error  AMCL std  planned std  median NEES  beyond 3 sigma",
        ]
        for k, r in enumerate(self.rounds, 1):
            a = r.agreement
            lines.append(
                f"# {k:5d}  {r.information:11.4g}  {a.steps:5d}  {100 * a.rms_error:7.1f} cm  {100 * a.own_std:6.1f} cm"
                f"  {100 * a.planned_std:8.1f} cm  {a.nees:11.2f}  {100 * a.beyond:12.1f}%"
            )
        lines.append(f"# {self.verdict}")
        f = self.failures
        lower, upper = f.limits
        driven = f"{f.metres / 1000:.1f} km" if f.metres >= 1000 else f"{f.metres:.0f} m"
        lines += [
            f"# wall hits: {f.hits} in {driven} of the moves' paths driven, {f.rate:.3g} per m "
            f"(95% limits {lower:.3g} to {upper:.3g}); failure_rate "
            + (
                f"{m.failure_rate:.3g}: the count agrees with the scenario's (more sessions narrow the limits)"
                if self.kept_rate
                else f"{m.failure_rate:.3g}: the upper limit (the count rejects the scenario's {self.rate_before:.3g})"
            ),
            "# put it under models.range_sensor of the scenario (docs/scenario.md):",
            f"localiser: {{model: amcl, sigma_hit: {m.sigma_hit:g}, z_hit: {m.z_hit:g}, z_rand: {m.z_rand:g}, "
            f"max_beams: {m.max_beams}, update_min_d: {m.update_min_d:g}, update_min_a: {m.update_min_a:g}, "
            f"information: {m.information:.4g}, lidar_only: {'true' if m.lidar_only else 'false'}, "
            f"failure_rate: {m.failure_rate:.3g}, floor_beams: {m.floor_beams:g}, heading_blur: {m.heading_blur:g}"
            f"{_prediction(m)}}}",
        ]
        return "\n".join(lines) + "\n"


def _prediction(m: ScanModel) -> str:
    """The localiser line's ``prediction_noise`` (nav2's alpha1-4) where the model predicts with AMCL's motion model."""
    if m.prediction_noise is None:
        return ""
    alphas = ", ".join(f"alpha{k}: {a:g}" for k, a in enumerate(m.prediction_noise, 1))
    return f", prediction_noise: {{{alphas}}}"


def nees_quantile(rows: np.ndarray, q: float = QUANTILE) -> float:
    """The q quantile of the driving steps' NEES eᵀ P⁻¹ e (rows as :mod:`consistency` records them)."""
    nees = planned_nees(rows)
    return float(np.quantile(nees, q)) if nees.size else math.nan


def scale(nees: np.ndarray) -> float:
    """The factor s on every step's NEES (a belief whose covariance is 1/s times the plan's) that
    the targets ask for (module docstring, step 2): the middle, on a log scale, of the band
    [1 / m, min(4 / m, 9 / t)] (m the median, t the 95% quantile) where it is not empty, else
    9 / the :data:`QUANTILE` quantile; nan for no step."""
    v = np.asarray(nees, dtype=float)
    v = v[~np.isnan(v)]
    if not v.size:
        return math.nan
    m, t = float(np.median(v)), float(np.quantile(v, 1.0 - BEYOND))
    low = MEDIAN_RANGE[0] / m if m > 0 else math.inf
    high = min(MEDIAN_RANGE[1] / m if m > 0 else math.inf, 9.0 / t if t > 0 else math.inf)
    if low <= high and math.isfinite(low) and math.isfinite(high):
        return math.sqrt(low * high)
    q = float(np.quantile(v, QUANTILE))
    return 9.0 / q if q > 0 and math.isfinite(q) else math.nan


def with_model(scenario: Scenario, model: ScanModel) -> Scenario:
    """The scenario with its robots' localiser model replaced."""
    sensor = scenario.models.range_sensor
    assert sensor is not None
    return replace(scenario, models=replace(scenario.models, range_sensor=replace(sensor, localiser=model)))


def calibrate(
    path: str | Path,
    localisation: Localisation,
    sessions: int = 8,
    rounds: int = 4,
    seed: int = 0,
    workers: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> Calibration:
    """Fit ``information`` of the scenario's scan model to AMCL (the module docstring); AMCL's
    analytic parameters (sigma_hit, z_hit, z_rand, max_beams, update thresholds) are those of
    ``localisation.amcl``."""
    from tmpnav import pipeline
    from tmpnav.execution.result import execute

    say = progress or (lambda _: None)
    scenario, world = pipeline.load_world(path)
    sensor = scenario.models.range_sensor
    if sensor is None:
        raise ScenarioError(
            [
                Problem(
                    str(path),
                    "models.range_sensor",
                    "the robots carry no range sensor; expected a lidar for AMCL to localise with (calibration "
                    "fits the lidar's scan model)",
                )
            ]
        )
    p = localisation.amcl
    own = sensor.localiser if sensor.localiser.kind is ScanModelKind.AMCL else None
    # the executing AMCL's parameters; the scenario's own choices (walls, the floor, the noise its
    # beliefs predict with) carried over
    base = own or NAV2_AMCL
    model = replace(
        base,
        sigma_hit=p.sigma_hit,
        z_hit=p.z_hit,
        z_rand=p.z_rand,
        max_beams=p.max_beams,
        update_min_d=p.update_min_d,
        update_min_a=p.update_min_a,
        lidar_only=sensor.localiser.lidar_only,
    )
    done: list[Round] = []
    described = ""
    for k in range(rounds):
        options = pipeline.PlanOptions.of(accept_risk=True)
        report = pipeline.plan(path, options, loaded=(with_model(scenario, model), world))
        result = execute(report, sessions, seed, workers, localisation)
        described = result.localiser
        rows = np.concatenate(list(result.consistency.values())) if result.consistency else np.zeros((0, 8))
        hits, metres = wall_hits_driven(report, result)
        nees = planned_nees(rows)
        r = Round(model.information, overall(result.consistency), nees_quantile(rows), hits, metres, scale(nees))
        done.append(r)
        say(
            f"round {k + 1}: information {r.information:.4g}: median NEES {r.agreement.nees:.2f}, "
            f"{100 * r.agreement.beyond:.1f}% of {r.agreement.steps} driving steps beyond 3 sigma"
            + (": both targets met" if r.meets_both else "")
        )
        if not math.isfinite(r.scale) or r.scale <= 0 or _done(r):
            break
        model = replace(model, information=_next(done))
    best = fitted_round(done)
    rounds_done = tuple(done)
    before = sensor.localiser.failure_rate if sensor.localiser.kind is ScanModelKind.AMCL else NAV2_AMCL.failure_rate
    rate = Failures.of(rounds_done).fitted(before)
    fitted = replace(model, information=best.information, failure_rate=rate)
    return Calibration(fitted, rounds_done, described, before)


def path_lengths(report: PlanReport) -> dict[tuple[str, int], float]:
    """(robot, plan step as the executions key it) -> metres of the move's planned path."""
    return {
        (robot, move.step): float(step_lengths(move.planned_means).sum())
        for robot, moves in queues(report).items()
        for move in moves
        if move.planned_means is not None
    }


def wall_hits_driven(report: PlanReport, result: ExecutionResult) -> tuple[int, float]:
    """The executions of a move with a wall hit, and the metres of the moves' planned paths times
    their executions, in the first configuration run (the one AMCL runs)."""
    lengths = path_lengths(report)
    hits, metres = 0, 0.0
    for robot, step, walls, _, _ in result.move_rates(result.configs[0]):
        if (robot, step) in lengths:
            hits += walls.events
            metres += lengths[(robot, step)] * walls.sessions
    return hits, metres


def _done(r: Round) -> bool:
    """A round that ends the fit: it meets both targets near the band's middle, or its tail is at
    the target (module docstring, step 3)."""
    if r.meets_both and abs(math.log(r.scale)) <= math.log(CENTRED):
        return True
    return abs(r.quantile / 9.0 - 1.0) <= TOLERANCE and not r.meets_both


def fitted_round(done: list[Round]) -> Round:
    """The round the fit keeps: of those that met both targets the one that asked the least change
    of its NEES, else the one nearest the tail target (its QUANTILE quantile nearest 9)."""
    both = [r for r in done if r.meets_both]
    if both:
        return min(both, key=lambda r: abs(math.log(r.scale)) if r.scale > 0 else math.inf)
    return min(done, key=lambda r: abs(math.log(r.quantile / 9.0)) if r.quantile > 0 else math.inf)


def _next(done: list[Round]) -> float:
    """The next factor: kappa s^(1/g), g from the last two rounds' quantiles (module docstring)."""
    last = done[-1]
    g = FIRST_EXPONENT
    if len(done) >= 2:
        prev = done[-2]
        dk = math.log(last.information / prev.information)
        dq = math.log(last.quantile / prev.quantile) if prev.quantile > 0 and last.quantile > 0 else 0.0
        if dk != 0.0 and dq / dk > 0:
            g = min(max(dq / dk, EXPONENTS[0]), EXPONENTS[1])
    factor = last.scale ** (1.0 / g)
    return last.information * min(max(factor, 1.0 / STEP), STEP)
