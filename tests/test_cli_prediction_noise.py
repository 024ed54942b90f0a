"""The planned beliefs predicted with nav2's alphas (localiser.prediction_noise), and far
returns blurred by the cloud's heading spread (localiser.heading_blur), end to end."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.planning.test_safety import four_rooms
from tests.test_cli_plan import assert_clean_failure, tmpnav
from tmpnav.errors import ScenarioError

pytestmark = pytest.mark.slow


def widest_std(out: Path) -> float:
    """The largest position std (m, along the widest axis) over every robot's planned trajectory."""
    doc = json.loads((out / "plan.json").read_text())
    covs = np.array([p["cov"] for steps in doc["trajectories"].values() for p in steps])[:, :2, :2]
    return float(np.sqrt(np.linalg.eigvalsh(covs)[:, -1].max()))


def test_the_plan_predicts_with_the_fitted_alphas_unless_the_scenario_names_other_alphas(tmp_path: Path) -> None:
    """By default (prediction_noise absent) the fitted alphas of 0.03 each spread the planned
    beliefs; {} names nav2's own alphas, 0.2 each, the rate AMCL's cloud spreads at, and they spread
    the beliefs wider; alphas of a robot's odometry (0.01 each) spread them least: the summary says
    which. A value out of range is one error line naming the key."""
    doc = four_rooms(1)
    doc["models"]["range_sensor"]["localiser"] = {"model": "amcl"}
    widths = {}
    cache = tmp_path / "cache"
    for name, alphas, said in (
        ("own", {f"alpha{k}": 0.01 for k in range(1, 5)}, "0.01, 0.01, 0.01, 0.01"),
        ("fitted", None, "0.03, 0.03, 0.03, 0.03"),
        ("nav2", {}, "0.2, 0.2, 0.2, 0.2"),
    ):
        variant = copy.deepcopy(doc)
        if alphas is not None:
            variant["models"]["range_sensor"]["localiser"]["prediction_noise"] = alphas
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(variant))
        out = tmp_path / name
        run = tmpnav("plan", str(out) + ".yaml", "-q", "--accept-risk", "--cache-dir", str(cache), "-o", str(out))
        assert run.returncode == 0, run.stderr
        assert f"its drift predicted with nav2's alpha1-4 {said} (prediction_noise)" in run.stdout
        widths[name] = widest_std(out)
    assert widths["nav2"] > 1.2 * widths["fitted"] and widths["fitted"] > widths["own"]
    with_model = copy.deepcopy(doc)
    blurred = copy.deepcopy(doc)
    blurred["models"]["range_sensor"]["localiser"]["heading_blur"] = 0.1
    (tmp_path / "blur.yaml").write_text(yaml.safe_dump(blurred))
    blur = tmpnav("plan", str(tmp_path / "blur.yaml"), "-q", "--accept-risk", "--cache-dir", str(cache))
    assert blur.returncode == 0, blur.stderr
    assert "far returns blurred by a 0.1 rad heading spread (heading_blur)" in blur.stdout
    with_model["models"]["range_sensor"]["localiser"]["prediction_noise"] = {"alpha3": 3}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(with_model))
    refused = tmpnav("validate", str(bad))
    assert_clean_failure(refused, ScenarioError.exit_code, "models.range_sensor.localiser.prediction_noise.alpha3")
