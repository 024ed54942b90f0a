"""plan.png: a valid, non-blank image of the plan, and the choices behind it."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from tmpnav.report.plan_plot import at_most, ellipse_spacing, ellipse_steps, goal_steps, plan_extent, plot_plan
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


@pytest.mark.slow
def test_each_robots_ellipses_in_its_own_colour(plan_report: Any) -> None:
    from matplotlib.colors import to_rgb
    from matplotlib.patches import Ellipse

    from tmpnav.report.figures import darker, robot_color
    from tmpnav.report.plan_plot import plan_figure

    fig = plan_figure(plan_report)
    edges = {tuple(round(c, 3) for c in p.get_edgecolor()[:3]) for p in fig.axes[0].patches if isinstance(p, Ellipse)}
    for index in range(2):
        assert tuple(round(c, 3) for c in darker(robot_color(index))) in edges
        assert tuple(round(c, 3) for c in to_rgb("#e41a1c")) not in edges  # the one red edge of every robot


@pytest.mark.slow
def test_the_plan_says_when_and_in_what_units(plan_report: Any) -> None:
    from tmpnav.report.plan_plot import arrivals, plan_figure

    ax = plan_figure(plan_report).axes[0]
    title = ax.get_title()
    makespan = plan_report.schedule.makespan
    assert "cost (unit-less)" in title and f", makespan {makespan:.1f} s (all robots at once)," in title
    found = arrivals(plan_report)
    assert [(a.step, a.robot) for a in found] == [(a.index, m[0]) for a in plan_report.actions for m in a.moves]
    # each badge's time is when the robot's move ends on the shared clock, the schedule's
    ends = {(m.step + 1, m.robot): m.end for m in plan_report.schedule.moves}
    assert [a.t for a in found] == [ends[(a.step, a.robot)] for a in found]
    assert max(a.t for a in found if a.t is not None) == makespan
    # and the robot's belief is at the goal node then
    for a in found:
        at = next(s for s in plan_report.trajectories[a.robot] if abs(s.t - a.t) < 1e-6)
        action = plan_report.actions[a.step - 1]
        assert at.node == action.paths[[m[0] for m in action.moves].index(a.robot)][-1]
    notes = {t.get_text() for t in ax.texts}
    # with the move's collision bound beside it
    assert all(f"{a.t:.1f} s, {at_most(a.risk)}" in notes for a in found)
    assert "collision bound: plan" in title


def test_room_names_that_would_stick_out_of_a_cropped_view_are_hidden() -> None:
    import matplotlib.pyplot as plt

    from tmpnav.report.labels import ROOM_LABEL, keep_labels_inside

    fig, ax = plt.subplots(figsize=(4, 3))
    ax.set_xlim(0, 10)
    ax.set_ylim(0, 10)
    ax.set_aspect("equal")
    inside = ax.text(1, 9, "L1", fontsize=11, va="top", gid=ROOM_LABEL)
    edge = ax.text(9.8, 9, "L3", fontsize=11, va="top", gid=ROOM_LABEL)
    other = ax.text(9.8, 5, "not a room name", gid="note")
    keep_labels_inside(ax)
    assert inside.get_visible() and not edge.get_visible() and other.get_visible()
    plt.close(fig)


def _square_axes(size: tuple[float, float]) -> tuple[Any, Any]:
    """A figure of ``size`` inches with axes over [0, 10] x [0, 10], equal aspect."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=size)
    ax.set_xlim(0, 10)
    ax.set_ylim(0, 10)
    ax.set_aspect("equal")
    return fig, ax


def test_a_badges_note_that_would_run_out_of_the_axes_goes_to_its_other_side() -> None:
    """Past the right edge it would run under the legend beside the map, below the bottom off
    the figure: there it is put to the badge's left, or above it; elsewhere it stays."""
    import matplotlib.pyplot as plt

    from tmpnav.report.figures import badge_note
    from tmpnav.report.labels import keep_labels_inside

    fig, ax = _square_axes((8, 6))
    for xy in ((2, 8), (9.6, 8), (2, 0.3), (9.6, 0.3)):
        badge_note(ax, xy, "227.5 s, p≤0.0023", "#1f77b4")
    keep_labels_inside(ax)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    box = ax.get_window_extent(renderer)
    notes = list(ax.texts)
    assert all(note.get_visible() for note in notes)
    for note in notes:
        extent = note.get_window_extent(renderer)
        assert box.x0 <= extent.x0 and extent.x1 <= box.x1 and box.y0 <= extent.y0 and extent.y1 <= box.y1
    assert notes[0].get_horizontalalignment() == "left" and notes[0].get_verticalalignment() == "top"
    assert notes[1].get_horizontalalignment() == "right" and notes[2].get_verticalalignment() == "bottom"
    assert notes[3].get_horizontalalignment() == "right" and notes[3].get_verticalalignment() == "bottom"
    plt.close(fig)


def test_notes_that_would_cover_each_other_take_both_sides_then_are_left_out() -> None:
    import matplotlib.pyplot as plt

    from tmpnav.report.figures import badge_note
    from tmpnav.report.labels import keep_labels_inside

    fig, ax = _square_axes((4, 3))
    for xy in ((5, 5), (5.1, 5), (5.2, 5), (2, 8)):
        badge_note(ax, xy, "227.5 s, p≤0.0023", "#1f77b4")
    keep_labels_inside(ax)
    first, second, third, apart = ax.texts
    assert first.get_visible() and first.get_horizontalalignment() == "left"
    assert second.get_visible() and second.get_horizontalalignment() == "right"  # the badge's other side
    assert not third.get_visible() and apart.get_visible()
    plt.close(fig)


def test_a_fleets_robots_that_share_a_colour_differ_in_their_line() -> None:
    from tmpnav.report.figures import ROBOT_COLORS, robot_color, robot_line

    styles = [(robot_color(i), str(robot_line(i))) for i in range(4 * len(ROBOT_COLORS))]
    assert len(set(styles)) == len(styles)  # 32 robots, each its own colour and line
    assert all(robot_line(i) == "-" for i in range(len(ROBOT_COLORS)))  # a team of up to 8: solid lines


def test_start_ellipses_too_small_to_see_are_magnified_and_the_title_says_so(tmp_path: Path) -> None:
    from tmpnav.pipeline import load_world
    from tmpnav.report import figures as fg

    root = Path(__file__).resolve().parents[2]
    scenario, _ = load_world(root / "configs" / "corridor.yaml")
    assert fg.start_sigma2(scenario.robots[0].cov) == pytest.approx(0.2)  # 2σ of 0.1 m: a few pixels over 50 m
    assert fg.start_magnification(scenario, 50.0) == 4 and fg.start_magnification(scenario, 5.0) == 1
    from tmpnav.report.world_plot import _robots_and_rooms

    assert "2 robots (2σ start ellipses: r1 0.20 m, r2 0.20 m, drawn 4x)" in _robots_and_rooms(scenario, 4)


def test_robot_names_that_would_cover_each_other_go_below_then_are_left_out() -> None:
    """A fleet queued at a corridor's end: each robot's name above its start, the next below it
    where it would cover a name, and left out where it covers one there too."""
    import matplotlib.pyplot as plt

    from tmpnav.report.labels import ROBOT_NAME, keep_labels_inside

    fig, ax = _square_axes((4, 3))
    names = [
        ax.annotate(name, xy, xytext=(8, 8), textcoords="offset points", fontsize=11, weight="bold", gid=ROBOT_NAME)
        for name, xy in (("r5", (5.0, 5.0)), ("r11", (5.2, 5.0)), ("r17", (5.4, 5.0)), ("r1", (1.0, 9.0)))
    ]
    keep_labels_inside(ax)
    first, second, third, apart = names
    assert first.get_visible() and first.xyann == (8, 8)
    assert second.get_visible() and second.xyann == (8, -8)  # below its start
    assert not third.get_visible() and apart.get_visible()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    shown = [n.get_window_extent(renderer) for n in names if n.get_visible()]
    assert not any(a.overlaps(b) for i, a in enumerate(shown) for b in shown[i + 1 :])
    plt.close(fig)
