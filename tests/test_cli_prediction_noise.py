"""The planned beliefs predicted with AMCL's own motion model (localiser.prediction_noise), and far
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


def test_the_plan_predicts_with_amcls_motion_model_unless_the_scenario_names_other_alphas(tmp_path: Path) -> None:
    """By default (prediction_noise absent, or {}) AMCL's motion model, nav2's alphas of 0.2 each,
    spreads the planned beliefs; alphas of a robot's odometry (0.01 each) spread them far less: the
    summary says which, and the beliefs are narrower. A value out of range is one error line naming
    the key."""
    doc = four_rooms(1)
    doc["models"]["range_sensor"]["localiser"] = {"model": "amcl"}
    own, amcl = tmp_path / "own.yaml", tmp_path / "amcl.yaml"
    amcl.write_text(yaml.safe_dump(doc))
    with_model = copy.deepcopy(doc)
    with_model["models"]["range_sensor"]["localiser"]["prediction_noise"] = {f"alpha{k}": 0.01 for k in range(1, 5)}
    own.write_text(yaml.safe_dump(with_model))
    cache = tmp_path / "cache"
    plain = tmpnav("plan", str(own), "-q", "--accept-risk", "--cache-dir", str(cache), "-o", str(tmp_path / "a"))
    assert plain.returncode == 0, plain.stderr
    assert "predicting with AMCL's motion model (alpha1-4 0.01, 0.01, 0.01, 0.01: prediction_noise)" in plain.stdout
    spread = tmpnav("plan", str(amcl), "-q", "--accept-risk", "--cache-dir", str(cache), "-o", str(tmp_path / "b"))
    assert spread.returncode == 0, spread.stderr
    assert "predicting with AMCL's motion model (alpha1-4 0.2, 0.2, 0.2, 0.2: prediction_noise)" in spread.stdout
    assert widest_std(tmp_path / "b") > 1.2 * widest_std(tmp_path / "a")
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
