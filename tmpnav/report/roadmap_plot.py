"""``tmpnav roadmap``: the PRM drawn over the map, with the rooms' pose instantiations."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection

from tmpnav.report import figures as fg
from tmpnav.types import Roadmap, Scenario
from tmpnav.world import World


def plot_roadmap(scenario: Scenario, world: World, roadmap: Roadmap, path: Path) -> None:
    fig, ax = fg.new_axes(world, extent=fg.scenario_extent(scenario, world))
    fg.draw_map(ax, world)
    fg.draw_rooms(ax, scenario)
    fg.draw_doors(ax, scenario)
    segments = roadmap.nodes[roadmap.edges]
    ax.add_collection(LineCollection(segments, colors="#93a1a1", linewidths=0.35, alpha=0.7, zorder=3))
    ax.plot(roadmap.nodes[:, 0], roadmap.nodes[:, 1], ".", ms=1.6, color="#586e75", zorder=4)
    inst = np.array([roadmap.nodes[i] for ids in roadmap.instantiations.values() for i in ids])
    ax.plot(inst[:, 0], inst[:, 1], "o", ms=5, color="black", zorder=5, label="pose instantiations")
    fg.draw_landmarks(ax, scenario)
    for i in range(len(scenario.robots)):
        fg.draw_robot_start(ax, scenario, i)
    ax.set_title(
        f"{scenario.name}: roadmap with {roadmap.n_nodes} nodes, {len(roadmap.edges)} edges, "
        f"{scenario.roadmap.instantiations} pose instantiations per room (seed {scenario.roadmap.seed})",
        fontsize=10,
    )
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=9, frameon=False)
    fg.save(fig, path)
