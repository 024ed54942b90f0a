"""Where a figure's labels go once the axes are laid out: room names inside the view, a step
badge's note beside its badge, a robot's name beside its start, none on top of another.

Each label carries a gid saying what it is (:data:`ROOM_LABEL`, :data:`BADGE_NOTE`,
:data:`ROBOT_NAME`); :func:`keep_labels_inside` places them all, after the figure's drawing and
before it is rendered (tmpnav.report.plan_plot).
"""

from __future__ import annotations

from matplotlib.axes import Axes
from matplotlib.backend_bases import RendererBase
from matplotlib.text import Annotation
from matplotlib.transforms import Bbox

ROOM_LABEL = "room-label"  # gid of the room names
BADGE_NOTE = "badge-note"  # gid of the notes beside the step badges
ROBOT_NAME = "robot-name"  # gid of the robots' names beside their start poses
#: points from a step badge's centre to the corner of its note
NOTE_OFFSET = 9


def keep_labels_inside(ax: Axes) -> None:
    """Hide the room names that do not fit wholly inside the axes (a room at the edge of a
    cropped view): a name cut in half reads as another name. Move a badge's note that would run
    out of the axes (over the legend beside them, or off the figure) or over another note to the
    badge's other side, and leave it out where it covers another there too (:func:`_place_note`).
    Move a robot's name that would cover another robot's below its start, and leave it out where
    it covers one there too (:func:`_place_name`)."""
    fig = ax.get_figure(root=True)
    if fig is None:
        return
    # the equal aspect shrinks the axes; applying it is all the layout the names need (a whole
    # draw, as fig.draw_without_rendering does, was a third of the time plan.png took)
    ax.apply_aspect()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    box = ax.get_window_extent(renderer).padded(-2.0)
    notes: list[Bbox] = []
    names: list[Bbox] = []
    for text in ax.texts:
        if text.get_gid() == BADGE_NOTE and isinstance(text, Annotation):
            _place_note(text, box, notes, renderer)
        if text.get_gid() == ROBOT_NAME and isinstance(text, Annotation):
            _place_name(text, names, renderer)
        if text.get_gid() != ROOM_LABEL:
            continue
        extent = text.get_window_extent(renderer)
        inside = box.x0 <= extent.x0 and extent.x1 <= box.x1 and box.y0 <= extent.y0 and extent.y1 <= box.y1
        text.set_visible(inside)


def _place_note(note: Annotation, box: Bbox, placed: list[Bbox], renderer: RendererBase) -> None:
    """A badge's note (tmpnav.report.figures.badge_note) past the right edge of ``box`` put to its
    badge's left, one past the bottom put above it (the note's offset mirrored about the badge);
    one that would then cover a note ``placed`` before it tried on the badge's other side, and
    left out where it covers one there too (a fleet's badges crowd: schedule.png gives every
    arrival's time)."""
    extent = note.get_window_extent(renderer)
    dx, dy = note.xyann
    if extent.x1 > box.x1:
        dx = dx - 2 * NOTE_OFFSET
        note.set_horizontalalignment("right")
    if extent.y0 < box.y0:
        dy = dy + 2 * NOTE_OFFSET
        note.set_verticalalignment("bottom")
    note.xyann = (dx, dy)
    extent = note.get_window_extent(renderer)
    if any(extent.overlaps(other) for other in placed):
        right = note.get_horizontalalignment() == "left"
        note.set_horizontalalignment("right" if right else "left")
        note.xyann = (dx - 2 * NOTE_OFFSET if right else dx + 2 * NOTE_OFFSET, dy)
        extent = note.get_window_extent(renderer)
        inside = box.x0 <= extent.x0 and extent.x1 <= box.x1
        if not inside or any(extent.overlaps(other) for other in placed):
            note.set_visible(False)
            return
    placed.append(extent)


def _place_name(name: Annotation, placed: list[Bbox], renderer: RendererBase) -> None:
    """A robot's name (tmpnav.report.figures.draw_robot_start, above its start) that would cover
    a name ``placed`` before it put below the start instead, and left out where it covers one
    there too: a fleet's robots queued a metre or two apart at a corridor's end (the legend
    gives each robot's line, the schedule each robot's moves)."""
    extent = name.get_window_extent(renderer)
    if any(extent.overlaps(other) for other in placed):
        dx, dy = name.xyann
        name.xyann = (dx, -dy)
        name.set_verticalalignment("top")
        extent = name.get_window_extent(renderer)
        if any(extent.overlaps(other) for other in placed):
            name.set_visible(False)
            return
    placed.append(extent)
