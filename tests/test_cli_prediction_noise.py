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


def test_the_plan_predicts_with_amcls_motion_model_when_the_scenario_names_it(tmp_path: Path) -> None:
    """Without prediction_noise the robots' own motion noise spreads their planned beliefs; with
    it ({} is nav2's defaults, 0.2 each) AMCL's, far larger: the summary says so and the beliefs
    are wider. A value out of range is one error line naming the key."""
    doc = four_rooms(1)
    doc["models"]["range_sensor"]["localiser"] = {"model": "amcl"}
    own, amcl = tmp_path / "own.yaml", tmp_path / "amcl.yaml"
    own.write_text(yaml.safe_dump(doc))
    with_model = copy.deepcopy(doc)
    with_model["models"]["range_sensor"]["localiser"]["prediction_noise"] = {}
    amcl.write_text(yaml.safe_dump(with_model))
    cache = tmp_path / "cache"
    plain = tmpnav("plan", str(own), "-q", "--accept-risk", "--cache-dir", str(cache), "-o", str(tmp_path / "a"))
    assert plain.returncode == 0, plain.stderr
    assert "AMCL's motion model" not in plain.stdout
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
