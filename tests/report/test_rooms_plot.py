"""The segmentation figure of ``tmpnav rooms``."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import pytest
from matplotlib.figure import Figure
from matplotlib.patches import Circle

import tmpnav
from tmpnav.report import rooms_plot

OFFICE_MAP = Path(__file__).resolve().parents[2] / "configs" / "office" / "office.yaml"


def test_every_room_name_is_visible_next_to_the_robot(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The placeholder robot stands on its room's roomiest spot, where the room's name goes:
    the name is drawn below the robot, not hidden under it."""
    proposal = tmpnav.segment_map(OFFICE_MAP)
    figures: list[Figure] = []
    monkeypatch.setattr(rooms_plot.fg, "save", lambda fig, path: figures.append(fig))
    rooms_plot.plot_rooms(proposal, tmp_path / "rooms.png", "office")
    (fig,) = figures
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    (ax,) = fig.axes
    (robot,) = [p for p in ax.patches if isinstance(p, Circle)]
    names = {t.get_text(): t for t in ax.texts}
    assert set(names) >= {r.name for r in proposal.rooms}
    hub = next(r for r in proposal.rooms if r.spot == proposal.robot_pose[:2])  # the robot's room
    assert not names[hub.name].get_window_extent(renderer).overlaps(robot.get_window_extent(renderer))
    others = [r for r in proposal.rooms if r is not hub]
    assert all(names[r.name].xyann == (0.0, 0.0) for r in others)  # the others stay on their spots
