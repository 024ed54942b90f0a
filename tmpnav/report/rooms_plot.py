"""``tmpnav rooms -o rooms.png``: the segmentation over the map, to check it before planning.

Each room's cells in a colour of its own under its outline (the polygon written to the
scenario), with its name at its roomiest spot (below the placeholder robot, which stands at
the roomiest spot of its room); doors from jamb to jamb; landmark candidates by kind; the
placeholder robot. Rooms no robot reaches from the placeholder are hatched.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.patches import Circle, Polygon

from tmpnav.report import figures as fg
from tmpnav.rooms.proposal import ROBOT_RADIUS, Proposal

KIND_MARKERS = {"pillar": "o", "obstacle": "s", "door-frame": "P", "corner": "^"}
LABEL_BELOW_ROBOT = 18.0  # points: a room's name drawn this far below a robot standing on its spot


def plot_rooms(proposal: Proposal, path: Path, title: str) -> None:
    """Write the segmentation figure (PNG) to ``path``, atomically."""
    import matplotlib.pyplot as plt

    xmin, ymin, xmax, ymax = fg.free_extent(proposal.grid)
    aspect = (ymax - ymin) / max(xmax - xmin, 1e-9)
    width = 12.0 if aspect < 1.2 else max(5.0, 9.0 / aspect)
    fig, ax = plt.subplots(figsize=(width, max(3.5, width * aspect + 1.2)))
    _draw_segmentation(ax, proposal)
    _draw_rooms(ax, proposal, proposal.robot_pose[:2])
    _draw_doors_and_landmarks(ax, proposal)
    x, y, _ = proposal.robot_pose
    ax.add_patch(Circle((x, y), ROBOT_RADIUS, color=fg.robot_color(0), zorder=7))
    ax.annotate("r1", (x, y), xytext=(7, 7), textcoords="offset points", color=fg.robot_color(0), weight="bold")
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=9, title="landmark candidates", frameon=False)
    fg.save(fig, path)


def _draw_segmentation(ax: Axes, proposal: Proposal) -> None:
    """The map in greys, each room's cells in a colour of its own over it."""
    import matplotlib.pyplot as plt

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
    n = max(int(labels.max()), 1)
    palette = plt.get_cmap("tab20")(np.arange(n) % 20)
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
        extent=extent,
        interpolation="nearest",
    )


def _draw_rooms(ax: Axes, proposal: Proposal, robot_xy: tuple[float, float]) -> None:
    """Outlines (hatched: left out, unreachable) and names at the roomiest spots; where the
    robot stands on that spot, the name goes below it so that the robot does not hide it."""
    for room in proposal.rooms:
        hatch = None if room.reachable else "//"
        ax.add_patch(Polygon(room.polygon, closed=True, fill=False, ec="black", lw=1.0, zorder=2, hatch=hatch))
        label = {"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.8}
        under = math.dist(room.spot, robot_xy) < 3 * ROBOT_RADIUS
        ax.annotate(
            room.name,
            room.spot,
            xytext=(0.0, -LABEL_BELOW_ROBOT if under else 0.0),
            textcoords="offset points",
            ha="center",
            va="top" if under else "center",
            fontsize=10,
            weight="bold",
            zorder=6,
            bbox=label,
        )


def _draw_doors_and_landmarks(ax: Axes, proposal: Proposal) -> None:
    for name, door in proposal.doors.items():
        (x0, y0), (x1, y1) = door.segment
        ax.plot([x0, x1], [y0, y1], color="#268bd2", lw=3.0, solid_capstyle="butt", zorder=4)
        ax.annotate(name, door.centre, xytext=(4, 4), textcoords="offset points", fontsize=7, color="#268bd2")
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
