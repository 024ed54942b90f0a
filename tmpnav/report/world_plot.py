"""``tmpnav show``: the map, rooms, doors, landmarks and the robots' initial beliefs."""

from __future__ import annotations

from pathlib import Path

from tmpnav.report import figures as fg
from tmpnav.types import Scenario
from tmpnav.world import World


def plot_world(scenario: Scenario, world: World, path: Path) -> None:
    """Write the world figure; robots are drawn with their 2-sigma initial ellipse."""
    fig, ax = fg.new_axes(world, extent=fg.scenario_extent(scenario, world))
    fg.draw_map(ax, world)
    fg.draw_rooms(ax, scenario)
    fg.draw_doors(ax, scenario)
    fg.draw_landmarks(ax, scenario, sensor_range=scenario.models.landmark_sensor.range)
    for i in range(len(scenario.robots)):
        fg.draw_robot_start(ax, scenario, i)
    goals = []
    if scenario.goals.visit:
        goals.append("visit " + ", ".join(scenario.goals.visit))
    goals += [f"{r} visits {', '.join(t)}" for r, t in scenario.goals.per_robot]
    ax.set_title(
        f"{scenario.name}: {len(scenario.rooms)} rooms, {len(scenario.landmarks)} landmarks "
        f"(dashed: landmark sensor range), {len(scenario.robots)} robots (2σ start ellipses)\n"
        f"goals: {'; '.join(goals)}",
        fontsize=10,
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=9, title="landmarks", frameon=False)
    fg.save(fig, path)
