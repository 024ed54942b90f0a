"""``tmpnav calibrate``: the localiser's failure rate it counts beside the information share.

The rate's limits are the exact Poisson ones; the scenario's rate stays where the count agrees
with it and moves to the upper limit where the count rejects it; the command writes a
localiser line that a scenario takes back.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tests.execution.test_amcl import NEEDS_AMCL
from tmpnav.belief.intervals import rate_limits
from tmpnav.execution.calibrate import Failures
from tmpnav.scenario import load
from tmpnav.types import NAV2_AMCL

ROOT = Path(__file__).resolve().parents[2]


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
