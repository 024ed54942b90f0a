"""schedule.png: a Gantt chart of the plan's schedule, its marks where the schedule puts them."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.colors import to_rgb
from matplotlib.patches import Rectangle
from PIL import Image

from tmpnav.report import figures as fg
from tmpnav.report.schedule_plot import plot_schedule, schedule_figure
from tmpnav.results import Schedule, TimedMove

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def bars(ax: Axes) -> list[Rectangle]:
    """The rectangles drawn in the axes (moves, waits, idle bands), not the legend's."""
    return [p for p in ax.patches if isinstance(p, Rectangle)]


def at(ax: Axes, x0: float, x1: float, y: float) -> list[Rectangle]:
    """The rectangles spanning [x0, x1] on the row at ``y``."""
    return [
        r
        for r in bars(ax)
        if r.get_x() == pytest.approx(x0)
        and r.get_x() + r.get_width() == pytest.approx(x1)
        and r.get_y() < y < r.get_y() + r.get_height()
    ]


def texts(ax: Axes) -> list[str]:
    return [t.get_text() for t in ax.texts]


@pytest.mark.slow
def test_plot_schedule_writes_a_png(plan_report: Any, tmp_path: Path) -> None:
    path = tmp_path / "figures" / "schedule.png"
    plot_schedule(plan_report, path)
    assert path.read_bytes()[:8] == PNG_MAGIC
    with Image.open(path) as image:
        width, height = image.size
        pixels = np.asarray(image.convert("RGB")).reshape(-1, 3).astype(int)
    assert width >= 800 and height >= 200
    assert os.listdir(path.parent) == ["schedule.png"]  # no temporary file left
    for color in fg.robot_colors(["r1", "r2"]).values():  # each robot's bars in its colour
        rgb = np.array([round(255 * c) for c in to_rgb(color)])
        assert (np.abs(pixels - rgb).sum(axis=1) < 12).sum() > 1000


@pytest.mark.slow
def test_every_move_a_bar_in_its_robots_colour_on_its_row(plan_report: Any) -> None:
    ax = schedule_figure(plan_report).axes[0]
    rows = {label.get_text(): y for label, y in zip(ax.get_yticklabels(), ax.get_yticks(), strict=True)}
    assert list(rows) == ["r1", "r2"]  # the scenario's order, top to bottom
    colors = fg.robot_colors(["r1", "r2"])
    for move in plan_report.schedule.moves:
        (bar,) = at(ax, move.start, move.end, rows[move.robot])
        assert bar.get_facecolor()[:3] == pytest.approx(to_rgb(colors[move.robot]))
        # labelled with its room (and, where there is room, its plan step)
        assert any(t in (move.target, f"#{move.step + 1} {move.target}") for t in texts(ax))


@pytest.mark.slow
def test_waits_pairs_idle_and_makespan(plan_report: Any) -> None:
    """The test plan: r2 waits for r1, they start their paired step together, r1 is idle at the end."""
    ax = schedule_figure(plan_report).axes[0]
    rows = {label.get_text(): y for label, y in zip(ax.get_yticklabels(), ax.get_yticks(), strict=True)}
    schedule = plan_report.schedule
    (paired,) = [m for m in schedule.timeline("r2") if m.partner == "r1"]
    (wait,) = at(ax, paired.ready, paired.start, rows["r2"])
    assert wait.get_hatch() and "wait for r1" in texts(ax)
    # the two bars of the paired step are outlined in black and joined at their start
    partner = next(m for m in schedule.timeline("r1") if m.step == paired.step)
    for m in (paired, partner):
        (bar,) = at(ax, m.start, m.end, rows[m.robot])
        assert bar.get_edgecolor()[:3] == (0.0, 0.0, 0.0)
    lines = [(line.get_xdata(), line.get_ydata()) for line in ax.get_lines()]
    assert any(list(x) == [paired.start] * 2 and min(y) < rows["r2"] and max(y) > rows["r1"] for x, y in lines)
    # r1 idle after its last move, until the makespan
    last = max(m.end for m in schedule.timeline("r1"))
    (idle,) = at(ax, last, schedule.makespan, rows["r1"])
    assert idle.get_facecolor()[3] < 0.3 and "idle" in texts(ax)
    assert any(list(x) == [schedule.makespan] * 2 for x, _ in lines)
    assert f"makespan {schedule.makespan:.1f} s" in texts(ax)
    title = ax.get_title()
    assert f"makespan {schedule.makespan:.1f} s" in title and "objective cost" in title and "1 paired" in title


@pytest.mark.slow
def test_short_moves_no_moves_and_the_planners_makespan(plan_report: Any) -> None:
    """Moves too short for their labels are labelled beside them, a move of no length still
    shows, a robot without moves is idle all along, and the planner's makespan is marked when
    its schedule ends elsewhere."""
    moves = (
        TimedMove(0, "r1", "A", "C", None, 0.0, 0.0, 0.5),
        TimedMove(1, "r1", "C", "C", None, 0.5, 0.5, 0.5),
        TimedMove(2, "r1", "C", "B", None, 0.5, 4.0, 40.0),
    )
    schedule = Schedule(("r1", "r2"), moves)
    planned = Schedule(("r1", "r2"), (*moves[:2], dataclasses.replace(moves[2], end=44.0)))
    report = dataclasses.replace(
        plan_report, schedule=schedule, task=dataclasses.replace(plan_report.task, schedule=planned)
    )
    ax = schedule_figure(report).axes[0]
    rows = {label.get_text(): y for label, y in zip(ax.get_yticklabels(), ax.get_yticks(), strict=True)}
    short = next(t for t in ax.texts if t.get_text() == "C")
    assert short.get_position()[1] < rows["r1"] - 0.2  # above the bar (the rows grow downwards)
    assert any(list(line.get_xdata()) == [0.5, 0.5] for line in ax.get_lines())  # the move of no length
    (held,) = at(ax, 0.5, 4.0, rows["r1"])
    assert held.get_hatch() and "wait" in texts(ax)  # held back: no partner to wait for
    assert len(at(ax, 0.0, 40.0, rows["r2"])) == 1  # r2 idle all along
    assert "no moves: idle" in texts(ax)
    assert "planner's makespan 44.0 s" in texts(ax) and "makespan 40.0 s" in texts(ax)
    assert ax.get_xlim()[1] >= 44.0


@pytest.mark.slow
def test_plan_and_schedule_figures_colour_robots_alike(plan_report: Any) -> None:
    from tmpnav.report.plan_plot import plan_figure

    plan_ax = plan_figure(plan_report).axes[0]
    line_colors = {to_rgb(line.get_color()) for line in plan_ax.get_lines()}
    ax = schedule_figure(plan_report).axes[0]
    for label in ax.get_yticklabels():
        assert to_rgb(label.get_color()) in line_colors
