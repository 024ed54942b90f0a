"""The simulated site's figure (docs/site.md): how the building the simulator scans differs from the map.

    .venv/bin/python benchmarks/plot_site.py [--session 1] [-o docs/figures/site-office.png]

Plans configs/office-ros.yaml (its default plan, taken as it is), draws one typical site of it
(tmpnav.execution.site, ``--site typical``) for the plan's paths: the map, each wall stretch
coloured by how far the site has it from the map's place, the clutter kept clear of the paths,
the people at t = 0 with their walks, and one scan from a pose on the paths, the map's ranges
against the site's; below, the difference beam by beam. An inset shows a corner's walls at the
grid's scale: the map's cells and the site's wall.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon
from scipy import ndimage

from tmpnav.api import plan
from tmpnav.execution.moves import queues
from tmpnav.execution.scans import ScanSimulator
from tmpnav.execution.site import Site, SiteNoise
from tmpnav.report.figures import draw_map
from tmpnav.types import RangeSensor
from tmpnav.world import World

ROOT = Path(__file__).resolve().parent.parent
CONFIG = "configs/office-ros.yaml"
CLUTTER, PERSON, PATH = "#d9822b", "#2b6cb0", "#38a169"


def wall_offsets(world: World, site: Site) -> tuple[np.ndarray, np.ndarray]:
    """The free cells along the walls (K, 2) m and how far the site's walls stand into the
    free space from the map's there (K,) m: the map's field less the site's walls' field."""
    sdf, moved = world.signed_distance, site.walls()
    edge = (sdf > 0) & (sdf < 1.5 * site.res)
    i, j = np.nonzero(edge)
    xy = np.column_stack([site.origin[0] + (j + 0.5) * site.res, site.origin[1] + (i + 0.5) * site.res])
    return xy, sdf[edge] - moved[edge]


def draw_site(ax: Axes, site: Site, paths: list[np.ndarray], t: float) -> None:
    """The clutter boxes, the people at ``t`` with their walks, and the robots' paths."""
    for line in paths:
        ax.plot(line[:, 0], line[:, 1], color=PATH, lw=1.5, alpha=0.8, zorder=2)
    half = site.noise.clutter_size / 2
    for x, y, theta in site.boxes:
        c, s = math.cos(theta), math.sin(theta)
        corners = [
            (x + c * u - s * v, y + s * u + c * v)
            for u, v in ((-half, -half), (half, -half), (half, half), (-half, half))
        ]
        ax.add_patch(Polygon(corners, closed=True, fc=CLUTTER, ec="black", lw=0.6, zorder=4))
    for a, b in site.walk_lines:
        ax.plot([a[0], b[0]], [a[1], b[1]], color=PERSON, lw=1, ls=":", zorder=3)
    for p in site.people_at(t):
        ax.add_patch(Circle(p, site.noise.person_radius, fc=PERSON, ec="black", lw=0.6, alpha=0.85, zorder=4))


def best_pose(world: World, site: Site, sensor: RangeSensor, paths: list[np.ndarray]) -> np.ndarray:
    """The point of the paths whose scan at t = 0 differs most from the map's by more than 0.3 m."""
    simulator, angles = ScanSimulator(world, sensor), sensor.beam_angles()
    best, most = np.zeros(3), -1
    for xy in np.concatenate(paths)[::2]:
        pose = np.array([xy[0], xy[1], 0.0])
        seen, mapped = site.ranges(pose, angles, sensor, 0.0), simulator.ranges(pose)[0]
        far = int(np.sum(np.abs(np.nan_to_num(seen, nan=99.0) - np.nan_to_num(mapped, nan=99.0)) > 0.3))
        if far > most:
            best, most = pose, far
    return best


def figure(session: int, out: Path) -> None:
    result = plan(CONFIG, accept_risk=True)
    report = result.report
    world, sensor = report.world, report.scenario.models.range_sensor
    assert sensor is not None
    paths = [np.asarray(m.points, dtype=float) for q in queues(report).values() for m in q]
    noise = SiteNoise()
    site = Site(world, noise, session, keep_clear=paths)
    pose = best_pose(world, site, sensor, paths)
    angles = sensor.beam_angles()
    mapped = ScanSimulator(world, sensor).ranges(pose)[0]
    seen = site.ranges(pose, angles, sensor, 0.0)

    fig, (ax, low) = plt.subplots(2, 1, figsize=(10, 8.6), gridspec_kw={"height_ratios": [3.0, 1.15]})
    draw_map(ax, world)
    xy, offset = wall_offsets(world, site)
    scale = 2.5 * noise.wall_offset
    dots = ax.scatter(
        xy[:, 0], xy[:, 1], c=100 * offset, s=2.5, cmap="RdBu_r", vmin=-100 * scale, vmax=100 * scale, zorder=1
    )
    fig.colorbar(dots, ax=ax, shrink=0.7, pad=0.01, label="wall into the room (+) or back (-) from the map, cm")
    draw_site(ax, site, paths, 0.0)
    psi = pose[2] + angles
    for r, colour, label, size in ((mapped, "0.45", "map's ranges", 16), (seen, "#c53030", "site's ranges", 9)):
        ok = ~np.isnan(r)
        ends = pose[:2] + r[ok, None] * np.column_stack([np.cos(psi[ok]), np.sin(psi[ok])])
        if colour != "0.45":
            for e in ends:
                ax.plot([pose[0], e[0]], [pose[1], e[1]], color=colour, lw=0.4, alpha=0.5, zorder=5)
        ax.scatter(
            ends[:, 0], ends[:, 1], s=size, color=colour, marker="o" if size < 10 else "x", label=label, zorder=6
        )
    ax.plot(*pose[:2], marker="^", ms=9, color="black", zorder=7, label="scanning from")
    ax.plot([], [], color=PATH, lw=1.5, label="the plan's paths (kept clear)")
    ax.add_patch(Polygon(np.zeros((4, 2)), fc=CLUTTER, ec="black", lw=0.6, label="unmapped clutter"))
    ax.add_patch(Circle((0, 0), 0, fc=PERSON, ec="black", lw=0.6, label="people at t = 0 (dotted: their walks)"))
    x0, y0, x1, y1 = 0.6, 0.6, 23.6, 13.4
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.09), ncol=3, fontsize=8, frameon=False)
    ax.set_title(f"{report.scenario.name}, --site typical: {site.text()}", fontsize=10)
    inset(ax, world, site)

    diff = seen - mapped
    deg = np.degrees(angles)
    low.axhline(0.0, color="0.6", lw=0.8)
    both = ~np.isnan(diff)
    low.vlines(deg[both], 0.0, diff[both], color="#c53030", lw=1.2)
    low.scatter(deg[both], diff[both], s=10, color="#c53030", zorder=3)
    lost = np.isnan(seen) != np.isnan(mapped)
    low.scatter(
        deg[lost], np.zeros(lost.sum()), marker="s", s=14, fc="none", ec="black", label="returns in one scan only"
    )
    low.set_yscale("symlog", linthresh=0.01, linscale=0.5)
    ticks = [-10.0, -1.0, -0.1, -0.01, 0.0, 0.01, 0.1, 1.0, 10.0]
    low.set_yticks(ticks, [f"{v:g} m" if abs(v) >= 1 else f"{100 * v:g} cm" if v else "0" for v in ticks])
    low.set_ylim(-12.0, 12.0)
    low.set_xlim(-180, 180)
    low.set_xticks(range(-180, 181, 45))
    low.set_xlabel("beam angle from the heading (deg)")
    low.set_ylabel("site - map")
    low.set_title(
        "the scan beam by beam: centimetres where walls are off, metres where clutter or a person is in the way",
        fontsize=9,
    )
    if lost.any():
        low.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}: {site.text()}; scan from ({pose[0]:.2f}, {pose[1]:.2f})")


def inset(ax: Axes, world: World, site: Site) -> None:
    """A metre of the walls at the grid's scale: the map's cells and the site's wall (its zero level)."""
    sdf = world.signed_distance
    # where a wall moved most, of the walls at least a third of a 0.5 m square thick (not the map's specks)
    thick = ndimage.uniform_filter(world.grid.occupied.astype(float), size=round(0.5 / site.res)) > 0.33
    xy, offset = wall_offsets(world, site)
    i, j, _ = world.grid.cells(xy)
    clear = np.array([np.hypot(*(site.boxes[:, :2] - p).T).min(initial=np.inf) > 1.0 for p in xy])
    k = int(np.argmax(np.abs(offset) * thick[i, j] * clear))
    cx, cy = xy[k]
    box = ax.inset_axes((0.72, 0.04, 0.26, 0.26))
    draw_map(box, world)
    xs, ys = world.grid.cell_centers()
    box.contour(xs, ys, site.walls(), levels=[0.0], colors="#c53030", linewidths=1.5)
    box.contour(xs, ys, sdf, levels=[0.0], colors="black", linewidths=0.8, linestyles="--")
    box.set_xlim(cx - 0.5, cx + 0.5)
    box.set_ylim(cy - 0.5, cy + 0.5)
    box.set_xticks([])
    box.set_yticks([])
    box.set_title("1 m of wall: map (dashed), site (red)", fontsize=7)
    ax.indicate_inset_zoom(box, edgecolor="0.3")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--session", type=int, default=1, help="the session's seed of the site drawn")
    parser.add_argument("-o", "--output", type=Path, default=ROOT / "docs" / "figures" / "site-office.png")
    args = parser.parse_args()
    figure(args.session, args.output)


if __name__ == "__main__":
    main()
