"""The Python API (tmpnav.api, re-exported lazily by tmpnav): load, plan, read, export."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import tmpnav
from tmpnav.errors import ScenarioError

ROOT = Path(__file__).resolve().parent.parent
TWO_ROOMS = ROOT / "tests" / "fixtures" / "two_rooms.yaml"


def test_import_tmpnav_stays_light() -> None:
    code = "import sys, tmpnav; print(sorted(m for m in ('tmpnav.api', 'numpy', 'scipy') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
    assert callable(tmpnav.plan) and tmpnav.plan is tmpnav.api.plan
    with pytest.raises(AttributeError):
        _ = tmpnav.no_such_thing  # type: ignore[attr-defined]


def test_load_checks_the_scenario(tmp_path: Path) -> None:
    scenario = tmpnav.load(TWO_ROOMS)
    assert [r.name for r in scenario.rooms] == ["A", "B", "C"]
    bad = tmp_path / "bad.yaml"
    bad.write_text(TWO_ROOMS.read_text().replace("r1: [B]", "r1: [Z]"))
    with pytest.raises(ScenarioError, match="'Z' is not a room"):
        tmpnav.load(bad)


@pytest.mark.slow
def test_plan_read_save_and_export(tmp_path: Path) -> None:
    result = tmpnav.plan(TWO_ROOMS, cache_dir=tmp_path / "cache", workers=1)
    # the two robots swap rooms through one door: kept apart by a sidestep, no longer the planner's optimum
    assert result.status == "solved-satisficing" and result.document()["risk"]["kept_apart"]["conflicts_left"] == 0
    assert result.scenario.name == "two-rooms"
    assert result.planner_cost == pytest.approx(sum(s.planner_cost for s in result.steps))
    assert result.resimulated_cost == pytest.approx(sum(s.resimulated_cost for s in result.steps))
    moved = {m[0]: m[2] for s in result.steps for m in s.moves}
    assert moved == {"r1": "B", "r2": "A"}
    assert all(len(s.goal_poses) == len(s.robots) for s in result.steps)
    assert set(result.trajectories) == {"r1", "r2"}
    # what the summary reports, from the result: the makespan, the objective in its units, the
    # collision bound, the largest std (plan.json's definition), conflicts left and warnings
    doc = result.document()
    assert result.makespan == doc["schedule"]["makespan"]
    assert result.objective == (doc["objective"]["name"], doc["objective"]["resimulated"], doc["objective"]["units"])
    assert result.risk == pytest.approx(doc["risk"]["plan"], abs=1e-9)  # plan.json rounds to 1e-9
    assert result.largest_move_risk == pytest.approx(doc["risk"]["largest_move"], abs=1e-9)
    assert result.largest_std == pytest.approx(doc["risk"]["largest_std"])
    assert result.conflicts == [] and doc["risk"]["conflicts"] == []
    assert isinstance(result.warnings, list) and all(isinstance(w, str) for w in result.warnings)
    written = result.save(tmp_path / "out")
    assert [p.name for p in written] == ["plan.json", "plan.png", "schedule.png"]
    doc = json.loads((tmp_path / "out" / "plan.json").read_text())
    assert doc["cost"]["planner"] == result.planner_cost
    waypoints = result.waypoints()
    assert waypoints["r1"][-1].room == "B" and waypoints["r1"][0].kind == "start"
    from_file = tmpnav.export_nav2(tmp_path / "out" / "plan.json", tmp_path / "nav2")
    from_result = result.export_nav2(tmp_path / "nav2-again")
    assert [p.read_text() for p in from_file] == [p.read_text() for p in from_result]


def test_segment_map_and_write_skeleton(tmp_path: Path) -> None:
    proposal = tmpnav.segment_map(ROOT / "configs" / "office" / "office.yaml", max_rooms=4)
    assert len(proposal.rooms) == 4
    path = tmpnav.write_skeleton(proposal, tmp_path / "office.yaml")
    scenario = tmpnav.load(path)
    assert scenario.name == "office" and len(scenario.rooms) == 4


def test_a_path_under_configs_names_a_shipped_file_from_any_directory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # no configs/ here: the shipped scenario and map are used
    assert tmpnav.load("configs/two-rooms.yaml").name == tmpnav.load(ROOT / "configs" / "two-rooms.yaml").name
    assert len(tmpnav.segment_map("configs/office/office.yaml").rooms) == 8


def beside_the_clone(tmp_path: Path) -> Path:
    """A folder that holds the clone under the name a `git clone` gives it, tmpnav (a link here):
    Python puts the working directory first on sys.path, where that folder, with no __init__.py,
    is a namespace package named tmpnav."""
    (tmp_path / "tmpnav").symlink_to(ROOT, target_is_directory=True)
    return tmp_path


def test_import_tmpnav_from_the_folder_that_holds_the_clone(tmp_path: Path) -> None:
    code = "import tmpnav; print(tmpnav.__file__); print(tmpnav.load('configs/two-rooms.yaml').name)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=beside_the_clone(tmp_path))
    assert proc.returncode == 0, (
        f"{proc.stderr}\n(the clone folder was imported as tmpnav: is .venv's tmpnav-checkout.pth missing? "
        "`make` writes it, docs/usage.md 'Python API')"
    )
    found, name = proc.stdout.split()
    assert Path(found).resolve() == ROOT / "tmpnav" / "__init__.py" and name == "two-rooms"


@pytest.mark.slow
def test_the_readme_snippet_runs_outside_the_checkout(tmp_path: Path) -> None:
    """docs/usage.md's "Python API" block, as a user pastes it, in a directory that is not the
    checkout but holds it: the folder a `git clone` was run in."""
    readme = (ROOT / "docs" / "usage.md").read_text(encoding="utf-8")
    snippet = re.search(r"## Python API\n\n```python\n(.*?)```", readme, re.S)
    assert snippet is not None
    env = {**os.environ, "TMPNAV_CACHE_DIR": str(tmp_path / "cache")}
    cwd = beside_the_clone(tmp_path)
    proc = subprocess.run(
        [sys.executable, "-c", snippet[1]], capture_output=True, text=True, cwd=cwd, env=env, timeout=600
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("solved-satisficing ")  # the corridor's swap, kept apart by a detour
    assert (tmp_path / "out" / "plan.json").is_file() and (tmp_path / "out" / "nav2" / "r1.csv").is_file()
    assert len(tmpnav.load(tmp_path / "office-rooms.yaml").rooms) == 8
