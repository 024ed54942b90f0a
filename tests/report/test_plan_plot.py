"""plan.png: a valid, non-blank image of the plan, and the choices behind it."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from tmpnav.report.plan_plot import ellipse_spacing, ellipse_steps, goal_steps, plan_extent, plot_plan
from tmpnav.types import TrajectoryStep

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def assert_png(path: Path) -> None:
    assert path.read_bytes()[:8] == PNG_MAGIC
    with Image.open(path) as image:
        image.verify()
    with Image.open(path) as image:
        width, height = image.size
        pixels = np.asarray(image.convert("RGB"))
    assert width >= 600 and height >= 400
    # not blank: the map, the trajectories and their colours are there
    assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 50


@pytest.mark.slow
@pytest.mark.parametrize("crop", [True, False])
def test_plot_plan_writes_a_png(plan_report: Any, tmp_path: Path, crop: bool) -> None:
    path = tmp_path / "figures" / "plan.png"
    plot_plan(plan_report, path, crop=crop)
    assert_png(path)
    assert os.listdir(path.parent) == ["plan.png"]  # no temporary file left


@pytest.mark.slow
def test_plot_uses_the_robot_colours(plan_report: Any, tmp_path: Path) -> None:
    from matplotlib.colors import to_rgb

    from tmpnav.report.figures import robot_color

    path = tmp_path / "plan.png"
    plot_plan(plan_report, path)
    with Image.open(path) as image:
        pixels = np.asarray(image.convert("RGB")).reshape(-1, 3).astype(int)
    for index in range(2):
        rgb = np.array([round(255 * c) for c in to_rgb(robot_color(index))])
        assert (np.abs(pixels - rgb).sum(axis=1) < 12).sum() > 100, f"robot {index} not drawn"


@pytest.mark.slow
def test_ellipses_at_start_goals_and_end(plan_report: Any) -> None:
    spacing = ellipse_spacing(plan_report)
    assert spacing >= 0.6
    for robot, steps in plan_report.trajectories.items():
        goals = goal_steps(plan_report, robot)
        chosen = ellipse_steps(steps, spacing, goals)
        assert chosen[0] == 0 and chosen[-1] == len(steps) - 1
        assert goals <= set(chosen)
        assert len(chosen) < len(steps)  # not every control step: the figure stays readable
        nodes = {steps[i].node for i in goals}
        moved = [p[-1] for a in plan_report.actions for m, p in zip(a.moves, a.paths, strict=True) if m[0] == robot]
        assert nodes == set(moved)


@pytest.mark.slow
def test_plan_extent_is_inside_the_map(plan_report: Any) -> None:
    xmin, ymin, xmax, ymax = plan_report.world.grid.extent
    box = plan_extent(plan_report)
    # the plan uses all three rooms of this small map: the figure shows the whole map
    assert box is None
    box = plan_extent(plan_report, margin=0.0, min_aspect=0.0)
    if box is not None:
        assert xmin <= box[0] < box[2] <= xmax and ymin <= box[1] < box[3] <= ymax


def test_ellipse_steps_skip_turning_on_the_spot() -> None:
    cov = ((0.01, 0.0, 0.0), (0.0, 0.01, 0.0), (0.0, 0.0, 0.001))
    still = [TrajectoryStep(0.5 * k, (0.0, 0.0, 0.1 * k), cov) for k in range(10)]
    moving = [TrajectoryStep(5.0 + 0.5 * k, (0.25 * k, 0.0, 0.0), cov) for k in range(1, 21)]
    chosen = ellipse_steps(still + moving, spacing=1.0)
    assert chosen[0] == 0 and chosen[-1] == 29
    assert not set(chosen) & set(range(1, 10))  # turning in place adds no ellipse
    assert np.diff([(still + moving)[i].mean[0] for i in chosen[1:]]).min() >= 1.0 - 1e-9
    assert ellipse_steps([], 1.0) == []
