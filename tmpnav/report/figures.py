"""Drawing primitives shared by every figure (the only code that imports matplotlib).

Figures are drawn on Agg canvases of their own, without pyplot (no figure manager, no backend
to choose: importing pyplot took about 0.3 s of every command that writes a figure), and written
atomically (:mod:`tmpnav.atomic`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import BinaryIO

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.patches import Circle, Ellipse, Polygon
from matplotlib.transforms import Bbox
from numpy.typing import NDArray

from tmpnav.atomic import write_file
from tmpnav.cachedir import CacheDir
from tmpnav.errors import OutputError
from tmpnav.report import figure_format, figure_suffixes
from tmpnav.report.labels import BADGE_NOTE, NOTE_OFFSET, ROBOT_NAME, ROOM_LABEL
from tmpnav.roadmap.store import stored_localisability
from tmpnav.types import Roadmap, RosMap, Scenario
from tmpnav.world import World
from tmpnav.world.grid import OccupancyGrid
from tmpnav.world.scan_information import LOCALISABILITY_POINTS

ROBOT_COLORS = ("#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")
LANDMARK_MARKERS = ("*", "P", "X", "D", "p", "h", "s", "^")
#: the picture formats Agg draws (the others have a renderer of their own)
AGG_FORMATS = frozenset(("png", "jpg", "jpeg", "tif", "tiff", "webp", "gif"))


#: the line of the robots past each len(ROBOT_COLORS): a fleet's robots that share a colour
#: are told apart by it (solid, dashed, dotted, dash-dotted)
ROBOT_LINES = ("-", (0, (5, 2)), (0, (1, 1.5)), (0, (5, 2, 1, 2)))


def robot_color(index: int) -> str:
    """The colour of the robot at ``index`` in the scenario's list of robots."""
    return ROBOT_COLORS[index % len(ROBOT_COLORS)]


def robot_line(index: int) -> str | tuple[float, tuple[float, ...]]:
    """The line style of the robot at ``index``: solid for the first len(ROBOT_COLORS) robots,
    then another for each round of the colours (:data:`ROBOT_LINES`)."""
    return ROBOT_LINES[(index // len(ROBOT_COLORS)) % len(ROBOT_LINES)]


def robot_colors(names: Sequence[str]) -> dict[str, str]:
    """Each robot's colour by name, ``names`` in the scenario's order: the one rule every figure
    of a plan (plan.png, schedule.png) colours its robots by, so a robot keeps its colour."""
    return {name: robot_color(index) for index, name in enumerate(names)}


def darker(color: str, factor: float = 0.6) -> tuple[float, float, float]:
    """``color`` darkened towards black: an outline that stands out against its own fill."""
    r, g, b = to_rgb(color)
    return r * factor, g * factor, b * factor


def new_axes(
    world: World,
    width: float = 12.0,
    extent: tuple[float, float, float, float] | None = None,
    max_height: float | None = None,
) -> tuple[Figure, Axes]:
    """A figure sized to the aspect ratio of the map (or of ``extent``: xmin, ymin, xmax, ymax,
    a part of it), with axes in metres; with ``max_height`` (inches) a tall view gets narrower."""
    xmin, ymin, xmax, ymax = extent if extent is not None else world.grid.extent
    aspect = (ymax - ymin) / max(xmax - xmin, 1e-9)
    if max_height is not None and width * aspect + 1.2 > max_height:
        width = max(4.0, (max_height - 1.2) / aspect)
    fig, ax = subplots((width, max(3.0, width * aspect + 1.2)))
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return fig, ax


def subplots(figsize: tuple[float, float]) -> tuple[Figure, Axes]:
    """A figure of ``figsize`` inches on an Agg canvas of its own, with one axes (what
    ``pyplot.subplots`` gives, without pyplot's registry of open figures)."""
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots()


def free_extent(grid: OccupancyGrid, margin: float = 1.0, min_area: float = 1.0) -> tuple[float, float, float, float]:
    """The part of the grid (xmin, ymin, xmax, ymax) around its known free space: the free
    regions of at least ``min_area`` m² (specks of free space in the unknown are left out),
    plus ``margin`` metres, within the grid. The whole grid if nothing is free."""
    from scipy import ndimage

    comp, n = ndimage.label(~grid.occupied)
    big = np.nonzero(np.bincount(comp.ravel(), minlength=n + 1)[1:] * grid.resolution**2 >= min_area)[0] + 1
    rows, cols = np.nonzero(np.isin(comp, big))
    gx0, gy0, gx1, gy1 = grid.extent
    if rows.size == 0:
        return gx0, gy0, gx1, gy1
    (x0, y0), r = grid.origin, grid.resolution
    return (
        max(gx0, x0 + cols.min() * r - margin),
        max(gy0, y0 + rows.min() * r - margin),
        min(gx1, x0 + (cols.max() + 1) * r + margin),
        min(gy1, y0 + (rows.max() + 1) * r + margin),
    )


def scenario_extent(scenario: Scenario, world: World) -> tuple[float, float, float, float] | None:
    """The view of ``show`` and ``roadmap``: for a ROS map, its known free space together with
    everything the scenario places (rooms, doors, landmarks, robots); None (the whole map) for a
    polygonal map, whose bounds the user chose."""
    if not isinstance(scenario.map, RosMap):
        return None
    x0, y0, x1, y1 = free_extent(world.grid)
    points = [p for room in scenario.rooms for p in room.polygon]
    points += [p for door in scenario.doors for p in door.segment]
    points += [lm.position for lm in scenario.landmarks] + [(r.pose.x, r.pose.y) for r in scenario.robots]
    gx0, gy0, gx1, gy1 = world.grid.extent
    for x, y in points:
        x0, y0, x1, y1 = (
            min(x0, max(gx0, x - 1.0)),
            min(y0, max(gy0, y - 1.0)),
            max(x1, min(gx1, x + 1.0)),
            max(y1, min(gy1, y + 1.0)),
        )
    return x0, y0, x1, y1


def draw_map(ax: Axes, world: World) -> None:
    """Occupied cells in dark grey on white."""
    xmin, ymin, xmax, ymax = world.grid.extent
    ax.imshow(
        world.grid.occupied,
        origin="lower",
        extent=(xmin, xmax, ymin, ymax),
        cmap="Greys",
        vmin=0,
        vmax=1.25,
        interpolation="nearest",
        zorder=0,
    )


#: the localisability map's colour scale: a scan's worst position std from LOCALISE_LOW (m, well
#: localised: no colour) to LOCALISE_HIGH (and beyond, or a direction the scan does not see: full colour)
LOCALISE_LOW, LOCALISE_HIGH = 0.01, 1.0


def draw_localisability(
    ax: Axes,
    scenario: Scenario,
    world: World,
    view: tuple[float, float, float, float] | None = None,
    alpha: float = 1.0,
    points: int = LOCALISABILITY_POINTS,
    cache: CacheDir | None = None,
) -> AxesImage | None:
    """Where a robot can localise with its range sensor (tmpnav.world.scan_information.localisability): each
    point coloured by the position std one scan leaves along its worst direction, on a log scale
    from 1 cm (white) to 1 m or unseen (dark red); walls left clear. None without a range sensor.
    With ``cache``, the map is read from it when an earlier figure computed it."""
    sensor = scenario.models.range_sensor
    if sensor is None:
        return None
    found = stored_localisability(cache, world, sensor, view, points)
    sigma = np.where(np.isinf(found.sigma), LOCALISE_HIGH, found.sigma)
    shade = np.clip(np.log10(sigma / LOCALISE_LOW) / np.log10(LOCALISE_HIGH / LOCALISE_LOW), 0.0, 1.0)
    half = (found.xs[1] - found.xs[0]) / 2 if found.xs.size > 1 else world.grid.resolution / 2
    return ax.imshow(
        np.ma.masked_invalid(shade),
        origin="lower",
        extent=(found.xs[0] - half, found.xs[-1] + half, found.ys[0] - half, found.ys[-1] + half),
        cmap="Reds",
        vmin=0.0,
        vmax=1.0,
        alpha=alpha,
        interpolation="nearest",
        zorder=0.5,
    )


def localisability_colorbar(fig: Figure, ax: Axes, image: AxesImage) -> None:
    """A colour bar in metres for :func:`draw_localisability`'s image."""
    ticks = [0.01, 0.03, 0.1, 0.3, 1.0]
    scale = np.log10(LOCALISE_HIGH / LOCALISE_LOW)
    bar = fig.colorbar(image, ax=ax, orientation="horizontal", fraction=0.035, pad=0.1, shrink=0.45, aspect=40)
    bar.set_ticks([np.log10(t / LOCALISE_LOW) / scale for t in ticks])
    bar.set_ticklabels([f"{t:g} m" for t in ticks[:-1]] + ["1 m, unseen"], fontsize=8)
    bar.set_label("localisability: one scan's position std, worst direction", fontsize=9)


def draw_rooms(ax: Axes, scenario: Scenario, view: tuple[float, float, float, float] | None = None) -> None:
    """Rooms, each named in the top-left corner of its part inside ``view`` (xmin, ymin, xmax, ymax;
    None: the whole room), away from robots and paths; tmpnav.report.labels.keep_labels_inside then hides a
    name that still sticks out of the axes. Stations are drawn at their poses (:func:`draw_stations`)."""
    for room in scenario.places:
        poly = np.array(room.polygon)
        ax.add_patch(Polygon(poly, closed=True, facecolor="#fdf6e3", edgecolor="#b58900", lw=0.8, alpha=0.55, zorder=1))
        x0, y0 = poly[:, 0].min(), poly[:, 1].min()
        x1, y1 = poly[:, 0].max(), poly[:, 1].max()
        if view is not None:
            x0, y0, x1, y1 = max(x0, view[0]), max(y0, view[1]), min(x1, view[2]), min(y1, view[3])
        if x1 - x0 < 0.5 or y1 - y0 < 0.5:  # (almost) out of view
            continue
        ax.text(
            x0 + 0.25,
            y1 - 0.25,
            room.name,
            ha="left",
            va="top",
            fontsize=11,
            color="#7a5c00",
            weight="bold",
            zorder=2,
            gid=ROOM_LABEL,
        )
    draw_stations(ax, scenario)


def draw_stations(ax: Axes, scenario: Scenario) -> None:
    """Each station (``goals.jobs`` with a place) as a small square at its pose, a tick along its
    heading, and its name beside it."""
    for station in scenario.stations:
        job = scenario.goals.job(station.name)
        if job is None or job.pose is None:
            continue
        x, y, theta = job.pose
        ax.plot([x], [y], marker="s", ms=5, mfc="#fdf6e3", mec="#7a5c00", mew=1.0, ls="none", zorder=3)
        ax.plot([x, x + 0.35 * np.cos(theta)], [y, y + 0.35 * np.sin(theta)], color="#7a5c00", lw=1.0, zorder=3)
        ax.annotate(
            station.name,
            (x, y),
            xytext=(-5, 5),  # above left: a plan's step badges take the lower right
            textcoords="offset points",
            ha="right",
            va="bottom",
            fontsize=8,
            color="#7a5c00",
            zorder=3,
            gid=ROOM_LABEL,
        )


def draw_doors(ax: Axes, scenario: Scenario) -> None:
    for door in scenario.doors:
        (x0, y0), (x1, y1) = door.segment
        if door.open:
            ax.plot([x0, x1], [y0, y1], zorder=3, solid_capstyle="butt", color="#268bd2", lw=2.0, ls=":")
        else:
            ax.plot([x0, x1], [y0, y1], zorder=3, solid_capstyle="butt", color="#dc322f", lw=3.0)


def draw_landmarks(ax: Axes, scenario: Scenario, sensor_range: float | None = None) -> None:
    kinds = list(dict.fromkeys(lm.kind for lm in scenario.landmarks))
    for lm in scenario.landmarks:
        k = kinds.index(lm.kind)
        color = matplotlib.colormaps["tab10"](k % 10)
        label = lm.kind if lm is next(x for x in scenario.landmarks if x.kind == lm.kind) else None
        ax.plot(
            *lm.position,
            marker=LANDMARK_MARKERS[k % len(LANDMARK_MARKERS)],
            ms=13,
            color=color,
            mec="black",
            mew=0.6,
            ls="none",
            zorder=6,
            label=label,
        )
        if sensor_range:
            ax.add_patch(
                Ellipse(
                    lm.position,
                    2 * sensor_range,
                    2 * sensor_range,
                    fill=False,
                    ls="--",
                    lw=0.5,
                    ec=color,
                    alpha=0.6,
                    zorder=2,
                )
            )


def covariance_ellipse(
    mean: NDArray[np.float64], cov: NDArray[np.float64], n_sigma: float = 2.0, **style: object
) -> Ellipse:
    """The n-sigma ellipse of the (x, y) block of a pose covariance."""
    vals, vecs = np.linalg.eigh(np.asarray(cov)[:2, :2])
    vals = np.clip(vals, 0.0, None)
    angle = float(np.degrees(np.arctan2(vecs[1, 1], vecs[0, 1])))
    width, height = 2 * n_sigma * np.sqrt(vals[1]), 2 * n_sigma * np.sqrt(vals[0])
    return Ellipse((float(mean[0]), float(mean[1])), width, height, angle=angle, **style)


def start_sigma2(cov: NDArray[np.float64]) -> float:
    """The 2-sigma radius (m) of a start belief along its most uncertain (x, y) direction."""
    return 2.0 * float(np.sqrt(max(np.linalg.eigvalsh(np.asarray(cov)[:2, :2]).max(), 0.0)))


def draw_robot_start(ax: Axes, scenario: Scenario, index: int, magnify: float = 1.0) -> None:
    """A robot at its start: its footprint (outline), heading, and the 2-sigma ellipse of its start
    belief filled in its colour on top, so that an ellipse smaller than the robot still shows
    (``magnify``: drawn that many times its size, which the caller says in the title)."""
    robot = scenario.robots[index]
    color = robot_color(index)
    x, y, th = robot.pose.x, robot.pose.y, robot.pose.theta
    ax.add_patch(Circle((x, y), robot.radius, fill=False, ec=color, lw=1.2, zorder=7))
    ax.arrow(x, y, 0.8 * np.cos(th), 0.8 * np.sin(th), width=0.06, color=color, zorder=7, length_includes_head=True)
    cov = np.asarray(robot.cov, dtype=float) * magnify**2
    ellipse = covariance_ellipse(np.array([x, y]), cov, 2.0, fc=(*to_rgb(color), 0.55), ec=darker(color))
    ellipse.set_linewidth(1.4)
    ellipse.set_zorder(7.5)
    ax.add_patch(ellipse)
    x0, x1 = ax.get_xlim()
    right = x > x1 - 0.1 * (x1 - x0)  # near the right edge: the name goes to the left, inside the axes
    ax.annotate(
        robot.name,
        (x, y),
        xytext=(-8 if right else 8, 8),
        textcoords="offset points",
        ha="right" if right else "left",
        color=color,
        fontsize=11,
        weight="bold",
        zorder=8,
        gid=ROBOT_NAME,
    )


def start_magnification(scenario: Scenario, view_width: float, share: float = 0.015) -> int:
    """How many times to draw the start ellipses so that the largest spans at least ``share`` of
    the view's width (a 0.2 m ellipse on a 50 m map is a few pixels); 1 when it already does."""
    largest = max((start_sigma2(r.cov) for r in scenario.robots), default=0.0)
    if largest <= 0.0:
        return 1
    return max(1, int(np.ceil(share * view_width / largest)))


def draw_instantiations(ax: Axes, roadmap: Roadmap, ms: float = 3.0, label: str | None = None) -> None:
    """The rooms' pose instantiations (sampled goal poses) as small black dots, as in the paper's Fig. 2."""
    ids = [i for nodes in roadmap.instantiations.values() for i in nodes]
    if not ids:
        return
    xy = np.asarray(roadmap.nodes)[ids]
    ax.plot(xy[:, 0], xy[:, 1], "o", ms=ms, color="black", ls="none", zorder=4, label=label)


def step_badge(ax: Axes, xy: tuple[float, float], text: str, color: str, offset: tuple[float, float] = (0, 0)) -> None:
    """A numbered round label (a plan step at its goal) in a robot's colour, ``offset`` in points."""
    ax.annotate(
        text,
        xy,
        xytext=offset,
        textcoords="offset points",
        ha="center",
        va="center",
        fontsize=8,
        weight="bold",
        color=color,
        bbox={"boxstyle": "circle,pad=0.25", "fc": "white", "ec": color, "lw": 1.4},
        arrowprops=None if offset == (0, 0) else {"arrowstyle": "-", "color": color, "lw": 0.8},
        zorder=9,
    )


def badge_note(ax: Axes, xy: tuple[float, float], text: str, color: str, offset: tuple[float, float] = (0, 0)) -> None:
    """A small note (an arrival time) to the lower right of a :func:`step_badge` at ``xy``
    (to its left or above where that runs out of the axes: tmpnav.report.labels.keep_labels_inside)."""
    ax.annotate(
        text,
        xy,
        xytext=(offset[0] + NOTE_OFFSET, offset[1] - NOTE_OFFSET),
        textcoords="offset points",
        ha="left",
        va="top",
        fontsize=7,
        color=darker(color, 0.8),
        bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8},
        zorder=9,
        gid=BADGE_NOTE,
    )


def render(fig: Figure, path: Path | BinaryIO, dpi: int = 110, fmt: str = "png") -> None:
    """Write the figure in format ``fmt`` to ``path`` (a temporary file of :mod:`tmpnav.atomic`,
    whose suffix says nothing, or an open binary file), cropped to what it draws."""
    fig.savefig(path, dpi=dpi, bbox_inches=tight_box(fig, dpi, fmt), format=fmt)


def tight_box(fig: Figure, dpi: int, fmt: str) -> Bbox | str:
    """What ``bbox_inches="tight"`` saves (the figure's artists, padded as matplotlib pads them), in
    inches, for a format Agg draws; "tight" for the others (their own renderer measures the text).

    matplotlib's "tight" draws the whole figure once without output to lay it out, measures it,
    then draws it: a quarter of a figure's time went to that first draw. Measuring needs only the
    layout, and gives the same box (the same pixels: tests/report/test_figures.py)."""
    if fmt not in AGG_FORMATS:
        return "tight"
    fig.set_dpi(dpi)  # as savefig sets it while it measures: text is laid out in pixels
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    box: Bbox = fig.get_tightbbox(renderer)
    pad = float(matplotlib.rcParams["savefig.pad_inches"])
    return box.padded(pad)


def save(fig: Figure, path: Path, dpi: int = 110) -> None:
    """Write the figure to ``path`` atomically (all or nothing), in the format its suffix
    names (``world.svg`` is an SVG, see FIGURE_FORMATS)."""
    fmt = figure_format(Path(path).name)
    if fmt is None:
        raise OutputError(f"cannot write {path}: expected a picture file ending in {figure_suffixes()}")
    write_file(path, lambda tmp: render(fig, tmp, dpi, fmt))
