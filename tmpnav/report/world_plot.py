"""``tmpnav show``: the map, rooms, doors, landmarks and the robots' initial beliefs."""

from __future__ import annotations

from pathlib import Path

from tmpnav.report import figures as fg
from tmpnav.types import Scenario
from tmpnav.world import World


def plot_world(scenario: Scenario, world: World, path: Path, localisability: bool = False) -> None:
    """Write the world figure; robots are drawn with their 2-sigma initial ellipse, magnified
    (and the title says so) where it would be too small to see. With ``localisability``, where
    the robots' range sensor pins them down (tmpnav.report.figures.draw_localisability)."""
    extent = fg.scenario_extent(scenario, world)
    fig, ax = fg.new_axes(world, extent=extent)
    fg.draw_map(ax, world)
    image = fg.draw_localisability(ax, scenario, world, extent) if localisability else None
    if image is not None:
        fg.localisability_colorbar(fig, ax, image)
    fg.draw_rooms(ax, scenario)
    fg.draw_doors(ax, scenario)
    fg.draw_landmarks(ax, scenario, sensor_range=scenario.models.landmark_sensor.range)
    xmin, _, xmax, _ = extent if extent is not None else world.grid.extent
    magnify = fg.start_magnification(scenario, xmax - xmin)
    for i in range(len(scenario.robots)):
        fg.draw_robot_start(ax, scenario, i, magnify)
    ax.set_title(f"{_robots_and_rooms(scenario, magnify)}\ngoals: {_goals(scenario)}", fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=9, title="landmarks", frameon=False)
    fg.save(fig, path)


def _robots_and_rooms(scenario: Scenario, magnify: int) -> str:
    sizes = ", ".join(f"{r.name} {fg.start_sigma2(r.cov):.2f} m" for r in scenario.robots[:4])
    sizes += ", ..." if len(scenario.robots) > 4 else ""
    drawn = f", drawn {magnify}x" if magnify > 1 else ""
    return (
        f"{scenario.name}: {len(scenario.places)} rooms, "
        + (f"{len(scenario.stations)} stations, " if scenario.stations else "")
        + f"{len(scenario.landmarks)} landmarks "
        f"(dashed: landmark sensor range), {len(scenario.robots)} robots (2σ start ellipses: {sizes}{drawn})"
    )


def _goals(scenario: Scenario) -> str:
    goals = []
    if scenario.goals.visit:
        goals.append("visit " + ", ".join(scenario.goals.visit))
    goals += [f"{r} visits {', '.join(t)}" for r, t in scenario.goals.per_robot]
    return "; ".join(goals)
