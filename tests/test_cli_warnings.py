"""Warnings a run that exits 0 prints on stderr (issue 57): a ROS map whose robots carry no range
sensor, and a plan that leaves robots in each other's way."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.test_cli_plan import ROOT, tmpnav


@pytest.fixture(scope="module")
def office_without_models(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """office-ros with its models: section deleted (by mistake, as the issue found it)."""
    folder = tmp_path_factory.mktemp("office")
    shutil.copytree(ROOT / "configs" / "office", folder / "office")
    text = (ROOT / "configs" / "office-ros.yaml").read_text()
    kept = [line for line in text.splitlines() if not line.startswith(("models:", "  range_sensor:"))]
    assert len(kept) == len(text.splitlines()) - 2
    path = folder / "office-nomodels.yaml"
    path.write_text("\n".join(kept) + "\n")
    return path


def test_validate_warns_of_a_ros_map_without_a_range_sensor(office_without_models: Path) -> None:
    """It validated "ok" and said nothing; the plan then had bounds of 1 and 10 m spreads."""
    proc = tmpnav("validate", str(office_without_models), cwd=office_without_models.parent)
    assert proc.returncode == 0, proc.stderr
    assert ": ok: 7 rooms" in proc.stdout
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("warning: office-nomodels.yaml") and "models.range_sensor" in lines[0]
    assert "add 'models: {range_sensor: {}}'" in lines[0]


def test_a_ros_map_with_a_range_sensor_validates_without_warning() -> None:
    proc = tmpnav("validate", str(ROOT / "configs" / "office-ros.yaml"))
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr


def test_validate_warns_of_a_robot_that_starts_nearer_the_walls_than_its_std(tmp_path: Path) -> None:
    """office-ros' r2 stood 5 cm from clutter in the corridor: under the AMCL model every move
    from there was over the chance constraint, and the plan left r2 idle in r1's way."""
    shutil.copytree(ROOT / "configs" / "office", tmp_path / "office")
    text = (ROOT / "configs" / "office-ros.yaml").read_text()
    near = text.replace("{name: r2, pose: [12.0, 6.8, 0.0]}", "{name: r2, pose: [12.0, 7.2, 0.0]}")
    assert near != text
    (tmp_path / "near.yaml").write_text(near)
    proc = tmpnav("validate", "near.yaml", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith("warning: near.yaml:24: robots.r2.pose: r2 starts 0.05 m from the map's walls")
    assert "less than 1 std of its initial position (0.10 m)" in line and "0.05 m further clear" in line


@pytest.mark.slow
def test_a_plan_with_robots_in_each_others_way_says_so_on_stderr(tmp_path: Path) -> None:
    """The paper's corridor plan sends r1 and r2 head-on through each other; without a chance
    constraint (the paper's model) it is not refused, and exited 0 with the conflict only in the
    summary on stdout."""
    proc = tmpnav(
        "plan", str(ROOT / "configs" / "corridor.yaml"), "--costs", "table", "--no-keep-apart", "-q",
        "--cache-dir", str(tmp_path),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "robots in each other's way: 1, the first:" in proc.stdout
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("warning: the plan leaves robots in each other's way: r1 and r2 at ")
    assert "--keep-apart keeps robots apart" in lines[0]


@pytest.mark.slow
def test_a_revision_with_robots_in_each_others_way_says_so_on_stderr(tmp_path: Path) -> None:
    """tmpnav replan warns as tmpnav plan does: the corridor's head-on plan revised at its start."""
    corridor = str(ROOT / "configs" / "corridor.yaml")
    options = ("--costs", "table", "--no-keep-apart", "-q", "--cache-dir", str(tmp_path / "cache"))
    proc = tmpnav("plan", corridor, *options, "-o", str(tmp_path / "first"))
    assert proc.returncode == 0, proc.stderr
    (tmp_path / "state.yaml").write_text("time: 0\n")
    proc = tmpnav(
        "replan", corridor, "--plan", str(tmp_path / "first" / "plan.json"), "--state", str(tmp_path / "state.yaml"),
        *options,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    warnings = [line for line in proc.stderr.splitlines() if line.startswith("warning: ")]
    head_on = "warning: the plan leaves robots in each other's way: r1 and r2 at "
    assert any(line.startswith(head_on) for line in warnings), proc.stderr
