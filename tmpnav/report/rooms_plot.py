"""``tmpnav rooms -o rooms.png``: the segmentation over the map, to check it before planning.

Each room's and place's cells in a colour of its own under its outline (the polygon written to
the scenario), with its name at its spot (below a placeholder robot standing there); halls
outlined thick, with their names; doors from jamb to jamb, connections between the places of a
hall dashed; landmark candidates by kind; the placeholder robots. Rooms no robot reaches from
the placeholder are hatched.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon

from tmpnav.report import figures as fg
from tmpnav.rooms.proposal import ROBOT_RADIUS, Proposal

KIND_MARKERS = {"pillar": "o", "obstacle": "s", "door-frame": "P", "corner": "^"}
LABEL_BELOW_ROBOT = 18.0  # points: a room's name drawn this far below a robot standing on its spot
DOOR_COLOUR = "#268bd2"
LINK_COLOUR = "#073642"
HALL_COLOUR = "#6c3483"


def plot_rooms(proposal: Proposal, path: Path, title: str) -> None:
    """Write the segmentation figure (PNG) to ``path``, atomically."""
    xmin, ymin, xmax, ymax = fg.free_extent(proposal.grid)
    aspect = (ymax - ymin) / max(xmax - xmin, 1e-9)
    width = 12.0 if aspect < 1.2 else max(5.0, 9.0 / aspect)
    fig, ax = fg.subplots((width, max(3.5, width * aspect + 1.2)))
    _draw_segmentation(ax, proposal)
    _draw_halls(ax, proposal)
    robots = [r.pose[:2] for r in proposal.robots]
    points_per_m = fig.get_figwidth() * 72 * ax.get_position().width / max(xmax - xmin, 1e-9)
    _draw_rooms(ax, proposal, robots, max(LABEL_BELOW_ROBOT, ROBOT_RADIUS * points_per_m + 6))
    _draw_doors_and_landmarks(ax, proposal)
    for k, robot in enumerate(proposal.robots):
        x, y, _ = robot.pose
        ax.add_patch(Circle((x, y), ROBOT_RADIUS, color=fg.robot_color(k), zorder=7))
        ax.annotate(
            robot.name, (x, y), xytext=(7, 7), textcoords="offset points", color=fg.robot_color(k), weight="bold"
        )
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    _legend(ax, proposal)
    fg.save(fig, path)


def _draw_segmentation(ax: Axes, proposal: Proposal) -> None:
    """The map in greys, each room's cells in a colour of its own over it."""
    import matplotlib

    gx0, gy0, gx1, gy1 = proposal.grid.extent
    extent = (gx0, gx1, gy0, gy1)
    ax.imshow(
        proposal.grid.occupied,
        cmap="Greys",
        vmin=0,
        vmax=1.25,
        zorder=0,
        origin="lower",
        extent=extent,
        interpolation="nearest",
    )
    labels = proposal.segmentation.labels
    lx0, ly0, lx1, ly1 = proposal.segmentation.grid.extent  # the part of the map segmented
    n = max(int(labels.max()), 1)
    palette = matplotlib.colormaps["tab20"](np.arange(n) % 20)
    colours = ListedColormap(np.vstack([[0, 0, 0, 0], palette]))  # label k gets colour k, 0 none
    masked = np.ma.masked_equal(labels, 0)
    ax.imshow(
        masked,
        cmap=colours,
        vmin=-0.5,
        vmax=n + 0.5,
        alpha=0.45,
        zorder=1,
        origin="lower",
        extent=(lx0, lx1, ly0, ly1),
        interpolation="nearest",
    )


def _draw_halls(ax: Axes, proposal: Proposal) -> None:
    """Each hall's outline, thick, and its name just inside its upper left corner (the legend
    says how large it is and how many places it was split into)."""
    for hall in proposal.halls:
        ax.add_patch(Polygon(hall.polygon, closed=True, fill=False, ec=HALL_COLOUR, lw=3.0, zorder=3))
        corner = hall.polygon[np.argmax(hall.polygon[:, 1] - hall.polygon[:, 0] * 1e-3)]
        ax.annotate(
            hall.name,
            corner,
            xytext=(5, -5),
            textcoords="offset points",
            ha="left",
            va="top",
            fontsize=9,
            color=HALL_COLOUR,
            weight="bold",
            zorder=6,
        )


def _draw_rooms(ax: Axes, proposal: Proposal, robots: list[tuple[float, float]], below: float) -> None:
    """Outlines (hatched: left out, unreachable) and names at the spots; where a robot stands
    on that spot, the name goes ``below`` points below it so that the robot does not hide it."""
    for room in proposal.rooms:
        hatch = None if room.reachable else "//"
        lw = 0.6 if room.hall else 1.0
        ax.add_patch(Polygon(room.polygon, closed=True, fill=False, ec="black", lw=lw, zorder=2, hatch=hatch))
        label = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.8}
        under = any(math.dist(room.spot, xy) < 3 * ROBOT_RADIUS for xy in robots)
        ax.annotate(
            room.name,
            room.spot,
            xytext=(0.0, -below if under else 0.0),
            textcoords="offset points",
            ha="center",
            va="top" if under else "center",
            fontsize=9 if room.hall else 10,
            weight="bold",
            zorder=6,
            bbox=label,
        )


def _draw_doors_and_landmarks(ax: Axes, proposal: Proposal) -> None:
    for name, door in proposal.doors.items():
        (x0, y0), (x1, y1) = door.segment
        if name in proposal.connections:
            ax.plot([x0, x1], [y0, y1], color=LINK_COLOUR, lw=1.6, ls=(0, (3, 2)), zorder=4)
            continue
        ax.plot([x0, x1], [y0, y1], color=DOOR_COLOUR, lw=3.0, solid_capstyle="butt", zorder=4)
        ax.annotate(name, door.centre, xytext=(4, 4), textcoords="offset points", fontsize=7, color=DOOR_COLOUR)
    for kind, marker in KIND_MARKERS.items():
        xy = np.array([lm.position for lm in proposal.landmarks.values() if lm.kind == kind]).reshape(-1, 2)
        if xy.size:
            ax.plot(
                xy[:, 0],
                xy[:, 1],
                marker,
                label=f"{kind} ({xy.shape[0]})",
                ms=8,
                mfc="#ff7f0e",
                mec="black",
                mew=0.7,
                ls="none",
                zorder=5,
            )


def _legend(ax: Axes, proposal: Proposal) -> None:
    """The landmark candidates by kind; on a map with halls, first the doors, the connections
    and each hall with its size and places."""
    if not proposal.halls:
        ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=9, title="landmark candidates", frameon=False)
        return
    links = len(proposal.connections)
    handles: list = [
        Line2D([], [], color=DOOR_COLOUR, lw=3.0, label=f"door ({len(proposal.doors) - links})"),
        Line2D([], [], color=LINK_COLOUR, lw=1.6, ls=(0, (3, 2)), label=f"connection ({links})"),
    ]
    for hall in proposal.halls:
        label = f"{hall.name}: hall of {hall.area:.0f} m², {len(hall.places)} places"
        handles.append(Line2D([], [], color=HALL_COLOUR, lw=3.0, label=label))
    marks = ax.get_legend_handles_labels()[0]
    if marks:
        handles += [Line2D([], [], ls="none", label="landmark candidates:"), *marks]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=9, frameon=False)
