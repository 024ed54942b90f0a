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
   each step's NEES eᵀ P⁻¹ e scales with about kappa^g. The next factor puts the NEES's
   :data:`QUANTILE` quantile at 9 (that share of the driving steps within 3 predicted sigma):
   kappa_n+1 = kappa_n (9 / q_n)^(1/g), with g measured from the last two rounds once there
   are two (1 before), and no more than :data:`STEP` times or a :data:`STEP`th of kappa_n;
3. repeat until the quantile is within :data:`TOLERANCE` of 9 or the rounds run out.

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

#: the share of driving steps the fitted model keeps within 3 predicted sigma (at most 5% may lie
#: out; AMCL's errors have long tails, so a higher share would inflate the median step's belief)
QUANTILE = 0.96
#: a round whose quantile is within this ratio of 9 ends the fit
TOLERANCE = 0.1
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
        r = Round(model.information, overall(result.consistency), nees_quantile(rows), hits, metres)
        done.append(r)
        say(
            f"round {k + 1}: information {r.information:.4g}: median NEES {r.agreement.nees:.2f}, "
            f"{100 * r.agreement.beyond:.1f}% of {r.agreement.steps} driving steps beyond 3 sigma"
        )
        if not math.isfinite(r.quantile) or r.quantile <= 0 or abs(r.quantile / 9.0 - 1.0) <= TOLERANCE:
            break
        model = replace(model, information=_next(done))
    best = min(done, key=lambda r: abs(math.log(r.quantile / 9.0)) if r.quantile > 0 else math.inf)
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


def _next(done: list[Round]) -> float:
    """The next factor: kappa (9 / q)^(1/g), g from the last two rounds (module docstring)."""
    last = done[-1]
    g = FIRST_EXPONENT
    if len(done) >= 2:
        prev = done[-2]
        dk = math.log(last.information / prev.information)
        dq = math.log(last.quantile / prev.quantile) if prev.quantile > 0 and last.quantile > 0 else 0.0
        if dk != 0.0 and dq / dk > 0:
            g = min(max(dq / dk, EXPONENTS[0]), EXPONENTS[1])
    factor = (9.0 / last.quantile) ** (1.0 / g)
    return last.information * min(max(factor, 1.0 / STEP), STEP)
