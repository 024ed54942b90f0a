"""What a valid scenario may still lack: one-line warnings that ``validate`` and ``plan`` print.

A scenario can be valid and still not say what its author meant: robots on a ROS map (a
building's own lidar map) with no ``models.range_sensor`` plan with the paper's landmark-only
model, whose robots drift metres between landmarks, with no collision threshold by default. That
is the model of the paper's corridor, not of a nav2 fleet; a ``models:`` section deleted by
mistake would otherwise go unnoticed until the plan's bounds of 1 and its conflicts. A scenario
with a ``models:`` section and no range sensor in it has chosen that model (the paper's
sparse-warehouse does): it gets no warning.
"""

from __future__ import annotations

from tmpnav.scenario.load import display_path
from tmpnav.types import RosMap, Scenario


def warnings(scenario: Scenario) -> list[str]:
    """The scenario's warnings, each one line naming the file, the key and what to add."""
    out = []
    line = scenario.line_of("models")
    if isinstance(scenario.map, RosMap) and scenario.models.range_sensor is None and line is None:
        where = display_path(scenario.source)
        out.append(
            f"{where}{f':{line}' if line else ''}: models.range_sensor: the robots on this ROS map carry no range "
            "sensor, so they plan with the paper's landmark-only model (metres of drift between landmarks, no "
            "collision threshold); add 'models: {range_sensor: {}}' for a typical 2D lidar (docs/scenario.md)"
        )
    return out
