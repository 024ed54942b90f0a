"""``tmpnav calibrate``: the information share it fits, and the localiser's failure rate it counts.

The fit aims at the middle of the scales of the belief that meet both consistency targets (a
median NEES of 1-4, at most 5% of the steps beyond 3 sigma) and at the tail where none does; the
rate's limits are the exact Poisson ones; the scenario's rate stays where the count agrees
with it and moves to the upper limit where the count rejects it; the command writes a
localiser line that a scenario takes back.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.execution.test_amcl import NEEDS_AMCL
from tmpnav.belief.intervals import rate_limits
from tmpnav.execution.calibrate import BEYOND, MEDIAN_RANGE, QUANTILE, Failures, Round, fitted_round, scale
from tmpnav.execution.consistency import Agreement
from tmpnav.scenario import load
from tmpnav.types import NAV2_AMCL

ROOT = Path(__file__).resolve().parents[2]


def _chi2(n: int = 200_000, seed: int = 1) -> np.ndarray:
    """The NEES of a consistent 2-D Gaussian belief: chi-square with 2 degrees of freedom."""
    return np.random.default_rng(seed).chisquare(2, n)


def test_a_consistent_belief_is_asked_for_almost_no_change() -> None:
    s = scale(_chi2())
    # the band of a chi-square(2): [1 / 1.386, 9 / 5.99] = [0.72, 1.50], its log middle 1.04
    assert s == pytest.approx(np.sqrt(1.0 / (2 * np.log(2)) * 9.0 / -2.0 / np.log(0.05)), rel=0.01)
    assert 0.9 < s < 1.1


@pytest.mark.parametrize("wider", [0.25, 4.0])
def test_the_scale_undoes_a_belief_too_wide_or_too_narrow(wider: float) -> None:
    """A belief k times too wide in variance gives every NEES / k: the scale asks k back."""
    nees = _chi2()
    assert scale(nees / wider) == pytest.approx(wider * scale(nees), rel=1e-9)


def test_the_scale_meets_both_targets_where_a_band_exists() -> None:
    nees = _chi2() * 3.0  # too narrow: median 4.2, 16% beyond
    scaled = scale(nees) * nees
    assert MEDIAN_RANGE[0] <= np.median(scaled) <= MEDIAN_RANGE[1]
    assert np.mean(scaled > 9.0) <= BEYOND


def test_a_tail_too_long_for_any_gaussian_puts_the_quantile_at_9() -> None:
    """AMCL lost for 10% of the steps, 30 times as far off: no scale gives a median of 1 with 5% beyond."""
    nees = _chi2()
    nees[: nees.size // 10] *= 900.0
    s = scale(nees)
    assert s == pytest.approx(9.0 / np.quantile(nees, QUANTILE))
    assert np.median(s * nees) < MEDIAN_RANGE[0]
    assert scale(np.full(3, np.nan)) != scale(np.full(3, np.nan))  # no step: nan


def _round(information: float, nees: float, beyond: float, s: float, quantile: float = 9.0) -> Round:
    return Round(information, Agreement(100, 0.1, 0.3, 0.1, nees, beyond), quantile, scale=s)


def test_the_fit_keeps_the_round_that_met_both_targets_before_the_one_nearest_the_tail() -> None:
    tail = _round(0.1, 0.7, 0.04, 1.7, quantile=9.0)  # at the tail target, median below 1
    both_far = _round(0.2, 1.05, 0.049, 0.6, quantile=8.0)
    both_near = _round(0.15, 1.4, 0.02, 1.1, quantile=7.0)
    assert fitted_round([tail, both_far, both_near]) is both_near
    assert fitted_round([tail, both_far]) is both_far
    assert fitted_round([tail, _round(0.3, 2.0, 0.12, 0.5, quantile=20.0)]) is tail


def test_the_rates_limits_are_the_exact_poisson_ones() -> None:
    assert rate_limits(0, 1000.0) == pytest.approx((0.0, 2.995732 / 1000.0), rel=1e-6)  # -ln 0.05
    lower, upper = rate_limits(4, 74924.5)
    assert lower == pytest.approx(1.36632 / 74924.5, rel=1e-5)
    assert upper == pytest.approx(9.15352 / 74924.5, rel=1e-5)
    assert upper == pytest.approx(NAV2_AMCL.failure_rate, rel=0.01)  # the shipped default's count
    assert rate_limits(3, 0.0) == (0.0, float("inf"))


@pytest.mark.parametrize(
    ("hits", "metres", "kept"),
    [
        (0, 40.0, True),  # a short run cannot tell: the scenario's rate stays
        (4, 74924.5, True),  # the default's own count agrees with it
        (0, 60000.0, False),  # 60 km without a hit: below the default, at the upper limit
        (20, 20000.0, False),  # far more hits than the default allows: raised to the upper limit
    ],
)
def test_the_scenarios_rate_stays_unless_the_count_rejects_it(hits: int, metres: float, kept: bool) -> None:
    f = Failures(hits, metres)
    fitted = f.fitted(NAV2_AMCL.failure_rate)
    assert (fitted == NAV2_AMCL.failure_rate) is kept
    if not kept:
        assert fitted == pytest.approx(f.limits[1])
        lower, upper = f.limits
        assert upper < NAV2_AMCL.failure_rate or lower > NAV2_AMCL.failure_rate


def test_calibrate_writes_a_localiser_line_with_the_failure_rate(tmp_path: Path) -> None:
    pytest.importorskip("amcl", reason=NEEDS_AMCL)
    out = tmp_path / "fit.yaml"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "tmpnav",
            "calibrate",
            "configs/office-ros.yaml",
            *("--sessions", "2", "--rounds", "1"),
            *("--workers", "1", "-q", "-o", str(out)),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    text = out.read_text()
    assert "# wall hits: " in text and "m of the moves' paths driven" in text
    localiser = yaml.safe_load(next(line for line in text.splitlines() if line.startswith("localiser:")))["localiser"]
    assert localiser["failure_rate"] == pytest.approx(NAV2_AMCL.failure_rate, rel=0.01)  # 2 short runs agree with it
    doc = yaml.safe_load((ROOT / "configs" / "office-ros.yaml").read_text())
    doc["map"]["ros"] = str(ROOT / "configs" / doc["map"]["ros"])
    doc["models"]["range_sensor"]["localiser"] = localiser
    scenario_file = tmp_path / "office-ros-fitted.yaml"
    scenario_file.write_text(yaml.safe_dump(doc))
    scenario = load(scenario_file)
    sensor = scenario.models.range_sensor
    assert sensor is not None and sensor.localiser.hazard == pytest.approx(localiser["failure_rate"])


def test_calibrate_keeps_the_scenarios_prediction_noise_whatever_alphas_amcl_executed_with(tmp_path: Path) -> None:
    """A scenario whose beliefs predict with alphas of its own (prediction_noise) and a heading
    spread of its own (heading_blur) is calibrated with them, and the fitted line keeps them,
    whatever alphas the AMCL that executed spreads its particles with (--nav2-params): calibration
    fits the information share alone."""
    pytest.importorskip("amcl", reason=NEEDS_AMCL)
    doc = yaml.safe_load((ROOT / "configs" / "office-ros.yaml").read_text())
    doc["map"]["ros"] = str(ROOT / "configs" / doc["map"]["ros"])
    doc["models"]["range_sensor"]["localiser"] = {
        "model": "amcl",
        "prediction_noise": {"alpha1": 0.1},
        "heading_blur": 0.08,
    }
    scenario_file, params, out = tmp_path / "s.yaml", tmp_path / "nav2.yaml", tmp_path / "fit.yaml"
    scenario_file.write_text(yaml.safe_dump(doc))
    alphas = {"alpha1": 0.3, "alpha2": 0.1, "alpha3": 0.25, "alpha4": 0.05}
    params.write_text(yaml.safe_dump({"amcl": {"ros__parameters": alphas}}))
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "tmpnav",
            "calibrate",
            str(scenario_file),
            *("--nav2-params", str(params), "--sessions", "1", "--rounds", "1"),
            *("--workers", "1", "-q", "-o", str(out)),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    line = next(line for line in out.read_text().splitlines() if line.startswith("localiser:"))
    localiser = yaml.safe_load(line)["localiser"]
    assert localiser["prediction_noise"] == {"alpha1": 0.1, "alpha2": 0.2, "alpha3": 0.2, "alpha4": 0.2}
    assert localiser["heading_blur"] == 0.08
    doc["models"]["range_sensor"]["localiser"] = localiser
    scenario_file.write_text(yaml.safe_dump(doc))
    sensor = load(scenario_file).models.range_sensor
    assert sensor is not None and sensor.localiser.prediction_noise == (0.1, 0.2, 0.2, 0.2)
